// Flattening of the manifest into TreeLayout (see tree_layout.h).
#include "tree_layout.h"

#include <algorithm>

namespace octolod::runtime {
namespace {

// Expected decoded size: what NodeMesh holds (4-byte floats and 4-byte indices).
std::uint64_t decoded_bytes(const LodInfo& lod, const VertexLayout& layout) {
  if (lod.vertices == 0 && lod.triangles == 0) return lod.bytes;
  return std::uint64_t{lod.vertices} * layout.bytes() + std::uint64_t{lod.triangles} * 12u;
}

}  // namespace

Result<TreeLayout> build_tree_layout(const Manifest& manifest) {
  if (manifest.nodes.empty()) return bad_input_error("manifest has no nodes");
  const std::size_t count = manifest.nodes.size();
  TreeLayout t;
  t.nodes.resize(count);
  t.manifest_to_internal.assign(count, 0);

  // depth-first preorder numbering, children in octant order
  std::vector<std::uint32_t> order;
  order.reserve(count);
  std::vector<std::int32_t> stack{0};
  while (!stack.empty()) {
    const auto m = static_cast<std::size_t>(stack.back());
    stack.pop_back();
    t.manifest_to_internal[m] = static_cast<std::uint32_t>(order.size());
    order.push_back(static_cast<std::uint32_t>(m));
    const auto& kids = manifest.nodes[m].children;
    for (auto it = kids.rbegin(); it != kids.rend(); ++it)
      if (*it >= 0) stack.push_back(*it);
  }
  if (order.size() != count) return bad_input_error("manifest nodes are not one tree");

  // per-node own boxes, then subtree unions bottom-up (children follow parents in preorder)
  std::vector<Bounds> box(count);
  for (std::size_t i = 0; i < count; ++i) {
    const NodeInfo& info = manifest.nodes[order[i]];
    if (!info.bounds.empty()) box[i] = info.bounds;
    else if (!info.lods.empty() && !info.cell.empty()) box[i] = info.cell;
  }
  std::vector<std::uint32_t> end(count);
  for (std::size_t i = count; i-- > 0;) {
    end[i] = static_cast<std::uint32_t>(i + 1);
    for (std::int32_t c : manifest.nodes[order[i]].children) {
      if (c < 0) continue;
      const std::uint32_t ci = t.manifest_to_internal[static_cast<std::size_t>(c)];
      if (!box[ci].empty()) box[i].extend(box[ci]);
      end[i] = std::max(end[i], end[ci]);
    }
  }
  if (box[0].empty()) return bad_input_error("manifest holds no geometry (every bounds is empty)");

  for (std::size_t i = 0; i < count; ++i) {
    const NodeInfo& info = manifest.nodes[order[i]];
    LayoutNode& n = t.nodes[i];
    n.manifest_index = order[i];
    n.depth = info.depth;
    n.subtree_end = end[i];
    n.parent = info.parent < 0
                   ? -1
                   : static_cast<std::int32_t>(t.manifest_to_internal[static_cast<std::size_t>(info.parent)]);
    if (!box[i].empty()) {
      const glm::vec3 lo(box[i].min[0], box[i].min[1], box[i].min[2]);
      const glm::vec3 hi(box[i].max[0], box[i].max[1], box[i].max[2]);
      n.center = 0.5f * (lo + hi);
      n.half = 0.5f * (hi - lo);
    }
    n.child_begin = static_cast<std::uint32_t>(t.children.size());
    for (std::int32_t c : info.children) {
      if (c < 0) continue;
      const std::uint32_t ci = t.manifest_to_internal[static_cast<std::size_t>(c)];
      if (box[ci].empty()) continue;  // nothing to draw below it
      t.children.push_back(ci);
    }
    n.child_count = static_cast<std::uint32_t>(t.children.size()) - n.child_begin;
    n.lod_begin = static_cast<std::uint32_t>(t.slot_error.size());
    n.lod_count = static_cast<std::uint32_t>(info.lods.size());
    n.min_error = info.lods.empty() ? 0.0f : static_cast<float>(info.lods[0].error);
    for (const LodInfo& lod : info.lods) {
      n.min_error = std::min(n.min_error, static_cast<float>(lod.error));
      t.slot_error.push_back(static_cast<float>(lod.error));
      t.slot_bytes.push_back(decoded_bytes(lod, manifest.layout));
      t.slot_triangles.push_back(lod.triangles);
      t.slot_node.push_back(static_cast<std::uint32_t>(i));
    }
  }
  t.child_coarsest_slot.reserve(t.children.size());
  for (std::uint32_t child : t.children)
    t.child_coarsest_slot.push_back(t.nodes[child].lod_count > 0 ? t.slot_end(child) - 1 : kNoSlot);
  t.min_distance = std::max(2e-6f * glm::length(t.nodes[0].half), 1e-12f);
  return t;
}

std::vector<const LodInfo*> slot_lods(const Manifest& manifest, const TreeLayout& layout) {
  std::vector<const LodInfo*> lods(layout.slot_node.size());
  for (const LayoutNode& n : layout.nodes)
    for (std::uint32_t l = 0; l < n.lod_count; ++l) lods[n.lod_begin + l] = &manifest.nodes[n.manifest_index].lods[l];
  return lods;
}

}  // namespace octolod::runtime
