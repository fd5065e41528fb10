// Streaming PLY writer: declare counts up front, then stream vertices and triangles (in that
// order). The file appears at `path` only after finish() succeeded (written to a temporary
// sibling, then renamed); destroying an unfinished writer removes the temporary.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "octolod/formats/ply.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod {

struct PlyWriteOptions {
  PlyFormat format = PlyFormat::binary_little_endian;
  VertexLayout layout;
  PlyColorType color_type = PlyColorType::uchar;
  std::vector<std::string> comments;  // one "comment" line each; must not contain newlines
  // When set, x, y, z are written as double, each the given float plus this origin (in
  // double): a mesh held relative to a point of the input (PlyInfo::position_origin) written
  // back in the input's own coordinates, without rounding them to float.
  std::optional<std::array<double, 3>> position_origin;
};

class PlyWriter {
 public:
  static Result<std::unique_ptr<PlyWriter>> create(const std::filesystem::path& path,
                                                   const PlyWriteOptions& options,
                                                   std::uint64_t vertex_count,
                                                   std::uint64_t triangle_count);
  virtual ~PlyWriter() = default;

  // layout.floats() floats per vertex; all vertices before any triangle.
  virtual Status write_vertices(std::span<const float> vertices) = 0;
  // 3 indices per triangle, each < vertex_count.
  virtual Status write_triangles(std::span<const std::uint32_t> triangles) = 0;
  // Checks that exactly the declared counts were written, flushes, and publishes the file.
  virtual Status finish() = 0;
};

// Convenience: writes a whole in-memory mesh.
Status write_ply(const std::filesystem::path& path, const PlyWriteOptions& options,
                 std::span<const float> vertices, std::span<const std::uint32_t> triangles);

}  // namespace octolod
