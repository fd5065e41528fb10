// Conservative geometric error of a simplification (seed 3.5.3, 5.3.2: every node LOD stores an
// upper bound on its distance from the surface it replaces).
#pragma once

#include "octolod/formats/node_file.h"

namespace octolod::bake {

// An upper bound, in model units, of the one-sided Hausdorff distance from `input` to `output`:
// max over points x of the input's triangles of dist(x, output's triangles). 0 when the input has
// no triangles, +infinity when only the output has none. Never below the true value (up to a
// relative 1e-6 margin added for rounding); usually within a few percent of it.
double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output);

}  // namespace octolod::bake
