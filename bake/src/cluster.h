// The two per-node clustering operators behind bake::simplify_node (seed 3.5, 4.4): the seed's
// one-representative fan (cluster_bade2006.cpp) and a Lindstrom 2000 uniform grid inside the node
// (cluster_grid.cpp), both on a node prepared once (welded, boundary found).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "boundary_edges.h"
#include "wedges.h"
#include "octolod/formats/bounds.h"
#include "octolod/formats/node_file.h"

namespace octolod::bake {

struct PreparedNode {
  // The input with identical vertex records welded and repeated faces dropped
  // (without_repeated_triangles): the input itself (not copied) when it has neither, which is
  // the rule (a merged input is welded already, a clustering's wedges nearly always differ, and
  // its triple table keeps at most one face per winding).
  const NodeMesh& mesh() const { return cleaned ? *cleaned : *input; }
  const NodeMesh* input = nullptr;  // not owned: outlives the PreparedNode
  std::optional<NodeMesh> cleaned;
  PositionIds positions;
  Boundary boundary;  // empty (nothing locked) without lock_boundary
  // Without lock_boundary: the boundary edges (find_boundary), clustered like the interior, each
  // adding a border quadric (add_plane_quadrics) so that the border keeps its place. Empty with
  // it.
  std::vector<BoundaryEdge> free_border;
  Bounds cell;                    // the node's octree cell, model units
  Bounds mesh_bounds;             // tight bounds of mesh
  // triangle_normal of every triangle of mesh (twice its area), and the mesh's area: the
  // resolution search, the halving order and the clustered mesh all need them
  std::vector<std::array<double, 3>> face_normal;
  double area = 0.0;
  // Empty (prepare_node leaves it so), or per position the unit sum of the normals of its
  // triangles (position_facings), zero where they cancel: which way the surface faces there.
  // When set, the grid keeps the opposite facings of a cell apart (up to four sides per cell;
  // simplify_node sets it for the step it takes again where the plain grid dropped surface).
  std::vector<std::array<float, 3>> facing;
  std::array<double, 3> origin;   // cell centre: the local origin of the quadric arithmetic
};

// A uniform grid of cubic cells over a clustering domain: the node's cell extended by the
// bounds of its triangles (which stick out of the cell: they are assigned by centroid), in local
// coordinates (model units relative to an origin, the cell centre).
struct GridDomain {
  std::array<double, 3> min;
  std::array<double, 3> max;
  double cell_size;                    // side / g
  std::array<std::uint32_t, 3> dims;   // cells per axis, at most g
};
// g cells along the domain's longest side (g >= 1).
GridDomain make_grid_domain(const Bounds& cell, const Bounds& mesh_bounds,
                            const std::array<double, 3>& origin, std::uint32_t g);
// The box of the cell with linear index `key` (GridCellKeys), cut to the domain.
ClampBox grid_cell_box(const GridDomain& grid, std::uint64_t key);

// Linear cell index (x major) of model-unit positions in a GridDomain, clamped to the grid.
class GridCellKeys {
 public:
  GridCellKeys(const GridDomain& grid, const std::array<double, 3>& origin) : dims_(grid.dims) {
    inverse_size_ = 1.0 / grid.cell_size;
    for (std::size_t i = 0; i < 3; ++i) {
      start_[i] = origin[i] + grid.min[i];
      last_cell_[i] = static_cast<double>(grid.dims[i] - 1);
    }
  }
  // cell along axis i = floor((x - origin - min) / size), from the model-unit float x, clamped
  // to the grid; truncation is the floor once negatives are clamped (and no libm call, which
  // std::floor is without SSE4.1)
  std::uint64_t key(const float* position) const {
    std::uint64_t key = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      const double cell = (static_cast<double>(position[i]) - start_[i]) * inverse_size_;
      key = key * dims_[i] + static_cast<std::uint32_t>(cell > 0.0 ? std::min(cell, last_cell_[i]) : 0.0);
    }
    return key;
  }

