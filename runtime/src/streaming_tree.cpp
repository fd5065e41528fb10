// StreamingTree: one frame = install completed loads, select the cut, substitute resident LODs
// for missing ones, then page. docs/design.md "The runtime"; seed 002 sections 3.6 and 4.5;
// El-Sana & Chiang 2000 (prefetching, buffer management with second chance, I/O separate from
// rendering); Holst & Schumann (caching measured along camera paths).
#include "octolod/runtime/streaming_tree.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include <time.h>

#include <glm/gtc/matrix_transform.hpp>

#include "load_queue.h"
#include "node_cache.h"
#include "selection.h"
#include "tree_layout.h"

namespace octolod::runtime {
namespace {

// CPU time of the calling thread in milliseconds (POSIX thread CPU clock).
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// How urgent a load is, before its priority (its size on screen) among loads equally urgent.
enum Urgency : std::uint8_t {
  kDetail = 0,    // a wanted or prefetched LOD
  kFallback = 1,  // a parent whose absence made an ancestor above it replace a whole subtree
  kHole = 2,      // a region with nothing resident to draw at all
};

Status validate(const StreamingOptions& o) {
  if (o.max_resident_bytes == 0) return usage_error("max_resident_bytes must be positive");
  if (!(o.target_sse_pixels > 0.0) || !std::isfinite(o.target_sse_pixels))
    return usage_error("target_sse_pixels must be a positive number of pixels");
  if (!(o.max_cut_fraction > 0.0 && o.max_cut_fraction <= 1.0))
    return usage_error("max_cut_fraction must be in (0, 1]");
  if (o.max_loads_in_flight == 0) return usage_error("max_loads_in_flight must be at least 1");
  if (o.prefetch_checks_per_frame == 0 || o.prediction_visits_per_frame == 0)
    return usage_error("prefetch_checks_per_frame and prediction_visits_per_frame must be at least 1");
  if (!(o.prediction_frames >= 0.0) || !std::isfinite(o.prediction_frames))
    return usage_error("prediction_frames must be a non-negative number of frames");
  if (o.mode == SelectionMode::distance) {
    if (o.distance_thresholds.empty())
      return usage_error("distance mode needs distance_thresholds (model units per depth)");
    for (double t : o.distance_thresholds)
      if (!(t > 0.0) || !std::isfinite(t))
        return usage_error("distance_thresholds must be positive distances in model units");
  }
  return {};
}

}  // namespace

struct StreamingTree::Impl {
  struct Draw {
    std::uint32_t node;  // internal index
    std::uint32_t slot;
    bool fallback;
  };
  struct Candidate {
    float priority;
    std::uint32_t slot;
    Urgency urgency = kDetail;
  };

  // `t` was built from `*m`.
  Impl(std::shared_ptr<const Manifest> m, TreeLayout t, std::shared_ptr<const NodeSource> source,
       std::shared_ptr<Executor> exec, StreamingOptions o)
      : manifest(std::move(m)), options(std::move(o)), tree(std::move(t)),
        cache(tree, options.max_resident_bytes),
        loads(std::make_shared<LoadQueue>(std::move(source), manifest, slot_lods(*manifest, tree),
                                          manifest->layout)),
        executor(std::move(exec)),
        root_slot(tree.nodes[0].lod_count > 0 ? tree.slot_end(0) - 1 : kNoSlot),
        candidate_mark(tree.slot_error.size(), 0), drawn_mark(tree.slot_error.size(), 0),
        pending_mark(tree.slot_error.size(), 0) {}

  ~Impl() { loads->shutdown(); }

  const FrameResult& update(const Camera& camera);
  void install_completions(FrameStats& stats);
  SelectionCounters select_within_budget(SelectionView& view);
  std::uint64_t cut_bytes() const {
    std::uint64_t sum = 0;
    for (const WantedLod& w : cut) sum += tree.slot_bytes[w.slot];
    return sum;
  }
  void resolve(const SelectionView& view, FrameStats& stats);
  bool substitute_same_node(const WantedLod& wanted);
  enum class Cover { drawn, impossible, out_of_checks };
  Cover cover_with_descendants(std::uint32_t node, const Frustum& frustum);
  bool substitute_ancestor(std::uint32_t node, std::uint32_t& covered_end);
  void request_nearest_ancestor(const WantedLod& wanted);
  void request_parent_fallback(const WantedLod& wanted, const SelectionView& view);
  void update_in_use();
  void hand_out_draws(FrameStats& stats);
  void collect_prefetch(const SelectionView& view, const Camera& camera);
  std::uint32_t consider_neighbours(const WantedLod& wanted);
  void consider_prefetch(std::uint32_t slot, float priority);
  void issue_loads(const SelectionView& view, const Camera& camera, FrameStats& stats);
  enum class Issued { queued, skipped, no_room };
  Issued issue(std::uint32_t slot, std::uint32_t protect_from_frame, FrameStats& stats);
  void log_failure(std::uint32_t slot, const Status& status) const;

