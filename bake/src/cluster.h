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
