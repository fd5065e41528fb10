// Pointer dereferencing (seed 3.3, 4.2.2, Table 4.1): vertex ids replaced by vertex records
// while the vertex file is read strictly front to back, through a sliding window (the window
// pass) or by sorted scans (the seed's three passes).
#include "dereference.h"

#include <algorithm>
#include <cassert>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace octolod::bake {
namespace {

std::uint32_t load_u32(const std::byte* p) {
  std::uint32_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

Status missing_vertex(const RecordReader& vertices, std::uint64_t id) {
  return io_error("vertex file '" + vertices.path().string() + "' has " +
                  std::to_string(vertices.record_count()) + " vertices, vertex " +
                  std::to_string(id) + " is missing");
}

}  // namespace

WindowDereferencer::WindowDereferencer(VertexLayout layout, std::size_t window_vertices,
                                       RecordReader& vertices, RecordOutput& out, FarFn far)
    : layout_(layout),
      window_vertices_(window_vertices),
      vertices_(vertices),
      out_(out),
      far_(std::move(far)),
      window_(window_vertices * layout.bytes()) {
  assert(window_vertices > 0 && (window_vertices & (window_vertices - 1)) == 0 &&
         "WindowDereferencer: the window holds a power of two of vertices");
  far_batch_.reserve(std::max<std::size_t>(1, (std::size_t{64} << 10) / sizeof(TriangleRecord)));
}

// Reads until vertex `last` is in the window, keeping vertex `keep` (last - keep <
// window_vertices_) in it; reads ahead of what `last` needs, so the window is not refilled
// vertex by vertex.
Status WindowDereferencer::fill_to(std::uint64_t keep, std::uint64_t last) {
  const std::size_t vertex_bytes = layout_.bytes();
  const std::size_t read_ahead = std::max<std::size_t>(1, window_vertices_ / 8);
  while (end_ <= last) {
    const std::uint64_t want = std::max<std::uint64_t>(last + 1 - end_, read_ahead);
    auto block = vertices_.read(std::min<std::uint64_t>(want, keep + window_vertices_ - end_));
    if (!block.ok()) return block.status();
    if (block->empty()) return missing_vertex(vertices_, last);
    const std::byte* src = block->data();
    for (std::size_t n = block->size() / vertex_bytes; n > 0;) {
      const std::size_t slot = static_cast<std::size_t>(end_ & (window_vertices_ - 1));
      const std::size_t run = std::min<std::size_t>(n, window_vertices_ - slot);
      std::memcpy(window_.get() + slot * vertex_bytes, src, run * vertex_bytes);
      src += run * vertex_bytes;
      end_ += run;
      n -= run;
    }
  }
  return {};
}

Status WindowDereferencer::flush_far() {
  if (far_batch_.empty()) return {};
  OCTOLOD_RETURN_IF_ERROR(far_(far_batch_));
  stats_.far += far_batch_.size();
  far_batch_.clear();
  return {};
}

Status WindowDereferencer::add(std::span<const TriangleRecord> triangles) {
  const std::size_t out_bytes = soup_record_bytes(layout_);
  const std::uint64_t mask = window_vertices_ - 1;
  const TriangleRecord* t = triangles.data();
  std::size_t left = triangles.size();
  while (left > 0) {
    auto space = out_.reserve(left);
    if (!space.ok()) return space.status();
    const std::size_t n = space->size() / out_bytes;
    std::byte* dst = space->data();
    std::size_t written = 0;
    for (std::size_t i = 0; i < n; ++i, ++t) {
      std::uint32_t ids[3];
      for (int c = 0; c < 3; ++c) ids[c] = static_cast<std::uint32_t>(t->corner[c]);
      const std::uint64_t lo = std::min({ids[0], ids[1], ids[2]});
      const std::uint64_t hi = std::max({ids[0], ids[1], ids[2]});
      const std::uint64_t first = end_ > window_vertices_ ? end_ - window_vertices_ : 0;
      if (hi - lo >= window_vertices_ || lo < first) {
        far_batch_.push_back(*t);
        if (far_batch_.size() == far_batch_.capacity()) OCTOLOD_RETURN_IF_ERROR(flush_far());
        continue;
      }
      OCTOLOD_RETURN_IF_ERROR(fill_to(lo, hi));
      std::uint32_t slots[3];
      for (int c = 0; c < 3; ++c) slots[c] = static_cast<std::uint32_t>(ids[c] & mask);
      store_soup_record(dst + written * out_bytes, layout_,
                        reinterpret_cast<const float*>(window_.get()), slots,
                        static_cast<std::uint32_t>(t->triangle));
      ++written;
    }
    OCTOLOD_RETURN_IF_ERROR(out_.commit(written));
    stats_.near += written;
    left -= n;
  }
  return {};
}

Status WindowDereferencer::finish() { return flush_far(); }

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
          if (next->empty()) return missing_vertex(vertices, id);
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
                                             VertexLayout layout) {
  const std::size_t out_bytes = soup_record_bytes(layout);
  const std::size_t count = triangles.size() / 3;
  std::vector<std::byte> soup(count * out_bytes);
  for (std::size_t t = 0; t < count; ++t) {
    const std::uint32_t* corners = triangles.data() + 3 * t;
    for (std::size_t c = 0; c < 3; ++c)
      assert(std::size_t{corners[c]} * layout.floats() < vertices.size() &&
             "dereference_in_memory: vertex id out of range");
    store_soup_record(soup.data() + t * out_bytes, layout, vertices.data(), corners,
                      static_cast<std::uint32_t>(t));
  }
  return soup;
}

}  // namespace octolod::bake
