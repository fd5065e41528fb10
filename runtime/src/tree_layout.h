// The manifest flattened for per-frame work: nodes renumbered in depth-first preorder (so a
// subtree is the index range [n, subtree_end)), subtree boxes, and one "slot" per node LOD with
// its error and decoded size, all in flat arrays so selection allocates nothing and stays in cache.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "octolod/formats/manifest.h"
#include "octolod/formats/status.h"

namespace octolod::runtime {

inline constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

struct LayoutNode {
  // Union of the node's tight bounds and all its descendants' (model space): the region whose
  // original surface any LOD of this node replaces. Tight bounds of simplified parents need not
  // contain their children's, so culling and distances use the union.
  glm::vec3 center{0.0f};
  glm::vec3 half{0.0f};
  // Smallest error of the node's LODs (model units; unused without LODs): selection refines a
  // node whose every LOD is too coarse without reading the per-slot errors.
  float min_error = 0.0f;
  std::uint32_t subtree_end = 0;     // one past the last node of this subtree (preorder)
  std::int32_t parent = -1;          // internal index, -1 for the root
  std::uint32_t child_begin = 0;     // into TreeLayout::children
  std::uint32_t child_count = 0;     // children holding geometry only
  std::uint32_t lod_begin = 0;       // first slot (finest LOD)
  std::uint32_t lod_count = 0;
  std::uint32_t depth = 0;
  std::uint32_t manifest_index = 0;
};

struct TreeLayout {
  std::vector<LayoutNode> nodes;        // nodes[0] is the root
  std::vector<std::uint32_t> children;  // internal indices, grouped by parent, octant order
  // Parallel to `children`: each child's coarsest slot (kNoSlot when it has no LOD), so a
  // parent's children's slots are read from one place instead of from every child's node.
  std::vector<std::uint32_t> child_coarsest_slot;
  // Per slot (node LOD), indexed by LayoutNode::lod_begin + lod.
  std::vector<float> slot_error;             // model units
  std::vector<std::uint64_t> slot_bytes;     // expected decoded NodeMesh bytes
  std::vector<std::uint32_t> slot_triangles;
  std::vector<std::uint32_t> slot_node;      // internal node index
  std::vector<std::uint32_t> manifest_to_internal;
  float min_distance = 1e-6f;  // distances are clamped to this (model units)

  std::uint32_t slot_end(std::uint32_t node) const {
    return nodes[node].lod_begin + nodes[node].lod_count;
  }
};

// Fails with bad_input when the manifest has no nodes or no geometry at all.
Result<TreeLayout> build_tree_layout(const Manifest& manifest);

// For the loaders, which the layout does not outlive: per slot of `layout` (built from
// `manifest`), the manifest's LodInfo (its file relative to the tree root, its counts and size).
// Pointers, not copies (a 100M-triangle tree has 282K of them): valid while `manifest` lives
// unchanged.
std::vector<const LodInfo*> slot_lods(const Manifest& manifest, const TreeLayout& layout);

}  // namespace octolod::runtime
