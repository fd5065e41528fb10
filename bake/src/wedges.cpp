// Clustered mesh construction with wedges (Garland & Heckbert 1998; Hoppe 1999; Lindstrom 2000;
// seed 3.5, 4.4). See wedges.h for the rules.
#include "wedges.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "quadric.h"

namespace octolod::bake {
namespace {

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
  h *= 0xFF51AFD7ED558CCDull;
  return h ^ (h >> 29);
}

struct RecordHash {
  const float* base;
  std::size_t stride;
  std::size_t operator()(std::uint32_t v) const {
    std::uint64_t h = 0;
    for (std::size_t i = 0; i < stride; ++i) {
      std::uint32_t bits;
      std::memcpy(&bits, base + v * stride + i, 4);
      h = mix(h, bits);
    }
    return static_cast<std::size_t>(h);
  }
};
struct RecordEqual {
  const float* base;
  std::size_t stride;
  bool operator()(std::uint32_t a, std::uint32_t b) const {
    return std::memcmp(base + a * stride, base + b * stride, stride * 4) == 0;
  }
};

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t v) {
  while (parent[v] != v) {
    parent[v] = parent[parent[v]];
    v = parent[v];
  }
  return v;
}

struct Triple {
  std::uint32_t c[3];
  friend bool operator==(const Triple&, const Triple&) = default;
};
struct TripleHash {
  std::size_t operator()(const Triple& t) const {
    return static_cast<std::size_t>(mix(mix(mix(0, t.c[0]), t.c[1]), t.c[2]));
  }
};

// One candidate output triangle: the sources that map onto one cluster triple.
struct Candidate {
  std::uint32_t count = 0;
  std::uint32_t first_triangle = 0;
  std::array<double, 3> normal{};  // area-weighted source normals, in the sorted triple's winding
};

std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace

NodeMesh weld_identical_vertices(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  const std::size_t vertex_count = mesh.vertex_count();
  NodeMesh out;
  out.layout = mesh.layout;
  std::vector<std::uint32_t> remap(vertex_count);
  std::unordered_map<std::uint32_t, std::uint32_t, RecordHash, RecordEqual> table(
      vertex_count, RecordHash{mesh.vertices.data(), stride}, RecordEqual{mesh.vertices.data(), stride});
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const auto [it, inserted] = table.try_emplace(static_cast<std::uint32_t>(v), next);
    if (inserted) {
      out.vertices.insert(out.vertices.end(), mesh.vertices.begin() + static_cast<std::ptrdiff_t>(v * stride),
                          mesh.vertices.begin() + static_cast<std::ptrdiff_t>((v + 1) * stride));
      ++next;
    }
    remap[v] = it->second;
  }
  out.indices.resize(mesh.indices.size());
  for (std::size_t i = 0; i < mesh.indices.size(); ++i) out.indices[i] = remap[mesh.indices[i]];
  return out;
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