  std::uint32_t coarsest_resident(std::uint32_t node) const {
    for (std::uint32_t s = tree.slot_end(node); s-- > tree.nodes[node].lod_begin;)
      if (cache.resident(s)) return s;
    return kNoSlot;
  }
  std::uint32_t finest_resident(std::uint32_t node) const {
    for (std::uint32_t s = tree.nodes[node].lod_begin; s < tree.slot_end(node); ++s)
      if (cache.resident(s)) return s;
    return kNoSlot;
  }
  std::uint32_t slot_of(std::uint32_t manifest_node, std::uint32_t lod) const {
    if (manifest_node >= tree.manifest_to_internal.size()) return kNoSlot;
    const LayoutNode& n = tree.nodes[tree.manifest_to_internal[manifest_node]];
    return lod < n.lod_count ? n.lod_begin + lod : kNoSlot;
  }

  std::shared_ptr<const Manifest> manifest;  // shared with the load queue (its file names)
  StreamingOptions options;
  TreeLayout tree;
  NodeCache cache;
  std::shared_ptr<LoadQueue> loads;
  std::shared_ptr<Executor> executor;
  const std::uint32_t root_slot;  // the root's coarsest LOD: requested first, pinned
  std::uint32_t frame = 0;
  std::uint32_t requested = 0;  // slots queued or loading
  std::uint32_t cover_checks_left = 0;  // this frame's, see StreamingOptions::max_cover_checks_per_frame
  float coarsening = 1.0f;  // last frame's, the starting point of the next
  bool has_previous_eye = false;
  glm::vec3 previous_eye{0.0f};

