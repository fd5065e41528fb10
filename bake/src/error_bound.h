// Conservative geometric error of a simplification (seed 3.5.3, 5.3.2: every node LOD stores an
// upper bound on its distance from the surface it replaces).
#pragma once

#include <cstdint>
#include <span>

#include "octolod/formats/node_file.h"

namespace octolod::bake {

// An upper bound, in model units, of the one-sided Hausdorff distance from `input` to `output`:
// max over points x of the input's triangles of dist(x, output's triangles). 0 when the input has
// no triangles, +infinity when only the output has none. Never below the true value (up to a
// relative 1e-6 margin added for rounding); usually within a few percent of it.
// Closest-point queries (measure::TriangleBvh) for every input vertex, refinement where needed.
double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output);

// The same, much faster when a simplification knows where each input triangle went:
// `nearby_output_triangle[t]` is an output triangle near the image of input triangle t (or
// 0xFFFFFFFF: none). For a fixed output triangle T the distance x -> dist(x, T) is convex, so
// max over corners of dist(corner, T) bounds dist(x, output) over the whole input triangle;
// three point-triangle distances per input triangle replace the queries, which only the
// triangles without a hint still need. Exactly as conservative; as tight as the hints are good
// (the image of a triangle that survived clustering is the natural choice). Empty span: no hints.
double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output,
                             std::span<const std::uint32_t> nearby_output_triangle);

}  // namespace octolod::bake
