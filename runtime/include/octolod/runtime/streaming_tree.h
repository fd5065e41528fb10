// StreamingTree: view-dependent selection and paging of a baked LOD octree (docs/design.md "The
// runtime"; seed 002 sections 3.6 and 4.5; El-Sana & Chiang 2000 for prefetching, buffer
// management with second chance and I/O separate from rendering; Holst & Schumann for caching
// measured along camera paths).
//
// Per update(camera): install the loads that completed since the last frame, select a cut of the
// octree (frustum culling, screen-space error or distance thresholds), replace every wanted LOD
// that is not resident by a resident substitute (a frame never waits on I/O), then queue loads
// for what was missing and prefetches for what is likely next.
//
// Use:
//   auto loaders = std::make_shared<ThreadPoolExecutor>(2);
//   auto tree = StreamingTree::open_directory("baked/rock", loaders, {.max_resident_bytes = 64 << 20});
//   if (!tree.ok()) { /* tree.status().message() */ }
//   every frame:
//     const FrameResult& frame = tree.value()->update(camera);   // never blocks on I/O
//     for (const DrawItem& d : frame.draws) draw(*d.mesh);
//   A GPU copy keyed by d.mesh.get() must hold d.mesh while it lives (samples/engine_example):
//   once nothing holds a mesh its address can come back with another node's mesh. Held meshes
//   are memory outside max_resident_bytes, so drop them with their uploads. The game owns the
//   Executor: destroying the last owner of a ThreadPoolExecutor joins its threads, which waits
//   out the reads they are in.
//
// Coordinates: cameras and the drawn meshes are in the tree's frame, model units relative to
// manifest().origin (zeros unless the bake recentred double input positions); a game places the
// tree at that point of its world (in double, or relative to its own floating origin).
// Texture: manifest().texture, when not empty, is the image the meshes' UVs index (a path
// relative to the tree's root, loaded by the game as it loads its images); v is up, (0, 0) at the
// image's lower-left corner: flip it for an API whose image rows start at the top.
//
// Thread safety: a StreamingTree is used from one thread (the render thread); update() and the
// accessors must not run concurrently. Loads run on the injected Executor and read through the
// injected NodeSource; both may be shared by several trees.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string_view>
#include <vector>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"
#include "octolod/runtime/camera.h"
#include "octolod/runtime/executor.h"
#include "octolod/runtime/node_source.h"

