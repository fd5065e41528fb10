// Cut selection, see selection.h. The culling test is the p-vertex / n-vertex test with plane
// masks (a box entirely inside a plane's half-space passes that plane for its whole subtree,
// since subtree boxes nest); the error rule is docs/design.md's
//   error · viewport_h / (2·tan(fovy/2) · distance) <= target_sse_pixels
// with 1/tan(fovy/2) read from the projection (|projection[1][1]|), rewritten as
// error <= distance · error_per_distance, so no division per LOD; for an orthographic projection
// (no division by distance) error · viewport_h · |projection[1][1]| / 2 <= target_sse_pixels.
#include "selection.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace octolod::runtime {

SelectionView make_selection_view(const Camera& camera, const StreamingOptions& options) {
  SelectionView v;
  v.frustum = extract_frustum(camera.projection * camera.view);
  v.eye = camera.position;
  v.pixels_per_unit = 0.5f * camera.viewport_height_px * std::abs(camera.projection[1][1]);
  v.orthographic = is_orthographic(camera.projection);
  v.error_per_distance = static_cast<float>(options.target_sse_pixels) / v.pixels_per_unit;
  v.mode = options.mode;
  v.distance_thresholds = &options.distance_thresholds;
  return v;
}

float distance_to_node(const TreeLayout& tree, std::uint32_t node, glm::vec3 eye) {
  const LayoutNode& n = tree.nodes[node];
  const glm::vec3 outside = glm::max(glm::abs(eye - n.center) - n.half, glm::vec3(0.0f));
  return std::max(glm::length(outside), tree.min_distance);
}

namespace {

constexpr std::uint32_t kRefine = kNoSlot;

// The slot to draw for `node` at `distance`, or kRefine to descend into its children.
std::uint32_t choose_lod(const TreeLayout& tree, const LayoutNode& n, float true_distance,
                         const SelectionView& view) {
  if (n.lod_count == 0) return kRefine;
  const float distance = true_distance * view.coarsening;
  if (view.mode == SelectionMode::screen_space_error) {
    // (orthographic: the coarsening relaxes the target as a distance would)
    const float allowed = (view.orthographic ? view.coarsening : distance) * view.error_per_distance;
    if (n.min_error > allowed) return n.child_count > 0 ? kRefine : n.lod_begin;
    for (std::uint32_t i = n.lod_count; i-- > 0;)
      if (tree.slot_error[n.lod_begin + i] <= allowed) return n.lod_begin + i;
    return n.child_count > 0 ? kRefine : n.lod_begin;  // a leaf draws its finest at worst
  }
  const std::vector<double>& thresholds = *view.distance_thresholds;
  const double refine_below = thresholds[std::min<std::size_t>(n.depth, thresholds.size() - 1)];
  if (distance < refine_below && n.child_count > 0) return kRefine;
  if (distance < 2.0 * refine_below) return n.lod_begin;
  // compared before the cast: a distance scaled past float's range makes the log infinite
  const double coarser = std::floor(std::log2(distance / refine_below));
  if (!(coarser < static_cast<double>(n.lod_count - 1))) return n.lod_begin + n.lod_count - 1;
  return n.lod_begin + static_cast<std::uint32_t>(coarser);
}

}  // namespace

void select_cut(const TreeLayout& tree, const SelectionView& view, std::vector<StackEntry>& stack,
                std::vector<WantedLod>& cut, SelectionCounters& counters) {
  cut.clear();
  start_cut(stack);
  continue_cut(tree, view, stack, cut, counters, std::numeric_limits<std::uint32_t>::max());
}

void start_cut(std::vector<StackEntry>& stack) {
  stack.clear();
  stack.push_back({0, 0x3Fu});
}

bool continue_cut(const TreeLayout& tree, const SelectionView& view, std::vector<StackEntry>& stack,
                  std::vector<WantedLod>& cut, SelectionCounters& counters, std::uint32_t max_visits) {
  const auto& planes = view.frustum.planes;
  for (std::uint32_t visits = 0; !stack.empty(); ++visits) {
    if (visits == max_visits) return false;
    const StackEntry entry = stack.back();
    stack.pop_back();
    const LayoutNode& n = tree.nodes[entry.node];
    ++counters.visited;

    // cull
    std::uint32_t mask = entry.plane_mask;
    bool outside = false;
    for (std::uint32_t i = 0; i < 6; ++i) {
      if ((mask & (1u << i)) == 0) continue;
      const Plane& p = planes[i];
      const float c = glm::dot(p.normal, n.center) + p.d;
      const float r = std::abs(p.normal.x) * n.half.x + std::abs(p.normal.y) * n.half.y +
                      std::abs(p.normal.z) * n.half.z;
      if (c + r < 0.0f) {
        outside = true;
        break;
      }
      if (c - r >= 0.0f) mask &= ~(1u << i);
    }
    if (outside) {
      ++counters.culled;
      continue;
    }

    // choose a LOD or refine
    const glm::vec3 delta = glm::max(glm::abs(view.eye - n.center) - n.half, glm::vec3(0.0f));
    const float distance = std::max(glm::length(delta), tree.min_distance);
    const std::uint32_t slot = choose_lod(tree, n, distance, view);
    if (slot != kRefine) {
      cut.push_back({entry.node, slot, 2.0f * glm::length(n.half) * view.pixels_at(distance)});
      continue;
    }
    for (std::uint32_t c = n.child_count; c-- > 0;)
      stack.push_back({tree.children[n.child_begin + c], mask});
  }
  return true;
}

}  // namespace octolod::runtime
