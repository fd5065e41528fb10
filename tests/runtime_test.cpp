// runtime_tests: selection, paging and fallbacks of octolod::runtime, stepped frame by frame
// against an in-memory source with a SynchronousExecutor (cesium-native style: assert per-frame
// counters). Numbers for the synthetic tree (make_full_octree, cube [0,64]^3, 60 degree fov,
// 1000 px viewport, target 2 px): an error e meets the target from distance 433·e on, so
//   root     lods (0.64, 2.56): coarse from 1108.5, fine from 277
//   depth 1  lods (0.32, 1.28): coarse from 554,    fine from 138.6
//   leaves   lods (0,    0.64): coarse from 277,    fine always
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <future>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "node_cache.h"
#include "runtime_test_helpers.h"
#include "tree_layout.h"

namespace octolod::runtime {
namespace {

using testing::draws_of;
using testing::expect_covering_cut;
using testing::look;
using testing::make_full_octree;
using testing::settle;
using testing::SyntheticTree;

const glm::vec3 kCenter(32.0f, 32.0f, 32.0f);
// On the +z axis through the centre, `d` model units in front of the cube's z = 64 face.
Camera front(float d) { return look(glm::vec3(32.0f, 32.0f, 64.0f + d), kCenter); }

struct Fixture {
  SyntheticTree tree;
  std::shared_ptr<SynchronousExecutor> executor = std::make_shared<SynchronousExecutor>();
  std::unique_ptr<StreamingTree> streaming;
  std::vector<std::string> log;

