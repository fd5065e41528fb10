// Uniform-grid vertex clustering inside an octree node (Lindstrom 2000, "Out-of-core
// simplification of large polygonal models"; seed 3.5, 4.4 with the node boundary locked): the
// node's domain (its cell extended by the bounds of its triangles, which stick out of the cell
// since they are assigned by centroid) is cut into cubic cells, g along its longest side; every
// unlocked vertex belongs to the cell containing it, every locked position is a cluster of its
// own. wedges.cpp turns the clustering into the mesh.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "cluster.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

constexpr std::uint64_t kLockedKey = 1ull << 63;

struct GridDomain {
  std::array<double, 3> min;  // local coordinates (relative to PreparedNode::origin)
  double cell_size;
  std::array<std::uint32_t, 3> dims;
};

GridDomain make_domain(const PreparedNode& node, std::uint32_t g) {
  Bounds domain = node.cell;
  if (!node.mesh_bounds.empty()) domain.extend(node.mesh_bounds);
  GridDomain grid{};
  double side = 0.0;
  for (std::size_t i = 0; i < 3; ++i) {
    grid.min[i] = static_cast<double>(domain.min[i]) - node.origin[i];
    side = std::max(side, static_cast<double>(domain.max[i]) - domain.min[i]);
  }
  grid.cell_size = side > 0.0 ? side / g : 1.0;
  for (std::size_t i = 0; i < 3; ++i) {
    const double extent = static_cast<double>(domain.max[i]) - domain.min[i];
    const double cells = std::ceil(extent / grid.cell_size);
    grid.dims[i] = static_cast<std::uint32_t>(std::clamp(cells, 1.0, static_cast<double>(g)));
  }
  return grid;
}

std::uint32_t cell_index(const GridDomain& grid, std::size_t axis, double local) {
  const double cell = std::floor((local - grid.min[axis]) / grid.cell_size);
  return static_cast<std::uint32_t>(std::clamp(cell, 0.0, static_cast<double>(grid.dims[axis] - 1)));
}

// Cluster key of every vertex: the linear cell index, or kLockedKey | position id.
std::vector<std::uint64_t> vertex_keys(const PreparedNode& node, const GridDomain& grid) {
  const std::size_t stride = node.mesh.layout.floats();
  std::vector<std::uint64_t> keys(node.mesh.vertex_count());
  for (std::size_t v = 0; v < keys.size(); ++v) {
    const std::uint32_t position = node.positions.of_vertex[v];
    if (node.boundary.locked_position[position]) {
      keys[v] = kLockedKey | position;
      continue;
    }
    std::uint64_t key = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      const double local = static_cast<double>(node.mesh.vertices[v * stride + i]) - node.origin[i];
      key = key * grid.dims[i] + cell_index(grid, i, local);
    }
    keys[v] = key;
  }
  return keys;
}

// Dense cluster ids in ascending key order (grid cells first, then locked positions in order of
// first use), and the sorted distinct keys.
std::pair<std::vector<std::uint32_t>, std::vector<std::uint64_t>> dense_ids(
    const std::vector<std::uint64_t>& keys) {
  std::vector<std::uint64_t> distinct = keys;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  std::vector<std::uint32_t> ids(keys.size());
  for (std::size_t v = 0; v < keys.size(); ++v)
    ids[v] = static_cast<std::uint32_t>(std::lower_bound(distinct.begin(), distinct.end(), keys[v]) - distinct.begin());
  return {std::move(ids), std::move(distinct)};
}

}  // namespace

std::size_t count_grid_triangles(const PreparedNode& node, std::uint32_t g) {
  const GridDomain grid = make_domain(node, g);
  const auto [cluster, distinct] = dense_ids(vertex_keys(node, grid));
  struct Triple {
    std::uint32_t c[3];
    bool operator<(const Triple& o) const {
      return c[0] != o.c[0] ? c[0] < o.c[0] : c[1] != o.c[1] ? c[1] < o.c[1] : c[2] < o.c[2];
    }
    bool operator==(const Triple& o) const = default;
  };
  std::vector<Triple> triples;
  triples.reserve(node.mesh.triangle_count());
  for (std::size_t t = 0; t < node.mesh.triangle_count(); ++t) {
    Triple triple{{cluster[node.mesh.indices[3 * t]], cluster[node.mesh.indices[3 * t + 1]],
                   cluster[node.mesh.indices[3 * t + 2]]}};
    std::sort(triple.c, triple.c + 3);
    if (triple.c[0] == triple.c[1] || triple.c[1] == triple.c[2]) continue;
    triples.push_back(triple);
  }
  std::sort(triples.begin(), triples.end());
  std::size_t count = 0;
  for (std::size_t i = 0; i < triples.size();) {
    std::size_t j = i + 1;
    while (j < triples.size() && triples[j] == triples[i]) ++j;
    count += (j - i) % 2;
    i = j;
  }
  return count;
}

std::uint32_t choose_grid_resolution(const PreparedNode& node, std::size_t target) {
  // Triangles grow about like g^2 on a surface: guess from a power law through the last
  // evaluation, keep a feasible lower and an infeasible upper end, stop when they are close.
  if (count_grid_triangles(node, 1) > target) return 1;
  constexpr std::uint32_t kMaxResolution = 1u << 16;
  std::uint32_t lo = 1, hi = kMaxResolution + 1;
  std::uint32_t g = 8;
  for (int evaluation = 0; evaluation < 10 && hi - lo > std::max(1u, lo / 32); ++evaluation) {
    g = std::clamp(g, lo + 1, hi - 1);
    const std::size_t count = count_grid_triangles(node, g);
    if (count <= target) lo = g;
    else hi = g;
    if (count >= node.mesh.triangle_count() && count <= target) break;  // nothing left to merge
    const double ratio = count > 0 ? std::sqrt(static_cast<double>(target) / static_cast<double>(count)) : 4.0;
    const double next = std::clamp(static_cast<double>(g) * ratio, static_cast<double>(g) / 4.0,
                                    static_cast<double>(g) * 4.0);
    g = static_cast<std::uint32_t>(std::lround(next));
    if (g <= lo || g >= hi) g = lo + (hi - lo) / 2;  // the model stalled: bisect
  }
  return lo;
}

NodeMesh cluster_grid(const PreparedNode& node, std::uint32_t g) {
  const GridDomain grid = make_domain(node, g);
  auto [cluster, distinct] = dense_ids(vertex_keys(node, grid));
  Clustering clustering;
  clustering.of_vertex = std::move(cluster);
  clustering.count = static_cast<std::uint32_t>(distinct.size());
  clustering.locked.resize(distinct.size());
  clustering.box.resize(distinct.size());
  for (std::size_t c = 0; c < distinct.size(); ++c) {
    const std::uint64_t key = distinct[c];
    clustering.locked[c] = (key & kLockedKey) != 0;
    if (clustering.locked[c]) continue;
    std::uint64_t rest = key;
    for (std::size_t i = 3; i-- > 0;) {
      const auto index = static_cast<double>(rest % grid.dims[i]);
      rest /= grid.dims[i];
      clustering.box[c].min[i] = grid.min[i] + index * grid.cell_size;
      clustering.box[c].max[i] = grid.min[i] + (index + 1.0) * grid.cell_size;
    }
  }
  return build_clustered_mesh(node.mesh, clustering, node.origin);
}

}  // namespace octolod::bake
