// The boundary of a node mesh (seed 3.5, 4.4): the edges whose vertices must stay put so that
// octree nodes simplified independently never crack.
//
// Edges are keyed on vertex POSITION identity — the exact float bits of x,y,z — not on vertex
// ids: vertices that differ only in normal, colour or uv (an attribute seam) are one geometric
// vertex, and the edge they share is interior if triangles use it on both sides. A boundary edge
// is an edge used by an odd number of the node's triangles (normally exactly one: the node's
// border, or the asset's own border). Odd rather than "exactly one" makes the boundary the mod-2
// boundary of the triangle set, which every clustering here preserves: a non-manifold edge used
// three times stays locked too. (An edge used twice in this node and once in a neighbour is
// interior here; such non-manifold edges across nodes may open — the seed shares this limit.)
//
// Every vertex record whose position is an end of a boundary edge is locked: kept bit-identical
// in every LOD. A vertex on an attribute seam interior to the node is not locked.
//
// Only the boundary edges another node can share need to be kept (NeighbourReach): the rest,
// the mesh's own border deep inside the node, is clustered like the interior.
#pragma once

#include <cstdint>
#include <vector>

#include "octolod/bake/simplify.h"
#include "octolod/formats/node_file.h"

namespace octolod::bake {

// A dense id per distinct position (exact bits of x,y,z), numbered in order of first use.
struct PositionIds {
  std::vector<std::uint32_t> of_vertex;  // NodeMesh vertex -> position id
  std::uint32_t count = 0;
};
PositionIds make_position_ids(const NodeMesh& mesh);

// One boundary edge: vertex ids a -> b in the winding of the first triangle that uses it.
struct BoundaryEdge {
  std::uint32_t a;
  std::uint32_t b;
  std::uint32_t triangle;  // that triangle
};

struct Boundary {
  std::vector<BoundaryEdge> edges;             // in order of first use (triangle, then corner)
  std::vector<std::uint8_t> locked_position;   // per position id: 1 when on a boundary edge
  // With NeighbourReach: the boundary edges no other node can share (the mesh's own border
  // deep inside the node), not in `edges` and not locked.
  std::vector<BoundaryEdge> free_edges;
};

// Edges with both ends at the same position (degenerate triangles) are never boundary edges.
// With `neighbours`, only the boundary edges other nodes may share with the node of `cell` are
// kept (and their ends locked): those within neighbours.reach of its faces (NeighbourReach).
Boundary find_boundary(const NodeMesh& mesh, const PositionIds& positions, const Bounds& cell = {},
                       const NeighbourReach& neighbours = {});

}  // namespace octolod::bake
