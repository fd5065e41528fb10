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

namespace {

// A node vertex in the node's local frame (position relative to the origin, attributes as they are).
void local_vertex(const PreparedNode& node, std::uint32_t v, double* x) {
  const NodeMesh& mesh = node.mesh();
  const int n = static_cast<int>(mesh.layout.floats());
  const float* f = &mesh.vertices[v * mesh.layout.floats()];
  for (int i = 0; i < 3; ++i) x[i] = static_cast<double>(f[i]) - node.origin[static_cast<std::size_t>(i)];
  for (int i = 3; i < n; ++i) x[i] = f[i];
}

// The mean of the node's vertex records (each once), local frame.
void node_mean(const PreparedNode& node, double* mean) {
  const NodeMesh& mesh = node.mesh();
  const int n = static_cast<int>(mesh.layout.floats());
  for (int i = 0; i < n; ++i) mean[i] = 0.0;
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    double x[kMaxQuadricDim];
    local_vertex(node, v, x);
    for (int i = 0; i < n; ++i) mean[i] += x[i] / static_cast<double>(mesh.vertex_count());
  }
}

// Calls f(p, normal, area) for every triangle: its corners in the local frame and its normal
// (twice the area long).
template <class F>
void for_each_local_triangle(const PreparedNode& node, F&& f) {
  const NodeMesh& mesh = node.mesh();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    double p[3][kMaxQuadricDim];
    for (int k = 0; k < 3; ++k) local_vertex(node, mesh.indices[3 * t + static_cast<std::size_t>(k)], p[k]);
    const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const double normal[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                              e1[0] * e2[1] - e1[1] * e2[0]};
    f(p, normal, 0.5 * std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]));
  }
}

}  // namespace

Bade2006Fan bade2006_fan(const PreparedNode& node) {
  const NodeMesh& mesh = node.mesh();
  const std::size_t stride = mesh.layout.floats();
  Bade2006Fan fan;
  NodeMesh& out = fan.mesh;
  out.layout = mesh.layout;
  if (node.boundary.edges.empty()) return fan;

  // the representative: the node's position quadric optimum, or the cell centre (local origin)
  // when outside the cell
  std::vector<double> position_quadric(quadric_doubles(3), 0.0);
  double* mean = fan.mean.data();
  node_mean(node, mean);
  for_each_local_triangle(node, [&](const double(&p)[3][kMaxQuadricDim], const double* normal, double area) {
    double q[kMaxQuadricDoubles];
    plane_quadric(normal, p[0], area, q);
    add_quadric(3, position_quadric.data(), q);
  });
  double* rep = fan.representative.data();
  minimize_quadric(3, position_quadric.data(), mean, rep);
  bool inside = true;
  for (std::size_t i = 0; i < 3; ++i) {
    const double lo = static_cast<double>(node.cell.min[i]) - node.origin[i];
    const double hi = static_cast<double>(node.cell.max[i]) - node.origin[i];
    inside = inside && rep[i] >= lo && rep[i] <= hi;
  }
  if (!inside) rep[0] = rep[1] = rep[2] = 0.0;
  out.vertices.assign(stride, 0.0f);
  for (std::size_t i = 0; i < 3; ++i) out.vertices[i] = static_cast<float>(rep[i] + node.origin[i]);

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
  return fan;
}

void set_bade2006_attributes(const PreparedNode& node, Bade2006Fan& fan) {
  const VertexLayout layout = node.mesh().layout;
  const int n = static_cast<int>(layout.floats());
  if (n == 3 || fan.mesh.vertices.empty()) return;
  // the attributes minimizing the node's full quadric at the representative's position
  std::vector<double> full_quadric(quadric_doubles(n), 0.0);
  for_each_local_triangle(node, [&](const double(&p)[3][kMaxQuadricDim], const double*, double area) {
    double q[kMaxQuadricDoubles];
    triangle_quadric(n, p[0], p[1], p[2], area, q);
    add_quadric(n, full_quadric.data(), q);
  });
  double rep[kMaxQuadricDim];
  std::copy(fan.representative.begin(), fan.representative.end(), rep);
  minimize_quadric_free_tail(n, 3, full_quadric.data(), fan.mean.data() + 3, rep);
  finish_attributes(layout, layout.normal ? fan.mean.data() + 3 : nullptr, rep + 3);
  for (int i = 3; i < n; ++i) fan.mesh.vertices[static_cast<std::size_t>(i)] = static_cast<float>(rep[i]);
}

NodeMesh cluster_bade2006(const PreparedNode& node) {
  Bade2006Fan fan = bade2006_fan(node);
  set_bade2006_attributes(node, fan);
  return std::move(fan.mesh);
}

}  // namespace octolod::bake