NodeMesh build_clustered_mesh(const NodeMesh& mesh, const Clustering& clustering,
                              const std::array<double, 3>& origin) {
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
  for (std::size_t t = 0; t < triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = mesh.indices[3 * t + static_cast<std::size_t>(k)];
      const std::uint32_t v = mesh.indices[3 * t + static_cast<std::size_t>((k + 1) % 3)];
      if (cluster[u] != cluster[v] || locked(u)) continue;
      const std::uint32_t ru = find_root(parent, u), rv = find_root(parent, v);
      if (ru < rv) parent[rv] = ru;
      else if (rv < ru) parent[ru] = rv;
    }
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

  auto local_vertex = [&](std::uint32_t v, double* out) {
    const float* f = &mesh.vertices[v * stride];
    for (int i = 0; i < 3; ++i) out[i] = static_cast<double>(f[i]) - origin[static_cast<std::size_t>(i)];
    for (int i = 3; i < n; ++i) out[i] = f[i];
  };

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

  // quadrics: every triangle's area-weighted quadric added to the cluster (position-only) and
  // the wedge (generalized) of each of its corners
  const std::size_t q3 = quadric_doubles(3);
  const std::size_t qn = quadric_doubles(n);
  std::vector<double> cluster_quadric(clustering.count * q3, 0.0);
  std::vector<double> wedge_quadric(attribute_count > 0 ? wedge_count * qn : 0, 0.0);
  std::vector<std::array<double, 3>> face_normal(triangle_count);  // area-weighted (x2)
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t* corner = &mesh.indices[3 * t];
    double p[3][kMaxQuadricDim];
    for (int k = 0; k < 3; ++k) local_vertex(corner[k], p[k]);
    const std::array<double, 3> e1{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const std::array<double, 3> e2{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    face_normal[t] = cross(e1, e2);
    if (locked(corner[0]) && locked(corner[1]) && locked(corner[2])) continue;
    const std::array<double, 3>& fn = face_normal[t];
    const double area = 0.5 * std::sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
    if (!(area > 0.0)) continue;
    double quadric3[quadric_doubles(3)];
    double quadric_n[kMaxQuadricDoubles];
    triangle_quadric(3, p[0], p[1], p[2], area, quadric3);
    if (attribute_count > 0) triangle_quadric(n, p[0], p[1], p[2], area, quadric_n);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = corner[k];
      if (locked(v)) continue;
      add_quadric(3, &cluster_quadric[cluster[v] * q3], quadric3);
      if (attribute_count > 0) add_quadric(n, &wedge_quadric[wedge[v] * qn], quadric_n);
    }
  }

  // representatives: cluster positions, then wedge attributes with the position fixed
  std::vector<float> wedge_record(wedge_count * stride);
  std::vector<double> cluster_position(clustering.count * 3);
  for (std::uint32_t c = 0; c < clustering.count; ++c) {
    if (clustering.locked[c] || cluster_vertices[c] == 0) continue;
    double mean[3];
    for (int i = 0; i < 3; ++i) mean[i] = cluster_sum[c * 3 + static_cast<std::size_t>(i)] / cluster_vertices[c];
    double* x = &cluster_position[c * 3];
    minimize_quadric(3, &cluster_quadric[c * q3], mean, x);
    for (std::size_t i = 0; i < 3; ++i) x[i] = std::clamp(x[i], clustering.box[c].min[i], clustering.box[c].max[i]);
  }
  for (std::size_t w = 0; w < wedge_count; ++w) {
    const auto root = static_cast<std::uint32_t>(order[w]);
    float* record = &wedge_record[w * stride];
    if (locked(root)) {
      std::memcpy(record, &mesh.vertices[root * stride], stride * 4);
      continue;
    }
    const std::uint32_t c = cluster[root];
    double v[kMaxQuadricDim];
    for (int i = 0; i < 3; ++i) v[i] = cluster_position[c * 3 + static_cast<std::size_t>(i)];
    if (attribute_count > 0) {
      double mean[kMaxQuadricDim];
      for (int i = 0; i < n; ++i) mean[i] = wedge_sum[w * stride + static_cast<std::size_t>(i)] / wedge_vertices[w];
      minimize_quadric_free_tail(n, 3, &wedge_quadric[w * qn], mean + 3, v);
      finish_attributes(layout, layout.normal ? mean + 3 : nullptr, v + 3);
    }
    for (int i = 0; i < 3; ++i) record[i] = static_cast<float>(v[i] + origin[static_cast<std::size_t>(i)]);
    for (int i = 3; i < n; ++i) record[i] = static_cast<float>(v[i]);
  }

  // candidate triangles: sources counted per cluster triple
  std::unordered_map<Triple, std::uint32_t, TripleHash> candidate_of;
  std::vector<Candidate> candidates;
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t* corner = &mesh.indices[3 * t];
    const std::uint32_t c0 = cluster[corner[0]], c1 = cluster[corner[1]], c2 = cluster[corner[2]];
    if (c0 == c1 || c1 == c2 || c0 == c2) continue;
    Triple sorted{{c0, c1, c2}};
    std::sort(sorted.c, sorted.c + 3);
    // the source's winding agrees with the sorted triple's iff it is an even permutation of it
    const bool even = (c0 < c1) + (c1 < c2) + (c2 < c0) == 2;
    const auto [it, inserted] = candidate_of.try_emplace(sorted, static_cast<std::uint32_t>(candidates.size()));
    if (inserted) candidates.push_back({0, static_cast<std::uint32_t>(t), {}});
    Candidate& candidate = candidates[it->second];
    ++candidate.count;
    for (std::size_t i = 0; i < 3; ++i) candidate.normal[i] += even ? face_normal[t][i] : -face_normal[t][i];
  }

  // output: odd candidates, oriented like their sources, vertices compacted in wedge order
  NodeMesh out;
  out.layout = layout;
  std::vector<std::uint32_t> kept;  // wedge corners of kept triangles
  for (const Candidate& candidate : candidates) {
    if (candidate.count % 2 == 0) continue;
    const std::uint32_t* corner = &mesh.indices[3 * static_cast<std::size_t>(candidate.first_triangle)];
    std::array<std::uint32_t, 3> w{wedge[corner[0]], wedge[corner[1]], wedge[corner[2]]};
    const float* pos[3];
    for (int k = 0; k < 3; ++k) pos[k] = &wedge_record[w[static_cast<std::size_t>(k)] * stride];
    if (std::memcmp(pos[0], pos[1], 12) == 0 || std::memcmp(pos[1], pos[2], 12) == 0 ||
        std::memcmp(pos[0], pos[2], 12) == 0)
      continue;
    const std::array<double, 3> e1{double(pos[1][0]) - pos[0][0], double(pos[1][1]) - pos[0][1], double(pos[1][2]) - pos[0][2]};
    const std::array<double, 3> e2{double(pos[2][0]) - pos[0][0], double(pos[2][1]) - pos[0][1], double(pos[2][2]) - pos[0][2]};
    const std::array<double, 3> normal = cross(e1, e2);
    const std::uint32_t c0 = cluster[corner[0]], c1 = cluster[corner[1]], c2 = cluster[corner[2]];
    const bool even = (c0 < c1) + (c1 < c2) + (c2 < c0) == 2;
    const double agreement = (even ? 1.0 : -1.0) *
        (normal[0] * candidate.normal[0] + normal[1] * candidate.normal[1] + normal[2] * candidate.normal[2]);
    if (agreement < 0.0) std::swap(w[1], w[2]);
    kept.insert(kept.end(), w.begin(), w.end());
  }
  std::vector<std::uint32_t> output_id(wedge_count, UINT32_MAX);
  for (std::uint32_t w : kept) output_id[w] = 0;
  std::uint32_t next = 0;
  for (std::size_t w = 0; w < wedge_count; ++w) {
    if (output_id[w] == UINT32_MAX) continue;
    output_id[w] = next++;
    out.vertices.insert(out.vertices.end(), wedge_record.begin() + static_cast<std::ptrdiff_t>(w * stride),
                        wedge_record.begin() + static_cast<std::ptrdiff_t>((w + 1) * stride));
  }
  out.indices.reserve(kept.size());
  for (std::uint32_t w : kept) out.indices.push_back(output_id[w]);
  return out;
}

}  // namespace octolod::bake