  explicit Fixture(std::uint32_t levels, StreamingOptions options = {})
      : Fixture(make_full_octree(levels), std::move(options)) {}
  Fixture(SyntheticTree t, StreamingOptions options) : tree(std::move(t)) {
    options.log = [this](std::string_view message) { log.emplace_back(message); };
    auto opened = StreamingTree::open(tree.manifest, tree.source, executor, std::move(options));
    EXPECT_TRUE(opened.ok()) << opened.status().message();
    if (opened.ok()) streaming = std::move(opened).value();
  }
  const FrameResult& settle_at(const Camera& camera) { return settle(*streaming, *executor, camera); }
};

// --- frustum ----------------------------------------------------------------------------------

TEST(Frustum, BoxStraddlingTheFrustumWithEveryCornerOutsideIsKept) {
  // Camera at the origin looking down -z. The slab spans the whole view at z in [-1000, -5] but
  // each of its corners (x, y = +-1000) lies outside the side planes: the seed's "a corner is
  // inside" test would cull it.
  const Camera c = look(glm::vec3(0.0f), glm::vec3(0, 0, -1));
  const Frustum f = extract_frustum(c.projection * c.view);
  EXPECT_EQ(classify_box(f, glm::vec3(0, 0, -502.5f), glm::vec3(1000, 1000, 497.5f)), Containment::intersects);
}

TEST(Frustum, BoxBehindTheCameraIsOutsideAndBoxInFrontIsInside) {
  const Camera c = look(glm::vec3(0.0f), glm::vec3(0, 0, -1));
  const Frustum f = extract_frustum(c.projection * c.view);
  EXPECT_EQ(classify_box(f, glm::vec3(0, 0, 2), glm::vec3(1)), Containment::outside);
  EXPECT_EQ(classify_box(f, glm::vec3(0, 0, -50), glm::vec3(1)), Containment::inside);
  EXPECT_EQ(classify_box(f, glm::vec3(0, 0, -20000), glm::vec3(1)), Containment::outside);  // past far
}

// --- selection --------------------------------------------------------------------------------

TEST(Selection, FarCameraDrawsTheRootsCoarsestLodOnly) {
  Fixture fx(3);
  const FrameResult& frame = fx.settle_at(front(1468.0f));
  EXPECT_EQ(frame.stats.visited, 1u);
  EXPECT_EQ(frame.stats.culled, 0u);
  EXPECT_EQ(frame.stats.wanted, 1u);
  ASSERT_EQ(frame.draws.size(), 1u);
  EXPECT_EQ(frame.draws[0].node, 0u);
  EXPECT_EQ(frame.draws[0].lod, 1u);
  EXPECT_FALSE(frame.draws[0].is_fallback);
  EXPECT_EQ(frame.stats.drawn_triangles, SyntheticTree::kCoarseTriangles);
}

TEST(Selection, RefinementStopsWhenScreenSpaceErrorIsMet) {
  Fixture fx(3);
  // 200 units away the root's finest LOD is 4.6 px off, the depth-1 fine LODs (200..232 units
  // away) at most 1.4 px: refine once, stop.
  const FrameResult& frame = fx.settle_at(front(200.0f));
  EXPECT_EQ(frame.stats.visited, 9u);
  EXPECT_EQ(frame.stats.culled, 0u);
  EXPECT_EQ(frame.stats.wanted, 8u);
  EXPECT_EQ(frame.stats.drawn_nodes, 8u);
  EXPECT_EQ(frame.stats.fallbacks, 0u);
  EXPECT_EQ(frame.stats.cache_hits, 8u);
  EXPECT_EQ(frame.stats.cache_misses, 0u);
  EXPECT_EQ(frame.stats.drawn_triangles, 8u * SyntheticTree::kFineTriangles);
  for (const DrawItem& d : frame.draws) {
    EXPECT_EQ(d.depth, 1u);
    EXPECT_EQ(d.lod, 0u);
  }
}

TEST(Selection, MovingCloserRefines) {
  Fixture fx(3);
  const float distances[] = {1468.0f, 500.0f, 200.0f, 100.0f};
  const std::uint64_t expected_triangles[] = {16, 64, 8 * 64, 64 * 64};
  for (int i = 0; i < 4; ++i) {
    const FrameResult& frame = fx.settle_at(front(distances[i]));
    EXPECT_EQ(frame.stats.drawn_triangles, expected_triangles[i]) << "at distance " << distances[i];
    EXPECT_EQ(frame.stats.fallbacks, 0u);
  }
}

TEST(Selection, MatchesTheReferenceCutFromManyViewpoints) {
  Fixture fx(4);
  const Camera cameras[] = {
      front(150.0f),
      look(glm::vec3(-40, 80, 120), kCenter),
      look(glm::vec3(10, 20, 30), glm::vec3(60, 50, 40)),   // inside the model
      look(glm::vec3(32, 32, 32), glm::vec3(100, 32, 32)),  // at the centre, half of it behind
      look(glm::vec3(300, -50, 10), kCenter),
  };
  for (const Camera& camera : cameras) {
    const FrameResult& frame = fx.settle_at(camera);
    std::map<std::uint32_t, std::uint32_t> expected;
    testing::reference_cut(fx.tree.manifest, camera, 2.0, 0, expected);
    EXPECT_EQ(draws_of(frame), expected);
    EXPECT_EQ(frame.stats.fallbacks, 0u);
    expect_covering_cut(fx.tree, frame, camera);
  }
}

// The field of view that refines is the projection's, the one that culls: a camera zoomed by
// its projection alone (20 degrees instead of 60) gets the finer reference cut of that field of
// view, and a projection flipped for a y-down clip space (Vulkan) the same cut as unflipped.
// Before, a separate fovy field decided the refinement, whatever the projection said.
TEST(Selection, TheFieldOfViewComesFromTheProjection) {
  Fixture fx(4);
  const float narrow = glm::radians(20.0f);
  Camera zoomed = look(glm::vec3(-40, 80, 120), kCenter);
  zoomed.projection = glm::perspective(narrow, 1.0f, 0.01f, 10000.0f);
  std::map<std::uint32_t, std::uint32_t> expected;
  testing::reference_cut(fx.tree.manifest, zoomed, 2.0, 0, expected, narrow);
  std::map<std::uint32_t, std::uint32_t> wide;
  testing::reference_cut(fx.tree.manifest, zoomed, 2.0, 0, wide);
  ASSERT_NE(expected, wide);  // the test tells the two fields of view apart
  EXPECT_EQ(draws_of(fx.settle_at(zoomed)), expected);

  Camera flipped = zoomed;
  flipped.projection[1][1] = -flipped.projection[1][1];
  EXPECT_TRUE(is_usable(flipped));
  EXPECT_EQ(draws_of(fx.settle_at(flipped)), expected);
}

// An orthographic view (glm::ortho) draws a node as large at every distance, so its cut does not
// coarsen as the camera backs away: the same reference cut from 200 and from 2,000 units, finer
// than a perspective camera's at 2,000. Before, the error was divided by the distance as for a
// perspective, and the far orthographic view drew the root's coarsest LOD.
TEST(Selection, AnOrthographicViewRefinesTheSameAtEveryDistance) {
  Fixture fx(4);
  constexpr float kHeight = 300.0f;  // model units the view spans vertically
  auto ortho = [&](float distance) {
    Camera camera = look(kCenter + glm::vec3(0, 0, distance), kCenter);
    camera.projection = glm::ortho(-kHeight / 2, kHeight / 2, -kHeight / 2, kHeight / 2, 0.01f, 10000.0f);
    return camera;
  };
  EXPECT_TRUE(is_orthographic(ortho(200.0f).projection));
  EXPECT_FALSE(is_orthographic(look(kCenter + glm::vec3(0, 0, 200.0f), kCenter).projection));
  std::map<std::uint32_t, std::uint32_t> expected;
  testing::reference_cut(fx.tree.manifest, ortho(200.0f), 2.0, 0, expected, testing::kFovy, kHeight);
  ASSERT_GT(expected.size(), 1u);  // refined below the root
  EXPECT_EQ(draws_of(fx.settle_at(ortho(200.0f))), expected);
  EXPECT_EQ(draws_of(fx.settle_at(ortho(2000.0f))), expected);
  EXPECT_NE(draws_of(fx.settle_at(look(kCenter + glm::vec3(0, 0, 2000.0f), kCenter))), expected);
}

TEST(Selection, LargeNodeStraddlingTheFrustumIsKept) {
  Fixture fx(3);
  // Inside the root box near its centre: every corner of the root and of the depth-1 nodes is
  // off screen, yet they straddle the view and must be refined, not culled.
  const Camera camera = look(glm::vec3(33, 31, 30), glm::vec3(33, 31, -100));
  const FrameResult& frame = fx.settle_at(camera);
  EXPECT_GT(frame.stats.drawn_nodes, 0u);
  std::map<std::uint32_t, std::uint32_t> expected;
  testing::reference_cut(fx.tree.manifest, camera, 2.0, 0, expected);
  EXPECT_EQ(draws_of(frame), expected);
  expect_covering_cut(fx.tree, frame, camera);
}

TEST(Selection, NodesBehindTheCameraAreCulled) {
  Fixture fx(3);
  fx.settle_at(front(200.0f));
  const FrameResult& away = fx.streaming->update(look(glm::vec3(32, 32, 264), glm::vec3(32, 32, 1000)));
  EXPECT_EQ(away.stats.visited, 1u);
  EXPECT_EQ(away.stats.culled, 1u);
  EXPECT_EQ(away.stats.wanted, 0u);
  EXPECT_TRUE(away.draws.empty());

  // From the centre looking along +x, the four depth-1 nodes with x < 32 are behind the near plane.
  const FrameResult& half = fx.settle_at(look(glm::vec3(32, 32, 32), glm::vec3(100, 32, 32)));
  EXPECT_GE(half.stats.culled, 4u);
  for (const DrawItem& d : half.draws)
    EXPECT_GT(fx.tree.manifest.nodes[d.node].bounds.max[0], 32.0f) << fx.tree.manifest.nodes[d.node].path;
}

TEST(Selection, DistanceModeUsesPerDepthThresholds) {
  StreamingOptions options;
  options.mode = SelectionMode::distance;
  options.distance_thresholds = {300.0, 100.0};
  Fixture fx(3, options);
  // Root: 1468 >= 4·300 -> its coarse LOD; 450 -> finest (below 2·300).
  EXPECT_EQ(draws_of(fx.settle_at(front(1468.0f))), (std::map<std::uint32_t, std::uint32_t>{{0, 1}}));
  EXPECT_EQ(draws_of(fx.settle_at(front(450.0f))), (std::map<std::uint32_t, std::uint32_t>{{0, 0}}));
  // 180 < 300 refines the root; depth-1 nodes at 180 (z upper half) draw LOD 0, at 212 LOD 1.
  const FrameResult& frame = fx.settle_at(front(180.0f));
  ASSERT_EQ(frame.draws.size(), 8u);
  for (const DrawItem& d : frame.draws) {
    const bool near_half = fx.tree.manifest.nodes[d.node].cell.min[2] >= 32.0f;
    EXPECT_EQ(d.lod, near_half ? 0u : 1u) << fx.tree.manifest.nodes[d.node].path;
  }
}

// --- paging -----------------------------------------------------------------------------------

TEST(Paging, RootCoarsestLodIsRequestedFirstAndPinned) {
  StreamingOptions options;
  options.max_loads_in_flight = 1;
  Fixture fx(3, options);
  const FrameResult& first = fx.streaming->update(front(100.0f));
  EXPECT_TRUE(first.draws.empty());  // nothing resident yet: the only frame with holes
  EXPECT_GT(first.stats.holes, 0u);
  EXPECT_EQ(first.stats.loads_issued, 1u);
  fx.executor->run_pending();
  EXPECT_EQ(fx.tree.source->total_reads(), 1u);
  EXPECT_EQ(fx.tree.source->read_count("lod1.bin"), 1u);

  const FrameResult& second = fx.streaming->update(front(100.0f));
  EXPECT_EQ(second.stats.loads_completed, 1u);
  EXPECT_EQ(second.stats.holes, 0u);
  ASSERT_EQ(second.draws.size(), 1u);  // the root stands in for all 64 wanted leaves
  EXPECT_EQ(second.draws[0].node, 0u);
  EXPECT_TRUE(second.draws[0].is_fallback);
  EXPECT_EQ(second.stats.cache_misses, 64u);
  EXPECT_EQ(second.stats.waiting_on_io, 0u);

  // Pinned: however tight the budget gets elsewhere, it stays.
  fx.settle_at(front(100.0f));
  fx.settle_at(look(glm::vec3(32, 32, 264), glm::vec3(32, 32, 1000)));
  EXPECT_TRUE(fx.streaming->is_resident(0, 1));
}

TEST(Paging, ResidentBytesNeverExceedABudgetSmallerThanTheCut) {
  StreamingOptions options;
  options.max_resident_bytes = 30000;  // the 64-leaf cut needs 64 · 1560 = 99840
  options.max_loads_in_flight = 4;
  Fixture fx(3, options);
  const Camera camera = front(100.0f);
  std::uint32_t fallbacks = 0;
  for (int i = 0; i < 40; ++i) {
    const FrameResult& frame = fx.streaming->update(camera);
    EXPECT_LE(frame.stats.resident_bytes, options.max_resident_bytes);
    EXPECT_LE(frame.stats.resident_bytes + frame.stats.reserved_bytes, options.max_resident_bytes);
    if (i > 0) {
      EXPECT_EQ(frame.stats.holes, 0u);
      expect_covering_cut(fx.tree, frame, camera);
    }
    fallbacks += frame.stats.fallbacks;
    fx.executor->run_pending();
  }
  EXPECT_GT(fallbacks, 0u);  // while the cut loaded
  // The target was relaxed until the cut fits half the budget: the 8 depth-1 nodes at LOD 0
  // (8 · 1560 bytes), all drawn as wanted.
  const FrameResult& last = fx.streaming->update(camera);
  EXPECT_GT(last.stats.coarsening, 1.0f);
  EXPECT_EQ(last.stats.drawn_nodes, 8u);
  for (const DrawItem& d : last.draws) EXPECT_EQ(d.depth, 1u);
  EXPECT_LE(last.stats.wanted_bytes, options.max_resident_bytes / 2);
  EXPECT_EQ(last.stats.fallbacks, 0u);
  EXPECT_EQ(last.stats.cache_misses, 0u);
  expect_covering_cut(fx.tree, last, camera);
}

// When no factor fits the cut (here the pinned root alone is over half the budget), the factor
// stops at its cap instead of growing by 1.5^40 per frame to infinity, where it stayed for every
// later view (and, in distance mode, the LOD index cast from log2(inf) was undefined).
TEST(Paging, ACutThatNoCoarseningFitsKeepsTheFactorBounded) {
  for (const SelectionMode mode : {SelectionMode::screen_space_error, SelectionMode::distance}) {
    StreamingOptions options;
    options.mode = mode;
    options.distance_thresholds = {200.0, 100.0, 50.0};
    options.max_resident_bytes = testing::decoded_bytes(SyntheticTree::kCoarseTriangles) * 3 / 2;
    Fixture fx(3, options);
    for (int i = 0; i < 20; ++i) {
      const FrameResult& frame = fx.streaming->update(front(100.0f));
      EXPECT_TRUE(std::isfinite(frame.stats.coarsening)) << i;
      EXPECT_LE(frame.stats.coarsening, 1.2e7f) << i;
      EXPECT_LE(frame.stats.resident_bytes + frame.stats.reserved_bytes, options.max_resident_bytes);
      if (i > 2) {
        EXPECT_EQ(draws_of(frame), (std::map<std::uint32_t, std::uint32_t>{{0, 1}})) << i;
      }
      fx.executor->run_pending();
    }
  }
}

// Every slot's LodInfo, which the loaders read the file and its size from, is that node LOD's in
// the manifest (whose nodes are in another order than the layout's preorder). The layout used to
// hold these pointers and gave them away to the loaders, left empty behind.
TEST(TreeLayoutSlots, EverySlotHasItsNodeLodsInfo) {
  const SyntheticTree t = make_full_octree(3);
  Result<TreeLayout> layout = build_tree_layout(t.manifest);
  ASSERT_TRUE(layout.ok()) << layout.status().message();
  const std::vector<const LodInfo*> lods = slot_lods(t.manifest, layout.value());
  ASSERT_EQ(lods.size(), layout->slot_error.size());
  for (std::size_t m = 0; m < t.manifest.nodes.size(); ++m) {
    const LayoutNode& n = layout->nodes[layout->manifest_to_internal[m]];
    ASSERT_EQ(n.lod_count, t.manifest.nodes[m].lods.size());
    for (std::uint32_t l = 0; l < n.lod_count; ++l)
      EXPECT_EQ(lods[n.lod_begin + l], &t.manifest.nodes[m].lods[l]) << t.manifest.nodes[m].path << " LOD " << l;
  }
}

// A load that cannot get its room reclaims nothing: the free entries it could have taken stay
// as second chances. Before, it reclaimed every unprotected one and still failed.
TEST(NodeCacheRoom, AFailedRequestReclaimsNothing) {
  const SyntheticTree t = make_full_octree(2);
  Result<TreeLayout> layout = build_tree_layout(t.manifest);
  ASSERT_TRUE(layout.ok()) << layout.status().message();
  const auto mesh = std::make_shared<const NodeMesh>(testing::strip_mesh(t.manifest.nodes[1].bounds, 16));
  const std::uint64_t bytes = mesh_bytes(*mesh);
  NodeCache cache(layout.value(), 3 * bytes);
  const std::uint32_t old_slot = layout->nodes[1].lod_begin, recent[2] = {layout->nodes[2].lod_begin,
                                                                          layout->nodes[3].lod_begin};
  cache.request(old_slot);
  cache.install(old_slot, mesh, 1);
  for (const std::uint32_t slot : recent) {
    cache.request(slot);
    cache.install(slot, mesh, 5);
  }
  EXPECT_FALSE(cache.make_room(2 * bytes, 3));  // only the frame-1 entry may go: not enough
  EXPECT_TRUE(cache.resident(old_slot));
  EXPECT_EQ(cache.resident_bytes(), 3 * bytes);
  EXPECT_TRUE(cache.make_room(bytes, 3));
  EXPECT_FALSE(cache.resident(old_slot));
  for (const std::uint32_t slot : recent) EXPECT_TRUE(cache.resident(slot));
}

TEST(Paging, RelaxedTargetReturnsToTheConfiguredOneWhenTheViewAllows) {
  StreamingOptions options;
  options.max_resident_bytes = 30000;
  Fixture fx(3, options);
  EXPECT_GT(fx.settle_at(front(100.0f)).stats.coarsening, 1.0f);
  const FrameResult& far = fx.settle_at(front(500.0f));  // the root's finest LOD: 1560 bytes
  EXPECT_EQ(far.stats.coarsening, 1.0f);
  EXPECT_EQ(draws_of(far), (std::map<std::uint32_t, std::uint32_t>{{0, 0}}));
}

TEST(Paging, DrawnMeshesOutliveTheTree) {
  std::shared_ptr<const NodeMesh> kept;
  {
    Fixture fx(3);
    const FrameResult& frame = fx.settle_at(front(200.0f));
    ASSERT_FALSE(frame.draws.empty());
    kept = frame.draws.front().mesh;
  }
  ASSERT_TRUE(kept);
  EXPECT_EQ(kept->triangle_count(), SyntheticTree::kFineTriangles);
}

TEST(Paging, BudgetForTheWholeCutShowsFallbacksButNeverExceedsIt) {
  StreamingOptions options;
  options.max_resident_bytes = 20000;
  options.max_cut_fraction = 1.0;
  Fixture fx(3, options);
  const Camera camera = front(100.0f);
  for (int i = 0; i < 40; ++i) {
    const FrameResult& frame = fx.streaming->update(camera);
    EXPECT_LE(frame.stats.resident_bytes + frame.stats.reserved_bytes, options.max_resident_bytes);
    if (i > 0) expect_covering_cut(fx.tree, frame, camera);
    fx.executor->run_pending();
  }
  const FrameResult& last = fx.streaming->update(camera);
  EXPECT_LE(last.stats.wanted_bytes, options.max_resident_bytes);
  EXPECT_EQ(last.stats.holes, 0u);
}

// The cut fits the budget (max_cut_fraction 1: 64 leaves · 1560 bytes = the whole budget) but
// not next to the pinned root drawn in its place while it loads: some of its loads find no room
// every frame, and the frame says so. With room to spare none is turned away.
TEST(Paging, LoadsTheBudgetHasNoRoomForAreCounted) {
  const Camera camera = front(100.0f);  // wants every leaf's LOD 0
  StreamingOptions tight;
  tight.max_resident_bytes = 64 * testing::decoded_bytes(SyntheticTree::kFineTriangles);
  tight.max_cut_fraction = 1.0;
  Fixture fx(3, tight);
  std::uint32_t over_budget = 0;
  for (int i = 0; i < 30; ++i) {
    const FrameResult& frame = fx.streaming->update(camera);
    EXPECT_EQ(frame.stats.coarsening, 1.0f);
    over_budget += frame.stats.loads_over_budget;
    fx.executor->run_pending();
  }
  const FrameResult& last = fx.streaming->update(camera);
  EXPECT_GT(over_budget, 0u);
  EXPECT_GT(last.stats.loads_over_budget, 0u);  // for as long as the view stays
  EXPECT_GT(last.stats.cache_misses, 0u);
  EXPECT_LE(last.stats.resident_bytes + last.stats.reserved_bytes, tight.max_resident_bytes);

  Fixture roomy(3);
  for (int i = 0; i < 30; ++i) {
    EXPECT_EQ(roomy.streaming->update(camera).stats.loads_over_budget, 0u) << i;
    roomy.executor->run_pending();
  }
}

// Pulled back from the 64 resident leaves, the camera wants the 8 depth-1 nodes, none resident
// (no prefetch, and the leaves loaded in one go, so no parent was asked for as a fallback):
// each is covered by its 8 leaves, 8 checks apiece. With 20 checks a frame the
// third cover runs out, is given up (FrameStats::covers_out_of_checks), and the pinned root (the
// nearest resident ancestor) draws in place of everything; with the default the 64 leaves stand
// in. Before, covers had no bound.
TEST(Paging, CoveringByDescendantsChecksAtMostTheFramesNodes) {
  const Camera near = front(100.0f), far = front(200.0f);  // all leaves; the depth-1 nodes' LOD 0
  for (const std::uint32_t checks : {20u, StreamingOptions{}.max_cover_checks_per_frame}) {
    StreamingOptions options;
    options.prefetch = false;
    options.max_loads_in_flight = 80;
    options.max_cover_checks_per_frame = checks;
    Fixture fx(3, options);
    fx.settle_at(near);
    const FrameResult& frame = fx.streaming->update(far);
    ASSERT_EQ(frame.stats.cache_misses, 8u);
    if (checks == 20u) {
      EXPECT_EQ(draws_of(frame), (std::map<std::uint32_t, std::uint32_t>{{0, 1}}));
      EXPECT_EQ(frame.stats.cover_checks, 20u);
      EXPECT_EQ(frame.stats.covers_out_of_checks, 1u);  // the root then draws the other five too
    } else {
      EXPECT_EQ(frame.stats.drawn_nodes, 64u);
      for (const DrawItem& d : frame.draws) EXPECT_EQ(d.depth, 2u);
      EXPECT_EQ(frame.stats.cover_checks, 64u);
      EXPECT_EQ(frame.stats.covers_out_of_checks, 0u);
    }
    EXPECT_EQ(frame.stats.fallbacks, frame.stats.drawn_nodes);
    expect_covering_cut(fx.tree, frame, far);
  }
}

TEST(Paging, NothingDrawnIsEvicted) {
  StreamingOptions options;
  options.max_resident_bytes = 40000;
  Fixture fx(4, options);
  for (int i = 0; i < 60; ++i) {
    const float angle = 0.15f * static_cast<float>(i);
    const Camera camera = look(kCenter + glm::vec3(std::cos(angle), 0.3f, std::sin(angle)) * 90.0f, kCenter);
    const FrameResult& frame = fx.streaming->update(camera);
    for (const DrawItem& d : frame.draws)
      EXPECT_TRUE(fx.streaming->is_resident(d.node, d.lod)) << "frame " << i << " node " << d.node;
    EXPECT_LE(frame.stats.resident_bytes, options.max_resident_bytes);
    if (i > 0) expect_covering_cut(fx.tree, frame, camera);
    if (i % 2 == 0) fx.executor->run_pending();  // loads arrive every other frame
  }
}

TEST(Paging, ReleasedEntriesComeBackWithoutIoAsSecondChanceHits) {
  Fixture fx(3);
  const FrameResult& near = fx.settle_at(front(100.0f));
  ASSERT_EQ(near.stats.drawn_nodes, 64u);
  fx.settle_at(front(1468.0f));  // only the root now; the 64 leaves go to the free list
  const std::uint64_t reads = fx.tree.source->total_reads();
  const FrameResult& back = fx.streaming->update(front(100.0f));
  EXPECT_EQ(back.stats.second_chance_hits, 64u);
  EXPECT_EQ(back.stats.cache_hits, 64u);
  EXPECT_EQ(back.stats.cache_misses, 0u);
  EXPECT_EQ(back.stats.fallbacks, 0u);
  EXPECT_EQ(back.stats.drawn_nodes, 64u);
  fx.executor->run_pending();
  EXPECT_EQ(fx.tree.source->total_reads(), reads);
}

TEST(Paging, FreeListEntriesAreReclaimedOnlyWhenALoadNeedsTheMemory) {
  StreamingOptions options;
  // Each corner's cut takes 285480 bytes and they share about 47K: one fits, both do not.
  options.max_resident_bytes = 400000;
  options.max_cut_fraction = 0.75;
  options.prefetch = false;
  Fixture fx(4, options);
  const Camera corner_a = look(glm::vec3(-20, -20, -20), glm::vec3(0, 0, 0));
  const Camera corner_b = look(glm::vec3(84, 84, 84), glm::vec3(64, 64, 64));
  const FrameResult& a = fx.settle_at(corner_a);
  ASSERT_EQ(a.stats.fallbacks, 0u);
  ASSERT_EQ(a.stats.coarsening, 1.0f);
  const std::vector<DrawItem> a_draws = a.draws;
  const FrameResult& b = fx.settle_at(corner_b);
  EXPECT_EQ(b.stats.fallbacks, 0u);
  EXPECT_LE(b.stats.resident_bytes, options.max_resident_bytes);

  std::vector<std::string> reclaimed;
  std::uint32_t kept = 0;
  for (const DrawItem& d : a_draws) {
    if (fx.streaming->is_resident(d.node, d.lod)) ++kept;
    else reclaimed.push_back(fx.tree.manifest.nodes[d.node].lods[d.lod].file);
  }
  EXPECT_GT(kept, 0u);  // memory B did not need: still there
  ASSERT_FALSE(reclaimed.empty());  // memory B needed: reused

  const FrameResult& again = fx.streaming->update(corner_a);
  EXPECT_EQ(again.stats.cache_misses, reclaimed.size());
  EXPECT_GT(again.stats.second_chance_hits, 0u);
  fx.settle_at(corner_a);
  for (const std::string& file : reclaimed) EXPECT_EQ(fx.tree.source->read_count(file), 2u) << file;
}

TEST(Paging, QueuedLoadsAreCancelledWhenTheCameraTurnsAway) {
  StreamingOptions options;
  options.max_loads_in_flight = 4;
  options.prefetch = false;
  Fixture fx(3, options);
  fx.streaming->update(front(100.0f));  // the root and 3 leaves
  fx.executor->run_pending();
  const FrameResult& queued = fx.streaming->update(front(100.0f));
  EXPECT_EQ(queued.stats.loads_completed, 4u);
  EXPECT_EQ(queued.stats.loads_issued, 4u);
  EXPECT_EQ(queued.stats.loads_in_flight, 4u);
  // Turn away before the loader ran: all four are dropped, nothing is read.
  const std::uint64_t reads = fx.tree.source->total_reads();
  const FrameResult& away = fx.streaming->update(look(glm::vec3(32, 32, 164), glm::vec3(32, 32, 1000)));
  EXPECT_EQ(away.stats.loads_cancelled, 4u);
  EXPECT_EQ(away.stats.loads_in_flight, 0u);
  fx.executor->run_pending();
  EXPECT_EQ(fx.tree.source->total_reads(), reads);
}

TEST(Paging, NeededLoadsComeBeforePrefetchesAndHigherPriorityFirst) {
  StreamingOptions options;
  options.max_loads_in_flight = 1;
  Fixture fx(3, options);
  fx.streaming->update(front(100.0f));
  fx.executor->run_pending();  // root
  // The root stands in for the 64 wanted leaves: first the coarsest LOD of every leaf's parent
  // (so that a fallback there covers one octant), then the leaves, each nearest first (z high);
  // prefetches never outrank needed loads.
  auto resident_lods = [&](std::uint32_t depth, std::uint32_t lod) {
    std::vector<std::uint32_t> found;
    for (std::uint32_t n = 0; n < fx.tree.manifest.nodes.size(); ++n)
      if (fx.tree.manifest.nodes[n].depth == depth && fx.streaming->is_resident(n, lod)) found.push_back(n);
    return found;
  };
  fx.streaming->update(front(100.0f));
  fx.executor->run_pending();
  fx.streaming->update(front(100.0f));
  const std::vector<std::uint32_t> first = resident_lods(1, 1);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(fx.tree.manifest.nodes[first[0]].cell.max[2], 64.0f) << fx.tree.manifest.nodes[first[0]].path;
  for (int i = 1; i < 8; ++i) {
    fx.executor->run_pending();
    fx.streaming->update(front(100.0f));
  }
  EXPECT_EQ(resident_lods(1, 1).size(), 8u);
  EXPECT_TRUE(resident_lods(1, 0).empty());
  EXPECT_TRUE(resident_lods(2, 0).empty());
  fx.executor->run_pending();
  fx.streaming->update(front(100.0f));
  const std::vector<std::uint32_t> leaves = resident_lods(2, 0);
  ASSERT_EQ(leaves.size(), 1u);
  EXPECT_EQ(fx.tree.manifest.nodes[leaves[0]].cell.max[2], 64.0f) << fx.tree.manifest.nodes[leaves[0]].path;
}

// A valid node file that is not the one the manifest describes (LOD 1's bytes under LOD 0's
// name, and a manifest edited to its size: the cache budgets by the manifest's counts) fails its
// load like a corrupt one.
TEST(Paging, ANodeFileWithOtherCountsThanTheManifestFailsItsLoad) {
  SyntheticTree t = make_full_octree(3);
  const std::uint32_t swapped = t.node_at("7/7");
  NodeInfo& node = t.manifest.nodes[swapped];
  Result<std::vector<std::byte>> coarser = t.source->read(node.lods[1].file, node.lods[1].bytes);
  ASSERT_TRUE(coarser.ok());
  t.source->put(node.lods[0].file, coarser.value());
  node.lods[0].bytes = node.lods[1].bytes;
  Fixture fx(std::move(t), {});

  const Camera camera = front(100.0f);  // wants every leaf's LOD 0
  for (int i = 0; i < 30; ++i) {
    fx.streaming->update(camera);
    fx.executor->run_pending();
  }
  EXPECT_TRUE(fx.streaming->is_bad(swapped, 0));
  EXPECT_FALSE(fx.streaming->is_bad(swapped, 1));
  ASSERT_EQ(fx.log.size(), 1u);
  EXPECT_NE(fx.log[0].find("triangles and"), std::string::npos) << fx.log[0];
}

// A node file of another size than the manifest lists (here LOD 1's bytes under LOD 0's name) is
// refused by the source before it is decoded, and the load fails like a missing file: logged
// once with both sizes, marked bad, the node's other LOD drawn, no holes.
TEST(Paging, ANodeFileOfAnotherSizeThanTheManifestSaysFailsItsLoad) {
  Fixture fx(3);
  const std::uint32_t swapped = fx.tree.node_at("7/7");
  const NodeInfo& node = fx.tree.manifest.nodes[swapped];
  Result<std::vector<std::byte>> coarser = fx.tree.source->read(node.lods[1].file, node.lods[1].bytes);
  ASSERT_TRUE(coarser.ok());
  fx.tree.source->put(node.lods[0].file, coarser.value());

  const Camera camera = front(100.0f);  // wants every leaf's LOD 0
  for (int i = 0; i < 30; ++i) {
    const FrameResult& frame = fx.streaming->update(camera);
    if (i > 0) expect_covering_cut(fx.tree, frame, camera);
    fx.executor->run_pending();
  }
  EXPECT_TRUE(fx.streaming->is_bad(swapped, 0));
  EXPECT_FALSE(fx.streaming->is_bad(swapped, 1));
  ASSERT_EQ(fx.log.size(), 1u);
  const std::string sizes = std::to_string(node.lods[1].bytes) + " bytes, the manifest says " +
                            std::to_string(node.lods[0].bytes);
  EXPECT_NE(fx.log[0].find(node.lods[0].file + ": " + sizes), std::string::npos) << fx.log[0];
  const std::map<std::uint32_t, std::uint32_t> draws = draws_of(fx.streaming->update(camera));
  ASSERT_EQ(draws.count(swapped), 1u);
  EXPECT_EQ(draws.at(swapped), 1u);
}

TEST(Paging, CorruptNodeFileIsLoggedOnceAndAnAncestorIsDrawnForever) {
  Fixture fx(3);
  const std::uint32_t broken = fx.tree.node_at("7/7");
  // LOD 0 fails its checksum, LOD 1 is missing (replaced by a truncated file).
  std::vector<std::byte> bytes = encode_node_file(testing::strip_mesh(fx.tree.manifest.nodes[broken].bounds, 64));
  bytes[bytes.size() / 2] ^= std::byte{0x40};
  fx.tree.source->put(fx.tree.manifest.nodes[broken].lods[0].file, bytes);
  fx.tree.source->put(fx.tree.manifest.nodes[broken].lods[1].file, std::vector<std::byte>(10));

  const Camera camera = front(100.0f);
  for (int i = 0; i < 30; ++i) {
    const FrameResult& frame = fx.streaming->update(camera);
    if (i > 0) expect_covering_cut(fx.tree, frame, camera);
    fx.executor->run_pending();
  }
  const FrameResult& frame = fx.streaming->update(camera);
  EXPECT_TRUE(fx.streaming->is_bad(broken, 0));
  EXPECT_TRUE(fx.streaming->is_bad(broken, 1));
  ASSERT_EQ(fx.log.size(), 2u);  // one line per bad LOD, however many frames pass
  EXPECT_NE(fx.log[0].find("7/7"), std::string::npos) << fx.log[0];
  // The nearest ancestor, node "7", was loaded for it and stands in; its other children are
  // drawn by it too, everything else as wanted.
  const std::uint32_t parent = fx.tree.node_at("7");
  std::map<std::uint32_t, std::uint32_t> draws = draws_of(frame);
  EXPECT_EQ(draws.count(broken), 0u);
  ASSERT_EQ(draws.count(parent), 1u);
  EXPECT_EQ(frame.stats.drawn_nodes, 64u - 8u + 1u);
  EXPECT_EQ(frame.stats.fallbacks, 1u);
  expect_covering_cut(fx.tree, frame, camera);
}

TEST(Paging, NoHolesWhileLoadsTrickleInAlongAPath) {
  StreamingOptions options;
  options.max_loads_in_flight = 2;
  options.max_resident_bytes = 60000;
  Fixture fx(4, options);
  for (int i = 0; i < 80; ++i) {
    const float t = static_cast<float>(i) / 80.0f;
    const Camera camera = look(glm::vec3(32.0f + 60.0f * std::sin(6.0f * t), 40.0f, 400.0f - 390.0f * t), kCenter);
    const FrameResult& frame = fx.streaming->update(camera);
    if (i > 0) {
      EXPECT_EQ(frame.stats.holes, 0u) << "frame " << i;
      expect_covering_cut(fx.tree, frame, camera);
    }
    if (i % 3 == 0) fx.executor->run_pending();
  }
}

TEST(Paging, PrefetchMakesAnApproachCheaper) {
  auto misses_along_approach = [](bool prefetch) {
    StreamingOptions options;
    options.prefetch = prefetch;
    options.max_loads_in_flight = 4;
    Fixture fx(4, options);
    std::uint64_t misses = 0;
    for (int i = 0; i < 60; ++i) {
      const FrameResult& frame = fx.streaming->update(front(1500.0f - 24.0f * static_cast<float>(i)));
      if (i > 0) misses += frame.stats.cache_misses;
      fx.executor->run_pending();
    }
    return misses;
  };
  const std::uint64_t with = misses_along_approach(true);
  const std::uint64_t without = misses_along_approach(false);
  EXPECT_LT(with, without);
}

TEST(Paging, PrefetchLoadsTheNeighboursOfTheCut) {
  Fixture fx(3);
  fx.settle_at(front(200.0f));  // cut: the 8 depth-1 nodes at LOD 0
  EXPECT_TRUE(fx.streaming->is_resident(fx.tree.node_at("7"), 1));    // coarser step
  EXPECT_TRUE(fx.streaming->is_resident(fx.tree.node_at("7/7"), 1));  // children's coarsest
  StreamingOptions off;
  off.prefetch = false;
  Fixture without(3, off);
  without.settle_at(front(200.0f));
  EXPECT_FALSE(without.streaming->is_resident(without.tree.node_at("7"), 1));
  EXPECT_FALSE(without.streaming->is_resident(without.tree.node_at("7/7"), 1));
}

TEST(Paging, PrefetchPlanningSpreadOverFramesReachesEveryNeighbour) {
  // Cut: the 8 depth-1 nodes at LOD 0. Their neighbours are their LOD 1 and their 64 children's
  // coarsest LODs; with 2 checks per frame, one cut entry's neighbours are planned per frame,
  // round robin, so after the cut has loaded they all arrive within a few frames more.
  StreamingOptions options;
  options.prefetch_checks_per_frame = 2;
  options.prediction_visits_per_frame = 1;
  Fixture fx(3, options);
  const Camera camera = front(200.0f);
  std::uint32_t most_prefetches = 0;
  for (int i = 0; i < 30; ++i) {
    const FrameResult& frame = fx.streaming->update(camera);
    // frame 0 queues the root and the cut; from frame 1 on (all loaded) only prefetches
    if (i > 0) most_prefetches = std::max(most_prefetches, frame.stats.loads_issued);
    fx.executor->run_pending();
  }
  for (const char* path : {"0", "3", "7"}) EXPECT_TRUE(fx.streaming->is_resident(fx.tree.node_at(path), 1)) << path;
  for (const char* path : {"0/0", "3/5", "7/7"}) EXPECT_TRUE(fx.streaming->is_resident(fx.tree.node_at(path), 1)) << path;
  EXPECT_LE(most_prefetches, 9u);  // one cut entry's neighbours at a time
}

TEST(Executor, AThreadPoolOfZeroThreadsStillRunsItsTasks) {
  std::promise<void> ran;
  {
    ThreadPoolExecutor pool(0);
    pool.post([&] { ran.set_value(); });
  }  // the destructor runs every posted task
  EXPECT_EQ(ran.get_future().wait_for(std::chrono::seconds(0)), std::future_status::ready);
}

TEST(Paging, ThreadPoolLoadsConvergeToTheReferenceCut) {
  SyntheticTree tree = make_full_octree(4);
  auto executor = std::make_shared<ThreadPoolExecutor>(2);
  auto opened = StreamingTree::open(tree.manifest, tree.source, executor, StreamingOptions{});
  ASSERT_TRUE(opened.ok()) << opened.status().message();
  StreamingTree& streaming = *opened.value();
  const Camera camera = look(glm::vec3(-30, 70, 110), kCenter);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  const std::uint32_t root = tree.node_at("");
  const auto root_coarsest = static_cast<std::uint32_t>(tree.manifest.nodes[root].lods.size() - 1);
  const FrameResult* frame = &streaming.update(camera);
  while (std::chrono::steady_clock::now() < deadline &&
         (frame->stats.loads_in_flight > 0 || frame->stats.loads_issued > 0 || frame->stats.loads_completed > 0)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    // holes only until the root's coarsest LOD has arrived (streaming_tree.h), which on a slow
    // or busy machine (sanitizers) can take more than the first millisecond
    const bool root_arrived = streaming.is_resident(root, root_coarsest);
    frame = &streaming.update(camera);
    if (root_arrived) {
      EXPECT_EQ(frame->stats.holes, 0u);
    }
  }
  EXPECT_TRUE(streaming.is_resident(root, root_coarsest));
  std::map<std::uint32_t, std::uint32_t> expected;
  testing::reference_cut(tree.manifest, camera, 2.0, 0, expected);
  EXPECT_EQ(draws_of(*frame), expected);
  expect_covering_cut(tree, *frame, camera);
}

// A camera with a NaN (lookAt with eye == target makes the view NaN), or without a field of view
// (a projection without vertical scale) or a viewport, is skipped: the previous frame's draws, no loads, and the next good camera
// selects as if it had not come.
TEST(Selection, AnUnusableCameraChangesNothing) {
  Fixture fx(3);
  const Camera good = front(100.0f);
  const std::map<std::uint32_t, std::uint32_t> settled = draws_of(fx.settle_at(good));
  const std::uint64_t reads = fx.tree.source->total_reads();
  Camera nan_eye = good;
  nan_eye.position.x = std::numeric_limits<float>::quiet_NaN();
  Camera no_fov = good;
  no_fov.projection[1][1] = 0.0f;
  Camera no_viewport = good;
  no_viewport.viewport_height_px = 0.0f;
  const Camera same_point = look(kCenter, kCenter);
  for (const Camera& bad : {nan_eye, no_fov, no_viewport, same_point}) {
    EXPECT_FALSE(is_usable(bad));
    const FrameResult& frame = fx.streaming->update(bad);
    EXPECT_TRUE(frame.stats.camera_rejected);
    EXPECT_EQ(draws_of(frame), settled);
    EXPECT_EQ(frame.stats.drawn_nodes, settled.size());
    EXPECT_EQ(frame.stats.loads_issued, 0u);
    EXPECT_EQ(fx.executor->pending(), 0u);
  }
  const FrameResult& again = fx.streaming->update(good);
  EXPECT_FALSE(again.stats.camera_rejected);
  EXPECT_EQ(again.stats.coarsening, 1.0f);
  EXPECT_EQ(draws_of(again), settled);
  EXPECT_EQ(fx.tree.source->total_reads(), reads);
}

// Runs posted tasks one at a time, in order, when the test says.
class StepExecutor final : public Executor {
 public:
  void post(std::function<void()> task) override { tasks_.push_back(std::move(task)); }
  bool run_one() {
    if (tasks_.empty()) return false;
    std::function<void()> task = std::move(tasks_.front());
    tasks_.pop_front();
    task();
    return true;
  }

