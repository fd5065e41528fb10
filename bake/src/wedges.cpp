// Clustered mesh construction with wedges (Garland & Heckbert 1998; Hoppe 1999; Lindstrom 2000;
// seed 3.5, 4.4). See wedges.h for the rules.
#include "wedges.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

#include "diagonal_flips.h"
#include "flat_hash.h"
#include "folded_fans.h"
#include "inside_out.h"
#include "point_triangle.h"
#include "quadric.h"

namespace octolod::bake {
namespace {

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t v) {
  while (parent[v] != v) {
    parent[v] = parent[parent[v]];
    v = parent[v];
  }
  return v;
}

// One candidate output triangle: the sources that map onto one cluster triple.
struct Candidate {
  TripleSources sources;
  std::uint32_t first_like = kNoTriangle;      // the first source winding like the sorted triple
  std::uint32_t first_opposite = kNoTriangle;  // the first winding the other way
};

// Per input triangle, an output triangle near its image under the clustering (for the error
// bound): the image itself when it survived; else the first output triangle on one of the
// image's edges (a triangle collapsed to a segment); else the first one at one of its clusters
// (collapsed to a point); else kNoTriangle (the image's neighbourhood cancelled entirely).
// `kept_cluster` holds the clusters of the output triangles' corners; the fans (CSR, output
// triangles in increasing order per cluster) are those of ClusteredMesh.
std::vector<std::uint32_t> nearby_output_triangles(const NodeMesh& mesh, const std::vector<std::uint32_t>& cluster,
                                                   const std::vector<std::uint32_t>& kept_cluster,
                                                   const std::vector<std::uint32_t>& fan_offset,
                                                   const std::vector<std::uint32_t>& fan_triangle,
                                                   const std::vector<std::uint32_t>& candidate_of_triangle,
                                                   const std::vector<std::uint32_t>& output_of_candidate) {
  const std::size_t triangle_count = mesh.triangle_count();
  std::vector<std::uint32_t> nearby(triangle_count, kNoTriangle);
  // the first output triangle with corners at clusters a and b (a != b): the first of a's fan
  // that has a corner at b
  auto edge_triangle = [&](std::uint32_t a, std::uint32_t b) {
    for (std::uint32_t i = fan_offset[a]; i < fan_offset[a + 1]; ++i) {
      const std::uint32_t* corner = &kept_cluster[3 * std::size_t{fan_triangle[i]}];
      if (corner[0] == b || corner[1] == b || corner[2] == b) return fan_triangle[i];
    }
    return kNoTriangle;
  };
  auto cluster_triangle = [&](std::uint32_t a) {
    return fan_offset[a] < fan_offset[a + 1] ? fan_triangle[fan_offset[a]] : kNoTriangle;
  };
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t candidate = candidate_of_triangle[t];
    if (candidate != kNoTriangle) nearby[t] = output_of_candidate[candidate];
    if (nearby[t] != kNoTriangle) continue;
    const std::uint32_t c[3] = {cluster[mesh.indices[3 * t]], cluster[mesh.indices[3 * t + 1]],
                                cluster[mesh.indices[3 * t + 2]]};
    for (std::size_t k = 0; k < 3 && nearby[t] == kNoTriangle; ++k) {
      const std::uint32_t a = c[k], b = c[(k + 1) % 3];
      if (a != b) nearby[t] = edge_triangle(a, b);
    }
    for (std::size_t k = 0; k < 3 && nearby[t] == kNoTriangle; ++k) nearby[t] = cluster_triangle(c[k]);
  }
  return nearby;
}

