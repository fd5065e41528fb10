// bake::simplify_node: input checks, node preparation (weld, position ids, boundary) and the
// choice between the seed's operator and the grid (seed 3.5, 4.4), with the error bound of the
// result (seed 3.5.3).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "cluster.h"
#include "error_bound.h"
#include "octolod/bake/simplify.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

Status check_mesh(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  if (mesh.vertices.size() % stride != 0)
    return bad_input_error("node mesh: " + std::to_string(mesh.vertices.size()) +
                           " vertex floats is not a multiple of " + std::to_string(stride) + " (" +
                           mesh.layout.describe() + ")");
  if (mesh.indices.size() % 3 != 0)
    return bad_input_error("node mesh: " + std::to_string(mesh.indices.size()) + " indices is not a multiple of 3");
  const std::size_t vertex_count = mesh.vertex_count();
  for (std::size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= vertex_count)
      return bad_input_error("node mesh: index " + std::to_string(i) + " is " + std::to_string(mesh.indices[i]) +
                             ", but there are only " + std::to_string(vertex_count) + " vertices");
  for (std::size_t v = 0; v < vertex_count; ++v)
    for (std::size_t k = 0; k < 3; ++k)
      if (!std::isfinite(mesh.vertices[v * stride + k]))
        return bad_input_error("node mesh: vertex " + std::to_string(v) + " has a non-finite position");
  return {};
}

// When the clustered mesh keeps less than this share of the wanted triangles, the search with
// the fast count ended low (the surviving triangles overshot the kept ones, or a halving search
// whose probes they all put over the target: a 100K half city stopped at 0.72 of its target)
// and the step searches again with the exact count, keeping whichever result has more.
constexpr double kRecountShare = 0.85;

// A grid step whose output keeps less than this share of its input's area is taken again with
// the cells that hold opposite facings split. A 64K tube (1 x 1000) needs it at steps keeping
// 60-70% (its 1% cut's RMS: 12.75 plain, 1.10 at 0.65, 0.41 at 0.7, back to 12.75 at 0.6); the
// 1M city's steps mostly keep 65-70% (walls dropped), where the second try costs 40% more CPU
// and wins little (its cuts' RMS the same within 1%).
constexpr double kSplitAreaShare = 0.65;

// The grid method for a wanted triangle count: the adaptive grid searched with the fast count
// (SearchCount::surviving), again with the exact one where that ended far below the target.
// With cells split by facing, the exact count at once: there the surviving triangles overshoot
// the kept ones much more (up to 20% on a 20K city: the sides of a split box meet in cluster
// triples of both windings that face the same way), and the recount would nearly always run.
ClusteredMesh cluster_for_target(const PreparedNode& node, std::size_t target) {
  auto clustered = [&](SearchCount count) {
    return build_clustered_mesh(node.mesh(), node.face_normal, adaptive_grid_clustering(node, target, count),
                                node.origin, node.free_border);
  };
  if (!node.facing.empty()) return clustered(SearchCount::kept);
  ClusteredMesh fast = clustered(SearchCount::surviving);
  if (static_cast<double>(fast.mesh.triangle_count()) >= kRecountShare * static_cast<double>(target)) return fast;
  ClusteredMesh exact = clustered(SearchCount::kept);
  const std::size_t kept = exact.mesh.triangle_count();
  return kept > fast.mesh.triangle_count() && kept <= target ? std::move(exact) : std::move(fast);
}

}  // namespace

PreparedNode prepare_node(const NodeMesh& mesh, const Bounds& cell, bool lock_boundary,
                          const NeighbourReach& neighbours) {
  PreparedNode node;
  node.input = &mesh;
  node.positions = make_position_ids(mesh);
  if (may_have_identical_records(mesh, node.positions)) {
    node.cleaned = weld_if_needed(mesh);
    if (node.cleaned) node.positions = make_position_ids(node.mesh());  // else the same mesh's
  }
  if (std::optional<NodeMesh> once = without_repeated_triangles(node.mesh(), node.positions)) {
    node.cleaned = std::move(once);
    node.positions = make_position_ids(node.mesh());
  }
  node.cell = cell;
  prepare_boundary(node, lock_boundary, neighbours);
  node.mesh_bounds = node.mesh().bounds();
  node.face_normal = face_normals(node.mesh());
  node.area = surface_area(node.face_normal);
  for (std::size_t i = 0; i < 3; ++i)
    node.origin[i] = 0.5 * (static_cast<double>(cell.min[i]) + static_cast<double>(cell.max[i]));
  return node;
}

