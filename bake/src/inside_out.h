// Triangles a vertex clustering turned inside out. The output rule winds each kept triangle to
// face like its sources (wedges.h, append_kept_triangles); where the one source of a cluster
// triple faces otherwise than the surface around it (a sliver at a sharp bend, whose corners the
// cells pull into a steep triangle), the kept triangle faces against every neighbour and runs
// each shared edge the same way as that neighbour does. It is drawn from behind (dark with
// two-sided lighting, a hole where back faces are culled, as games do), and the next LOD's
// triangle made from it inherits its facing. Measured before this pass (triangles facing
// against their corners' normals by more than 120 degrees): 0, 0, 0, 3 and 7 in the chains of
// five 20K-triangle rocks (39.5K triangles each); 27, 24 and 20 in the depth 0, 1 and 2 cuts of
// a 1M rock (11.5K, 77K and 194K triangles), where 0, 1 and 0 are left.
#pragma once

#include <cstddef>

#include "octolod/formats/node_file.h"

namespace octolod::bake {

// Re-winds (corners 1 and 2 swapped) every triangle of `mesh` that has neighbours across at
// least two of its edges, whose normal points against the sum of its neighbours' normals, and
// that is wound against the surface: with normals in the layout, its normal also points against
// the mean of its corners' normals (which come from the input surface's); without, it runs every
// shared edge the same way as the triangles there and none the other way. Edges and neighbours
// are found by corner position, so that attribute seams do not hide them. Left as they are: a
// two-sided sheet's triangles (each faces like its own normals, and runs its twin's edges the
// other way), a flattened closed part (consistently wound, facing like its normals), a mesh
// whose normals all point inwards (every triangle faces like its neighbours). Positions,
// attributes, the triangles' order and which edges are boundary edges (used by an odd number of
// triangles) do not change. Returns the number of triangles re-wound.
std::size_t rewind_inside_out(NodeMesh& mesh);

}  // namespace octolod::bake
