// Uniform-grid vertex clustering inside an octree node (Lindstrom 2000, "Out-of-core
// simplification of large polygonal models"; seed 3.5, 4.4 with the node boundary locked): the
// node's domain (its cell extended by the bounds of its triangles, which stick out of the cell
// since they are assigned by centroid) is cut into cubic cells, g along its longest side; every
// unlocked vertex belongs to the cell containing it, every locked position is a cluster of its
// own. wedges.cpp turns the clustering into the mesh.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <utility>
#include <vector>

#include "cluster.h"
#include "flat_hash.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

constexpr std::uint64_t kLockedKey = 1ull << 63;

struct GridDomain {
  std::array<double, 3> min;  // local coordinates (relative to PreparedNode::origin)
  std::array<double, 3> max;
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
    grid.max[i] = static_cast<double>(domain.max[i]) - node.origin[i];
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

// Cluster key of every vertex: the linear cell index, or kLockedKey | position id.
std::vector<std::uint64_t> vertex_keys(const PreparedNode& node, const GridDomain& grid) {
  const std::size_t stride = node.mesh.layout.floats();
  const double inverse_size = 1.0 / grid.cell_size;
  // cell along axis i = floor((x - origin - min) / size), from the model-unit float x, clamped
  // to the grid; truncation is the floor once negatives are clamped (and no libm call, which
  // std::floor is without SSE4.1)
  std::array<double, 3> start;
  std::array<double, 3> last_cell;
  for (std::size_t i = 0; i < 3; ++i) {
    start[i] = node.origin[i] + grid.min[i];
    last_cell[i] = static_cast<double>(grid.dims[i] - 1);
  }
  std::vector<std::uint64_t> keys(node.mesh.vertex_count());
  for (std::size_t v = 0; v < keys.size(); ++v) {
    const std::uint32_t position = node.positions.of_vertex[v];
    if (node.boundary.locked_position[position]) {
      keys[v] = kLockedKey | position;
      continue;
    }
    std::uint64_t key = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      const double cell = (static_cast<double>(node.mesh.vertices[v * stride + i]) - start[i]) * inverse_size;
      key = key * grid.dims[i] + static_cast<std::uint32_t>(cell > 0.0 ? std::min(cell, last_cell[i]) : 0.0);
    }
    keys[v] = key;
  }
  return keys;
}

// Dense cluster ids in ascending key order (grid cells first, then locked positions in order of
// first use), and the sorted distinct keys. A hash table assigns ids in order of first use; only
// the distinct keys are sorted.
std::pair<std::vector<std::uint32_t>, std::vector<std::uint64_t>> dense_ids(
    const std::vector<std::uint64_t>& keys, bool sorted_ids) {
  FlatHashMap<2> table(keys.size());
  std::vector<std::uint64_t> distinct;
  std::vector<std::uint32_t> ids(keys.size());
  for (std::size_t v = 0; v < keys.size(); ++v) {
    bool inserted = false;
    ids[v] = table.find_or_insert({static_cast<std::uint32_t>(keys[v] >> 32), static_cast<std::uint32_t>(keys[v])},
                                  static_cast<std::uint32_t>(distinct.size()), inserted);
    if (inserted) distinct.push_back(keys[v]);
  }
  if (!sorted_ids) return {std::move(ids), std::move(distinct)};
  std::vector<std::uint32_t> by_key(distinct.size());
  std::iota(by_key.begin(), by_key.end(), 0u);
  std::sort(by_key.begin(), by_key.end(), [&distinct](std::uint32_t a, std::uint32_t b) { return distinct[a] < distinct[b]; });
  std::vector<std::uint32_t> rank(distinct.size());
  std::vector<std::uint64_t> sorted(distinct.size());
  for (std::size_t r = 0; r < by_key.size(); ++r) {
    rank[by_key[r]] = static_cast<std::uint32_t>(r);
    sorted[r] = distinct[by_key[r]];
  }
  for (std::uint32_t& id : ids) id = rank[id];
  return {std::move(ids), std::move(sorted)};
}

double surface_area(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  double area = 0.0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float* p[3];
    for (std::size_t k = 0; k < 3; ++k) p[k] = &mesh.vertices[mesh.indices[3 * t + k] * stride];
    const double e1[3] = {double(p[1][0]) - p[0][0], double(p[1][1]) - p[0][1], double(p[1][2]) - p[0][2]};
    const double e2[3] = {double(p[2][0]) - p[0][0], double(p[2][1]) - p[0][1], double(p[2][2]) - p[0][2]};
    const double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2], nz = e1[0] * e2[1] - e1[1] * e2[0];
    area += 0.5 * std::sqrt(nx * nx + ny * ny + nz * nz);
  }
  return area;
}

// An upper bound of count_grid_triangles(node, 1) without clustering: at g = 1 every unlocked
// vertex is in the one cell, so a surviving triangle has at least two locked corners.
std::size_t coarsest_count_bound(const PreparedNode& node) {
  const std::vector<std::uint8_t>& locked = node.boundary.locked_position;
  const std::vector<std::uint32_t>& position = node.positions.of_vertex;
  std::size_t count = 0;
  for (std::size_t t = 0; t < node.mesh.triangle_count(); ++t) {
    const std::uint32_t* corner = &node.mesh.indices[3 * t];
    count += locked[position[corner[0]]] + locked[position[corner[1]]] + locked[position[corner[2]]] >= 2;
  }
  return count;
}

}  // namespace