 private:
  std::deque<std::function<void()>> tasks_;
};

// Reads through another source, calling `on_read` first (from the loader task).
class HookedSource final : public NodeSource {
 public:
  HookedSource(std::shared_ptr<const NodeSource> inner, std::function<void()> on_read)
      : inner_(std::move(inner)), on_read_(std::move(on_read)) {}
  Result<std::vector<std::byte>> read(std::string_view file, std::uint64_t expected_bytes) const override {
    on_read_();
    return inner_->read(file, expected_bytes);
  }

 private:
  std::shared_ptr<const NodeSource> inner_;
  std::function<void()> on_read_;
};

// A node whose wanted LOD and descendants are missing falls back to its nearest resident
// ancestor, which replaces everything under it. Without prefetches only the root and the wanted
// leaves were ever requested, so the root stood in for all 64 leaves until the last arrived; now
// the parents' coarsest LODs come with the first leaves and each octant shows as it completes.
TEST(Paging, AFallbackAsksForTheParentSoTheRootDoesNotStandInForLong) {
  StreamingOptions options;
  options.prefetch = false;
  options.max_loads_in_flight = 8;
  Fixture fx(3, options);
  const Camera camera = front(20.0f);
  int root_only_frames = 0, frames = 0;
  for (; frames < 40; ++frames) {
    const FrameResult& frame = fx.streaming->update(camera);
    if (frame.draws.size() == 1 && frame.draws[0].node == 0) ++root_only_frames;
    if (frame.stats.fallbacks == 0 && !frame.draws.empty()) break;
    fx.executor->run_pending();
  }
  EXPECT_LT(frames, 40);
  EXPECT_EQ(root_only_frames, 1) << frames << " frames";  // before: 5 of 9
  EXPECT_TRUE(fx.streaming->is_resident(fx.tree.node_at("0"), 1));
}

// A NodeSource that throws (or memory running out) fails that load like a missing file: logged,
// marked bad, an ancestor drawn; the loader's accounting stays right, so the rest still loads.
TEST(Paging, ALoadThatThrowsFailsLikeAMissingFile) {
  SyntheticTree t = make_full_octree(2);
  const std::string broken = t.manifest.nodes[1].lods[0].file;
  struct Throwing final : NodeSource {
    std::shared_ptr<const NodeSource> inner;
    std::string broken;
    Result<std::vector<std::byte>> read(std::string_view file, std::uint64_t expected_bytes) const override {
      if (file == broken) throw std::runtime_error("simulated failure");
      return inner->read(file, expected_bytes);
    }
  };
  auto throwing = std::make_shared<Throwing>();
  throwing->inner = t.source;
  throwing->broken = broken;
  auto executor = std::make_shared<SynchronousExecutor>();
  std::vector<std::string> log;
  StreamingOptions options;
  options.log = [&](std::string_view message) { log.emplace_back(message); };
  auto opened = StreamingTree::open(t.manifest, throwing, executor, options);
  ASSERT_TRUE(opened.ok());
  const FrameResult& frame = settle(*opened.value(), *executor, front(50.0f));
  EXPECT_TRUE(opened.value()->is_bad(1, 0));
  ASSERT_EQ(log.size(), 1u);
  EXPECT_NE(log[0].find(broken + ": load failed: simulated failure"), std::string::npos) << log[0];
  EXPECT_EQ(frame.stats.loads_in_flight, 0u);
  EXPECT_EQ(frame.stats.holes, 0u);
  EXPECT_GT(frame.stats.drawn_nodes, 1u);
}

// Two trees on one executor take turns: a loader task loads one request, so tree A, whose
// render thread keeps queueing loads while A's loads run, cannot hold the executor's thread.
// Before, A's first task looped while A had requests, and B's root waited for A's whole cut.
TEST(Paging, TreesSharingAnExecutorTakeTurns) {
  SyntheticTree a = make_full_octree(3), b = make_full_octree(2);
  auto executor = std::make_shared<StepExecutor>();
  StreamingOptions options;
  options.max_loads_in_flight = 4;
  options.prefetch = false;
  std::unique_ptr<StreamingTree> tree_a;
  std::uint64_t a_loads = 0;
  auto source_a = std::make_shared<HookedSource>(a.source, [&] {
    ++a_loads;
    tree_a->update(front(100.0f));  // A's next frame, while its load runs
  });
  auto opened_a = StreamingTree::open(a.manifest, source_a, executor, options);
  auto opened_b = StreamingTree::open(b.manifest, b.source, executor, options);
  ASSERT_TRUE(opened_a.ok() && opened_b.ok());
  tree_a = std::move(opened_a).value();
  tree_a->update(front(100.0f));
  opened_b.value()->update(front(100.0f));
  while (b.source->total_reads() == 0 && a_loads < 100 && executor->run_one()) {
  }
  EXPECT_EQ(b.source->total_reads(), 1u);
  EXPECT_LE(a_loads, options.max_loads_in_flight);
}

TEST(Paging, TreeCanBeDestroyedWithLoadsStillPosted) {
  SyntheticTree tree = make_full_octree(3);
  auto executor = std::make_shared<SynchronousExecutor>();
  {
    auto opened = StreamingTree::open(tree.manifest, tree.source, executor, StreamingOptions{});
    ASSERT_TRUE(opened.ok());
    opened.value()->update(front(100.0f));
  }
  EXPECT_GT(executor->pending(), 0u);
  executor->run_pending();  // the tasks own their queue; nothing is loaded after shutdown
  EXPECT_EQ(tree.source->total_reads(), 0u);
}

// --- on disk ----------------------------------------------------------------------------------

std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("octolod_runtime_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(Disk, OpenDirectoryStreamsNodeFilesFromDisk) {
  const SyntheticTree tree = make_full_octree(3);
  const auto dir = scratch_dir("open");
  testing::write_tree(tree, dir);
  auto executor = std::make_shared<SynchronousExecutor>();
  auto opened = StreamingTree::open_directory(dir, executor, StreamingOptions{});
  ASSERT_TRUE(opened.ok()) << opened.status().message();
  const FrameResult& frame = settle(*opened.value(), *executor, front(200.0f));
  EXPECT_EQ(frame.stats.drawn_nodes, 8u);
  EXPECT_EQ(frame.stats.fallbacks, 0u);
  EXPECT_EQ(frame.stats.loads_failed, 0u);
  std::filesystem::remove_all(dir);
}

// Node 7/7 of a full octree of depth 3, damaged on disk by `damage` (given the tree's directory
// and the node's LODs): both of its LODs fail their loads, each logged once, and for a camera
// that wants all 64 leaves its parent 7 draws in its place, without holes. Returns the log.
std::vector<std::string> expect_damaged_node_falls_back(
    const char* scratch, const std::function<void(const std::filesystem::path&, const std::vector<LodInfo>&)>& damage) {
  const SyntheticTree tree = make_full_octree(3);
  const auto dir = scratch_dir(scratch);
  testing::write_tree(tree, dir);
  const std::uint32_t broken = tree.node_at("7/7");
  damage(dir, tree.manifest.nodes[broken].lods);

  auto executor = std::make_shared<SynchronousExecutor>();
  std::vector<std::string> log;
  StreamingOptions options;
  options.log = [&log](std::string_view message) { log.emplace_back(message); };
  auto opened = StreamingTree::open_directory(dir, executor, options);
  EXPECT_TRUE(opened.ok()) << opened.status().message();
  if (opened.ok()) {
    const Camera camera = front(100.0f);
    const FrameResult& frame = settle(*opened.value(), *executor, camera);
    EXPECT_TRUE(opened.value()->is_bad(broken, 0));
    EXPECT_TRUE(opened.value()->is_bad(broken, 1));
    EXPECT_EQ(log.size(), 2u);
    const std::map<std::uint32_t, std::uint32_t> draws = draws_of(frame);
    EXPECT_EQ(draws.count(broken), 0u);
    EXPECT_EQ(draws.count(tree.node_at("7")), 1u);
    EXPECT_EQ(frame.stats.fallbacks, 1u);
    EXPECT_EQ(frame.stats.holes, 0u);
    expect_covering_cut(tree, frame, camera);
  }
  std::filesystem::remove_all(dir);
  return log;
}

TEST(Disk, CorruptAndMissingNodeFilesOnDiskFallBackToTheirAncestor) {
  const std::vector<std::string> log =
      expect_damaged_node_falls_back("corrupt", [](const std::filesystem::path& dir, const std::vector<LodInfo>& lods) {
        // flip one payload bit in the middle of LOD 0; LOD 1 disappears
        const auto corrupt = dir / lods[0].file;
        std::fstream file(corrupt, std::ios::in | std::ios::out | std::ios::binary);
        const auto middle = static_cast<std::streamoff>(std::filesystem::file_size(corrupt) / 2);
        file.seekg(middle);
        const char byte = static_cast<char>(file.get() ^ 0x10);
        file.seekp(middle);
        file.put(byte);
        ASSERT_TRUE(file.good());
        std::filesystem::remove(dir / lods[1].file);
      });
  ASSERT_FALSE(log.empty());
  EXPECT_NE(log[0].find("7/7"), std::string::npos) << log[0];
}

TEST(Disk, FileSourceReportsAMissingFileAsAnIoError) {
  const FileSource source(std::filesystem::temp_directory_path());
  Result<std::vector<std::byte>> read = source.read("octolod_no_such_dir/lod0.bin", 100);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), ErrorCode::io);
  EXPECT_NE(read.status().message().find("lod0.bin"), std::string::npos);
}