 private:
  std::array<std::uint32_t, 3> dims_;
  std::array<double, 3> start_;
  std::array<double, 3> last_cell_;
  double inverse_size_;
};

// `mesh` must be valid (indices in range, finite positions; checked by simplify_node) and
// outlive the result, which refers to it. Without lock_boundary the boundary is left empty
// (nothing locked: SimplifyOptions::lock_boundary); with it, the boundary edges `neighbours`
// may share are kept.
PreparedNode prepare_node(const NodeMesh& mesh, const Bounds& cell, bool lock_boundary = true,
                          const NeighbourReach& neighbours = {});
// Sets node.boundary and node.free_border as prepare_node does for these arguments, from the
// node's mesh, positions and cell (set by prepare_node, and the same for any boundary choice: a
// copy of a prepared node takes another boundary without preparing it again).
void prepare_boundary(PreparedNode& node, bool lock_boundary, const NeighbourReach& neighbours = {});

// The next resolution of a search for the finest grid whose triangle count (the last one,
// `count` at resolution g) stays within `target`, given the finest feasible resolution `lo` and
// the coarsest infeasible one `hi` found so far: triangles grow about like g^2 on a surface, so
// a power-law step towards 0.95 x target, at least 15% coarser when over it, at most 4x either
// way; the middle of (lo, hi) when that step leaves the interval. Shared by the in-memory grid's
// search and the streamed leaf's.
std::uint32_t next_search_resolution(std::uint32_t g, std::size_t count, std::size_t target, std::uint32_t lo,
                                     std::uint32_t hi);

// Grid method at resolution g (cells along the longest side of cell ∪ mesh bounds, g >= 1).
ClusteredMesh cluster_grid(const PreparedNode& node, std::uint32_t g);
// How the resolution searches count the triangles of a clustering: `surviving`, the triangles
// whose corners fall in three distinct clusters, an upper bound of what build_clustered_mesh
// keeps (one or two copies per cluster triple of one or more of them) and a pass over the
// indices; or `kept`, what it keeps (a table of the cluster triples, KeptTriangleCounter: exact
// but for the same-facing pairs it drops; counting so took 10% of a 1M rock bake). On 1M rock
// and city bakes the surviving triangles were on average 0.2% and 1.2% above the kept ones, at
// most 8% and 29%.
enum class SearchCount { surviving, kept };

// Grid method for a wanted triangle count: a coarse grid whose resolution is searched for about
// 0.8 x target triangles, then the clusters with the highest quadric error per area (where the
// surface bends inside the cell) halved into the 2 x 2 x 2 cells of the grid at twice the
// resolution, as many as keep the count within `target` (interpolation and bisection, at most 6
// counts, stopping within 3% below the target). The clustering for
// build_clustered_mesh: clusters in key order (coarse cells, halved cells, locked positions), so
// the result depends only on the node. Below 8 coarse cells along the longest side, the uniform
// grid for the target (choose_grid_resolution) instead; when even the coarsest grid is over the
// target (the locked boundary dominates) nothing is halved: the caller sees the count. Counts as
// `count` says.
Clustering adaptive_grid_clustering(const PreparedNode& node, std::size_t target, SearchCount count);
// Triangles cluster_grid(node, g) would keep (before the rare drop of triangles whose corners
// coincide after rounding), or an upper bound of them (`surviving`), without solving any
// quadric: what the resolution searches evaluate.
std::size_t count_grid_triangles(const PreparedNode& node, std::uint32_t g, SearchCount count);
// The resolution whose count (as `count` says) is at most `target` and is as fine as a short
// search finds (at most 12 counts; it stops within 15% below the target; the count is nearly but
// not exactly monotone in g); 1 when even g = 1 exceeds it.
std::uint32_t choose_grid_resolution(const PreparedNode& node, std::size_t target,
                                     SearchCount count = SearchCount::kept);

// The seed's operator: one representative, every boundary edge fanned to it. Empty when the node
// has no boundary (a closed surface inside one node has nothing to fan).
NodeMesh cluster_bade2006(const PreparedNode& node);

}  // namespace octolod::bake
