#include "mesh_file.h"

#include <string>
#include <utility>

#include "command.h"
#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"

namespace octolod::cli {

Result<MeshFile> read_mesh_file(const std::filesystem::path& path,
                                const std::optional<std::array<double, 3>>& frame) {
  PlyReadOptions options;
  options.recentre_double_positions = true;
  options.position_origin = frame;
  Result<PlyMesh> ply = read_ply(path, options);
  if (!ply.ok()) return ply.status();
  warn_trailing_bytes(path.string(), ply->info.trailing_bytes);
  if (ply->triangles.empty())
    return bad_input_error(path.string() + ": the mesh has no triangles (" +
                           std::to_string(ply->info.vertex_count) + " vertices, " +
                           std::to_string(ply->info.face_count) + " faces)");
  MeshFile file;
  file.color_type = ply->info.color_type;
  file.origin = ply->info.position_origin;
  file.mesh.layout = ply->info.layout;
  file.mesh.vertices = std::move(ply->vertices);
  file.mesh.indices = std::move(ply->triangles);
  return file;
}

Status write_mesh_file(const std::filesystem::path& path, const NodeMesh& mesh, bool ascii,
                       PlyColorType color_type, const std::array<double, 3>& origin,
                       const std::string& texture) {
  PlyWriteOptions options;
  options.format = ascii ? PlyFormat::ascii : PlyFormat::binary_little_endian;
  options.layout = mesh.layout;
  options.color_type = color_type;
  if (origin != std::array<double, 3>{0.0, 0.0, 0.0}) options.position_origin = origin;
  if (!texture.empty()) options.comments.push_back("TextureFile " + texture);
  return write_ply(path, options, mesh.vertices, mesh.indices);
}

}  // namespace octolod::cli
