// The seed's per-node simplification operator (Bade, Daman, Sunar, Tan 2006, sections 3.5 and
// 4.4): the whole node is one cluster whose representative minimizes the node's summed quadric
// (Garland & Heckbert 1998), pulled to the cell centre when it falls outside the cell; the
// node's boundary edges are kept and each one (a,b) is fanned to the representative as the
// triangle (a,b,rep) in the edge's winding. The cone over the boundary has exactly that boundary,
// so neighbouring nodes never crack; interior detail and attribute seams are lost — this method
// exists as the seed's baseline, the grid method is the default.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "cluster.h"
#include "quadric.h"
#include "wedges.h"

namespace octolod::bake {

NodeMesh cluster_bade2006(const PreparedNode& node) {
  const NodeMesh& mesh = node.mesh();
  const VertexLayout layout = mesh.layout;
  const int n = static_cast<int>(layout.floats());
  const std::size_t stride = layout.floats();
  NodeMesh out;
  out.layout = layout;
  if (node.boundary.edges.empty()) return out;

  // the node's quadrics and mean (each vertex record once)
  std::vector<double> position_quadric(quadric_doubles(3), 0.0);
  std::vector<double> full_quadric(quadric_doubles(n), 0.0);
  double mean[kMaxQuadricDim] = {};
  auto local_vertex = [&](std::uint32_t v, double* x) {
    const float* f = &mesh.vertices[v * stride];
    for (int i = 0; i < 3; ++i) x[i] = static_cast<double>(f[i]) - node.origin[static_cast<std::size_t>(i)];
    for (int i = 3; i < n; ++i) x[i] = f[i];
  };
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    double x[kMaxQuadricDim];
    local_vertex(v, x);
    for (int i = 0; i < n; ++i) mean[i] += x[i] / static_cast<double>(mesh.vertex_count());
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    double p[3][kMaxQuadricDim];
    for (int k = 0; k < 3; ++k) local_vertex(mesh.indices[3 * t + static_cast<std::size_t>(k)], p[k]);
    const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const double normal[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                              e1[0] * e2[1] - e1[1] * e2[0]};
    const double area = 0.5 * std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    double q[kMaxQuadricDoubles];
    plane_quadric(normal, p[0], area, q);
    add_quadric(3, position_quadric.data(), q);
    if (n > 3) {
      triangle_quadric(n, p[0], p[1], p[2], area, q);
      add_quadric(n, full_quadric.data(), q);
    }
  }

  // the representative: quadric optimum, or the cell centre (local origin) when outside the cell
  double rep[kMaxQuadricDim];
  minimize_quadric(3, position_quadric.data(), mean, rep);
  bool inside = true;
  for (std::size_t i = 0; i < 3; ++i) {
    const double lo = static_cast<double>(node.cell.min[i]) - node.origin[i];
    const double hi = static_cast<double>(node.cell.max[i]) - node.origin[i];
    inside = inside && rep[i] >= lo && rep[i] <= hi;
  }
  if (!inside) rep[0] = rep[1] = rep[2] = 0.0;
  if (n > 3) {
    minimize_quadric_free_tail(n, 3, full_quadric.data(), mean + 3, rep);
    finish_attributes(layout, layout.normal ? mean + 3 : nullptr, rep + 3);
  }
  out.vertices.resize(stride);
  for (int i = 0; i < 3; ++i)
    out.vertices[static_cast<std::size_t>(i)] = static_cast<float>(rep[i] + node.origin[static_cast<std::size_t>(i)]);
  for (int i = 3; i < n; ++i) out.vertices[static_cast<std::size_t>(i)] = static_cast<float>(rep[i]);

  // the fan: locked vertices after the representative, in vertex id order
  std::vector<std::uint32_t> output_id(mesh.vertex_count(), UINT32_MAX);
  for (const BoundaryEdge& edge : node.boundary.edges) output_id[edge.a] = output_id[edge.b] = 0;
  std::uint32_t next = 1;
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (output_id[v] == UINT32_MAX) continue;
    output_id[v] = next++;
    out.vertices.insert(out.vertices.end(), mesh.vertices.begin() + static_cast<std::ptrdiff_t>(v * stride),
                        mesh.vertices.begin() + static_cast<std::ptrdiff_t>((v + 1) * stride));
  }
  for (const BoundaryEdge& edge : node.boundary.edges) {
    // a corner at the representative's exact position makes the triangle degenerate; its two
    // copies of the edge cancel, so dropping it keeps the boundary
    const float* pa = &mesh.vertices[edge.a * stride];
    const float* pb = &mesh.vertices[edge.b * stride];
    if (std::memcmp(pa, out.vertices.data(), 12) == 0 || std::memcmp(pb, out.vertices.data(), 12) == 0) continue;
    out.indices.insert(out.indices.end(), {output_id[edge.a], output_id[edge.b], 0u});
  }
  return out;
}

}  // namespace octolod::bake