  // Per-frame scratch, reused so a steady frame allocates nothing.
  std::vector<StackEntry> stack;
  std::vector<WantedLod> cut, predicted_cut;
  // Prefetch planning state carried across frames: the next cut entry whose neighbours are
  // considered, and the predicted view's selection in progress (empty stack: none).
  std::size_t neighbour_cursor = 0;
  SelectionView predicted_view;
  std::vector<StackEntry> predicted_stack;
  std::vector<Draw> draws;
  std::vector<std::uint32_t> in_use, previously_in_use;
  std::vector<Candidate> needed, prefetch;
  std::vector<std::uint32_t> candidate_mark;  // per slot: frame it became a load candidate
  std::vector<std::uint32_t> drawn_mark;      // per slot: last frame that drew it
  std::vector<std::uint32_t> pending_mark;    // per slot: frame its queued request was taken back
  std::vector<std::uint32_t> old_pending, new_pending;
  std::vector<LoadCompletion> completions;
  FrameResult result;
  std::vector<std::uint32_t> result_slots;  // slot of each of result.draws
  std::vector<DrawItem> handed_out;         // the last frame's draws while the next are made
  std::vector<std::uint32_t> handed_out_slots;
};

const FrameResult& StreamingTree::Impl::update(const Camera& camera) {
  const auto start = std::chrono::steady_clock::now();
  const double start_cpu_ms = thread_cpu_ms();
  FrameStats& stats = result.stats;
  if (!is_usable(camera)) {  // the last frame's draws again, and nothing planned from this view
    stats = FrameStats{};
    stats.camera_rejected = true;
    stats.coarsening = coarsening;
    stats.drawn_nodes = static_cast<std::uint32_t>(result.draws.size());
    for (const std::uint32_t slot : result_slots) stats.drawn_triangles += cache.triangles(slot);
    stats.resident_bytes = cache.resident_bytes();
    stats.reserved_bytes = cache.reserved_bytes();
    stats.loads_in_flight = requested;
    return result;
  }
  ++frame;
  stats = FrameStats{};

  install_completions(stats);

  SelectionView view = make_selection_view(camera, options);
  const SelectionCounters counters = select_within_budget(view);
  stats.visited = counters.visited;
  stats.culled = counters.culled;
  stats.wanted = static_cast<std::uint32_t>(cut.size());
  stats.wanted_bytes = cut_bytes();
  stats.coarsening = view.coarsening;

  needed.clear();
  resolve(view, stats);
  update_in_use();
  issue_loads(view, camera, stats);

  hand_out_draws(stats);
  stats.resident_bytes = cache.resident_bytes();
  stats.reserved_bytes = cache.reserved_bytes();
  stats.loads_in_flight = requested;
  has_previous_eye = true;
  previous_eye = camera.position;
  stats.selection_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stats.selection_cpu_ms = thread_cpu_ms() - start_cpu_ms;
  return result;
}

// Fills result.draws from `draws`. A mesh the last frame handed out too moves over from the old
// list (both are in increasing slot order) instead of being copied: a shared_ptr copy and the old
// copy's release would write to every drawn mesh's control block, a cache miss each.
void StreamingTree::Impl::hand_out_draws(FrameStats& stats) {
  handed_out.swap(result.draws);
  handed_out_slots.swap(result_slots);
  result.draws.clear();
  result_slots.clear();
  std::size_t old = 0;
  for (const Draw& d : draws) {
    const LayoutNode& n = tree.nodes[d.node];
    DrawItem item;
    item.node = n.manifest_index;
    item.lod = d.slot - n.lod_begin;
    item.depth = n.depth;
    while (old < handed_out_slots.size() && handed_out_slots[old] < d.slot) ++old;
    if (old < handed_out_slots.size() && handed_out_slots[old] == d.slot) item.mesh = std::move(handed_out[old].mesh);
    else item.mesh = cache.mesh(d.slot);
    item.is_fallback = d.fallback;
    stats.drawn_triangles += cache.triangles(d.slot);
    stats.fallbacks += d.fallback ? 1u : 0u;
    result.draws.push_back(std::move(item));
    result_slots.push_back(d.slot);
  }
  handed_out.clear();
  stats.drawn_nodes = static_cast<std::uint32_t>(draws.size());
}

// Selects the cut at the target, relaxed by a factor when it would not fit max_cut_fraction of
// the budget. Starts one step finer than the last frame's factor, so a steady view costs one or
// two selections and the factor returns to 1 when the view allows.
// The factor never passes kMaxCoarsening, so a view that no factor fits (the pinned root alone
// over the limit, a tree without coarse LODs) costs two selections per frame, and once the view
// allows the factor comes back down one step per frame.
SelectionCounters StreamingTree::Impl::select_within_budget(SelectionView& view) {
  constexpr float kStep = 1.5f;
  constexpr float kMaxCoarsening = 1.1e7f;  // about 1.5^40: beyond any tree's error range
  const auto limit = static_cast<std::uint64_t>(options.max_cut_fraction *
                                                static_cast<double>(options.max_resident_bytes));
  view.coarsening = std::clamp(coarsening / kStep, 1.0f, kMaxCoarsening);
  SelectionCounters counters;
  for (;;) {
    counters = {};
    select_cut(tree, view, stack, cut, counters);
    if (view.coarsening >= kMaxCoarsening || cut_bytes() <= limit) break;
    view.coarsening = std::min(view.coarsening * kStep, kMaxCoarsening);
  }
  coarsening = view.coarsening;
  return counters;
}

// Loads that finished since the last frame become resident (on the free list until drawn), in
// the room their requests reserved.
void StreamingTree::Impl::install_completions(FrameStats& stats) {
  loads->take_completed(completions);
  for (LoadCompletion& done : completions) {
    --requested;
    if (!done.status.ok()) {
      cache.mark_bad(done.slot);
      ++stats.loads_failed;
      log_failure(done.slot, done.status);
      continue;
    }
    cache.install(done.slot, std::move(done.mesh), frame);
    ++stats.loads_completed;
    if (done.slot == root_slot) cache.pin(done.slot);
  }
  completions.clear();
}

void StreamingTree::Impl::log_failure(std::uint32_t slot, const Status& status) const {
  if (!options.log) return;
  const LayoutNode& n = tree.nodes[tree.slot_node[slot]];
  const std::string& path = manifest->nodes[n.manifest_index].path;
  options.log("node '" + (path.empty() ? std::string("(root)") : path) + "' LOD " +
              std::to_string(slot - n.lod_begin) + " failed to load, drawing a fallback from now " +
              "on: " + status.message());
}

// Turns the wanted cut into draws that only use resident LODs, in preorder, without overlap:
// the wanted LOD if resident; else another LOD of the same node; else resident descendants that
// cover every visible part of the node; else the nearest ancestor with a resident LOD, which
// then replaces everything drawn below it. Missing LODs become load candidates.
void StreamingTree::Impl::resolve(const SelectionView& view, FrameStats& stats) {
  draws.clear();
  cover_checks_left = options.max_cover_checks_per_frame;
  std::uint32_t covered_end = 0;  // preorder nodes below this index are drawn by an ancestor
  for (const WantedLod& w : cut) {
    const bool resident = cache.resident(w.slot);
    std::size_t candidate = needed.size();
    if (resident) {
      ++stats.cache_hits;
      if (cache.second_chance(w.slot)) ++stats.second_chance_hits;
      cache.touch(w.slot, frame);  // wanted: not reclaimed for this frame's loads
    } else {
      ++stats.cache_misses;
      if (cache.state(w.slot) == SlotState::absent && candidate_mark[w.slot] != frame) {
        candidate_mark[w.slot] = frame;
        needed.push_back({w.priority, w.slot});
      }
    }
    if (w.node < covered_end) {  // an ancestor draws it
      if (!resident) request_parent_fallback(w, view);
      continue;
    }
    if (resident) {
      draws.push_back({w.node, w.slot, false});
      continue;
    }
    if (substitute_same_node(w)) continue;
    if (cache.state(w.slot) == SlotState::bad) request_nearest_ancestor(w);
    const Cover cover = cover_with_descendants(w.node, view.frustum);
    if (cover == Cover::drawn) continue;
    if (cover == Cover::out_of_checks) ++stats.covers_out_of_checks;
    if (substitute_ancestor(w.node, covered_end)) {
      request_parent_fallback(w, view);
      continue;
    }
    ++stats.holes;
    if (candidate < needed.size()) needed[candidate].urgency = kHole;
  }
  stats.cover_checks = options.max_cover_checks_per_frame - cover_checks_left;
}

// The nearest coarser resident LOD of the node, else the nearest finer one.
bool StreamingTree::Impl::substitute_same_node(const WantedLod& wanted) {
  const LayoutNode& n = tree.nodes[wanted.node];
  for (std::uint32_t s = wanted.slot + 1; s < tree.slot_end(wanted.node); ++s) {
    if (cache.resident(s)) {
      draws.push_back({wanted.node, s, true});
      return true;
    }
  }
  for (std::uint32_t s = wanted.slot; s-- > n.lod_begin;) {
    if (cache.resident(s)) {
      draws.push_back({wanted.node, s, true});
      return true;
    }
  }
  return false;
}

// Draws every visible child by its coarsest resident LOD, or recursively by its own children;
// all or nothing. Subtrees without any resident LOD fail at once (impossible), and so does the
// whole cover when the frame's checks (one per child looked at) run out (out_of_checks), so that
// a frame's covers check at most max_cover_checks_per_frame nodes.
StreamingTree::Impl::Cover StreamingTree::Impl::cover_with_descendants(std::uint32_t node,
                                                                       const Frustum& frustum) {
  const LayoutNode& n = tree.nodes[node];
  if (n.child_count == 0 || cache.subtree_resident(node) == 0) return Cover::impossible;
  const std::size_t mark = draws.size();
  for (std::uint32_t i = 0; i < n.child_count; ++i) {
    if (cover_checks_left == 0) {
      draws.resize(mark);
      return Cover::out_of_checks;
    }
    --cover_checks_left;
    const std::uint32_t child = tree.children[n.child_begin + i];
    const LayoutNode& c = tree.nodes[child];
    if (classify_box(frustum, c.center, c.half) == Containment::outside) continue;
    if (c.lod_count == 0 && c.child_count == 0) continue;  // nothing to draw there
    const std::uint32_t slot = coarsest_resident(child);
    if (slot != kNoSlot) {
      draws.push_back({child, slot, true});
      continue;
    }
    if (const Cover below = cover_with_descendants(child, frustum); below != Cover::drawn) {
      draws.resize(mark);
      return below;
    }
  }
  return Cover::drawn;
}

// The nearest ancestor with a resident LOD (its finest) replaces its whole subtree: draws already
// made inside it are the tail of the preorder draw list and are dropped.
bool StreamingTree::Impl::substitute_ancestor(std::uint32_t node, std::uint32_t& covered_end) {
  for (std::int32_t p = tree.nodes[node].parent; p >= 0; p = tree.nodes[static_cast<std::size_t>(p)].parent) {
    const auto ancestor = static_cast<std::uint32_t>(p);
    const std::uint32_t slot = finest_resident(ancestor);
    if (slot == kNoSlot) continue;
    const std::uint32_t end = tree.nodes[ancestor].subtree_end;
    while (!draws.empty() && draws.back().node >= ancestor && draws.back().node < end) draws.pop_back();
    draws.push_back({ancestor, slot, true});
    covered_end = end;
    return true;
  }
  return false;
}

// A bad LOD will never arrive: make sure the nearest ancestor with a LOD that is not bad gets
// loaded, so the fallback is that ancestor rather than whatever happens to be resident higher up.
void StreamingTree::Impl::request_nearest_ancestor(const WantedLod& wanted) {
  for (std::int32_t p = tree.nodes[wanted.node].parent; p >= 0; p = tree.nodes[static_cast<std::size_t>(p)].parent) {
    const auto ancestor = static_cast<std::uint32_t>(p);
    for (std::uint32_t s = tree.nodes[ancestor].lod_begin; s < tree.slot_end(ancestor); ++s) {
      const SlotState state = cache.state(s);
      if (state == SlotState::bad) continue;
      if (state == SlotState::absent && candidate_mark[s] != frame) {
        candidate_mark[s] = frame;
        needed.push_back({wanted.priority, s});
      }
      return;
    }
  }
}

// An ancestor above the parent replaced the node's whole subtree, resident siblings and all:
// the parent's coarsest LOD (a few hundred triangles) is asked for before any detail (largest on
// screen first among such parents), and the next fallback there covers the parent's children only.
// Without it a camera turning to a region whose middle levels were reclaimed drew the root alone
// until every wanted LOD below it had arrived.
void StreamingTree::Impl::request_parent_fallback(const WantedLod& wanted, const SelectionView& view) {
  const std::int32_t p = tree.nodes[wanted.node].parent;
  if (p < 0) return;
  const auto parent = static_cast<std::uint32_t>(p);
  const LayoutNode& n = tree.nodes[parent];
  if (n.lod_count == 0 || finest_resident(parent) != kNoSlot) return;
  const std::uint32_t slot = tree.slot_end(parent) - 1;
  if (cache.state(slot) == SlotState::absent && candidate_mark[slot] != frame) {
    candidate_mark[slot] = frame;
    const float size = 2.0f * glm::length(n.half) * view.pixels_at(distance_to_node(tree, parent, view.eye));
    needed.push_back({size, slot, kFallback});
  }
}

// What this frame draws is in use (never reclaimed); what the last frame drew and this one does
// not goes to the free list with its data (second chance).
void StreamingTree::Impl::update_in_use() {
  in_use.clear();
  for (const Draw& d : draws) {
    cache.use(d.slot, frame);
    drawn_mark[d.slot] = frame;
    in_use.push_back(d.slot);
  }
  for (std::uint32_t s : previously_in_use)
    if (drawn_mark[s] != frame) cache.release(s);
  previously_in_use.swap(in_use);
}

// Prefetch (El-Sana & Chiang 2000; docs/design.md): the LOD one step finer and one step coarser
// than wanted ones (the next LOD of the node, else its children's coarsest / its parent's
// finest), and the cut seen from where the camera will be if it keeps its velocity. Both are
// planned a bounded piece per frame (StreamingOptions::prefetch_checks_per_frame,
// prediction_visits_per_frame): a whole second selection every frame would cost as much as the
// frame's own.
void StreamingTree::Impl::collect_prefetch(const SelectionView& view, const Camera& camera) {
  if (neighbour_cursor >= cut.size()) neighbour_cursor = 0;
  std::uint32_t checks = 0;
  for (std::size_t k = 0; k < cut.size() && checks < options.prefetch_checks_per_frame; ++k) {
    checks += consider_neighbours(cut[neighbour_cursor]);
    if (++neighbour_cursor == cut.size()) neighbour_cursor = 0;
  }

  if (predicted_stack.empty()) {
    if (!has_previous_eye || options.prediction_frames <= 0.0) return;
    const glm::vec3 ahead =
        (camera.position - previous_eye) * static_cast<float>(options.prediction_frames);
    if (!(glm::length(ahead) > tree.min_distance)) return;
    Camera predicted = camera;
    predicted.position += ahead;
    predicted.view = camera.view * glm::translate(glm::mat4(1.0f), -ahead);
    predicted_view = make_selection_view(predicted, options);
    predicted_view.coarsening = view.coarsening;
    start_cut(predicted_stack);
  }
  predicted_cut.clear();
  SelectionCounters ignored;
  continue_cut(tree, predicted_view, predicted_stack, predicted_cut, ignored,
               options.prediction_visits_per_frame);
  for (const WantedLod& w : predicted_cut) consider_prefetch(w.slot, w.priority);
}

// Returns how many slots it checked.
std::uint32_t StreamingTree::Impl::consider_neighbours(const WantedLod& w) {
  const LayoutNode& n = tree.nodes[w.node];
  std::uint32_t checks = 0;
  if (w.slot > n.lod_begin) {
    consider_prefetch(w.slot - 1, w.priority);
    ++checks;
  } else {
    for (std::uint32_t i = n.child_begin; i < n.child_begin + n.child_count; ++i) {
      if (tree.child_coarsest_slot[i] == kNoSlot) continue;
      consider_prefetch(tree.child_coarsest_slot[i], w.priority);
      ++checks;
    }
  }
  if (w.slot + 1 < tree.slot_end(w.node)) {
    consider_prefetch(w.slot + 1, w.priority);
    ++checks;
  } else if (n.parent >= 0) {
    const LayoutNode& parent = tree.nodes[static_cast<std::size_t>(n.parent)];
    if (parent.lod_count > 0) {
      consider_prefetch(parent.lod_begin, w.priority);
      ++checks;
    }
  }
  return checks;
}

void StreamingTree::Impl::consider_prefetch(std::uint32_t slot, float priority) {
  if (candidate_mark[slot] == frame) return;
  candidate_mark[slot] = frame;
  if (cache.resident(slot)) {
    cache.touch(slot, frame);
  } else if (cache.state(slot) == SlotState::absent) {
    prefetch.push_back({priority, slot});
  }
}

// Re-plans the load queue: requests not started yet are taken back, then the most important
// candidates that fit the budget are queued (root first, then needed by priority, then
// prefetches if room is left); taken-back requests not queued again are cancelled.
void StreamingTree::Impl::issue_loads(const SelectionView& view, const Camera& camera,
                                      FrameStats& stats) {
  loads->take_pending(old_pending);
  for (std::uint32_t s : old_pending) {
    cache.cancel(s);
    --requested;
    pending_mark[s] = frame;
  }
  new_pending.clear();

  if (root_slot != kNoSlot) issue(root_slot, kNoSlot, stats);
  auto by_priority = [](const Candidate& a, const Candidate& b) {
    if (a.urgency != b.urgency) return a.urgency > b.urgency;
    return a.priority > b.priority || (a.priority == b.priority && a.slot < b.slot);
  };
  std::sort(needed.begin(), needed.end(), by_priority);
  // Needed loads may reclaim any free entry not wanted in this frame.
  for (const Candidate& c : needed) {
    if (requested >= options.max_loads_in_flight) break;
    if (issue(c.slot, frame, stats) == Issued::no_room) ++stats.loads_over_budget;
  }
  prefetch.clear();
  if (options.prefetch && requested < options.max_loads_in_flight) {
    // Collected after the needed loads took their room: prefetch touches protect entries.
    collect_prefetch(view, camera);
    // Only the best few can be queued: order just those.
    const std::size_t best = std::min<std::size_t>(prefetch.size(), 2u * options.max_loads_in_flight);
    std::partial_sort(prefetch.begin(), prefetch.begin() + static_cast<std::ptrdiff_t>(best),
                      prefetch.end(), by_priority);
    const std::uint32_t protect =
        frame > options.prefetch_protect_frames ? frame - options.prefetch_protect_frames : 0;
    for (std::size_t i = 0; i < best && requested < options.max_loads_in_flight; ++i)
      issue(prefetch[i].slot, protect, stats);
  }

  for (std::uint32_t s : old_pending)
    if (pending_mark[s] == frame) ++stats.loads_cancelled;

  std::reverse(new_pending.begin(), new_pending.end());  // most important last
  loads->set_pending(new_pending);
  const std::uint32_t tasks = loads->claim_tasks(options.max_loads_in_flight);
  for (std::uint32_t i = 0; i < tasks; ++i) executor->post([queue = loads] { queue->run_task(); });
}

// Queues a load of `slot` if it is absent and a load is free (else skipped), reserving its
// expected bytes; no_room when the budget cannot take them even by reclaiming the free entries
// used before `protect_from_frame`.
StreamingTree::Impl::Issued StreamingTree::Impl::issue(std::uint32_t slot, std::uint32_t protect_from_frame,
                                                       FrameStats& stats) {
  if (requested >= options.max_loads_in_flight) return Issued::skipped;
  if (cache.state(slot) != SlotState::absent) return Issued::skipped;
  if (!cache.make_room(tree.slot_bytes[slot], protect_from_frame)) return Issued::no_room;
  cache.request(slot);
  ++requested;
  new_pending.push_back(slot);
  if (pending_mark[slot] == frame) pending_mark[slot] = 0;  // taken back and queued again
  else ++stats.loads_issued;
  return Issued::queued;
}

// --- StreamingTree ------------------------------------------------------------------------------

StreamingTree::StreamingTree(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
StreamingTree::~StreamingTree() = default;

Result<std::unique_ptr<StreamingTree>> StreamingTree::open(Manifest manifest,
                                                           std::shared_ptr<const NodeSource> source,
                                                           std::shared_ptr<Executor> executor,
                                                           StreamingOptions options) {
  if (!source) return usage_error("StreamingTree::open needs a NodeSource");
  if (!executor) return usage_error("StreamingTree::open needs an Executor");
  OCTOLOD_RETURN_IF_ERROR(validate(options));
  // the layout walks the links (a cycle would never end) and the loaders read lod.file below the
  // source's root
  OCTOLOD_RETURN_IF_ERROR(validate_manifest(manifest, "StreamingTree::open"));
  auto shared = std::make_shared<const Manifest>(std::move(manifest));
  Result<TreeLayout> tree = build_tree_layout(*shared);
  if (!tree.ok()) return tree.status();
  const LayoutNode& root = tree->nodes[0];
  if (root.lod_count > 0) {
    const std::uint64_t root_bytes = tree->slot_bytes[root.lod_begin + root.lod_count - 1];
    if (root_bytes > options.max_resident_bytes)
      return usage_error("max_resident_bytes (" + std::to_string(options.max_resident_bytes) +
                         ") cannot hold the root's coarsest LOD (" + std::to_string(root_bytes) +
                         " bytes)");
  }
  auto impl = std::make_unique<Impl>(std::move(shared), std::move(tree).value(), std::move(source),
                                     std::move(executor), std::move(options));
  return std::unique_ptr<StreamingTree>(new StreamingTree(std::move(impl)));
}

Result<std::unique_ptr<StreamingTree>> StreamingTree::open_directory(
    const std::filesystem::path& root, std::shared_ptr<Executor> executor, StreamingOptions options) {
  Result<Manifest> manifest = read_tree_manifest(root);
  if (!manifest.ok()) return manifest.status();
  return open(std::move(manifest).value(), std::make_shared<FileSource>(root), std::move(executor),
              std::move(options));
}

const FrameResult& StreamingTree::update(const Camera& camera) { return impl_->update(camera); }
const Manifest& StreamingTree::manifest() const { return *impl_->manifest; }
const StreamingOptions& StreamingTree::options() const { return impl_->options; }

bool StreamingTree::is_resident(std::uint32_t node, std::uint32_t lod) const {
  const std::uint32_t slot = impl_->slot_of(node, lod);
  return slot != kNoSlot && impl_->cache.resident(slot);
}

bool StreamingTree::is_bad(std::uint32_t node, std::uint32_t lod) const {
  const std::uint32_t slot = impl_->slot_of(node, lod);
  return slot != kNoSlot && impl_->cache.state(slot) == SlotState::bad;
}

}  // namespace octolod::runtime