// The size is checked by fstat before anything is allocated: a sparse 1 GiB file in place of a
// node file fails at once, naming the file and both sizes, instead of being read whole.
TEST(Disk, FileSourceRefusesAFileOfAnotherSizeBeforeReadingIt) {
  const auto dir = scratch_dir("size");
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "lod0.bin", std::ios::binary) << "x";
  std::filesystem::resize_file(dir / "lod0.bin", 1ull << 30);
  const FileSource source(dir);
  Result<std::vector<std::byte>> read = source.read("lod0.bin", 1000);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), ErrorCode::bad_input);
  EXPECT_NE(read.status().message().find("lod0.bin: 1073741824 bytes, the manifest says 1000"), std::string::npos)
      << read.status().message();
  std::filesystem::resize_file(dir / "lod0.bin", 1000);
  Result<std::vector<std::byte>> right = source.read("lod0.bin", 1000);
  ASSERT_TRUE(right.ok()) << right.status().message();
  EXPECT_EQ(right->size(), 1000u);
  std::filesystem::remove_all(dir);
}

// A node file on disk padded past the size the manifest lists fails its load like a missing one:
// logged, marked bad, an ancestor drawn, no holes.
TEST(Disk, ANodeFileLargerThanTheManifestSaysFallsBackToItsAncestor) {
  std::string sizes;
  const std::vector<std::string> log =
      expect_damaged_node_falls_back("padded", [&](const std::filesystem::path& dir, const std::vector<LodInfo>& lods) {
        for (const LodInfo& lod : lods) std::ofstream(dir / lod.file, std::ios::binary | std::ios::app) << "trailing";
        sizes = lods[0].file + ": " + std::to_string(lods[0].bytes + 8) + " bytes, the manifest says " +
                std::to_string(lods[0].bytes);
      });
  EXPECT_TRUE(std::any_of(log.begin(), log.end(), [&](const std::string& line) {
    return line.find(sizes) != std::string::npos;
  })) << sizes;
}

