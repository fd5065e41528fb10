// View-dependent cut selection (seed 4.5; docs/design.md "The runtime"): frustum culling by
// box vs plane on subtree boxes, then per node the coarsest LOD within the screen-space error
// target (or the seed's distance thresholds), else its children. Iterative, allocation-free in
// steady state (the caller owns and reuses the output vectors).
#pragma once

#include <cstdint>
#include <vector>

#include "octolod/runtime/camera.h"
#include "octolod/runtime/streaming_tree.h"
#include "tree_layout.h"

namespace octolod::runtime {

// Per-frame view parameters, derived once from the Camera and the options.
struct SelectionView {
  Frustum frustum;
  glm::vec3 eye{0.0f};               // model space
  // viewport_h · |projection[1][1]| / 2: perspective, viewport_h / (2·tan(fovy/2)), the pixels a
  // model unit covers at unit distance (SSE = error·this / distance); orthographic, the pixels it
  // covers at every distance (SSE = error·this)
  float pixels_per_unit = 1.0f;
  bool orthographic = false;         // is_orthographic(camera.projection)
  // target_sse / pixels_per_unit: the error allowed per unit distance (perspective), the error
  // allowed (orthographic)
  float error_per_distance = 0.0f;
  // Pixels a model unit covers at `distance` (model units) from the eye.
  float pixels_at(float distance) const { return orthographic ? pixels_per_unit : pixels_per_unit / distance; }
  SelectionMode mode = SelectionMode::screen_space_error;
  const std::vector<double>* distance_thresholds = nullptr;  // distance mode only
  // >= 1: distances are multiplied by this before choosing (so the allowed error grows, or the
  // distance thresholds shrink, by this factor). Keeps a cut within the memory budget.
  float coarsening = 1.0f;
};
SelectionView make_selection_view(const Camera& camera, const StreamingOptions& options);

// One node LOD of the cut.
struct WantedLod {
  std::uint32_t node = 0;  // internal (preorder) index
  std::uint32_t slot = 0;  // TreeLayout slot
  // Projected size of the node's box in pixels (|2·half|·pixels_at(distance)): larger and nearer
  // nodes load first.
  float priority = 0.0f;
};

struct SelectionCounters {
  std::uint32_t visited = 0;
  std::uint32_t culled = 0;
};

struct StackEntry {
  std::uint32_t node;
  std::uint32_t plane_mask;  // planes the parent box was not entirely inside of
};

// Writes the cut to `cut` in preorder (increasing node index). `stack` is scratch.
void select_cut(const TreeLayout& tree, const SelectionView& view, std::vector<StackEntry>& stack,
                std::vector<WantedLod>& cut, SelectionCounters& counters);

// The same traversal spread over several calls, so its cost per call is bounded: start_cut()
// seeds `stack` with the root, then every continue_cut() visits at most `max_visits` more nodes
// and appends the cut entries it finds to `cut` (which it does not clear), in preorder across the
// calls. Returns true, with `stack` empty, once the whole tree has been traversed. `view` and the
// tree must not change between the calls of one traversal.
void start_cut(std::vector<StackEntry>& stack);
bool continue_cut(const TreeLayout& tree, const SelectionView& view, std::vector<StackEntry>& stack,
                  std::vector<WantedLod>& cut, SelectionCounters& counters, std::uint32_t max_visits);

// Distance from `eye` to the box (0 inside), clamped to at least tree.min_distance.
float distance_to_node(const TreeLayout& tree, std::uint32_t node, glm::vec3 eye);

}  // namespace octolod::runtime