// Moves x (outside or inside `box`) to the point of the segment from `inside` (a point of the box)
// to x that is nearest to x within the box. Per-axis clamping would instead slide the point along
// the box's faces, away from the direction in which the quadric falls; on the segment the
// quadric is convex and falls towards x, so the result is never worse than `inside`.
void pull_into_box(const double* inside, const ClampBox& box, double* x) {
  double t = 1.0;
  for (std::size_t i = 0; i < 3; ++i) {
    const double step = x[i] - inside[i];
    if (x[i] > box.max[i] && step > 0.0) t = std::min(t, (box.max[i] - inside[i]) / step);
    if (x[i] < box.min[i] && step < 0.0) t = std::min(t, (box.min[i] - inside[i]) / step);
  }
  t = std::max(t, 0.0);
  // the clamp only absorbs rounding: the segment point is in the box up to an ulp
  for (std::size_t i = 0; i < 3; ++i) x[i] = std::clamp(inside[i] + t * (x[i] - inside[i]), box.min[i], box.max[i]);
}

}  // namespace

std::optional<NodeMesh> weld_if_needed(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  const std::size_t vertex_count = mesh.vertex_count();
  const float* base = mesh.vertices.data();
  std::vector<std::uint32_t> remap(vertex_count);
  FlatIdSet table(vertex_count);
  auto hash = [base, stride](std::uint32_t v) {
    std::uint32_t bits[kMaxQuadricDim];
    std::memcpy(bits, base + v * stride, stride * 4);
    return hash_words(bits, stride);
  };
  auto equal = [base, stride](std::uint32_t a, std::uint32_t b) {
    return std::memcmp(base + a * stride, base + b * stride, stride * 4) == 0;
  };
  std::uint32_t next = 0;
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    const std::uint32_t first = table.find_or_insert(v, hash, equal);
    remap[v] = first == v ? next++ : remap[first];
  }
  if (next == vertex_count) return std::nullopt;
  NodeMesh out;
  out.layout = mesh.layout;
  out.vertices.reserve(std::size_t{next} * stride);
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (remap[v] == out.vertex_count()) out.vertices.insert(out.vertices.end(), base + v * stride, base + (v + 1) * stride);
  out.indices.resize(mesh.indices.size());
  for (std::size_t i = 0; i < mesh.indices.size(); ++i) out.indices[i] = remap[mesh.indices[i]];
  return out;
}

bool may_have_identical_records(const NodeMesh& mesh, const PositionIds& positions) {
  const std::size_t stride = mesh.layout.floats();
  const float* base = mesh.vertices.data();
  // the vertices of each position as a chain, each to the one before it there; a vertex is
  // compared with at most this many of them (a position shared by many wedges, or a degenerate
  // mesh with thousands of vertices at one point, would make the walk quadratic): past that,
  // maybe, and the caller's exact weld decides
  constexpr int kMaxCompared = 16;
  constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::vector<std::uint32_t> last(positions.count, kNone);
  std::vector<std::uint32_t> before(mesh.vertex_count());
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    std::uint32_t& at_position = last[positions.of_vertex[v]];
    before[v] = at_position;
    at_position = v;
    int compared = 0;
    for (std::uint32_t u = before[v]; u != kNone; u = before[u], ++compared)
      if (compared == kMaxCompared || std::memcmp(base + u * stride, base + v * stride, stride * 4) == 0) return true;
  }
  return false;
}

NodeMesh mesh_of_used_records(VertexLayout layout, std::span<const float> records,
                              std::span<const std::uint32_t> corners) {
  const std::size_t stride = layout.floats();
  constexpr std::uint32_t kUnused = ~std::uint32_t{0};
  std::vector<std::uint32_t> id(records.size() / stride, kUnused);
  for (const std::uint32_t r : corners) id[r] = 0;
  NodeMesh out;
  out.layout = layout;
  std::uint32_t next = 0;
  for (std::size_t r = 0; r < id.size(); ++r) {
    if (id[r] == kUnused) continue;
    id[r] = next++;
    out.vertices.insert(out.vertices.end(), records.begin() + static_cast<std::ptrdiff_t>(r * stride),
                        records.begin() + static_cast<std::ptrdiff_t>((r + 1) * stride));
  }
  out.indices.reserve(corners.size());
  for (const std::uint32_t r : corners) out.indices.push_back(id[r]);
  return out;
}

