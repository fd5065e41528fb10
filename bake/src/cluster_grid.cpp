// Grid vertex clustering inside an octree node (Lindstrom 2000, "Out-of-core simplification of
// large polygonal models"; seed 3.5, 4.4 with the node boundary locked): the node's domain (its
// cell extended by the bounds of its triangles, which stick out of the cell since they are
// assigned by centroid) is cut into cubic cells, g along its longest side; every unlocked vertex
// belongs to the cell containing it, every locked position is a cluster of its own. For a wanted
// triangle count the grid is adaptive on two levels (in the spirit of Shaffer & Garland 2001,
// "Efficient adaptive simplification of massive meshes"): the cells whose quadric error per area
// is highest are halved. With PreparedNode::facing set, a cell holding opposite facings (both
// sides of a thin part) is split into up to four sides, by facing. wedges.cpp turns the
// clustering into the mesh.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <utility>
#include <vector>

#include "cluster.h"
#include "flat_hash.h"
#include "quadric.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

constexpr std::uint64_t kLockedKey = 1ull << 63;
constexpr std::uint64_t kFineKey = 1ull << 62;  // a cell of the halved grid (adaptive clustering)
// The vertices of a cell that face away from its principal facing, and from its second axis
// (split_opposite_facings).
constexpr std::uint64_t kAwayKey = 1ull << 61;
constexpr std::uint64_t kAcrossKey = 1ull << 60;
constexpr std::uint64_t kCellBits = ~(kFineKey | kAwayKey | kAcrossKey);  // the cell index of an unlocked key
// A cell holds opposite facings, the two sides of a wall or a thin box, when the vertices'
// facings (PreparedNode::facing) sum to less than this share of their number (a 90-degree edge
// sums to 0.71 of it): one cluster would fold both sides into one sheet.
constexpr double kOppositeFacingShare = 0.3;
// A split cell is split across its second axis too where the facings' moment along it is at
// least this share of the moment along the principal one.
constexpr double kSecondAxisShare = 0.3;
// Adaptive grid: the coarse level alone keeps about this share of the wanted triangles (its
// resolution is searched for that count), halving the worst cells spends the rest. A 1M rock's
// 10/3/1% cuts, RMS / reference at the same count: uniform grid 1.61/1.56/1.23, shares 0.72,
// 0.8, 0.85: 1.14-1.27 / 1.39-1.51 / 1.03-1.10. At 0.36 a step could end far below its target
// (0.31 of its input instead of 0.5: no single halving fitted) with a bound too small for its
// error, and the 3% cut picked it (RMS 3.75x).
constexpr double kCoarseShare = 0.8;
// Counts the search for the number of halved cells may spend (each hashes every triangle).
constexpr int kHalvingSearchSteps = 6;
// Below this coarse resolution the cells are too few to choose among (a chain's last steps,
// where the locked boundary dominates the count): the uniform grid for the target instead. On a
// half rock's chain the step 1633 -> 795 triangles had a Hausdorff distance of 0.056 this way,
// 0.15 with 2 coarse cells and a few halved ones.
constexpr std::uint32_t kMinAdaptiveResolution = 8;

GridDomain make_domain(const PreparedNode& node, std::uint32_t g) {
  return make_grid_domain(node.cell, node.mesh_bounds, node.origin, g);
}

}  // namespace