std::size_t count_grid_triangles(const PreparedNode& node, std::uint32_t g) {
  const GridDomain grid = make_domain(node, g);
  const auto [cluster, distinct] = dense_ids(vertex_keys(node, grid), false);
  // parity per cluster triple: the number of triples seen an odd number of times
  FlatHashMap<3> parity(node.mesh.triangle_count());
  std::vector<std::uint8_t> odd;
  std::size_t count = 0;
  for (std::size_t t = 0; t < node.mesh.triangle_count(); ++t) {
    std::array<std::uint32_t, 3> triple{cluster[node.mesh.indices[3 * t]], cluster[node.mesh.indices[3 * t + 1]],
                                        cluster[node.mesh.indices[3 * t + 2]]};
    std::sort(triple.begin(), triple.end());
    if (triple[0] == triple[1] || triple[1] == triple[2]) continue;
    bool inserted = false;
    const std::uint32_t index = parity.find_or_insert(triple, static_cast<std::uint32_t>(odd.size()), inserted);
    if (inserted) odd.push_back(0);
    odd[index] ^= 1u;
    if (odd[index]) ++count;
    else --count;
  }
  return count;
}

std::uint32_t choose_grid_resolution(const PreparedNode& node, std::size_t target) {
  // Triangles grow about like g^2 on a surface. First guess from the area: a surface crosses
  // about 1.5 A / s^2 cubes of side s, and a closed mesh has about 2 triangles per vertex.
  // Then power-law corrections through the last count, keeping a feasible lower and an
  // infeasible upper end; stop once the count is within 15% below the target (at most 12 counts).
  // The count at g = 1 (the fallback) is only needed when its upper bound does not settle the
  // comparisons with it: most searches skip it.
  const std::size_t coarsest_bound = coarsest_count_bound(node);
  std::optional<std::size_t> coarsest;
  auto count_coarsest = [&] {
    if (!coarsest) coarsest = count_grid_triangles(node, 1);
    return *coarsest;
  };
  if (coarsest_bound > target && count_coarsest() > target) return 1;
  constexpr std::uint32_t kMaxResolution = 1u << 16;
  Bounds domain = node.cell;
  domain.extend(node.mesh_bounds);
  const double side = std::max({static_cast<double>(domain.max[0]) - domain.min[0],
                                static_cast<double>(domain.max[1]) - domain.min[1],
                                static_cast<double>(domain.max[2]) - domain.min[2]});
  const double area = surface_area(node.mesh);
  double guess = area > 0.0 ? side * std::sqrt(static_cast<double>(target) / (3.0 * area)) : 8.0;
  std::uint32_t lo = 1, hi = kMaxResolution + 1;
  std::uint32_t g = static_cast<std::uint32_t>(std::clamp(guess, 2.0, static_cast<double>(kMaxResolution)));
  // the feasible resolution with the most triangles so far: counts are not monotone in g (a
  // grid aligned with a city's lots collapses every box into a column of cells)
  std::uint32_t best = 1;
  std::size_t best_count = 0;
  for (int evaluation = 0; evaluation < 12 && hi - lo > 1; ++evaluation) {
    g = std::clamp(g, lo + 1, hi - 1);
    const std::size_t count = count_grid_triangles(node, g);
    if (count <= target) lo = g;
    else hi = g;
    if (count <= target && count > best_count) best = g, best_count = count;
    if (count <= target && (count >= node.mesh.triangle_count() || static_cast<double>(count) >= 0.85 * static_cast<double>(target)))
      break;  // close enough, or nothing left to merge
    // over the target: at least 15% coarser per step (counts with a large fixed part, locked
    // boundaries or many small parts, fall slower than g^2)
    double ratio = count > 0 ? std::sqrt(0.95 * static_cast<double>(target) / static_cast<double>(count)) : 4.0;
    if (count > target) ratio = std::min(ratio, 0.85);
    const double next = std::clamp(static_cast<double>(g) * ratio, static_cast<double>(g) / 4.0,
                                   static_cast<double>(g) * 4.0);
    g = static_cast<std::uint32_t>(std::lround(next));
    if (g <= lo || g >= hi) g = lo + (hi - lo) / 2;  // the model stalled: bisect
  }
  // g = 1 unless the search found more triangles (within the target) than it keeps
  if (best_count > coarsest_bound) return best;
  return best_count > count_coarsest() ? best : 1;
}

ClusteredMesh cluster_grid(const PreparedNode& node, std::uint32_t g) {
  const GridDomain grid = make_domain(node, g);
  auto [cluster, distinct] = dense_ids(vertex_keys(node, grid), true);
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
      // the cubic cell, cut to the domain (the last cell along an axis may stick out of it)
      clustering.box[c].min[i] = grid.min[i] + index * grid.cell_size;
      clustering.box[c].max[i] = std::min(grid.min[i] + (index + 1.0) * grid.cell_size, grid.max[i]);
    }
  }
  return build_clustered_mesh(node.mesh, clustering, node.origin);
}

}  // namespace octolod::bake
