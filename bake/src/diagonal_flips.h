// Edge flips after a vertex clustering. The clustering decides which cluster triples become
// triangles from the input's connectivity, so where four clusters form a bent quad it may pick
// the diagonal that cuts under a ridge or bridges a valley: a 1M rock's 10% cut had its
// Hausdorff distance at such edges' midpoints, and flipping them (with the input as the judge)
// lowered it by a fifth (seed 3: 0.0050 -> 0.0039; docs/benchmarks.md). The judge is the
// distance of each diagonal's midpoint, where the two triangulations of a quad differ most, to
// the input triangles around the quad. (Judging by the input vertices' distances to the quad
// instead, the energy of Hoppe et al. 1993, "Mesh optimization", flipped 100x fewer quads and
// missed the ridges: the input vertices sit in the clusters' cells, away from the diagonal's
// midpoint.)
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "clustered_output.h"

namespace octolod::bake {

// Flips, in place, interior edges of `corners` (wedge triples of input.output()'s triangles)
// whose two triangles (a, b, c) and (b, a, d) share both wedges of the edge a-b (no attribute
// seam) and bend (normals more than ~11 degrees apart), when c-d joins two clusters no triangle
// joins yet, each of the flipped pair (a, d, c), (b, c, d) faces within 60 degrees of the pair's
// summed normal (no sliver stood off the surface), and the midpoint of c-d lies nearer the input
// than the midpoint of a-b (squared distance under 0.95x; the input triangles with a corner in
// one of the four clusters). Each triangle flips at most once; edges are visited in triangle
// order, so the result depends on the input only. The edges used an odd number of times (the
// boundary) do not change, so neither does crack-freedom; the triangle count does not change.
// Returns the number of flips.
std::size_t flip_diagonals(InputDistances& input, std::vector<std::uint32_t>& corners);

}  // namespace octolod::bake