void prepare_boundary(PreparedNode& node, bool lock_boundary, const NeighbourReach& neighbours) {
  if (lock_boundary) {
    node.boundary = find_boundary(node.mesh(), node.positions, node.cell, neighbours);
    node.free_border = std::move(node.boundary.free_edges);
  } else {
    node.boundary = {};
    node.free_border = find_boundary(node.mesh(), node.positions).edges;
    node.boundary.locked_position.assign(node.positions.count, 0);
  }
}

Result<SimplifyResult> simplify_node(const NodeMesh& input, const Bounds& cell,
                                     const SimplifyOptions& options) {
  OCTOLOD_RETURN_IF_ERROR(check_mesh(input));
  if (cell.empty()) return usage_error("simplify_node: the node cell is empty");
  if (options.method == ClusterMethod::grid && options.target_triangles == 0 && options.grid_resolution == 0)
    return usage_error("simplify_node: the grid method needs target_triangles or grid_resolution");
  SimplifyResult result;
  result.mesh.layout = input.layout;
  if (input.triangle_count() == 0) return result;

  // bade2006 keeps every boundary edge: the seed's operator fans all of them
  if (options.method == ClusterMethod::bade2006) {
    const PreparedNode node = prepare_node(input, cell, true);
    result.mesh = cluster_bade2006(node);
    result.error_bound = hausdorff_upper_bound(node.mesh(), result.mesh);
    return result;
  }
  // The step, its error bound +infinity when it would exceed `max_error` or its error times
  // triangles would exceed `max_cost`.
  auto grid_step = [&](const PreparedNode& node, double max_cost, double max_error) {
    ClusteredMesh clustered = options.target_triangles > 0 ? cluster_for_target(node, options.target_triangles)
                                                           : cluster_grid(node, options.grid_resolution);
    SimplifyResult step;
    step.mesh = std::move(clustered.mesh);
    const auto triangles = static_cast<double>(step.mesh.triangle_count());
    step.error_bound = hausdorff_upper_bound(node.mesh(), step.mesh, clustered.hints(),
                                             std::min(max_error, triangles > 0.0 ? max_cost / triangles : kInfinity));
    return step;
  };
  auto cost = [](const SimplifyResult& step) {  // +infinity for an empty output (error +infinity)
    return std::isinf(step.error_bound) ? step.error_bound
                                        : step.error_bound * static_cast<double>(step.mesh.triangle_count());
  };
  // The grid step, and where it dropped much of the surface, the step again with the cells that
  // hold opposite facings split (PreparedNode::facing: both sides of a part thinner than a
  // cell), kept when it has the lower error within the target (both are within it: the chain
  // goes on from either; a collapsed part has the fewer triangles and the larger error).
  // (the facings do not depend on the boundary: computed once for either border)
  std::vector<std::array<float, 3>> facings;
  auto best_grid_step = [&](PreparedNode& node, double max_cost) {
    SimplifyResult plain = grid_step(node, max_cost, kInfinity);
    if (options.target_triangles == 0 || surface_area(face_normals(plain.mesh)) >= kSplitAreaShare * node.area)
      return plain;
    if (facings.empty()) facings = position_facings(node.mesh(), node.positions, node.face_normal);
    node.facing.swap(facings);
    SimplifyResult split = grid_step(node, max_cost, plain.error_bound);
    node.facing.swap(facings);
    const bool wins = split.mesh.triangle_count() <= options.target_triangles && split.error_bound < plain.error_bound;
    return wins ? split : plain;
  };
  PreparedNode node = prepare_node(input, cell, options.lock_boundary, options.neighbours);
  result = best_grid_step(node, kInfinity);
  // Below the root, a free border (the mesh's own, no neighbour shares it) is simplified where
  // that pays: the step is taken again with the border kept, and the free one stays when its
  // error times its triangles is the lower (a surface's error falls about like 1 / triangles).
  // Kept, the border costs a triangle per edge; freed, a border cluster's representative is
  // held on the border line by the border quadrics, and a bent surface beside the border is
  // flattened up to it. On the 1M terrain, freed everywhere, steps whose border was a few
  // percent of their triangles had up to 2.5x the error at the same count; where it was a fifth
  // or more, the free border's error times triangles was 0.65x the kept one's (geometric mean;
  // docs/benchmarks.md). No share of border edges told the two apart.
  if (options.lock_boundary && !node.free_border.empty()) {
    // (bounded only as far as it can win)
    PreparedNode with_border = node;
    prepare_boundary(with_border, true);
    SimplifyResult kept = best_grid_step(with_border, cost(result));
    if (cost(kept) <= cost(result)) result = std::move(kept);
  }
  return result;
}

}  // namespace octolod::bake
