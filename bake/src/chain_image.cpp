#include "chain_image.h"

#include <numeric>

#include "wedges.h"

namespace octolod::bake {

ChainImage::ChainImage(const NodeMesh& first)
    : vertex_(first.vertex_count()), triangle_(first.triangle_count()),
      incident_(first.vertex_count(), kNoTriangle), cluster_(first.vertex_count()) {
  std::iota(vertex_.begin(), vertex_.end(), 0u);
  std::iota(triangle_.begin(), triangle_.end(), 0u);
  for (std::size_t i = 0; i < first.indices.size(); ++i)
    if (incident_[first.indices[i]] == kNoTriangle) incident_[first.indices[i]] = static_cast<std::uint32_t>(i / 3);
}

ImageHints ChainImage::follow(const SimplifyStep& step, const NodeMesh& output) {
  for (std::size_t v = 0; v < vertex_.size(); ++v) cluster_[v] = step.vertex_cluster[vertex_[v]];
  for (std::uint32_t& t : triangle_)
    if (t != kNoTriangle) t = step.nearby_output_triangle[t];
  for (std::size_t v = 0; v < vertex_.size(); ++v) {
    std::uint32_t next = step.vertex_output[vertex_[v]];
    if (next == kNoVertex) {  // its wedge collapsed: a corner of the output near one of its triangles
      const std::uint32_t t = incident_[v] == kNoTriangle ? kNoTriangle : triangle_[incident_[v]];
      next = t == kNoTriangle ? 0 : output.indices[3 * std::size_t{t}];
    }
    vertex_[v] = next;
  }
  return {triangle_, cluster_, step.fan_offset, step.fan_triangle};
}

}  // namespace octolod::bake