GridDomain make_grid_domain(const Bounds& cell, const Bounds& mesh_bounds,
                            const std::array<double, 3>& origin, std::uint32_t g) {
  Bounds domain = cell;
  if (!mesh_bounds.empty()) domain.extend(mesh_bounds);
  GridDomain grid{};
  double side = 0.0;
  for (std::size_t i = 0; i < 3; ++i) {
    grid.min[i] = static_cast<double>(domain.min[i]) - origin[i];
    grid.max[i] = static_cast<double>(domain.max[i]) - origin[i];
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

ClampBox grid_cell_box(const GridDomain& grid, std::uint64_t key) {
  ClampBox box;
  for (std::size_t i = 3; i-- > 0;) {
    const auto index = static_cast<double>(key % grid.dims[i]);
    key /= grid.dims[i];
    // the cubic cell, cut to the domain (the last cell along an axis may stick out of it)
    box.min[i] = grid.min[i] + index * grid.cell_size;
    box.max[i] = std::min(grid.min[i] + (index + 1.0) * grid.cell_size, grid.max[i]);
  }
  return box;
}

namespace {

// The grid of `coarse` with every cell halved along each axis (same origin: every fine cell lies
// in one coarse cell).
GridDomain halved(const GridDomain& coarse) {
  GridDomain fine = coarse;
  fine.cell_size = coarse.cell_size / 2.0;
  for (std::size_t i = 0; i < 3; ++i) {
    const double cells = std::ceil((coarse.max[i] - coarse.min[i]) / fine.cell_size);
    fine.dims[i] = static_cast<std::uint32_t>(std::clamp(cells, 1.0, 2.0 * coarse.dims[i]));
  }
  return fine;
}

// In every cell that holds opposite facings (PreparedNode::facing: they nearly cancel, by
// kOppositeFacingShare, or some vertex faces more than 120 degrees away from the cell's net
// facing), the vertices are sorted into sides by the eigenvectors of the sum of f f^T over their
// facings f: kAwayKey for those facing away from the principal one, and where the facings spread
// across a second axis too (kSecondAxisShare: a tube's ring, a box) kAcrossKey for those facing
// away from it. Each side is a cluster of its own, so both sides of a part thinner than a cell
// stay apart, and a tube keeps four sides instead of folding into a flat ribbon. `keys` are
// cell indices of `grid` (or locked).
void split_opposite_facings(const PreparedNode& node, const GridDomain& grid, std::vector<std::uint64_t>& keys) {
  constexpr std::uint32_t kNone = FlatHashMap<2>::kMissing;
  // dense cell ids in order of first use: straight from the cell index where the grid has no
  // more cells than vertices (the coarse grids, where cells hold both sides), else hashed
  const std::uint64_t grid_cells = std::uint64_t{grid.dims[0]} * grid.dims[1] * grid.dims[2];
  const bool direct = grid_cells <= keys.size();
  std::vector<std::uint32_t> id_of_cell(direct ? grid_cells : 0, kNone);
  std::optional<FlatHashMap<2>> table;
  if (!direct) table.emplace(keys.size());
  struct Cell {
    std::array<double, 3> sum{};
    std::uint32_t count = 0;
  };
  std::vector<Cell> cells;
  std::vector<std::uint32_t> cell_of(keys.size(), kNone);
  for (std::size_t v = 0; v < keys.size(); ++v) {
    if (keys[v] & kLockedKey) continue;
    std::uint32_t c = kNone;
    if (direct) {
      std::uint32_t& id = id_of_cell[keys[v]];
      if (id == kNone) id = static_cast<std::uint32_t>(cells.size());
      c = id;
    } else {
      bool inserted = false;
      c = table->find_or_insert({static_cast<std::uint32_t>(keys[v] >> 32), static_cast<std::uint32_t>(keys[v])},
                                static_cast<std::uint32_t>(cells.size()), inserted);
    }
    if (c == cells.size()) cells.emplace_back();
    const std::array<float, 3>& f = node.facing[node.positions.of_vertex[v]];
    Cell& cell = cells[c];
    for (std::size_t i = 0; i < 3; ++i) cell.sum[i] += f[i];
    ++cell.count;
    cell_of[v] = c;
  }
  // the least facing along each cell's net facing: a cell is split where some vertex faces
  // more than 120 degrees away from it, or where the facings nearly cancel
  std::vector<double> least(cells.size(), 0.0);
  for (std::size_t v = 0; v < keys.size(); ++v) {
    if (cell_of[v] == kNone) continue;
    const std::array<double, 3>& sum = cells[cell_of[v]].sum;
    const std::array<float, 3>& f = node.facing[node.positions.of_vertex[v]];
    least[cell_of[v]] = std::min(least[cell_of[v]], f[0] * sum[0] + f[1] * sum[1] + f[2] * sum[2]);
  }
  // the cells to split, numbered; the moments of their facings (xx, xy, xz, yy, yz, zz)
  std::vector<std::uint32_t> split_of(cells.size(), kNone);
  std::vector<std::array<double, 6>> moment;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const Cell& cell = cells[c];
    const double net = std::sqrt(cell.sum[0] * cell.sum[0] + cell.sum[1] * cell.sum[1] + cell.sum[2] * cell.sum[2]);
    if (cell.count >= 2 && (net < kOppositeFacingShare * cell.count || least[c] < -0.5 * net)) {
      split_of[c] = static_cast<std::uint32_t>(moment.size());
      moment.push_back({});
    }
  }
  if (moment.empty()) return;
  for (std::size_t v = 0; v < keys.size(); ++v) {
    if (cell_of[v] == kNone || split_of[cell_of[v]] == kNone) continue;
    const std::array<float, 3>& f = node.facing[node.positions.of_vertex[v]];
    std::array<double, 6>& m = moment[split_of[cell_of[v]]];
    m[0] += f[0] * f[0], m[1] += f[0] * f[1], m[2] += f[0] * f[2];
    m[3] += f[1] * f[1], m[4] += f[1] * f[2], m[5] += f[2] * f[2];
  }
  // per split cell its principal facing, and a second axis where the facings spread across
  // it too (a tube's ring: four sides), else zero
  std::vector<std::array<std::array<double, 3>, 2>> axes(moment.size());
  for (std::size_t k = 0; k < moment.size(); ++k) {
    const Eigen3 eigen = symmetric_eigen3(moment[k]);
    axes[k][0] = eigen.vector[0];
    axes[k][1] = eigen.value[1] >= kSecondAxisShare * eigen.value[0] ? eigen.vector[1] : std::array<double, 3>{};
  }
  for (std::size_t v = 0; v < keys.size(); ++v) {
    if (cell_of[v] == kNone || split_of[cell_of[v]] == kNone) continue;
    const std::array<std::array<double, 3>, 2>& a = axes[split_of[cell_of[v]]];
    const std::array<float, 3>& f = node.facing[node.positions.of_vertex[v]];
    if (a[0][0] * f[0] + a[0][1] * f[1] + a[0][2] * f[2] < 0.0) keys[v] |= kAwayKey;
    if (a[1][0] * f[0] + a[1][1] * f[1] + a[1][2] * f[2] < 0.0) keys[v] |= kAcrossKey;
  }
}

// Cluster key of every vertex: the linear cell index (with kAwayKey / kAcrossKey where the cell
// is split by facing), or kLockedKey | position id.
std::vector<std::uint64_t> vertex_keys(const PreparedNode& node, const GridDomain& grid) {
  const std::size_t stride = node.mesh().layout.floats();
  const GridCellKeys cell_keys(grid, node.origin);
  std::vector<std::uint64_t> keys(node.mesh().vertex_count());
  for (std::size_t v = 0; v < keys.size(); ++v) {
    const std::uint32_t position = node.positions.of_vertex[v];
    keys[v] = node.boundary.locked_position[position] ? kLockedKey | position
                                                      : cell_keys.key(&node.mesh().vertices[v * stride]);
  }
  if (!node.facing.empty()) split_opposite_facings(node, grid, keys);
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

// An upper bound of count_grid_triangles(node, 1) without clustering: at g = 1 every unlocked
// vertex is in the one cell, so a surviving triangle has at least two locked corners.
std::size_t coarsest_count_bound(const PreparedNode& node) {
  const std::vector<std::uint8_t>& locked = node.boundary.locked_position;
  const std::vector<std::uint32_t>& position = node.positions.of_vertex;
  std::size_t count = 0;
  for (std::size_t t = 0; t < node.mesh().triangle_count(); ++t) {
    const std::uint32_t* corner = &node.mesh().indices[3 * t];
    count += locked[position[corner[0]]] + locked[position[corner[1]]] + locked[position[corner[2]]] >= 2;
  }
  return count;
}

// Triangles whose corners have three distinct cluster ids (or keys) `id` (per vertex): the
// sources build_clustered_mesh groups per cluster triple (SearchCount::surviving).
template <class Id>
std::size_t count_surviving_triangles(const PreparedNode& node, const std::vector<Id>& id) {
  std::size_t count = 0;
  const std::uint32_t* corner = node.mesh().indices.data();
  for (std::size_t t = 0; t < node.mesh().triangle_count(); ++t, corner += 3) {
    const Id a = id[corner[0]], b = id[corner[1]], c = id[corner[2]];
    count += a != b && b != c && a != c;
  }
  return count;
}

// Triangles the clustering given by per-vertex cluster ids keeps (before the rare drop of
// triangles whose corners coincide after rounding): build_clustered_mesh's rule per cluster
// triple (KeptTriangleCounter), without solving any quadric.
std::size_t count_kept_triangles(const PreparedNode& node, const std::vector<std::uint32_t>& cluster) {
  KeptTriangleCounter<3> counter(node.mesh().triangle_count());
  for (std::size_t t = 0; t < node.mesh().triangle_count(); ++t) {
    const std::uint32_t* corner = &node.mesh().indices[3 * t];
    const std::uint32_t c0 = cluster[corner[0]], c1 = cluster[corner[1]], c2 = cluster[corner[2]];
    if (c0 == c1 || c1 == c2 || c0 == c2) continue;
    counter.add(sorted_triple(c0, c1, c2), winds_like_sorted(c0, c1, c2));
  }
  return counter.kept();
}

// The clustering of per-vertex keys of `coarse` (and of `fine` where kFineKey is set): clusters
// in ascending key order, each unlocked one clamped to its cell.
Clustering clustering_from_keys(const std::vector<std::uint64_t>& keys, const GridDomain& coarse,
                                const GridDomain& fine) {
  auto [cluster, distinct] = dense_ids(keys, true);
  Clustering clustering;
  clustering.of_vertex = std::move(cluster);
  clustering.count = static_cast<std::uint32_t>(distinct.size());
  clustering.locked.resize(distinct.size());
  clustering.box.resize(distinct.size());
  for (std::size_t c = 0; c < distinct.size(); ++c) {
    const std::uint64_t key = distinct[c];
    clustering.locked[c] = (key & kLockedKey) != 0;
    if (clustering.locked[c]) continue;
    clustering.box[c] = grid_cell_box(key & kFineKey ? fine : coarse, key & kCellBits);
  }
  return clustering;
}

// The order in which the adaptive grid halves the clusters of `cluster` (dense ids of the coarse
// keys, `distinct` their keys): highest quadric error per area first, where the error is the
// cluster's position quadric (add_plane_quadrics, as build_clustered_mesh sums them) at its
// minimizer nearest the cluster's mean: the mean squared distance of its surface to the flat
// piece that replaces it, large where the surface bends within the cell. Locked clusters and clusters of one vertex (nothing to halve) are left out; equal
// errors in key order. With the quadrics and (for the unlocked clusters of more than one
// vertex) their minimizers, which the clusters left whole keep.
struct HalvingOrder {
  std::vector<std::uint32_t> order;
  std::vector<double> quadric;
  std::vector<double> minimizer;
};
HalvingOrder clusters_by_error(const PreparedNode& node, const std::vector<std::uint32_t>& cluster,
                               const std::vector<std::uint64_t>& distinct) {
  const std::size_t stride = node.mesh().layout.floats();
  const std::size_t count = distinct.size();
  std::vector<std::uint8_t> unlocked(cluster.size());
  for (std::size_t v = 0; v < cluster.size(); ++v) unlocked[v] = (distinct[cluster[v]] & kLockedKey) == 0;
  constexpr std::size_t q3 = quadric_doubles(3);
  std::vector<double> quadric(count * q3, 0.0), area(count, 0.0), sum(count * 3, 0.0);
  add_plane_quadrics(node.mesh(), node.face_normal, cluster, unlocked, node.origin, quadric.data(), area.data(),
                     node.free_border);
  std::vector<std::uint32_t> members(count, 0);
  for (std::uint32_t v = 0; v < cluster.size(); ++v) {
    if (!unlocked[v]) continue;
    for (std::size_t i = 0; i < 3; ++i)
      sum[cluster[v] * 3 + i] += static_cast<double>(node.mesh().vertices[v * stride + i]) - node.origin[i];
    ++members[cluster[v]];
  }
  std::vector<std::pair<double, std::uint32_t>> ranked;  // (-error per area, cluster)
  std::vector<double> minimizer(count * 3);
  for (std::uint32_t c = 0; c < count; ++c) {
    if ((distinct[c] & kLockedKey) || members[c] <= 1) continue;
    double mean[3];
    double* x = &minimizer[c * 3];
    for (std::size_t i = 0; i < 3; ++i) mean[i] = sum[c * 3 + i] / members[c];
    minimize_quadric(3, &quadric[c * q3], mean, x);
    if (area[c] > 0.0) ranked.push_back({-std::max(0.0, evaluate_quadric(3, &quadric[c * q3], x)) / area[c], c});
  }
  std::sort(ranked.begin(), ranked.end(), [&distinct](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : distinct[a.second] < distinct[b.second];
  });
  std::vector<std::uint32_t> order(ranked.size());
  for (std::size_t r = 0; r < ranked.size(); ++r) order[r] = ranked[r].second;
  return {std::move(order), std::move(quadric), std::move(minimizer)};
}

}  // namespace

std::size_t count_grid_triangles(const PreparedNode& node, std::uint32_t g, SearchCount count) {
  const std::vector<std::uint64_t> keys = vertex_keys(node, make_domain(node, g));
  return count == SearchCount::surviving ? count_surviving_triangles(node, keys)
                                         : count_kept_triangles(node, dense_ids(keys, false).first);
}

std::uint32_t next_search_resolution(std::uint32_t g, std::size_t count, std::size_t target, std::uint32_t lo,
                                     std::uint32_t hi) {
  // over the target: at least 15% coarser per step (counts with a large fixed part, locked
  // boundaries or many small parts, fall slower than g^2)
  double ratio = count > 0 ? std::sqrt(0.95 * static_cast<double>(target) / static_cast<double>(count)) : 4.0;
  if (count > target) ratio = std::min(ratio, 0.85);
  const double next = std::clamp(static_cast<double>(g) * ratio, static_cast<double>(g) / 4.0,
                                 static_cast<double>(g) * 4.0);
  const auto step = static_cast<std::uint32_t>(std::lround(next));
  return step <= lo || step >= hi ? lo + (hi - lo) / 2 : step;  // the model stalled: bisect
}

namespace {

// choose_grid_resolution's answer and the count it measured there.
struct GridChoice {
  std::uint32_t g;
  std::size_t count;
};

GridChoice search_grid_resolution(const PreparedNode& node, std::size_t target, SearchCount rule) {
  // Triangles grow about like g^2 on a surface. First guess from the area: a surface crosses
  // about 1.5 A / s^2 cubes of side s, and a closed mesh has about 2 triangles per vertex.
  // Then power-law corrections through the last count, keeping a feasible lower and an
  // infeasible upper end; stop once the count is within 15% below the target (at most 12 counts).
  // The count at g = 1 (the fallback) is only needed when its upper bound does not settle the
  // comparisons with it: most searches skip it.
  const std::size_t coarsest_bound = coarsest_count_bound(node);
  std::optional<std::size_t> coarsest;
  auto count_coarsest = [&] {
    if (!coarsest) coarsest = count_grid_triangles(node, 1, rule);
    return *coarsest;
  };
  if (coarsest_bound > target && count_coarsest() > target) return {1, *coarsest};
  constexpr std::uint32_t kMaxResolution = 1u << 16;
  Bounds domain = node.cell;
  domain.extend(node.mesh_bounds);
  const double side = std::max({static_cast<double>(domain.max[0]) - domain.min[0],
                                static_cast<double>(domain.max[1]) - domain.min[1],
                                static_cast<double>(domain.max[2]) - domain.min[2]});
  const double area = node.area;
  double guess = area > 0.0 ? side * std::sqrt(static_cast<double>(target) / (3.0 * area)) : 8.0;
  std::uint32_t lo = 1, hi = kMaxResolution + 1;
  std::uint32_t g = static_cast<std::uint32_t>(std::clamp(guess, 2.0, static_cast<double>(kMaxResolution)));
  // the feasible resolution with the most triangles so far: counts are not monotone in g (a
  // grid aligned with a city's lots collapses every box into a column of cells)
  std::uint32_t best = 1;
  std::size_t best_count = 0;
  for (int evaluation = 0; evaluation < 12 && hi - lo > 1; ++evaluation) {
    g = std::clamp(g, lo + 1, hi - 1);
    const std::size_t count = count_grid_triangles(node, g, rule);
    if (count <= target) lo = g;
    else hi = g;
    if (count <= target && count > best_count) best = g, best_count = count;
    if (count <= target && (count >= node.mesh().triangle_count() || static_cast<double>(count) >= 0.85 * static_cast<double>(target)))
      break;  // close enough, or nothing left to merge
    g = next_search_resolution(g, count, target, lo, hi);
  }
  // g = 1 unless the search found more triangles (within the target) than it keeps
  if (best_count > coarsest_bound) return {best, best_count};
  return best_count > count_coarsest() ? GridChoice{best, best_count} : GridChoice{1, *coarsest};
}

}  // namespace

std::uint32_t choose_grid_resolution(const PreparedNode& node, std::size_t target, SearchCount count) {
  return search_grid_resolution(node, target, count).g;
}

namespace {

// The uniform grid at resolution g as a clustering.
Clustering uniform_clustering(const PreparedNode& node, std::uint32_t g) {
  const GridDomain grid = make_domain(node, g);
  return clustering_from_keys(vertex_keys(node, grid), grid, grid);
}

}  // namespace

ClusteredMesh cluster_grid(const PreparedNode& node, std::uint32_t g) {
  return build_clustered_mesh(node.mesh(), node.face_normal, uniform_clustering(node, g), node.origin,
                              node.free_border);
}

Clustering adaptive_grid_clustering(const PreparedNode& node, std::size_t target, SearchCount rule) {
  const GridChoice choice =
      search_grid_resolution(node, static_cast<std::size_t>(kCoarseShare * static_cast<double>(target)), rule);
  const std::uint32_t g = choice.g;
  if (g < kMinAdaptiveResolution) return uniform_clustering(node, choose_grid_resolution(node, target, rule));
  const GridDomain coarse = make_domain(node, g);
  const GridDomain fine = halved(coarse);
  const std::vector<std::uint64_t> coarse_keys = vertex_keys(node, coarse);
  std::vector<std::uint64_t> fine_keys = vertex_keys(node, fine);
  for (std::uint64_t& key : fine_keys)
    if (!(key & kLockedKey)) key |= kFineKey;
  // (not a structured binding: the lambdas below capture them, which clang before 16 refuses)
  const auto coarse_ids = dense_ids(coarse_keys, false);
  const std::vector<std::uint32_t>& coarse_id = coarse_ids.first;
  const std::vector<std::uint64_t>& coarse_distinct = coarse_ids.second;
  const std::vector<std::uint32_t> fine_id = dense_ids(fine_keys, false).first;
  const auto [order, coarse_quadric, coarse_minimizer] = clusters_by_error(node, coarse_id, coarse_distinct);
  std::vector<std::uint32_t> rank(coarse_distinct.size(), UINT32_MAX);
  for (std::size_t r = 0; r < order.size(); ++r) rank[order[r]] = static_cast<std::uint32_t>(r);
  // cluster ids with the first `halved_count` clusters of `order` halved (ids past the coarse
  // ones for their fine cells)
  const auto first_fine = static_cast<std::uint32_t>(coarse_distinct.size());
  std::vector<std::uint32_t> ids(coarse_id.size());
  auto count_with = [&](std::size_t halved_count) {
    for (std::size_t v = 0; v < ids.size(); ++v)
      ids[v] = rank[coarse_id[v]] < halved_count ? first_fine + fine_id[v] : coarse_id[v];
    return rule == SearchCount::surviving ? count_surviving_triangles(node, ids) : count_kept_triangles(node, ids);
  };
  // The most halved clusters whose output stays within the target. The count grows with them,
  // nearly monotonically and about linearly: interpolation between a feasible and an infeasible
  // number, bisection when that stalls; it stops within 3% below the target. Nothing is halved
  // when even the coarse grid is over (g = 1: the locked boundary dominates, the caller sees the
  // count).
  std::size_t feasible = 0, infeasible = order.size() + 1;
  std::size_t feasible_count = choice.count, infeasible_count = 0;  // count_with(0)
  if (feasible_count > target) infeasible = 1;
  for (int evaluation = 0; evaluation < kHalvingSearchSteps && infeasible - feasible > 1 &&
                           static_cast<double>(feasible_count) < 0.97 * static_cast<double>(target);
       ++evaluation) {
    std::size_t probe = feasible + (infeasible - feasible) / 2;
    if (infeasible_count > feasible_count) {  // both ends measured: interpolate, away from the ends
      const double share = static_cast<double>(target - feasible_count) / static_cast<double>(infeasible_count - feasible_count);
      probe = std::clamp(feasible + static_cast<std::size_t>(share * static_cast<double>(infeasible - feasible)),
                         feasible + 1, infeasible - 1);
    }
    const std::size_t count = count_with(probe);
    if (count <= target) feasible = probe, feasible_count = count;
    else infeasible = probe, infeasible_count = count;
  }
  for (std::size_t v = 0; v < fine_keys.size(); ++v)
    if (rank[coarse_id[v]] >= feasible) fine_keys[v] = coarse_keys[v];
  Clustering clustering = clustering_from_keys(fine_keys, coarse, fine);
  // the coarse clusters left whole come first (in key order) and have the vertices they had in
  // clusters_by_error: its quadrics and minimizers
  std::vector<std::uint32_t> coarse_of;  // per whole coarse cluster, its coarse id
  for (std::size_t v = 0; v < fine_keys.size(); ++v) {
    if (rank[coarse_id[v]] < feasible || (fine_keys[v] & kLockedKey)) continue;
    const std::uint32_t c = clustering.of_vertex[v];
    if (c >= coarse_of.size()) coarse_of.resize(c + 1);
    coarse_of[c] = coarse_id[v];
  }
  constexpr std::size_t q3 = quadric_doubles(3);
  clustering.quadric.reserve(coarse_of.size() * q3);
  clustering.minimizer.reserve(coarse_of.size() * 3);
  for (const std::uint32_t c : coarse_of) {
    clustering.quadric.insert(clustering.quadric.end(), &coarse_quadric[c * q3], &coarse_quadric[c * q3] + q3);
    clustering.minimizer.insert(clustering.minimizer.end(), &coarse_minimizer[c * 3], &coarse_minimizer[c * 3] + 3);
  }
  return clustering;
}

}  // namespace octolod::bake
