// Split (seed 4.2.1): the PLY read in portions into vertex records and triangle index records.
#include "split.h"

#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <system_error>
#include <utility>

#include "octolod/bake/temp_file.h"
#include "page_array.h"
#include "record_file.h"

namespace octolod::bake {

Result<SplitResult> split_ply(PlyReader& reader, std::size_t batch_bytes, const SplitSinks& sinks) {
  SplitResult result;
  result.layout = reader.info().layout;
  result.vertex_count = reader.info().vertex_count;
  const std::size_t floats = result.layout.floats();
  const std::size_t corner_floats = 3 * std::size_t{reader.info().corners.floats()};  // per triangle
  if (corner_floats != 0 && !sinks.corner_values)
    return unsupported_error(reader.info().path.string() +
                             ": the faces' attributes per corner (texcoord, face colours) have no place here");
  const std::size_t batch_records = std::max<std::size_t>(1, batch_bytes / sizeof(TriangleRecord));
  const PageArray<TriangleRecord> batch(batch_records);
  std::uint64_t done = 0;
  std::uint64_t vertices_seen = 0;
  bool first_triangles = true;
  for (;;) {
    auto next = reader.next();
    if (!next.ok()) return next.status();
    const PlyBatch& b = next.value();
    if (b.kind == PlyBatch::Kind::end) break;
    if (b.kind == PlyBatch::Kind::vertices) {
      const std::size_t count = b.vertices.size() / floats;
      for (std::size_t i = 0; i < count; ++i) result.bounds.extend(&b.vertices[i * floats]);
      OCTOLOD_RETURN_IF_ERROR(sinks.vertices(b.first, b.vertices));
      done += count;
      vertices_seen += count;
    } else {
      if (first_triangles && sinks.vertices_done && vertices_seen == result.vertex_count) {
        OCTOLOD_RETURN_IF_ERROR(sinks.vertices_done(result.bounds));
      }
      first_triangles = false;
      const std::size_t count = b.triangles.size() / 3;
      constexpr std::uint64_t kMaxTriangles = std::numeric_limits<std::uint32_t>::max();
      if (b.first + count > kMaxTriangles) {
        std::string message;  // built in place: GCC 12 -O3 misreports "'" + std::string
        message.append("'").append(reader.info().path.string()).append("' has more than ");
        message.append(std::to_string(kMaxTriangles)).append(" triangles; triangle ids are 32-bit");
        return unsupported_error(std::move(message));
      }
      for (std::size_t start = 0; start < count; start += batch_records) {
        const std::size_t n = std::min(batch_records, count - start);
        const std::uint32_t* idx = b.triangles.data() + 3 * start;
        for (std::size_t i = 0; i < n; ++i) {
          batch[i] = TriangleRecord{{VertexId{idx[3 * i]}, VertexId{idx[3 * i + 1]},
                                     VertexId{idx[3 * i + 2]}},
                                    TriangleId{static_cast<std::uint32_t>(b.first + start + i)}};
        }
        OCTOLOD_RETURN_IF_ERROR(sinks.triangles(std::span<const TriangleRecord>(batch.get(), n)));
        if (corner_floats != 0)
          OCTOLOD_RETURN_IF_ERROR(
              sinks.corner_values(b.corner_values.subspan(corner_floats * start, corner_floats * n)));
      }
      result.triangle_count = b.first + count;
      done += count;
    }
    if (sinks.progress) sinks.progress(done);
  }
  result.origin = reader.info().position_origin;
  result.trailing_bytes = reader.info().trailing_bytes;
  return result;
}

Result<SplitResult> split_ply_to_files(const std::filesystem::path& ply,
                                       const std::filesystem::path& vertex_path,
                                       const std::filesystem::path& triangle_path,
                                       std::size_t buffer_bytes) {
  // The files are ours only once this function succeeds.
  TempFile vertex_owner(vertex_path);
  TempFile triangle_owner(triangle_path);
  PlyReadOptions read_options;
  read_options.buffer_bytes = std::max<std::size_t>(buffer_bytes, 4096);
  auto reader = PlyReader::open(ply, read_options);
  if (!reader.ok()) return reader.status();
  const VertexLayout layout = reader.value()->info().layout;
  auto vertices = RecordWriter::create(vertex_path, layout.bytes(), buffer_bytes);
  if (!vertices.ok()) return vertices.status();
  auto triangles = RecordWriter::create(triangle_path, sizeof(TriangleRecord), buffer_bytes);
  if (!triangles.ok()) return triangles.status();
  SplitSinks sinks;
  sinks.vertices = [&](std::uint64_t, std::span<const float> v) {
    return vertices->append(reinterpret_cast<const std::byte*>(v.data()), v.size() / layout.floats());
  };
  sinks.triangles = [&](std::span<const TriangleRecord> t) {
    return triangles->append(reinterpret_cast<const std::byte*>(t.data()), t.size());
  };
  auto result = split_ply(*reader.value(), buffer_bytes, sinks);
  if (!result.ok()) return result.status();
  OCTOLOD_RETURN_IF_ERROR(vertices->finish());
  OCTOLOD_RETURN_IF_ERROR(triangles->finish());
  vertex_owner.release();
  triangle_owner.release();
  return result;
}

}  // namespace octolod::bake
