// The two per-node clustering operators behind bake::simplify_node (seed 3.5, 4.4): the seed's
// one-representative fan (cluster_bade2006.cpp) and a Lindstrom 2000 uniform grid inside the node
// (cluster_grid.cpp), both on a node prepared once (welded, boundary found).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "boundary_edges.h"
#include "wedges.h"
#include "octolod/formats/bounds.h"
#include "octolod/formats/node_file.h"

namespace octolod::bake {

struct PreparedNode {
  NodeMesh mesh;                  // the input with identical vertex records welded
  PositionIds positions;
  Boundary boundary;
  Bounds cell;                    // the node's octree cell, model units
  Bounds mesh_bounds;             // tight bounds of mesh
  std::array<double, 3> origin;   // cell centre: the local origin of the quadric arithmetic
};

// `mesh` must be valid (indices in range, finite positions); checked by simplify_node.
PreparedNode prepare_node(const NodeMesh& mesh, const Bounds& cell);

// Grid method at resolution g (cells along the longest side of cell ∪ mesh bounds, g >= 1).
ClusteredMesh cluster_grid(const PreparedNode& node, std::uint32_t g);
// Grid method for a wanted triangle count: a coarse grid whose resolution is searched for about
// 0.8 x target triangles, then the clusters with the highest quadric error per area (where the
// surface bends inside the cell) halved into the 2 x 2 x 2 cells of the grid at twice the
// resolution, as many as keep the count within `target` (interpolation and bisection, at most 6
// counts, stopping within 3% below the target). The clustering for
// build_clustered_mesh: clusters in key order (coarse cells, halved cells, locked positions), so
// the result depends only on the node. Below 8 coarse cells along the longest side, the uniform
// grid for the target (choose_grid_resolution) instead; when even the coarsest grid is over the
// target (the locked boundary dominates) nothing is halved: the caller sees the count.
Clustering adaptive_grid_clustering(const PreparedNode& node, std::size_t target);
// Triangles cluster_grid(node, g) would keep (before the rare drop of triangles whose corners
// coincide after rounding), without solving any quadric: what the resolution search evaluates.
std::size_t count_grid_triangles(const PreparedNode& node, std::uint32_t g);
// The resolution whose output has at most `target` triangles and is as fine as a short search
// finds (at most 12 counts; it stops within 15% below the target; the count is nearly but not
// exactly monotone in g); 1 when even g = 1 exceeds it.
std::uint32_t choose_grid_resolution(const PreparedNode& node, std::size_t target);

// The seed's operator: one representative, every boundary edge fanned to it. Empty when the node
// has no boundary (a closed surface inside one node has nothing to fan).
NodeMesh cluster_bade2006(const PreparedNode& node);

}  // namespace octolod::bake
