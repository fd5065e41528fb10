// Conservative geometric error of a simplification (seed 3.5.3, 5.3.2: every node LOD stores an
// upper bound on its distance from the surface it replaces).
#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include "octolod/formats/node_file.h"

namespace octolod::bake {

// An upper bound, in model units, of the one-sided Hausdorff distance from `input` to `output`:
// max over points x of the input's triangles of dist(x, output's triangles), the exact distance
// between the surfaces the meshes' float positions define. 0 when the input has no triangles (or
// the output holds every input point), +infinity when only the output has none. Never below the
// true value (a relative margin of 1e-6 for this file's double arithmetic); usually within a few
// percent of it (error_bound.cpp: input triangles cut into pieces that each lie over one output
// triangle, or split). Closest-point queries (measure::TriangleBvh) for every input vertex.
// Distances measured in float can exceed it by float_measurement_margin: the bake adds that
// once to each stored error, not to every step's bound, so that it does not add up along chains.
double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output);

// An index that names no triangle.
inline constexpr std::uint32_t kNoTriangle = 0xFFFFFFFFu;

// Where a vertex clustering sent the input (all spans index the input / output meshes given
// with them; empty spans = unknown).
struct ImageHints {
  // Per input triangle: an output triangle at or next to its image, or kNoTriangle.
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

// How far a distance between points of `region` (model units) measured in float, from float
// positions with float arithmetic (measure::TriangleBvh, a runtime), may exceed the exact one:
// 8 float epsilons of its largest coordinate. Grows with the distance from the origin, not with
// the model's size: 0.1 for a model 100 km from it.
double float_measurement_margin(const Bounds& region);

}  // namespace octolod::bake
