#include "mesh_check.h"

#include <cmath>
#include <string>

namespace octolod::measure {

Status check_mesh(const NodeMesh& mesh, std::string_view name) {
  const std::uint32_t stride = mesh.layout.floats();
  if (mesh.vertices.size() % stride != 0)
    return bad_input_error(std::string(name) + ": " + std::to_string(mesh.vertices.size()) +
                           " vertex floats are not a multiple of the layout (" +
                           mesh.layout.describe() + ", " + std::to_string(stride) + " floats)");
  if (mesh.indices.size() % 3 != 0)
    return bad_input_error(std::string(name) + ": " + std::to_string(mesh.indices.size()) +
                           " indices are not a multiple of 3");
  const std::size_t vertex_count = mesh.vertex_count();
  for (std::size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= vertex_count)
      return bad_input_error(std::string(name) + ": index " + std::to_string(i) + " is " +
                             std::to_string(mesh.indices[i]) + ", but there are only " +
                             std::to_string(vertex_count) + " vertices");
  for (std::size_t v = 0; v < vertex_count; ++v)
    for (std::size_t k = 0; k < 3; ++k) {
      const float c = mesh.vertices[v * stride + k];
      if (!std::isfinite(c))
        return bad_input_error(std::string(name) + ": vertex " + std::to_string(v) +
                               " has a non-finite coordinate");
      if (std::abs(c) > kMaxVertexValue)
        return bad_input_error(std::string(name) + ": vertex " + std::to_string(v) + " has a coordinate of " +
                               beyond_max_vertex_value(c));
    }
  return {};
}

}  // namespace octolod::measure
