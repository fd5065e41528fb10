#include "mesh_file.h"

#include <string>
#include <utility>

#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"

namespace octolod::cli {

Result<MeshFile> read_mesh_file(const std::filesystem::path& path) {
  Result<PlyMesh> ply = read_ply(path);
  if (!ply.ok()) return ply.status();
  if (ply->triangles.empty())
    return bad_input_error(path.string() + ": the mesh has no triangles (" +
                           std::to_string(ply->info.vertex_count) + " vertices, " +
                           std::to_string(ply->info.face_count) + " faces)");
  MeshFile file;
  file.color_type = ply->info.color_type;
  file.mesh.layout = ply->info.layout;
  file.mesh.vertices = std::move(ply->vertices);
  file.mesh.indices = std::move(ply->triangles);
  return file;
}

Status write_mesh_file(const std::filesystem::path& path, const NodeMesh& mesh, bool ascii,
                       PlyColorType color_type) {
  PlyWriteOptions options;
  options.format = ascii ? PlyFormat::ascii : PlyFormat::binary_little_endian;
  options.layout = mesh.layout;
  options.color_type = color_type;
  return write_ply(path, options, mesh.vertices, mesh.indices);
}

}  // namespace octolod::cli
