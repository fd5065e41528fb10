// Split (seed 4.2.1): a PLY streamed in portions becomes vertex records (layout.floats() floats
// each, file order) and triangle index records (TriangleRecord, file order, triangle ids
// counting from 0), handed to sinks batch by batch. Memory: the reader's buffers plus one
// batch of triangle records, whatever the file's size. Also computes the bounds of the vertices.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

#include "octolod/bake/soup.h"
#include "octolod/formats/bounds.h"
#include "octolod/formats/ply_reader.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::bake {

struct SplitSinks {
  // Consecutive vertices, layout.floats() floats each; the span is valid during the call only.
  std::function<Status(std::uint64_t first, std::span<const float> vertices)> vertices;
  // Consecutive triangles; the span is valid during the call only.
  std::function<Status(std::span<const TriangleRecord> triangles)> triangles;
  // Required when the faces give their corners attributes (PlyInfo::corners), else never
  // called: right after each `triangles` call, the values of each corner of those triangles
  // (3 * PlyInfo::corners.floats() per triangle, PlyBatch::corner_values); the span is valid
  // during the call only.
  std::function<Status(std::span<const float> corner_values)> corner_values;
  // Optional: called once before the first triangle batch if every vertex came before it (the
  // vertex element precedes the faces), with the bounds of all vertices. An error it returns
  // ends the split.
  std::function<Status(const Bounds& bounds)> vertices_done;
  // Optional: vertices + triangles read so far (triangles counted as their PLY faces' share).
  std::function<void(std::uint64_t done)> progress;
};

struct SplitResult {
  VertexLayout layout;
  std::uint64_t vertex_count = 0;
  std::uint64_t triangle_count = 0;
  Bounds bounds;  // of all vertices, model units
  std::array<double, 3> origin{0.0, 0.0, 0.0};  // the reader's position_origin (PlyInfo)
  std::uint64_t trailing_bytes = 0;              // ignored after the last element (PlyInfo)
};

// Reads `reader` to its end. `batch_bytes` bounds the triangle record batch (at least one
// record). unsupported when the triangles would need ids of 2^32 or more, or when the faces
// give their corners attributes and `sinks` has no corner_values.
Result<SplitResult> split_ply(PlyReader& reader, std::size_t batch_bytes, const SplitSinks& sinks);

// The seed's two files: `vertex_path` (vertex records) and `triangle_path` (TriangleRecord),
// each written through a buffer of `buffer_bytes`. Files are removed again on error. Inputs with
// attributes per face corner are refused (unsupported): the two files have no place for them.
Result<SplitResult> split_ply_to_files(const std::filesystem::path& ply,
                                       const std::filesystem::path& vertex_path,
                                       const std::filesystem::path& triangle_path,
                                       std::size_t buffer_bytes);

}  // namespace octolod::bake
