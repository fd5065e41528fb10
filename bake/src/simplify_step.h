// One simplification step together with where it sent its input: what a LOD chain needs to
// bound a later LOD straight from its first one (chain_image.h). simplify_node is this step
// without the image.
#pragma once

#include <cstdint>
#include <vector>

#include "octolod/bake/simplify.h"
#include "octolod/formats/bounds.h"

namespace octolod::bake {

struct SimplifyStep {
  SimplifyResult result;
  // The grid method's image of the input (ClusteredMesh's fields of the same names), indexed
  // by the input as given, also when the step welded identical records first; all empty for
  // bade2006 and for an empty input. vertex_cluster and vertex_output of a vertex no triangle
  // uses: cluster 0 and kNoVertex.
  std::vector<std::uint32_t> vertex_cluster;
  std::vector<std::uint32_t> vertex_output;
  std::vector<std::uint32_t> nearby_output_triangle;
  std::vector<std::uint32_t> fan_offset;
  std::vector<std::uint32_t> fan_triangle;

  bool has_image() const { return !fan_offset.empty(); }
};

// simplify_node, keeping the image. Same errors.
Result<SimplifyStep> simplify_step(const NodeMesh& input, const Bounds& cell, const SimplifyOptions& options);

}  // namespace octolod::bake