TEST(Disk, WalkCommandReplaysAPathAndReportsJson) {
  const char* cli = std::getenv("OCTOLOD_CLI");
  if (cli == nullptr || !std::filesystem::exists(cli)) GTEST_SKIP() << "OCTOLOD_CLI not built";
  const SyntheticTree tree = make_full_octree(4);
  const auto dir = scratch_dir("walk");
  testing::write_tree(tree, dir);
  const auto out = dir / "walk.json";
  const auto csv = dir / "walk.csv";
  // paced at 240 frames per second (0.5 s): unpaced, the 120 updates can all run before the
  // loader threads deliver the root on a busy machine, and nothing is loaded or drawn
  const std::string command = std::string(cli) + " walk " + dir.string() +
                              " --path far-to-near --frames 120 --fps 240 --budget 200K --json --csv " +
                              csv.string() + " > " + out.string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(out);
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc.at("frames"), 120);
  EXPECT_EQ(doc.at("frames_waiting_on_io"), 0);
  EXPECT_LE(doc.at("max_resident_bytes").get<std::uint64_t>(), 200u * 1024u);
  EXPECT_GT(doc.at("loads").get<std::uint64_t>(), 0u);
  EXPECT_GT(doc.at("mean_drawn_triangles").get<double>(), 0.0);
  for (const char* key : {"mean_resident_bytes", "fallback_frames", "hits", "misses", "hit_rate", "selection_cpu_ms_p99",
                          "selection_ms_p50", "selection_ms_p99", "selection_ms_max"})
    EXPECT_TRUE(doc.contains(key)) << key;
  std::ifstream rows(csv);
  std::string line;
  std::getline(rows, line);
  const auto columns = [](const std::string& row) {
    std::vector<std::string> cells;
    std::stringstream cells_in(row);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const std::vector<std::string> header = columns(line);
  const auto column = [&](const char* name) {
    const auto at = std::find(header.begin(), header.end(), name);
    EXPECT_NE(at, header.end()) << name << " not in " << line;
    return static_cast<std::size_t>(at - header.begin());
  };
  const std::size_t over_budget = column("loads_over_budget"), checks = column("cover_checks"),
                    out_of_checks = column("covers_out_of_checks"), wanted = column("wanted"),
                    visited = column("visited");
  ASSERT_EQ(header.size(), out_of_checks + 1) << line;
  int lines = 1, over_budget_rows = 0, out_of_checks_rows = 0, max_checks = 0;
  std::vector<int> wanted_per_frame, visited_per_frame;
  for (; std::getline(rows, line); ++lines) {
    const std::vector<std::string> cells = columns(line);
    ASSERT_EQ(cells.size(), header.size()) << line;
    over_budget_rows += std::stoi(cells[over_budget]) > 0;
    out_of_checks_rows += std::stoi(cells[out_of_checks]) > 0;
    max_checks = std::max(max_checks, std::stoi(cells[checks]));
    wanted_per_frame.push_back(std::stoi(cells[wanted]));
    visited_per_frame.push_back(std::stoi(cells[visited]));
  }
  EXPECT_EQ(lines, 121);  // header + one row per frame
  // The path's 60-degree perspective refines as it nears: from 12 r the root's coarse LOD (error
  // 2.56) is 3.6 px, so the root's fine one is wanted alone; at 0.6 r the camera is at the
  // cube's face and the cut reaches the leaves. (Its cameras were once orthographic, 1,920 units
  // high: every frame wanted only the root.)
  ASSERT_EQ(wanted_per_frame.size(), 120u);
  EXPECT_EQ(wanted_per_frame.front(), 1);
  EXPECT_GT(wanted_per_frame.back(), 8);
  EXPECT_GT(visited_per_frame.back(), 9);
  EXPECT_EQ(doc.at("frames_over_budget"), over_budget_rows);
  EXPECT_EQ(doc.at("frames_out_of_cover_checks"), out_of_checks_rows);
  EXPECT_EQ(doc.at("max_cover_checks"), max_checks);
  std::filesystem::remove_all(dir);
}

