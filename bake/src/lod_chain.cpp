// LOD chains of one octree node by sequential simplification (seed 3.5.3, 5.3.2): each LOD is
// simplified from the previous one, and its error bound adds up along the chain (the triangle
// inequality: dist(original, LOD k) <= dist(original, LOD k-1) + dist(LOD k-1, LOD k)). Internal
// nodes start from the merge of one LOD per child (lod_tree.h: the finest that fit), for
// unbalanced trees too.
#include <cassert>
#include <cmath>

#include "octolod/bake/simplify.h"
#include "wedges.h"

namespace octolod::bake {

NodeMesh merge_meshes(std::span<const NodeMesh* const> meshes) {
  NodeMesh merged;
  if (meshes.empty()) return merged;
  merged.layout = meshes.front()->layout;
  std::size_t floats = 0, indices = 0;
  for (const NodeMesh* mesh : meshes) {
    assert(mesh->layout == merged.layout && "merge_meshes: every mesh must have the same layout");
    floats += mesh->vertices.size();
    indices += mesh->indices.size();
  }
  merged.vertices.reserve(floats);
  merged.indices.reserve(indices);
  for (const NodeMesh* mesh : meshes) {
    const auto base = static_cast<std::uint32_t>(merged.vertex_count());
    merged.vertices.insert(merged.vertices.end(), mesh->vertices.begin(), mesh->vertices.end());
    for (std::uint32_t index : mesh->indices) merged.indices.push_back(base + index);
  }
  return weld_identical_vertices(merged);
}

Result<std::vector<Lod>> build_lods(NodeMesh input, double input_error, const Bounds& cell,
                                    const LodOptions& options) {
  if (!(options.reduction > 0.0 && options.reduction < 1.0))
    return usage_error("build_lods: reduction must be in (0, 1)");
  if (options.max_lods == 0) return usage_error("build_lods: max_lods must be at least 1");
  std::vector<Lod> lods;
  double error = input_error;
  if (options.include_input) lods.push_back({std::move(input), error});
  // each step simplifies the last LOD (the input before the first)
  auto current = [&]() -> const NodeMesh& { return lods.empty() ? input : lods.back().mesh; };

  // an internal node's first step goes by its own limit (LodOptions::input_min_triangles)
  auto stop_at = [&] { return lods.empty() ? options.input_min_triangles : options.min_triangles; };
  while (lods.size() < options.max_lods && current().triangle_count() > stop_at()) {
    const std::size_t previous = current().triangle_count();
    const auto target = static_cast<std::size_t>(std::floor(static_cast<double>(previous) * options.reduction));
    // an internal node's first step only has to shrink its input (which is no LOD of its own)
    const std::size_t accept = lods.empty() ? previous - 1 : target;
    SimplifyOptions step;
    step.method = options.method;
    step.target_triangles = static_cast<std::uint32_t>(std::max<std::size_t>(target, 1));
    step.lock_boundary = options.lock_boundary;
    step.neighbours = options.neighbours;
    Result<SimplifyResult> simplified = simplify_node(current(), cell, step);
    if (!simplified.ok()) return simplified.status();
    const std::size_t count = simplified->mesh.triangle_count();
    if (count == 0 || count > accept) break;  // the locked boundary dominates
    error += simplified->error_bound;
    lods.push_back({std::move(simplified->mesh), error});
    if (lods.size() == 1) input = {};  // an internal node's merged input is no LOD of its own
  }
  if (lods.empty()) lods.push_back({std::move(input), error});
  return lods;
}

}  // namespace octolod::bake