std::optional<NodeMesh> without_repeated_triangles(const NodeMesh& mesh, const PositionIds& positions) {
  const std::size_t triangles = mesh.triangle_count();
  // every triangle's corner positions from the smallest id on, in its cyclic order
  std::vector<std::array<std::uint32_t, 3>> corners(triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t* v = &mesh.indices[3 * t];
    std::array<std::uint32_t, 3>& p = corners[t];
    p = {positions.of_vertex[v[0]], positions.of_vertex[v[1]], positions.of_vertex[v[2]]};
    std::rotate(p.begin(), std::min_element(p.begin(), p.end()), p.end());
  }
  FlatIdSet table(triangles);
  std::vector<std::uint32_t> kept;  // the corners of the triangles that repeat none
  for (std::uint32_t t = 0; t < triangles; ++t) {
    const std::uint32_t first = table.find_or_insert(
        t, [&](std::uint32_t u) { return hash_words(corners[u].data(), 3); },
        [&](std::uint32_t a, std::uint32_t b) { return corners[a] == corners[b]; });
    if (first == t) kept.insert(kept.end(), &mesh.indices[3 * std::size_t{t}], &mesh.indices[3 * std::size_t{t}] + 3);
  }
  if (kept.size() == mesh.indices.size()) return std::nullopt;
  return mesh_of_used_records(mesh.layout, mesh.vertices, kept);
}

NodeMesh weld_identical_vertices(const NodeMesh& mesh) {
  std::optional<NodeMesh> welded = weld_if_needed(mesh);
  return welded ? std::move(*welded) : mesh;
}

std::array<double, 3> triangle_normal(const float* p0, const float* p1, const float* p2) {
  const std::array<double, 3> e1{double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
  const std::array<double, 3> e2{double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
  return cross(e1, e2);
}

std::vector<std::array<double, 3>> face_normals(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  std::vector<std::array<double, 3>> normals(mesh.triangle_count());
  for (std::size_t t = 0; t < normals.size(); ++t)
    normals[t] = triangle_normal(&mesh.vertices[mesh.indices[3 * t] * stride], &mesh.vertices[mesh.indices[3 * t + 1] * stride],
                                 &mesh.vertices[mesh.indices[3 * t + 2] * stride]);
  return normals;
}

double surface_area(std::span<const std::array<double, 3>> face_normal) {
  double area = 0.0;
  for (const std::array<double, 3>& n : face_normal) area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return area;
}

std::vector<std::array<float, 3>> position_facings(const NodeMesh& mesh, const PositionIds& positions,
                                                   std::span<const std::array<double, 3>> face_normal) {
  std::vector<std::array<double, 3>> sum(positions.count, {0.0, 0.0, 0.0});
  for (std::size_t t = 0; t < face_normal.size(); ++t)
    for (std::size_t k = 0; k < 3; ++k) {
      std::array<double, 3>& s = sum[positions.of_vertex[mesh.indices[3 * t + k]]];
      for (std::size_t i = 0; i < 3; ++i) s[i] += face_normal[t][i];
    }
  std::vector<std::array<float, 3>> facing(sum.size(), {0.0f, 0.0f, 0.0f});
  for (std::size_t p = 0; p < sum.size(); ++p) {
    const double length = std::sqrt(sum[p][0] * sum[p][0] + sum[p][1] * sum[p][1] + sum[p][2] * sum[p][2]);
    if (length > 0.0)
      for (std::size_t i = 0; i < 3; ++i) facing[p][i] = static_cast<float>(sum[p][i] / length);
  }
  return facing;
}

bool orient_kept_triangle(const std::array<const float*, 3>& record, const std::array<double, 3>& facing,
                          std::array<std::uint32_t, 3>& corner) {
  if (std::memcmp(record[0], record[1], 12) == 0 || std::memcmp(record[1], record[2], 12) == 0 ||
      std::memcmp(record[0], record[2], 12) == 0)
    return false;
  const std::array<double, 3> normal = triangle_normal(record[0], record[1], record[2]);
  if (dot(normal, facing) < 0.0) std::swap(corner[1], corner[2]);
  return true;
}

void add_plane_quadrics(const NodeMesh& mesh, std::span<const std::array<double, 3>> normals,
                        const std::vector<std::uint32_t>& cluster, const std::vector<std::uint8_t>& counted,
                        const std::array<double, 3>& origin, double* quadrics, double* areas,
                        std::span<const BoundaryEdge> border) {
  constexpr std::size_t q3 = quadric_doubles(3);
  const std::size_t stride = mesh.layout.floats();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint32_t* corner = &mesh.indices[3 * t];
    if (!counted[corner[0]] && !counted[corner[1]] && !counted[corner[2]]) continue;
    const std::array<double, 3>& normal = normals[t];
    const double area = 0.5 * std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(area > 0.0)) continue;
    double p0[3];
    for (std::size_t i = 0; i < 3; ++i) p0[i] = static_cast<double>(mesh.vertices[corner[0] * stride + i]) - origin[i];
    double quadric[q3];
    plane_quadric(normal.data(), p0, area, quadric);
    for (int k = 0; k < 3; ++k) {
      if (!counted[corner[k]]) continue;
      add_quadric(3, &quadrics[cluster[corner[k]] * q3], quadric);
      if (areas) areas[cluster[corner[k]]] += area;
    }
  }
  for (const BoundaryEdge& edge : border) {
    if (!counted[edge.a] && !counted[edge.b]) continue;
    const Vec3d a = vertex_position(mesh, edge.a);
    const Vec3d along = sub(vertex_position(mesh, edge.b), a);
    const Vec3d across = cross(along, normals[edge.triangle]);
    const Vec3d p0 = sub(a, origin);
    double quadric[q3];
    plane_quadric(across.data(), p0.data(), kBorderWeight * dot(along, along), quadric);
    if (counted[edge.a]) add_quadric(3, &quadrics[cluster[edge.a] * q3], quadric);
    if (counted[edge.b]) add_quadric(3, &quadrics[cluster[edge.b] * q3], quadric);
  }
}

