// Where a LOD chain's first LOD went along the chain (lod_chain.cpp): each step's image of its
// input (SimplifyStep) composed onto the first LOD's vertices and triangles, so that a later LOD
// k can be bounded straight from LOD 0 (LOD 0's error + bound(LOD 0 -> LOD k), the triangle
// inequality once instead of once per step) with candidate output triangles as good as a single
// step's. Hints only: hausdorff_upper_bound stays an upper bound for any of them.
#pragma once

#include <cstdint>
#include <vector>

#include "error_bound.h"
#include "octolod/formats/node_file.h"
#include "simplify_step.h"

namespace octolod::bake {

class ChainImage {
 public:
  // Starts at the chain's first LOD (the current LOD is `first` itself); `first` is not kept.
  explicit ChainImage(const NodeMesh& first);

  // `step` simplified the current LOD into `output` (non-empty, step.has_image()): returns the
  // hints for hausdorff_upper_bound(first LOD, output), valid while `step` and this object are
  // unchanged, and makes `output` the current LOD.
  ImageHints follow(const SimplifyStep& step, const NodeMesh& output);

 private:
  std::vector<std::uint32_t> vertex_;    // per first-LOD vertex: a vertex of the current LOD
  std::vector<std::uint32_t> triangle_;  // per first-LOD triangle: a current LOD triangle near its image, or kNoTriangle
  std::vector<std::uint32_t> incident_;  // per first-LOD vertex: a triangle with a corner at it, or kNoTriangle
  std::vector<std::uint32_t> cluster_;   // per first-LOD vertex: its cluster in the last step followed
};

}  // namespace octolod::bake