namespace octolod::runtime {

enum class SelectionMode {
  // Coarsest LOD whose screen-space error error·viewport_h / (2·tan(fovy/2)·distance) is at most
  // target_sse_pixels, with 1/tan(fovy/2) the projection's |projection[1][1]| (camera.h); for an
  // orthographic projection error·viewport_h·|projection[1][1]|/2, the same at every distance.
  screen_space_error,
  // The seed's pure distance rule (seed 4.5), see StreamingOptions::distance_thresholds.
  distance,
};

struct StreamingOptions {
  // Cache budget in bytes of decoded NodeMesh payload (vertices + indices, 4 bytes per float or
  // index), counting resident entries and second-chance entries alike; loads in flight reserve
  // their size up front, so resident bytes never exceed it. Must hold at least the root's coarsest
  // LOD. Larger keeps more of the tree resident (fewer reloads); smaller means more fallbacks.
  std::uint64_t max_resident_bytes = 256ull << 20;
  // Screen-space error target in pixels (screen_space_error mode). Larger draws fewer triangles.
  double target_sse_pixels = 2.0;
  SelectionMode mode = SelectionMode::screen_space_error;
  // distance mode: distance in model units below which a node at depth k refines into its
  // children is distance_thresholds[min(k, size-1)]; a node not refined draws its finest LOD up
  // to twice that distance and one LOD coarser per further doubling. Must be non-empty and
  // positive in distance mode.
  std::vector<double> distance_thresholds;
  // Prefetch the LOD above and below every drawn one (parent / children of the cut) and the cut
  // along the predicted camera motion, with lower priority than needed loads and only into
  // budget not used by recently drawn entries.
  bool prefetch = true;
  // How many frames ahead the camera motion is extrapolated for prefetching.
  double prediction_frames = 15.0;
  // Prefetch planning is spread over frames so that it adds a bounded cost to every update()
  // instead of a second selection pass. Each frame checks at most this many neighbour LODs of the
  // cut (round robin over the cut: a cut of n entries, each with up to 10 neighbours, is covered
  // every ~10·n / prefetch_checks_per_frame frames) ...
  std::uint32_t prefetch_checks_per_frame = 64;
  // ... and visits at most this many nodes of the predicted view's selection, which resumes where
  // it stopped; a new prediction starts from the camera of the frame after the last one finished.
  // Larger reacts sooner to the camera's motion and costs more per frame.
  std::uint32_t prediction_visits_per_frame = 128;
  // Prefetches never reclaim a second-chance entry used within this many frames.
  std::uint32_t prefetch_protect_frames = 30;
  // The selected cut is kept within this fraction of max_resident_bytes: when the cut at the
  // target would need more, the frame's target is relaxed (FrameStats::coarsening) until it fits.
  // The rest of the budget holds the previous cut while the next one loads, second-chance
  // entries and prefetches. 1 lets the cut take everything (then a cut change may stall on
  // fallbacks until the old cut is no longer drawn).
  double max_cut_fraction = 0.5;
  // Loads queued or running at once; every update() re-plans the queue and refills it, so this
  // also caps the loads started per frame. More hides latency and raises throughput; fewer keeps
  // the queue closer to the current view (more of it can be cancelled).
  std::uint32_t max_loads_in_flight = 32;
  // A wanted LOD that is not resident may be drawn by resident descendants instead (ones that
  // cover all of its visible part, or none), found by checking the nodes below it. This caps the
  // nodes so checked per update(): without it a camera pulled back from a detailed view (every
  // wanted LOD missing, the fine cut below them resident) walked the whole resident part of the
  // tree in one frame. A cover that would need more checks is given up and the nearest resident
  // ancestor draws there instead (coarser) until the wanted LOD arrives. Larger keeps more
  // detail on screen while such a cut loads and costs more per frame: 35-55 ns a check
  // (docs/benchmarks.md, "Covers by descendants"), so 4096 checks add at most about 0.2 ms to a
  // frame, while the covers along camera paths with prefetch on needed at most 124 checks a
  // frame (10M triangles, 15K-180K nodes); 0: descendants never stand in.
  // FrameStats::cover_checks and covers_out_of_checks say what a frame used and gave up.
  std::uint32_t max_cover_checks_per_frame = 4096;
  // Called once per node LOD that failed to load (missing file, checksum failure, wrong layout),
  // from the thread that calls update(). Null: silent.
  std::function<void(std::string_view message)> log;
};

struct DrawItem {
  std::uint32_t node = 0;  // index into Manifest::nodes
  std::uint32_t lod = 0;   // index into NodeInfo::lods (0 = finest)
  std::uint32_t depth = 0; // octree depth of `node`, root = 0
  // GPU-ready interleaved vertices (model space) + 32-bit indices. Immutable; stays valid as long
  // as the caller holds this pointer, whatever the cache does afterwards.
  std::shared_ptr<const NodeMesh> mesh;
  // True when this stands in for a wanted LOD that is not resident yet (or failed to load):
  // another LOD of the same node, an ancestor, or descendants covering the same region.
  bool is_fallback = false;
};

// Counters of one update() call.
struct FrameStats {
  std::uint32_t visited = 0;        // nodes whose bounds were tested
  std::uint32_t culled = 0;         // of those, outside the frustum (their subtree is skipped)
  std::uint32_t wanted = 0;         // node LODs in the selected cut
  std::uint32_t drawn_nodes = 0;    // DrawItems returned
  std::uint64_t drawn_triangles = 0;
  std::uint64_t resident_bytes = 0; // cache holdings after this frame (resident + second chance)
  std::uint64_t reserved_bytes = 0; // budget held by loads queued or running
  std::uint32_t loads_issued = 0;   // loads queued this frame
  std::uint32_t loads_completed = 0;   // loads installed this frame
  std::uint32_t loads_failed = 0;      // loads that failed this frame (node LOD marked bad)
  std::uint32_t loads_cancelled = 0;   // queued loads dropped before they started: no longer wanted
  // Needed loads not queued this frame because the budget had no room for them next to what
  // the frame draws, what it wants and the loads in flight (they are tried again next frame).
  // Above 0 frame after frame: max_resident_bytes is too small for this view at this
  // max_cut_fraction (the cut fits, but not next to the fallbacks drawn while it loads).
  std::uint32_t loads_over_budget = 0;
  std::uint32_t loads_in_flight = 0;   // queued or running after this frame
  std::uint32_t cache_hits = 0;        // wanted LODs that were resident
  std::uint32_t second_chance_hits = 0;  // of those, reclaimed from the free list without I/O
  std::uint32_t cache_misses = 0;      // wanted LODs that were not resident
  std::uint32_t fallbacks = 0;         // DrawItems with is_fallback
  // Nodes checked this frame while looking for resident descendants to stand in for wanted LODs
  // that were not resident, at most StreamingOptions::max_cover_checks_per_frame ...
  std::uint32_t cover_checks = 0;
  // ... and the wanted LODs whose cover was given up because those checks ran out: the nearest
  // resident ancestor drew there instead (coarser) this frame.
  std::uint32_t covers_out_of_checks = 0;
  std::uint64_t wanted_bytes = 0;   // decoded size of the whole wanted cut
  // 1 when the cut meets target_sse_pixels (or the distance thresholds); otherwise the factor by
  // which distances were scaled up (the error target relaxed) to fit max_cut_fraction of the budget.
  float coarsening = 1.0f;
  std::uint32_t holes = 0;  // wanted regions with nothing resident to draw: only before the
                            // root's coarsest LOD has arrived, or when it failed to load
  // The camera was not usable (is_usable, camera.h): update() changed nothing, the draws are
  // the previous frame's (none before the first), and only the byte and in-flight counts are set.
  bool camera_rejected = false;
  // update() never blocks on a load, so this is always 0; a frame with cache_misses > 0 drew
  // fallbacks instead of waiting.
  std::uint32_t waiting_on_io = 0;
  // Wall time of the whole update() call in milliseconds: installing completed loads, selecting
  // the cut, substituting resident LODs, and planning loads and prefetches (what `octolod walk`
  // and bench/selection_bench report as selection_ms).
  double selection_ms = 0;
  // CPU time the calling thread spent in update(): selection_ms without the time the thread was
  // preempted (on a busy machine the wall time's tail is the scheduler's, not the runtime's).
  double selection_cpu_ms = 0;
};

struct FrameResult {
  std::vector<DrawItem> draws;  // in octree depth-first order; no two overlap
  FrameStats stats;
};

class StreamingTree {
 public:
  // Plans from `manifest` alone; loads nothing yet (the root's coarsest LOD is requested first
  // by the first update() and stays pinned once loaded; a root without LODs just means holes until
  // deeper nodes arrive). Fails with ErrorCode::usage on meaningless options or a budget that
  // cannot hold the root's coarsest LOD, ErrorCode::bad_input on a manifest that is not a tree
  // (validate_manifest: links out of range or cyclic, a LOD file outside the tree) or without
  // geometry.
  static Result<std::unique_ptr<StreamingTree>> open(Manifest manifest,
                                                     std::shared_ptr<const NodeSource> source,
                                                     std::shared_ptr<Executor> executor,
                                                     StreamingOptions options);
  // Reads `root`/manifest.json and streams the node files below `root` through a FileSource.
  static Result<std::unique_ptr<StreamingTree>> open_directory(const std::filesystem::path& root,
                                                               std::shared_ptr<Executor> executor,
                                                               StreamingOptions options);
  // Loads already posted finish on their own (they own their shared state) and are discarded.
  ~StreamingTree();
  StreamingTree(const StreamingTree&) = delete;
  StreamingTree& operator=(const StreamingTree&) = delete;

  // Selects and pages for one frame. Never waits on I/O. The returned reference stays valid until
  // the next update() or the tree's destruction; copy the DrawItems (or their meshes) to keep them.
  // A camera that is not is_usable() is skipped (FrameStats::camera_rejected).
  const FrameResult& update(const Camera& camera);

  const Manifest& manifest() const;
  const StreamingOptions& options() const;
  // Whether a node LOD is in the cache right now (resident or second chance).
  bool is_resident(std::uint32_t node, std::uint32_t lod) const;
  // Whether a node LOD failed to load and will never be requested again.
  bool is_bad(std::uint32_t node, std::uint32_t lod) const;

 private:
  struct Impl;
  explicit StreamingTree(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace octolod::runtime