// --- open -------------------------------------------------------------------------------------

// A manifest built in code gets the checks read_manifest makes: a child index out of range would
// be read past the nodes, a cycle walked forever, an absolute file read outside the tree.
TEST(Open, RejectsAManifestThatIsNotATree) {
  const SyntheticTree t = make_full_octree(2);
  auto executor = std::make_shared<SynchronousExecutor>();
  Manifest out_of_range = t.manifest, cycle = t.manifest, outside = t.manifest;
  out_of_range.nodes[0].children[3] = 99;
  cycle.nodes[1].children[0] = 0;
  outside.nodes[2].lods[0].file = "/etc/passwd";
  for (const Manifest* m : {&out_of_range, &cycle, &outside}) {
    auto opened = StreamingTree::open(*m, t.source, executor, {});
    ASSERT_FALSE(opened.ok());
    EXPECT_EQ(opened.status().code(), ErrorCode::bad_input);
    EXPECT_NE(opened.status().message().find("StreamingTree::open: invalid manifest"), std::string::npos)
        << opened.status().message();
  }
}

TEST(Open, RejectsMeaninglessOptions) {
  SyntheticTree tree = make_full_octree(2);
  auto executor = std::make_shared<SynchronousExecutor>();
  auto open_with = [&](StreamingOptions o) {
    return StreamingTree::open(tree.manifest, tree.source, executor, std::move(o)).status().code();
  };
  StreamingOptions tiny;
  tiny.max_resident_bytes = 100;  // the root's coarsest LOD is 408 bytes
  EXPECT_EQ(open_with(tiny), ErrorCode::usage);
  StreamingOptions distance;
  distance.mode = SelectionMode::distance;
  EXPECT_EQ(open_with(distance), ErrorCode::usage);
  StreamingOptions sse;
  sse.target_sse_pixels = 0;
  EXPECT_EQ(open_with(sse), ErrorCode::usage);
  StreamingOptions no_checks;
  no_checks.prefetch_checks_per_frame = 0;
  EXPECT_EQ(open_with(no_checks), ErrorCode::usage);
  EXPECT_EQ(StreamingTree::open(Manifest{}, tree.source, executor, {}).status().code(), ErrorCode::bad_input);
}

}  // namespace
}  // namespace octolod::runtime
