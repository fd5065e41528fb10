// Conservative geometric error of a simplification (seed 3.5.3, 5.3.2: every node LOD stores an
// upper bound on its distance from the surface it replaces).
#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include "octolod/formats/node_file.h"

namespace octolod::bake {

// An upper bound, in model units, of the one-sided Hausdorff distance from `input` to `output`:
// max over points x of the input's triangles of dist(x, output's triangles). 0 when the input has
// no triangles, +infinity when only the output has none. Never below the true value, with margins
// for rounding added (relative 1e-6, and 8 float epsilons of the largest coordinate, so that
// distances measured in float do not exceed it either); usually within a few percent of it (error_bound.cpp:
// input triangles cut into pieces that each lie over one output triangle, or split).
// Closest-point queries (measure::TriangleBvh) for every input vertex.
double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output);

// Where a vertex clustering sent the input (all spans index the input / output meshes given
// with them; empty spans = unknown).
struct ImageHints {
  // Per input triangle: an output triangle at or next to its image, or 0xFFFFFFFF.
  std::span<const std::uint32_t> nearby_output_triangle;
  // Per input vertex: its cluster. Per cluster c: the output triangles with a corner at c's
  // representative are fan_triangle[fan_offset[c] .. fan_offset[c+1]).
  std::span<const std::uint32_t> vertex_cluster;
  std::span<const std::uint32_t> fan_offset;
  std::span<const std::uint32_t> fan_triangle;
};

// The same bound, faster with hints, and as tight: the candidate output triangles of an input
// triangle come from the hints instead of closest-point queries (its image, the images nearest
// to its corners, the fans around its corners' clusters), queries only for the few vertices
// whose hinted distance is the largest and for triangles the candidates do not cover. A caller
// that only needs the bound when it is at most `give_up` (model units) gets +infinity as soon
// as the bound is known to exceed it: the same answer for its comparison, for less work.
double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output, const ImageHints& hints,
                             double give_up = std::numeric_limits<double>::infinity());

}  // namespace octolod::bake
