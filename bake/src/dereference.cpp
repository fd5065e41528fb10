// Pointer dereferencing by sorted scans (seed 3.3, 4.2.2, Table 4.1): vertex ids replaced by
// vertex records while the vertex file is read strictly front to back.
#include "dereference.h"

#include <algorithm>
#include <cassert>
#include <cstring>
#include <numeric>
#include <string>

namespace octolod::bake {
namespace {

std::uint32_t load_u32(const std::byte* p) {
  std::uint32_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

}  // namespace

SortKeyFn last_corner_key(VertexLayout layout, int filled) {
  const std::size_t rb = working_record_bytes(layout, filled);
  const std::size_t id_offset = working_vertex_id_offset(layout, filled) + 4 * (2 - filled);
  const std::size_t tri_offset = rb - 4;
  return [rb, id_offset, tri_offset](std::span<const std::byte> records,
                                     std::span<std::uint64_t> keys) {
    const std::byte* p = records.data();
    for (std::size_t i = 0; i < keys.size(); ++i, p += rb) {
      keys[i] = (std::uint64_t{load_u32(p + id_offset)} << 32) | load_u32(p + tri_offset);
    }
  };
}

Status dereference_pass(int corner, VertexLayout layout, RecordSorter& sorted,
                        RecordReader& vertices, RecordOutput& out) {
  const std::size_t in_bytes = working_record_bytes(layout, corner);
  const std::size_t out_bytes = working_record_bytes(layout, corner + 1);
  const std::size_t vertex_bytes = layout.bytes();
  const std::size_t prefix = working_vertex_id_offset(layout, corner);  // filled corners
  const std::size_t suffix = in_bytes - prefix - 4;                     // ids after, triangle id
  assert(sorted.record_bytes() == in_bytes && "dereference_pass: sorter of the wrong records");

  // The block of the vertex file in memory: vertices [block_first, block_end).
  std::uint64_t block_first = 0;
  std::uint64_t block_end = 0;
  const std::byte* block = nullptr;
  for (;;) {
    auto in = sorted.next();
    if (!in.ok()) return in.status();
    if (in->empty()) break;
    const std::byte* rec = in->data();
    std::size_t left = in->size() / in_bytes;
    while (left > 0) {
      auto space = out.reserve(left);
      if (!space.ok()) return space.status();
      const std::size_t n = space->size() / out_bytes;
      std::byte* dst = space->data();
      for (std::size_t i = 0; i < n; ++i, rec += in_bytes, dst += out_bytes) {
        const std::uint32_t id = load_u32(rec + prefix);
        assert(id >= block_first && "dereference_pass: input not sorted by this corner's id");
        while (id >= block_end) {
          auto next = vertices.read();
          if (!next.ok()) return next.status();
          if (next->empty()) {
            return io_error("vertex file '" + vertices.path().string() + "' has " +
                            std::to_string(vertices.record_count()) + " vertices, vertex " +
                            std::to_string(id) + " is missing");
          }
          block = next->data();
          block_first = block_end;
          block_end += next->size() / vertex_bytes;
        }
        std::memcpy(dst, rec, prefix);
        std::memcpy(dst + prefix, block + (id - block_first) * vertex_bytes, vertex_bytes);
        std::memcpy(dst + prefix + vertex_bytes, rec + prefix + 4, suffix);
      }
      OCTOLOD_RETURN_IF_ERROR(out.commit(n));
      left -= n;
    }
  }
  return {};
}

Status dereference_in_core(VertexLayout layout, std::span<const float> vertices,
                           RecordSorter& sorted, RecordOutput& out) {
  const std::size_t out_bytes = soup_record_bytes(layout);
  assert(sorted.record_bytes() == sizeof(TriangleRecord));
  for (;;) {
    auto in = sorted.next();
    if (!in.ok()) return in.status();
    if (in->empty()) break;
    const std::byte* rec = in->data();
    std::size_t left = in->size() / sizeof(TriangleRecord);
    while (left > 0) {
      auto space = out.reserve(left);
      if (!space.ok()) return space.status();
      const std::size_t n = space->size() / out_bytes;
      std::byte* dst = space->data();
      for (std::size_t i = 0; i < n; ++i, rec += sizeof(TriangleRecord), dst += out_bytes) {
        const std::uint32_t corners[3] = {load_u32(rec), load_u32(rec + 4), load_u32(rec + 8)};
        store_soup_record(dst, layout, vertices.data(), corners, load_u32(rec + 12));
      }
      OCTOLOD_RETURN_IF_ERROR(out.commit(n));
      left -= n;
    }
  }
  return {};
}

std::vector<std::byte> dereference_in_memory(std::span<const float> vertices,
                                             std::span<const std::uint32_t> triangles,
                                             VertexLayout layout, SoupOrder order) {
  const std::size_t out_bytes = soup_record_bytes(layout);
  const std::size_t count = triangles.size() / 3;
  // Output order: triangle ids, stably sorted by corner 2's id for by_last_corner.
  std::vector<std::uint32_t> order_ids(count);
  std::iota(order_ids.begin(), order_ids.end(), 0u);
  if (order == SoupOrder::by_last_corner) {
    std::stable_sort(order_ids.begin(), order_ids.end(), [&](std::uint32_t a, std::uint32_t b) {
      return triangles[3 * std::size_t{a} + 2] < triangles[3 * std::size_t{b} + 2];
    });
  }
  std::vector<std::byte> soup(count * out_bytes);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t t = order_ids[i];
    const std::uint32_t* corners = triangles.data() + 3 * std::size_t{t};
    for (std::size_t c = 0; c < 3; ++c)
      assert(std::size_t{corners[c]} * layout.floats() < vertices.size() &&
             "dereference_in_memory: vertex id out of range");
    store_soup_record(soup.data() + i * out_bytes, layout, vertices.data(), corners, t);
  }
  return soup;
}

}  // namespace octolod::bake
