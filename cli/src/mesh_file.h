// Whole meshes in and out of PLY files for the measuring commands (eval, reference, compare,
// extract), which need the mesh in memory: about 50 bytes per triangle with all attributes.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>

#include "octolod/formats/node_file.h"
#include "octolod/formats/ply.h"
#include "octolod/formats/status.h"

namespace octolod::cli {

struct MeshFile {
  NodeMesh mesh;                                  // layout as the file's vertex properties
  PlyColorType color_type = PlyColorType::uchar;  // how the file stores colours
  // The point of the file's coordinates that mesh's positions are relative to (double).
  std::array<double, 3> origin{0.0, 0.0, 0.0};
};

// Reads a PLY file (any format the streaming reader accepts; polygons fan-triangulated), with
// positions relative to `frame` (another mesh's or a tree's origin), or when it is not given and
// the file's positions are double, to its first vertex rounded to whole units (as the bake
// reads them: geo-referenced coordinates keep their detail). Bytes after the last element are
// ignored with a warning on stderr (warn_trailing_bytes). Errors name the file: io when it
// cannot be opened or read, bad_input when it is malformed or holds no triangle (nothing to
// measure).
Result<MeshFile> read_mesh_file(const std::filesystem::path& path,
                                const std::optional<std::array<double, 3>>& frame = std::nullopt);

// Writes `mesh` atomically (PlyWriter: temporary sibling, then rename; nothing is left behind on
// failure): binary little-endian, or ascii when `ascii`; colours stored as `color_type`. With a
// non-zero `origin` (the mesh's positions are relative to it) positions are written as double
// with it added back: the file is in the input's coordinates. A non-empty `texture` (the image
// the UVs index, as a path relative to the file's directory) is named in a "comment TextureFile"
// line, as MeshLab writes and reads it.
Status write_mesh_file(const std::filesystem::path& path, const NodeMesh& mesh, bool ascii,
                       PlyColorType color_type = PlyColorType::uchar,
                       const std::array<double, 3>& origin = {0.0, 0.0, 0.0},
                       const std::string& texture = "");

}  // namespace octolod::cli
