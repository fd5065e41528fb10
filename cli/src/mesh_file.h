// Whole meshes in and out of PLY files for the measuring commands (eval, reference, compare,
// extract), which need the mesh in memory: about 50 bytes per triangle with all attributes.
#pragma once

#include <filesystem>

#include "octolod/formats/node_file.h"
#include "octolod/formats/ply.h"
#include "octolod/formats/status.h"

namespace octolod::cli {

struct MeshFile {
  NodeMesh mesh;                                  // layout as the file's vertex properties
  PlyColorType color_type = PlyColorType::uchar;  // how the file stores colours
};

// Reads a PLY file (any format the streaming reader accepts; polygons fan-triangulated).
// Errors name the file: io when it cannot be opened or read, bad_input when it is malformed or
// holds no triangle (nothing to measure).
Result<MeshFile> read_mesh_file(const std::filesystem::path& path);

// Writes `mesh` atomically (PlyWriter: temporary sibling, then rename; nothing is left behind on
// failure): binary little-endian, or ascii when `ascii`; colours stored as `color_type`.
Status write_mesh_file(const std::filesystem::path& path, const NodeMesh& mesh, bool ascii,
                       PlyColorType color_type = PlyColorType::uchar);

}  // namespace octolod::cli