void finish_attributes(VertexLayout layout, const double* fallback_normal, double* attributes) {
  if (layout.normal) {
    double* n = attributes;
    double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12)) {
      std::copy(fallback_normal, fallback_normal + 3, n);
      len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    if (len > 1e-12) {
      for (int i = 0; i < 3; ++i) n[i] /= len;
    } else {
      n[0] = 0.0, n[1] = 0.0, n[2] = 1.0;
    }
  }
  if (layout.color) {
    double* c = attributes + (layout.color_offset() - 3);
    for (int i = 0; i < 3; ++i) c[i] = std::clamp(c[i], 0.0, 1.0);
  }
}

void place_representative(const double* quadric, const double* mean, const ClampBox& box,
                          const double* best_vertex, double* x, const double* minimizer) {
  if (minimizer) std::copy(minimizer, minimizer + 3, x);
  else minimize_quadric(3, quadric, mean, x);
  pull_into_box(mean, box, x);
  if (best_vertex[3] < evaluate_quadric(3, quadric, x)) std::copy(best_vertex, best_vertex + 3, x);
}

ClusteredMesh build_clustered_mesh(const NodeMesh& mesh, std::span<const std::array<double, 3>> face_normal,
                                   const Clustering& clustering, const std::array<double, 3>& origin,
                                   std::span<const BoundaryEdge> free_border) {
  const VertexLayout layout = mesh.layout;
  const int n = static_cast<int>(layout.floats());
  const int attribute_count = n - 3;
  const std::size_t stride = layout.floats();
  const std::size_t vertex_count = mesh.vertex_count();
  const std::size_t triangle_count = mesh.triangle_count();
  const std::vector<std::uint32_t>& cluster = clustering.of_vertex;
  auto locked = [&](std::uint32_t v) { return clustering.locked[cluster[v]] != 0; };

  // wedges: union-find over original edges inside one unlocked cluster; the root is the smallest
  // vertex id of the wedge
  std::vector<std::uint32_t> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), 0u);
  auto join = [&](std::uint32_t u, std::uint32_t v) {
    if (cluster[u] != cluster[v] || locked(u)) return;
    const std::uint32_t ru = find_root(parent, u), rv = find_root(parent, v);
    if (ru < rv) parent[rv] = ru;
    else if (rv < ru) parent[ru] = rv;
  };
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t* corner = &mesh.indices[3 * t];
    join(corner[0], corner[1]), join(corner[1], corner[2]), join(corner[2], corner[0]);
  }
  std::vector<std::uint64_t> order;  // (cluster, root) of every wedge, sorted = output order
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (find_root(parent, v) == v) order.push_back((static_cast<std::uint64_t>(cluster[v]) << 32) | v);
  std::sort(order.begin(), order.end());
  std::vector<std::uint32_t> wedge_of_root(vertex_count, 0);
  for (std::size_t w = 0; w < order.size(); ++w)
    wedge_of_root[static_cast<std::uint32_t>(order[w])] = static_cast<std::uint32_t>(w);
  std::vector<std::uint32_t> wedge(vertex_count);
  for (std::uint32_t v = 0; v < vertex_count; ++v) wedge[v] = wedge_of_root[find_root(parent, v)];
  const std::size_t wedge_count = order.size();

  auto local_position = [&](std::uint32_t v, double* out) {
    const float* f = &mesh.vertices[v * stride];
    for (int i = 0; i < 3; ++i) out[i] = static_cast<double>(f[i]) - origin[static_cast<std::size_t>(i)];
  };
  auto local_vertex = [&](std::uint32_t v, double* out) {  // the whole record
    local_position(v, out);
    const float* f = &mesh.vertices[v * stride];
    for (int i = 3; i < n; ++i) out[i] = f[i];
  };

  // the scale of positions in the generalized quadrics: 1 / typical edge length, so a triangle
  // spans about one unit in position. Garland & Heckbert scale the model into the unit cube for
  // the same reason: with tiny triangles the attribute directions dominate the plane in R^n and
  // the attribute systems become nearly singular.
  const double total_area = surface_area(face_normal);
  const double position_scale =
      total_area > 0.0 ? std::sqrt(static_cast<double>(triangle_count) / (2.0 * total_area)) : 1.0;

  // means: positions per cluster, full vectors per wedge (each vertex counted once)
  std::vector<double> cluster_sum(clustering.count * 3, 0.0);
  std::vector<std::uint32_t> cluster_vertices(clustering.count, 0);
  std::vector<double> wedge_sum(wedge_count * stride, 0.0);
  std::vector<std::uint32_t> wedge_vertices(wedge_count, 0);
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (locked(v)) continue;
    double x[kMaxQuadricDim];
    local_vertex(v, x);
    for (int i = 0; i < 3; ++i) cluster_sum[cluster[v] * 3 + static_cast<std::size_t>(i)] += x[i];
    ++cluster_vertices[cluster[v]];
    for (int i = 0; i < n; ++i) wedge_sum[wedge[v] * stride + static_cast<std::size_t>(i)] += x[i];
    ++wedge_vertices[wedge[v]];
  }

  // A cluster of one vertex keeps that vertex: every plane of its triangles passes through it, so
  // it is the quadrics' minimizer (or, for a flat fan, the minimizer nearest the mean, itself),
  // and its attributes are those minimizing its wedge's quadric with the position fixed there.
  // Solving would only add rounding; such clusters (a large share at fine resolutions) get no
  // quadrics.
  std::vector<std::uint8_t> solved_vertex(vertex_count);
  for (std::uint32_t v = 0; v < vertex_count; ++v) solved_vertex[v] = !locked(v) && cluster_vertices[cluster[v]] > 1;
  auto solved = [&](std::uint32_t v) { return solved_vertex[v] != 0; };

  // position quadrics: every triangle's area-weighted plane quadric added to the cluster of each
  // of its corners that is solved, unless the clustering has the cluster's
  const std::size_t q3 = quadric_doubles(3);
  const std::size_t known_quadrics = clustering.quadric.size() / q3;
  std::vector<std::uint8_t> summed_here(vertex_count);
  for (std::uint32_t v = 0; v < vertex_count; ++v) summed_here[v] = solved(v) && cluster[v] >= known_quadrics;
  std::vector<double> summed_quadric(clustering.count * q3, 0.0);
  add_plane_quadrics(mesh, face_normal, cluster, summed_here, origin, summed_quadric.data(), nullptr, free_border);
  auto cluster_quadric = [&](std::uint32_t c) {
    return c < known_quadrics ? &clustering.quadric[c * q3] : &summed_quadric[c * q3];
  };
  auto triangle_area = [&](std::size_t t) {
    const std::array<double, 3>& fn = face_normal[t];
    return 0.5 * std::sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
  };

  // representatives: cluster positions, then wedge attributes with the position fixed. A
  // cluster's position is the minimizer of its quadric, pulled into its cell towards the mean
  // when it falls outside (a fold or a crease inside the cell: the planes meet far away), unless
  // one of the cluster's own vertices, which lie on the input surface, has a lower quadric error
  // than that point. On a 1M rock's 10/3/1% cuts this lowered the Hausdorff distance by 31/24/19%
  // and the RMS by 9/5/3% against clamping the minimizer per axis.
  std::vector<double> vertex_candidate(clustering.count * 4, std::numeric_limits<double>::infinity());
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (!solved(v)) continue;
    double x[3];
    local_position(v, x);
    double* best = &vertex_candidate[cluster[v] * 4];  // position, then its error
    const double error = evaluate_quadric(3, cluster_quadric(cluster[v]), x);
    if (error < best[3]) std::copy(x, x + 3, best), best[3] = error;
  }
  std::vector<float> wedge_record(wedge_count * stride);
  std::vector<double> cluster_position(clustering.count * 3);
  for (std::uint32_t c = 0; c < clustering.count; ++c) {
    if (clustering.locked[c] || cluster_vertices[c] <= 1) continue;
    double mean[3];
    for (int i = 0; i < 3; ++i) mean[i] = cluster_sum[c * 3 + static_cast<std::size_t>(i)] / cluster_vertices[c];
    place_representative(cluster_quadric(c), mean, clustering.box[c], &vertex_candidate[c * 4],
                         &cluster_position[c * 3], c < known_quadrics ? &clustering.minimizer[c * 3] : nullptr);
  }

  // every wedge's record but the attributes of the solved ones: those are solved below for the
  // wedges the output uses, once it is known (nothing before reads attributes)
  for (std::size_t w = 0; w < wedge_count; ++w) {
    const auto root = static_cast<std::uint32_t>(order[w]);
    float* record = &wedge_record[w * stride];
    if (locked(root)) {
      std::memcpy(record, &mesh.vertices[root * stride], stride * 4);
      continue;
    }
    const std::uint32_t c = cluster[root];
    if (cluster_vertices[c] == 1) {  // the vertex itself (see `solved`), attributes finished
      std::memcpy(record, &mesh.vertices[root * stride], 3 * 4);
      double v[kMaxQuadricDim];
      local_vertex(root, v);
      const double up[3] = {0.0, 0.0, 1.0};  // for a zero normal (finish_attributes' own last resort)
      finish_attributes(layout, up, v + 3);
      for (int i = 3; i < n; ++i) record[i] = static_cast<float>(v[i]);
      continue;
    }
    for (int i = 0; i < 3; ++i)
      record[i] = static_cast<float>(cluster_position[c * 3 + static_cast<std::size_t>(i)] + origin[static_cast<std::size_t>(i)]);
  }

  // candidate triangles: sources counted per cluster triple (the triple table freed before the
  // flips build their edge table)
  std::vector<Candidate> candidates;
  std::vector<std::uint32_t> candidate_of_triangle(triangle_count, kNoTriangle);
  {
    FlatHashMap<3> candidate_of(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
      const std::uint32_t* corner = &mesh.indices[3 * t];
      const std::uint32_t c0 = cluster[corner[0]], c1 = cluster[corner[1]], c2 = cluster[corner[2]];
      if (c0 == c1 || c1 == c2 || c0 == c2) continue;
      const bool even = winds_like_sorted(c0, c1, c2);
      bool inserted = false;
      const std::uint32_t index = candidate_of.find_or_insert(
          sorted_triple(c0, c1, c2), static_cast<std::uint32_t>(candidates.size()), inserted);
      if (inserted) candidates.emplace_back();
      candidate_of_triangle[t] = index;
      Candidate& candidate = candidates[index];
      if (candidate.sources.add(even, face_normal[t]))
        (even ? candidate.first_like : candidate.first_opposite) = static_cast<std::uint32_t>(t);
    }
  }

  // output: kept_copies per candidate, oriented like their sources, vertices compacted in wedge order
  ClusteredMesh result;
  std::vector<std::uint32_t> kept;  // wedge corners of kept triangles
  std::vector<std::uint32_t> output_of_candidate(candidates.size(), kNoTriangle);
  auto source_wedges = [&](std::uint32_t t) {
    if (t == kNoTriangle) return std::array<std::uint32_t, 3>{};
    const std::uint32_t* corner = &mesh.indices[3 * static_cast<std::size_t>(t)];
    return std::array<std::uint32_t, 3>{wedge[corner[0]], wedge[corner[1]], wedge[corner[2]]};
  };
  auto record_of = [&](std::uint32_t w) -> const float* { return &wedge_record[w * stride]; };
  for (std::size_t ci = 0; ci < candidates.size(); ++ci) {
    const Candidate& candidate = candidates[ci];
    const std::size_t before = kept.size();
    append_kept_triangles(candidate.sources, source_wedges(candidate.first_like),
                          source_wedges(candidate.first_opposite), record_of, kept);
    if (kept.size() > before) output_of_candidate[ci] = static_cast<std::uint32_t>(before / 3);
  }
  std::vector<std::uint32_t> wedge_cluster(wedge_count);
  for (std::size_t w = 0; w < wedge_count; ++w) wedge_cluster[w] = static_cast<std::uint32_t>(order[w] >> 32);
  candidates = {};
  FoldRepair folds;
  {  // (the input's triangles per cluster, which the passes gather, freed before the attribute solves)
    const ClusteredOutput clustered{mesh, cluster, clustering.count, wedge_cluster, wedge_record, wedge};
    InputDistances input(clustered);
    flip_diagonals(input, kept);
    folds = remove_folded_fans(input, kept);
  }
  for (std::uint32_t& o : output_of_candidate)
    if (o != kNoTriangle) o = folds.index[o];
  // attribute quadrics, once the positions and the output's triangles are known: every
  // triangle's generalized quadric (Garland & Heckbert 1998) added to the wedge of each of its
  // solved corners that the output uses (1.39M of the 4.12M solved wedges of a 1M city bake are
  // not: their clusters keep no triangle) as the block the attribute solve needs with the
  // wedge's position fixed (quadric.h, add_triangle_free_block: 44 doubles per wedge with every
  // attribute instead of the 78 of a whole quadric). The blocks are summed and solved a window
  // of wedges at a time, one pass over the triangles per window (each block still sums its
  // triangles in triangle order): the working set holds the blocks of 2048 wedges, or of a
  // sixteenth of them in a larger node, instead of every wedge's (352 bytes each: the largest
  // single array of an internal node's working set).
  const int m = attribute_count;
  const std::size_t block_size = m > 0 ? free_block_doubles(m) : 0;
  // per wedge, its place among the solved wedges the output uses, or kNoSlot
  constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;
  std::vector<std::uint32_t> slot_of_wedge;
  std::uint32_t solved_wedges = 0;
  if (m > 0) {
    std::vector<std::uint8_t> used(wedge_count, 0);
    for (const std::uint32_t w : kept) used[w] = 1;
    slot_of_wedge.assign(wedge_count, kNoSlot);
    for (std::size_t w = 0; w < wedge_count; ++w)
      if (used[w] && solved(static_cast<std::uint32_t>(order[w]))) slot_of_wedge[w] = solved_wedges++;
  }
  // wedges per window: at least kBlockWindow, at most kMaxBlockPasses passes over the triangles
  constexpr std::size_t kBlockWindow = 2048, kMaxBlockPasses = 16;
  const std::size_t window_size = std::max(kBlockWindow, (std::size_t{solved_wedges} + kMaxBlockPasses - 1) / kMaxBlockPasses);
  std::vector<double> window_block;
  auto sum_window_blocks = [&](std::size_t first_slot, std::size_t end_slot) {
    window_block.assign((end_slot - first_slot) * block_size, 0.0);
    auto in_window = [&](std::uint32_t v) {
      const std::uint32_t slot = slot_of_wedge[wedge[v]];  // kNoSlot: not solved, or not in the output
      return slot >= first_slot && slot < end_slot;
    };
    for (std::size_t t = 0; t < triangle_count; ++t) {
      const std::uint32_t* corner = &mesh.indices[3 * t];
      if (!in_window(corner[0]) && !in_window(corner[1]) && !in_window(corner[2])) continue;
      const double area = triangle_area(t);
      if (!(area > 0.0)) continue;
      double p[3][kMaxQuadricDim];
      for (int k = 0; k < 3; ++k) {
        local_vertex(corner[k], p[k]);
        for (int i = 0; i < 3; ++i) p[k][i] *= position_scale;
      }
      TriangleFreePart part;
      if (!triangle_free_part(n, p[0], p[1], p[2], area, part)) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = corner[k];
        if (!in_window(v)) continue;
        const std::uint32_t slot = slot_of_wedge[wedge[v]];
        double x[3];
        for (int i = 0; i < 3; ++i) x[i] = cluster_position[cluster[v] * 3 + static_cast<std::size_t>(i)] * position_scale;
        add_triangle_free_block(part, x, &window_block[(slot - first_slot) * block_size]);
      }
    }
  };

  std::size_t window_end = 0;  // slots [window_end - window size, window_end) have their blocks
  for (std::size_t w = 0; w < slot_of_wedge.size(); ++w) {
    const std::uint32_t slot = slot_of_wedge[w];
    if (slot == kNoSlot) continue;
    if (slot >= window_end) {
      const std::size_t first = slot;
      window_end = std::min<std::size_t>(solved_wedges, first + window_size);
      sum_window_blocks(first, window_end);
    }
    const std::size_t window_first = window_end - window_block.size() / block_size;
    double mean[kMaxQuadricDim], v[kMaxQuadricDim];
    for (int i = 0; i < n; ++i) mean[i] = wedge_sum[w * stride + static_cast<std::size_t>(i)] / wedge_vertices[w];
    minimize_free_block(m, &window_block[(slot - window_first) * block_size], mean + 3, v + 3);
    finish_attributes(layout, layout.normal ? mean + 3 : nullptr, v + 3);
    float* record = &wedge_record[w * stride];
    for (int i = 3; i < n; ++i) record[i] = static_cast<float>(v[i]);
  }
  window_block = {};

  result.mesh = mesh_of_used_records(layout, wedge_record, kept);
  rewind_inside_out(result.mesh);
  std::vector<std::uint32_t> kept_cluster(kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) kept_cluster[i] = wedge_cluster[kept[i]];
  result.vertex_cluster = cluster;
  result.fan_offset.assign(std::size_t{clustering.count} + 1, 0);
  for (std::uint32_t c : kept_cluster) ++result.fan_offset[c + 1];
  for (auto [c, triangle] : folds.fan_extra) ++result.fan_offset[c + 1];
  for (std::size_t c = 0; c < clustering.count; ++c) result.fan_offset[c + 1] += result.fan_offset[c];
  result.fan_triangle.resize(result.fan_offset.back());
  std::vector<std::uint32_t> fill(result.fan_offset.begin(), result.fan_offset.end() - 1);
  for (std::size_t i = 0; i < kept_cluster.size(); ++i)
    result.fan_triangle[fill[kept_cluster[i]]++] = static_cast<std::uint32_t>(i / 3);
  for (auto [c, triangle] : folds.fan_extra) result.fan_triangle[fill[c]++] = triangle;
  result.nearby_output_triangle = nearby_output_triangles(mesh, cluster, kept_cluster, result.fan_offset,
                                                          result.fan_triangle, candidate_of_triangle,
                                                          output_of_candidate);
  return result;
}

}  // namespace octolod::bake
