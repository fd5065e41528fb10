// The bake pipeline (seed 3.4, 4.3; docs/design.md stages 3 and 6): the leaves hold exactly
// the input's triangles (their LOD 0; the LOD chains are lod_tree_test.cpp's), the tree obeys
// max_tris / max_depth, bounds and cells are consistent,
// the output does not depend on threads or budget, and failures (out of space, a killed or
// interrupted bake, bad paths) publish nothing and leave no temporary file.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "octolod/bake/bake.h"
#include "octolod/bake/soup.h"
#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/ply_writer.h"
#include "octolod/samplegen/sample_generator.h"
#include "octolod/formats/ply_reader.h"
#include "ply_test_helpers.h"
#include "record_file.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

// Inputs shared by every test (generated once): a 60K-triangle rock with every attribute and a
// 300K one for the tests that need a bake to run long enough to be killed.
class BakeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("octolod-bake-test-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    samplegen::SampleSpec spec;
    spec.shape = samplegen::Shape::rock;
    spec.triangles = 60'000;
    ASSERT_TRUE(samplegen::write_sample_ply(spec, small_ply()).ok());
    spec.triangles = 300'000;
    ASSERT_TRUE(samplegen::write_sample_ply(spec, large_ply()).ok());
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  void SetUp() override {
    dir_ = root_ / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::create_directories(dir_ / "work");
  }
  void TearDown() override { fs::remove_all(dir_); }

  static fs::path small_ply() { return root_ / "rock60k.ply"; }
  static fs::path large_ply() { return root_ / "rock300k.ply"; }
  fs::path path(const std::string& name) const { return dir_ / name; }
  fs::path work() const { return dir_ / "work"; }
  // A sample of `shape` with about `triangles` triangles (every attribute) at path(name).
  fs::path write_sample(samplegen::Shape shape, std::uint64_t triangles, const std::string& name) const {
    samplegen::SampleSpec spec;
    spec.shape = shape;
    spec.triangles = triangles;
    const Status written = samplegen::write_sample_ply(spec, path(name));
    EXPECT_TRUE(written.ok()) << written.message();
    return path(name);
  }

  BakeOptions options(const std::string& out) const {
    BakeOptions o;
    o.input = small_ply();
    o.output = path(out);
    o.max_tris = 1000;
    o.max_depth = 8;
    o.memory_budget_bytes = 24 << 20;  // max_tris 1000 needs 19 MiB
    o.work_dir = work();
    o.threads = 2;
    return o;
  }

  // Names in `dir` that belong to a bake's temporary files.
  static std::vector<std::string> temp_entries(const fs::path& dir) {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(".octolod-tmp-", 0) == 0 || name.rfind("octolod-", 0) == 0 ||
          name.find(".tmp") != std::string::npos)
        found.push_back(name);
    }
    return found;
  }
  void expect_leaves_hold_exactly_the_input_triangles(std::uint64_t budget) const;
  void expect_out_of_space_anywhere_fails_cleanly(const BakeOptions& o,
                                                  std::vector<std::string>& messages) const;
  void expect_no_temp_files() const {
    EXPECT_EQ(temp_entries(dir_), std::vector<std::string>{});
    EXPECT_EQ(temp_entries(work()), std::vector<std::string>{});
  }

  static fs::path root_;
  fs::path dir_;
};

fs::path BakeTest::root_;

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Every file under `root`, relative path -> bytes.
std::map<std::string, std::string> tree_files(const fs::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file()) files[fs::relative(e.path(), root).string()] = read_bytes(e.path());
  return files;
}

// The manifest without what legitimately differs between bakes of the same tree.
Manifest without_run_details(Manifest m) {
  m.stage_seconds.clear();
  m.stats.clear();
  m.parameters.threads = 0;
  m.parameters.memory_budget_bytes = 0;
  return m;
}

// OUT_DIR/manifest.json of a bake, checked against what the bake's report says about it: the
// same manifest without its nodes, their LOD count, the root's coarsest LOD.
Manifest written_manifest(const fs::path& root, const BakeReport& report) {
  auto m = read_tree_manifest(root);
  EXPECT_TRUE(m.ok()) << m.status().message();
  if (!m.ok()) return {};
  Manifest header = m.value();
  header.nodes.clear();
  EXPECT_EQ(manifest_to_json(header), manifest_to_json(report.header));
  std::uint64_t lods = 0;
  for (const NodeInfo& n : m->nodes) lods += n.lods.size();
  EXPECT_EQ(report.lods, lods);
  EXPECT_EQ(report.nodes, m->nodes.size());
  const std::vector<LodInfo>& root_lods = m->nodes.front().lods;
  EXPECT_EQ(report.root_coarsest_triangles, root_lods.empty() ? 0u : root_lods.back().triangles);
  return std::move(m).value();
}

using Triangle = std::vector<float>;  // 3 corners x layout.floats()

// The input's triangles as the soup stage reads them from the PLY (order: PLY order).
std::vector<Triangle> input_triangles(const fs::path& ply, const fs::path& work,
                                      VertexLayout& layout) {
  std::vector<Triangle> out;
  SoupOptions o;
  o.work_dir = work;
  o.order = SoupOrder::by_triangle;
  std::size_t record_bytes = 0;
  o.sink = [&](std::span<const std::byte> records) {
    for (std::size_t i = 0; i < records.size(); i += record_bytes) {
      Triangle t(3 * layout.floats());
      for (int c = 0; c < 3; ++c)
        load_soup_corner(records.data() + i, layout, c, t.data() + static_cast<std::size_t>(c) * layout.floats());
      out.push_back(std::move(t));
    }
    return Status{};
  };
  // The layout is only known after the header: read it with a first, counting pass.
  {
    SoupOptions probe;
    probe.work_dir = work;
    probe.sink = [](std::span<const std::byte>) { return Status{}; };
    auto r = build_soup(ply, probe);
    EXPECT_TRUE(r.ok());
    layout = r->layout;
  }
  record_bytes = soup_record_bytes(layout);
  EXPECT_TRUE(build_soup(ply, o).ok());
  return out;
}

std::vector<Triangle> mesh_triangles(const NodeMesh& mesh) {
  std::vector<Triangle> out;
  const std::size_t f = mesh.layout.floats();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    Triangle tri;
    for (int c = 0; c < 3; ++c) {
      const float* v = mesh.vertices.data() + std::size_t{mesh.indices[3 * t + static_cast<std::size_t>(c)]} * f;
      tri.insert(tri.end(), v, v + f);
    }
    out.push_back(std::move(tri));
  }
  return out;
}

bool inside(const Bounds& outer, const Bounds& inner) {
  for (std::size_t a = 0; a < 3; ++a)
    if (inner.min[a] < outer.min[a] || inner.max[a] > outer.max[a]) return false;
  return true;
}

// At 26 MiB every leaf is built in memory; at 16 MiB the largest ones (up to 3009 triangles,
// over 16 MiB's max_depth_leaf_triangles) are built streaming.
TEST_F(BakeTest, LeavesHoldExactlyTheInputTrianglesInAConsistentTree) {
  for (const std::uint64_t budget : {std::uint64_t{26} << 20, std::uint64_t{16} << 20}) {
    SCOPED_TRACE(budget >> 20);
    expect_leaves_hold_exactly_the_input_triangles(budget);
  }
}

void BakeTest::expect_leaves_hold_exactly_the_input_triangles(std::uint64_t budget) const {
  BakeOptions o = options("out");
  o.max_tris = 700;
  o.max_depth = 2;  // shallow enough that some leaves at max depth exceed max_tris
  o.memory_budget_bytes = budget;
  auto baked = bake(o);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  auto manifest = read_manifest(path("out") / "manifest.json");
  ASSERT_TRUE(manifest.ok()) << manifest.status().message();
  const Manifest& m = manifest.value();
  EXPECT_EQ(without_run_details(m).nodes.size(), baked->nodes);

  VertexLayout layout;
  std::vector<Triangle> expected = input_triangles(small_ply(), work(), layout);
  EXPECT_EQ(m.layout, layout);
  EXPECT_EQ(m.input_triangles, expected.size());

  std::vector<Triangle> found;
  bool some_leaf_over_max = false;
  bool some_leaf_over_cap = false;
  for (const NodeInfo& n : m.nodes) {
    if (n.parent >= 0) {
      const NodeInfo& p = m.nodes[static_cast<std::size_t>(n.parent)];
      EXPECT_TRUE(inside(p.cell, n.cell)) << n.path;
      EXPECT_TRUE(inside(p.bounds, n.bounds)) << n.path;
      EXPECT_EQ(n.path, (p.path.empty() ? "" : p.path + "/") +
                            std::to_string(std::find(p.children.begin(), p.children.end(),
                                                     &n - m.nodes.data()) - p.children.begin()));
    }
    if (!n.is_leaf()) {
      EXPECT_GT(n.source_triangles, o.max_tris) << n.path;
      EXPECT_FALSE(n.lods.empty()) << "internal node '" << n.path << "' has no LOD";
      std::uint64_t sum = 0;
      for (std::int32_t c : n.children)
        if (c >= 0) sum += m.nodes[static_cast<std::size_t>(c)].source_triangles;
      EXPECT_EQ(sum, n.source_triangles);
      continue;
    }
    EXPECT_TRUE(n.source_triangles <= o.max_tris || n.depth == o.max_depth) << n.path;
    some_leaf_over_max = some_leaf_over_max || n.source_triangles > o.max_tris;
    some_leaf_over_cap = some_leaf_over_cap ||
                         n.source_triangles > max_depth_leaf_triangles(budget, layout, o.max_tris);
    ASSERT_GE(n.lods.size(), 1u);
    EXPECT_EQ(n.lods[0].error, 0.0);
    EXPECT_EQ(n.lods[0].file, (n.path.empty() ? "" : n.path + "/") + "lod0.olod");
    const fs::path file = path("out") / n.lods[0].file;
    EXPECT_EQ(fs::file_size(file), n.lods[0].bytes);
    auto mesh = read_node_file(file);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    EXPECT_EQ(mesh->triangle_count(), n.source_triangles);
    EXPECT_EQ(mesh->triangle_count(), n.lods[0].triangles);
    EXPECT_EQ(mesh->vertex_count(), n.lods[0].vertices);
    EXPECT_TRUE(inside(n.bounds, mesh->bounds())) << "bounds of " << n.path;
    // Each triangle's centroid lies in the leaf's cell (up to float rounding of the cell).
    const float slack = (n.cell.max[0] - n.cell.min[0]) * 1e-4f;
    for (const Triangle& t : mesh_triangles(mesh.value())) {
      for (std::size_t a = 0; a < 3; ++a) {
        const float c = (t[static_cast<std::size_t>(a)] + t[layout.floats() + static_cast<std::size_t>(a)] +
                         t[2 * layout.floats() + static_cast<std::size_t>(a)]) / 3.0f;
        EXPECT_GE(c, n.cell.min[a] - slack);
        EXPECT_LE(c, n.cell.max[a] + slack);
      }
      found.push_back(t);
    }
  }
  EXPECT_TRUE(some_leaf_over_max) << "the test wants a leaf at max depth over max_tris";
  EXPECT_EQ(some_leaf_over_cap, budget < (std::uint64_t{26} << 20));
  EXPECT_EQ(m.nodes[0].source_triangles, expected.size());
  EXPECT_EQ(m.bounds, m.nodes[0].bounds);
  // Same multiset of triangles, attributes and winding included.
  std::sort(expected.begin(), expected.end());
  std::sort(found.begin(), found.end());
  EXPECT_TRUE(found == expected);
  expect_no_temp_files();
}

// The smallest budget whose max_depth_leaf_triangles reaches `triangles` (> max_tris).
std::uint64_t budget_for_leaf(std::uint64_t triangles, VertexLayout layout, std::uint32_t max_tris) {
  std::uint64_t low = kMinBakeBudget, high = std::uint64_t{1} << 40;
  while (low < high) {
    const std::uint64_t mid = low + (high - low) / 2;
    if (max_depth_leaf_triangles(mid, layout, max_tris) >= triangles) high = mid;
    else low = mid + 1;
  }
  return low;
}

// max_depth 2 leaves the 60K rock's largest leaf at max depth with thousands of triangles: under
// the budget whose cap is one triangle short it is built streaming, on the records path and on
// the in-memory octree alike, with the same tree, the same triangles in that leaf's LOD 0 (in
// the same order) and the same files everywhere else; the budget whose cap it just reaches
// bakes the same manifest as a large budget.
TEST_F(BakeTest, LeafAtMaxDepthOverTheBudgetsCapIsStreamedIntoTheSameTree) {
  BakeOptions o = options("out");
  o.max_tris = 700;
  o.max_depth = 2;
  o.lods = false;
  o.memory_budget_bytes = 64 << 20;
  auto earlier = bake(o);
  ASSERT_TRUE(earlier.ok()) << earlier.status().message();
  EXPECT_EQ(earlier->streamed_leaves, 0u);
  const std::map<std::string, std::string> before = tree_files(path("out"));
  const Manifest earlier_manifest = written_manifest(path("out"), earlier.value());
  const NodeInfo* largest = nullptr;
  for (const NodeInfo& n : earlier_manifest.nodes)
    if (n.is_leaf() && (!largest || n.source_triangles > largest->source_triangles)) largest = &n;
  ASSERT_TRUE(largest && largest->depth == 2 && largest->source_triangles > o.max_tris + 1);
  const std::uint64_t fits = budget_for_leaf(largest->source_triangles, earlier_manifest.layout, o.max_tris);
  auto lod0 = [](const fs::path& tree, const NodeInfo& n) {
    auto mesh = read_node_file(tree / n.lods[0].file);
    EXPECT_TRUE(mesh.ok()) << mesh.status().message();
    return mesh.ok() ? mesh_triangles(mesh.value()) : std::vector<Triangle>{};
  };
  const std::vector<Triangle> largest_triangles = lod0(path("out"), *largest);

  o.memory_budget_bytes = fits - 1;
  std::optional<Manifest> first;
  for (bool in_memory : {true, false}) {
    o.in_memory_octree = in_memory;
    o.output = path(in_memory ? "in-memory" : "records");
    auto streamed = bake(o);
    ASSERT_TRUE(streamed.ok()) << streamed.status().message();
    EXPECT_EQ(streamed->octree_in_memory, in_memory);
    EXPECT_EQ(streamed->streamed_leaves, 1u);
    EXPECT_EQ(streamed->largest_streamed_leaf_triangles, largest->source_triangles);
    EXPECT_EQ(streamed->header.stats.at("lod_streamed_leaves"), 1.0);
    const Manifest m = written_manifest(o.output, streamed.value());
    ASSERT_EQ(m.nodes.size(), earlier_manifest.nodes.size());
    std::size_t changed = 0;
    for (std::size_t i = 0; i < m.nodes.size(); ++i) {
      const NodeInfo& n = m.nodes[i];
      EXPECT_EQ(n.path, earlier_manifest.nodes[i].path);
      EXPECT_EQ(n.source_triangles, earlier_manifest.nodes[i].source_triangles);
      if (!n.is_leaf()) continue;
      ASSERT_EQ(n.lods.size(), 1u);
      if (n.source_triangles < largest->source_triangles) {
        EXPECT_EQ(read_bytes(o.output / n.lods[0].file), before.at(n.lods[0].file)) << n.path;
        continue;
      }
      ++changed;
      EXPECT_TRUE(lod0(o.output, n) == largest_triangles) << n.path;
    }
    EXPECT_EQ(changed, 1u);
    if (first) {
      EXPECT_EQ(manifest_to_json(without_run_details(m)), manifest_to_json(without_run_details(*first)));
    }
    first = m;
    expect_no_temp_files();
  }

  o.memory_budget_bytes = fits;
  o.output = path("out");
  auto baked = bake(o);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  EXPECT_EQ(manifest_to_json(without_run_details(written_manifest(o.output, baked.value()))),
            manifest_to_json(without_run_details(earlier_manifest)));
}

TEST_F(BakeTest, WithoutLodsLeavesHoldOnlyTheirOriginalTrianglesWithTightBounds) {
  BakeOptions o = options("out");
  o.lods = false;
  auto baked = bake(o);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  const Manifest m = written_manifest(path("out"), baked.value());
  EXPECT_EQ(m.parameters.method, "");
  std::size_t leaves = 0;
  for (const NodeInfo& n : m.nodes) {
    if (!n.is_leaf()) {
      EXPECT_TRUE(n.lods.empty()) << n.path;
      continue;
    }
    ++leaves;
    ASSERT_EQ(n.lods.size(), 1u) << n.path;
    auto mesh = read_node_file(path("out") / n.lods[0].file);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    EXPECT_EQ(mesh->triangle_count(), n.source_triangles);
    EXPECT_EQ(mesh->bounds(), n.bounds) << "tight bounds of " << n.path;
  }
  EXPECT_GT(leaves, 20u);
  EXPECT_EQ(tree_files(path("out")).size(), leaves + 1);
}

TEST_F(BakeTest, OneAndTwoThreadsWriteIdenticalTrees) {
  BakeOptions one = options("one");
  one.threads = 1;
  BakeOptions two = options("two");
  two.threads = 2;
  ASSERT_TRUE(bake(one).ok());
  ASSERT_TRUE(bake(two).ok());
  auto a = tree_files(path("one"));
  auto b = tree_files(path("two"));
  auto ma = read_manifest(path("one") / "manifest.json");
  auto mb = read_manifest(path("two") / "manifest.json");
  ASSERT_TRUE(ma.ok() && mb.ok());
  EXPECT_EQ(manifest_to_json(without_run_details(ma.value())),
            manifest_to_json(without_run_details(mb.value())));
  a.erase("manifest.json");
  b.erase("manifest.json");
  EXPECT_GT(a.size(), 20u);
  EXPECT_TRUE(a == b);
}

TEST_F(BakeTest, TinyBudgetOutOfCoreGivesTheSameTreeAsALargeBudget) {
  BakeOptions small = options("small");
  // leaves small enough for a 2 MiB budget's node work (lod_tree.h, max_node_work_bytes)
  small.memory_budget_bytes = 2 << 20;
  small.force_out_of_core = true;
  small.max_tris = 60;
  BakeOptions large = options("large");
  large.memory_budget_bytes = 256 << 20;
  large.max_tris = 60;
  // In core without the in-memory octree: the soup's records sorted by cell.
  BakeOptions records = large;
  records.output = path("records");
  records.in_memory_octree = false;
  auto rs = bake(small);
  ASSERT_TRUE(rs.ok()) << rs.status().message();
  auto rl = bake(large);
  ASSERT_TRUE(rl.ok()) << rl.status().message();
  auto rr = bake(records);
  ASSERT_TRUE(rr.ok()) << rr.status().message();
  EXPECT_FALSE(rs->soup_in_core);
  EXPECT_TRUE(rl->soup_in_core);
  EXPECT_TRUE(rr->soup_in_core);
  EXPECT_FALSE(rs->octree_in_memory);
  EXPECT_TRUE(rl->octree_in_memory);
  EXPECT_FALSE(rr->octree_in_memory);
  EXPECT_GT(rs->sort_runs, 1u);
  EXPECT_EQ(rl->sort_runs, 0u);
  EXPECT_EQ(rr->sort_runs, 0u);
  // Out of core the soup goes straight into the octree sort; in core through a soup file.
  EXPECT_EQ(rs->header.stats.at("soup_streamed_to_sort"), 1.0);
  EXPECT_EQ(rr->header.stats.at("soup_streamed_to_sort"), 0.0);
  // The small budget keeps few children's LODs in memory: parents re-read the others.
  EXPECT_GT(rs->header.stats.at("lod_rereads"), 0.0);
  EXPECT_EQ(rl->header.stats.at("lod_rereads"), 0.0);
  auto a = tree_files(path("small"));
  auto b = tree_files(path("large"));
  auto c = tree_files(path("records"));
  a.erase("manifest.json");
  b.erase("manifest.json");
  c.erase("manifest.json");
  EXPECT_TRUE(a == b);
  EXPECT_TRUE(c == b);
  const Manifest ml = written_manifest(path("large"), rl.value());
  EXPECT_GT(ml.nodes.size(), 20u);
  EXPECT_EQ(manifest_to_json(without_run_details(written_manifest(path("small"), rs.value()))),
            manifest_to_json(without_run_details(ml)));
  EXPECT_EQ(manifest_to_json(without_run_details(written_manifest(path("records"), rr.value()))),
            manifest_to_json(without_run_details(ml)));
}

// A flat model's Morton keys share their upper y bits (a city 60 units high on a ground
// thousands wide): the out-of-core sort distributes by the bits that vary instead
// (VaryingKeyBits) and builds the tree the in-memory octree builds from the full keys.
TEST_F(BakeTest, FlatModelOutOfCoreSortsByTheBitsThatVaryIntoTheSameTree) {
  BakeOptions small = options("small");
  small.input = write_sample(samplegen::Shape::city, 30'000, "city.ply");
  small.memory_budget_bytes = 2 << 20;
  small.force_out_of_core = true;
  small.max_tris = 60;
  BakeOptions large = small;
  large.output = path("large");
  large.memory_budget_bytes = 256 << 20;
  large.force_out_of_core = false;
  auto rs = bake(small);
  ASSERT_TRUE(rs.ok()) << rs.status().message();
  auto rl = bake(large);
  ASSERT_TRUE(rl.ok()) << rl.status().message();
  EXPECT_TRUE(rl->octree_in_memory);
  EXPECT_GT(rs->sort_runs, 1u);
  const double key_bits = rs->header.stats.at("octree_sort_key_bits");
  EXPECT_GT(key_bits, 0.0);
  EXPECT_LE(key_bits, 3.0 * small.max_depth - 3);  // at least the top levels of y
  EXPECT_EQ(rl->header.stats.at("octree_sort_key_bits"), 0.0);
  auto a = tree_files(path("small"));
  auto b = tree_files(path("large"));
  a.erase("manifest.json");
  b.erase("manifest.json");
  EXPECT_GT(a.size(), 20u);
  EXPECT_TRUE(a == b);
  EXPECT_EQ(manifest_to_json(without_run_details(written_manifest(path("small"), rs.value()))),
            manifest_to_json(without_run_details(written_manifest(path("large"), rl.value()))));
}

// A textured scan's PLY has its UVs per face corner (texcoord) and one vertex per position; a
// segmented scan or a CAD export has a colour per face. The same rock written that way
// (test::write_face_attribute_ply, its seams welded) bakes out of core into the node files its
// vertex-per-wedge PLY gives in memory (the in-memory octree): UVs per corner, and UVs per
// corner with colours per face (every 97 triangles another colour, test::with_face_colours).
TEST_F(BakeTest, CornerAttributesBakeIntoTheSameTreeAsWedges) {
  auto rock = read_ply(small_ply());
  ASSERT_TRUE(rock.ok()) << rock.status().message();
  const test::TestMesh coloured = test::with_face_colours(rock->info.layout, rock->vertices, rock->triangles);
  for (const CornerAttributes corners : {CornerAttributes{.uv = true}, CornerAttributes{.color = true, .uv = true}}) {
    SCOPED_TRACE(corners.color ? "face colours and corner uvs" : "corner uvs");
    const std::string name = corners.color ? "coloured" : "textured";
    const std::vector<float>& vertices = corners.color ? coloured.vertices : rock->vertices;
    const std::vector<std::uint32_t>& triangles = corners.color ? coloured.triangles : rock->triangles;
    PlyWriteOptions write_options;
    write_options.layout = rock->info.layout;
    write_options.color_type = PlyColorType::float32;  // exact
    ASSERT_TRUE(write_ply(path(name + "-wedges.ply"), write_options, vertices, triangles).ok());
    test::write_face_attribute_ply(path(name + "-corners.ply"), rock->info.layout, vertices, triangles, corners);
    BakeOptions wedges = options(name + "-wedges");
    wedges.input = path(name + "-wedges.ply");
    wedges.memory_budget_bytes = 256 << 20;
    wedges.max_tris = 60;
    BakeOptions on_corners = options(name + "-corners");
    on_corners.input = path(name + "-corners.ply");
    on_corners.memory_budget_bytes = 2 << 20;
    on_corners.force_out_of_core = true;
    on_corners.max_tris = 60;
    auto rw = bake(wedges);
    ASSERT_TRUE(rw.ok()) << rw.status().message();
    auto rc = bake(on_corners);
    ASSERT_TRUE(rc.ok()) << rc.status().message();
    EXPECT_TRUE(rw->octree_in_memory);
    EXPECT_FALSE(rc->soup_in_core);
    EXPECT_LT(rc->header.input_vertices, rw->header.input_vertices);  // the seams' copies welded
    EXPECT_EQ(rc->header.layout, rw->header.layout);
    auto a = tree_files(path(name + "-wedges"));
    auto b = tree_files(path(name + "-corners"));
    a.erase("manifest.json");
    b.erase("manifest.json");
    EXPECT_GT(a.size(), 20u);
    EXPECT_TRUE(a == b);
    Manifest mc = without_run_details(written_manifest(path(name + "-corners"), rc.value()));
    mc.parameters.input = wedges.input.string();
    mc.input_vertices = rw->header.input_vertices;
    EXPECT_EQ(manifest_to_json(mc),
              manifest_to_json(without_run_details(written_manifest(path(name + "-wedges"), rw.value()))));
  }
}

// The image a PLY's TextureFile comment names (next to it) is copied into TREE/texture/ and
// named by the manifest. A missing image, a name reaching outside the PLY's directory and an
// input without UVs give a tree without a texture and say why; of several images the first is
// copied, with a warning.
TEST_F(BakeTest, TheTextureThePlyNamesIsCopiedIntoTheTree) {
  auto mesh = read_ply(small_ply());
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  fs::create_directories(path("in"));
  const std::string image = "\x89PNG\r\n\x1a\n not really an image, but bytes to copy";
  test::write_bytes(path("in/rock tex.png"), image);
  test::write_bytes(path("outside.png"), image);
  const auto bake_named = [&](const std::string& texture, const std::string& out) {
    test::write_face_attribute_ply(path("in/rock.ply"), mesh->info.layout, mesh->vertices, mesh->triangles,
                                   CornerAttributes{.uv = true}, texture);
    BakeOptions o = options(out);
    o.input = path("in/rock.ply");
    auto r = bake(o);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? std::move(r).value() : BakeReport{};
  };
  const BakeReport copied = bake_named("rock tex.png", "copied");
  EXPECT_EQ(copied.texture_warning, "");
  EXPECT_EQ(written_manifest(path("copied"), copied).texture, "texture/rock tex.png");
  EXPECT_EQ(read_bytes(path("copied/texture/rock tex.png")), image);

  // several textures (MeshLab's texnumber atlases): the first, and a warning that the others are not
  {
    std::string bytes = read_bytes(path("in/rock.ply"));
    const std::string first = "comment TextureFile rock tex.png\n";
    bytes.insert(bytes.find(first) + first.size(), "comment TextureFile rock 2.png\n");
    test::write_bytes(path("in/atlas.ply"), bytes);
    BakeOptions o = options("atlas");
    o.input = path("in/atlas.ply");
    auto r = bake(o);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->texture_warning, "its header names 2 textures (TextureFile comments); a tree carries one, the first "
                                  "('rock tex.png'): faces whose UVs index another show it instead");
    EXPECT_EQ(read_bytes(path("atlas/texture/rock tex.png")), image);
  }

  const std::pair<std::string, std::string> refused[] = {
      {"missing.png", "its TextureFile comment names 'missing.png', but '" + path("in/missing.png").string() +
                          "' is not a file: no texture in the tree"},
      {"../outside.png", "its TextureFile comment names '../outside.png', which is not a path inside the PLY's "
                         "directory: not copied into the tree"}};
  for (const auto& [name, warning] : refused) {
    const BakeReport r = bake_named(name, "refused");
    EXPECT_EQ(r.texture_warning, warning);
    EXPECT_EQ(written_manifest(path("refused"), r).texture, "");
    EXPECT_FALSE(fs::exists(path("refused/texture")));
  }
  // without UVs nothing indexes the image
  test::write_bytes(path("in/flat.ply"),
                    "ply\nformat ascii 1.0\ncomment TextureFile rock tex.png\nelement vertex 3\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  BakeOptions flat = options("flat");
  flat.input = path("in/flat.ply");
  auto r = bake(flat);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->texture_warning,
            "its TextureFile comment names 'rock tex.png', but it has no texture coordinates: no texture in the tree");
  EXPECT_FALSE(fs::exists(path("flat/texture")));
}

TEST_F(BakeTest, ASecondBakeReplacesTheFirstAtomically) {
  ASSERT_TRUE(bake(options("out")).ok());
  BakeOptions again = options("out");
  again.max_tris = 3000;
  again.memory_budget_bytes = 64 << 20;  // larger leaves, larger node work
  auto r = bake(again);
  ASSERT_TRUE(r.ok()) << r.status().message();
  auto m = read_manifest(path("out") / "manifest.json");
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->parameters.max_tris, 3000u);
  // No file of the first tree survives: every file is listed in the new manifest.
  std::size_t listed = 1;
  for (const NodeInfo& n : m->nodes) listed += n.lods.size();
  EXPECT_EQ(tree_files(path("out")).size(), listed);
  expect_no_temp_files();
}

// The new tree replaces the whole output directory, so an input inside it is refused before
// anything is written, and stays where it was with the earlier tree.
TEST_F(BakeTest, AnInputInsideTheOutputDirectoryIsRefused) {
  ASSERT_TRUE(bake(options("out")).ok());
  BakeOptions inside = options("out");
  inside.input = path("out") / "sub" / ".." / "input.ply";
  fs::copy_file(options("out").input, path("out") / "input.ply");
  const auto before = tree_files(path("out"));
  auto r = bake(inside);
  ASSERT_EQ(r.status().code(), ErrorCode::usage);
  EXPECT_NE(r.status().message().find("lies inside the output directory"), std::string::npos) << r.status().message();
  EXPECT_TRUE(tree_files(path("out")) == before);
  EXPECT_TRUE(fs::exists(path("out") / "input.ply"));
  expect_no_temp_files();
}

// Out of space at any point of a bake whose writes go through the record files (soup, sort
// runs, a streamed leaf's spill and edges): an io error naming the device's reason, the earlier
// tree unchanged, no temporary file. `messages` gets the errors.
void BakeTest::expect_out_of_space_anywhere_fails_cleanly(const BakeOptions& o,
                                                          std::vector<std::string>& messages) const {
  std::uint64_t total = 0;  // what the out-of-core bake writes through the hooked calls
  {
    ScopedIoFault never(ScopedIoFault::Op::write, std::uint64_t{1} << 40, ENOSPC);
    auto r = bake(o);
    ASSERT_TRUE(r.ok()) << r.status().message();
    total = never.bytes_seen();
  }
  ASSERT_GT(total, std::uint64_t{1} << 20);
  const auto before = tree_files(path("out"));
  for (const std::uint64_t after : {std::uint64_t{0}, total / 5, total / 2, total * 9 / 10}) {
    Status failure;
    {
      ScopedIoFault fault(ScopedIoFault::Op::write, after, ENOSPC);
      auto r = bake(o);
      if (!r.ok()) failure = r.status();
    }
    ASSERT_FALSE(failure.ok()) << "fault after " << after;
    EXPECT_EQ(failure.code(), ErrorCode::io);
    EXPECT_NE(failure.message().find("No space left on device"), std::string::npos)
        << failure.message();
    messages.push_back(failure.message());
    EXPECT_TRUE(tree_files(path("out")) == before);
    expect_no_temp_files();
  }
}

TEST_F(BakeTest, OutOfSpaceAnywhereLeavesThePreviousTreeAndNoTemporaryFile) {
  BakeOptions o = options("out");
  o.force_out_of_core = true;
  o.memory_budget_bytes = 4 << 20;
  o.max_tris = 150;  // node work that fits 4 MiB
  std::vector<std::string> messages;
  expect_out_of_space_anywhere_fails_cleanly(o, messages);
}

// The same with the rock in one root leaf, far over 4M's cap: built streaming (some fault hits
// the leaf's own files; without LODs, to keep the five bakes short under sanitizers).
TEST_F(BakeTest, OutOfSpaceInAStreamedLeafLeavesThePreviousTreeAndNoTemporaryFile) {
  BakeOptions o = options("out");
  o.force_out_of_core = true;
  o.memory_budget_bytes = 4 << 20;
  o.max_depth = 0;
  o.lods = false;
  std::vector<std::string> messages;
  expect_out_of_space_anywhere_fails_cleanly(o, messages);
  EXPECT_TRUE(std::any_of(messages.begin(), messages.end(), [](const std::string& m) {
    return m.find("-leaf") != std::string::npos;
  })) << "no fault in the streamed leaf's files";
}

TEST_F(BakeTest, BadOptionsAndPathsAreReportedBeforeAnythingIsWritten) {
  BakeOptions o = options("out");
  o.max_tris = 0;
  EXPECT_EQ(bake(o).status().code(), ErrorCode::usage);
  o = options("out");
  o.max_depth = 22;
  EXPECT_EQ(bake(o).status().code(), ErrorCode::usage);
  o = options("out");
  o.memory_budget_bytes = 1000;
  EXPECT_EQ(bake(o).status().code(), ErrorCode::usage);
  for (const double ratio : {0.0, 0.09, 0.51, 1.0, std::nan("")}) {
    o = options("out");
    o.lod_ratio = ratio;
    EXPECT_EQ(bake(o).status().code(), ErrorCode::usage) << ratio;
  }
  o = options("out");
  o.max_tris = 1'000'000;  // leaf buffers cannot fit a 16 MiB budget
  EXPECT_EQ(bake(o).status().code(), ErrorCode::usage);
  // A non-empty directory that is not a bake is never replaced.
  fs::create_directories(path("mine"));
  std::ofstream(path("mine") / "notes.txt") << "precious";
  o = options("mine");
  EXPECT_EQ(bake(o).status().code(), ErrorCode::usage);
  EXPECT_EQ(read_bytes(path("mine") / "notes.txt"), "precious");
  // Output under a regular file: the system refuses.
  std::ofstream(path("file")) << "x";
  o = options("file/out");
  EXPECT_EQ(bake(o).status().code(), ErrorCode::io);
  // Missing input.
  o = options("out");
  o.input = path("missing.ply");
  EXPECT_EQ(bake(o).status().code(), ErrorCode::io);
  EXPECT_FALSE(fs::exists(path("out")));
  expect_no_temp_files();
}

// The budget a refused bake names ("a budget of N MiB suffices"), after checking that it was refused
// as a usage error; 0 when the message names none.
std::uint64_t needed_mib(const Result<BakeReport>& refused) {
  EXPECT_EQ(refused.status().code(), ErrorCode::usage);
  const std::string message = refused.status().message();
  const std::string phrase = "a budget of ";
  const std::size_t at = message.find(phrase);
  EXPECT_NE(at, std::string::npos) << message;
  return at == std::string::npos ? 0 : std::stoull(message.substr(at + phrase.size()));
}

// A budget too small for max_tris (node work, leaf buffers, a quarter for the sort) is refused
// before anything is written, with the budget that suffices; that budget bakes, and the
// program's share (BakeOptions::program_bytes, the CLI's 8 MiB) comes on top of it.
TEST_F(BakeTest, ATooSmallBudgetNamesTheBudgetThatSuffices) {
  BakeOptions o = options("out");
  o.memory_budget_bytes = 8 << 20;
  const std::uint64_t needed = needed_mib(bake(o));
  EXPECT_GT(needed, 8u);
  EXPECT_FALSE(fs::exists(path("out")));
  expect_no_temp_files();

  o.memory_budget_bytes = needed << 20;
  auto baked = bake(o);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  EXPECT_EQ(written_manifest(path("out"), baked.value()).parameters.memory_budget_bytes, needed << 20);

  o.program_bytes = 8 << 20;  // the same budget no longer leaves the bake enough
  auto short_by_the_program = bake(o);
  ASSERT_EQ(short_by_the_program.status().code(), ErrorCode::usage);
  EXPECT_NE(short_by_the_program.status().message().find("a budget of " + std::to_string(needed + 8) + " MiB suffices"),
            std::string::npos)
      << short_by_the_program.status().message();
  o.memory_budget_bytes = (needed + 8) << 20;
  EXPECT_TRUE(bake(o).ok());
}

// Every thread past the second takes kNodeThreadBytes of the budget. A count the caller asks for
// that the budget cannot hold is refused by name; the machine's count (threads 0) gives way to
// the budget instead: where 2 threads are refused, it bakes on 1.
TEST_F(BakeTest, NodeThreadsTakeTheirShareOfTheBudget) {
  BakeOptions o = options("out");
  o.threads = 1000;
  auto refused = bake(o);
  EXPECT_NE(refused.status().message().find("on 1000 threads"), std::string::npos) << refused.status().message();
  EXPECT_GT(needed_mib(refused), 24u);
  EXPECT_FALSE(fs::exists(path("out")));

  // the smallest budget that 2 threads pass, to 16 KiB (refusals come before any work)
  o.threads = 2;
  std::uint64_t refused_at = 8 << 20, passes_at = 24 << 20;
  while (passes_at - refused_at > (16 << 10)) {
    o.memory_budget_bytes = (refused_at + passes_at) / 2 / 1024 * 1024;
    (bake(o).ok() ? passes_at : refused_at) = o.memory_budget_bytes;
  }
  o.memory_budget_bytes = refused_at;
  ASSERT_EQ(bake(o).status().code(), ErrorCode::usage);
  o.threads = 0;
  auto automatic = bake(o);
  ASSERT_TRUE(automatic.ok()) << automatic.status().message();
  EXPECT_EQ(written_manifest(path("out"), automatic.value()).parameters.threads, 1u);
  expect_no_temp_files();
}

// An input smaller than max_tris is one leaf of its own size: the budget is divided for its
// triangles (counted, as the header's faces may be polygons), not for a leaf of max_tris (which
// would need 1.8 GiB at max_tris 100000). Refused, the message names the input's size and the
// budget that suffices; the tree is the one a large budget bakes.
TEST_F(BakeTest, ASmallInputIsBudgetedForItsOwnSize) {
  BakeOptions o = options("out");
  o.input = write_sample(samplegen::Shape::rock, 3'000, "rock3k.ply");
  o.max_tris = 100'000;
  o.memory_budget_bytes = 8 << 20;
  auto refused = bake(o);
  EXPECT_NE(refused.status().message().find("an input of 3000 triangles"), std::string::npos)
      << refused.status().message();
  const std::uint64_t needed = needed_mib(refused);
  EXPECT_GT(needed, 8u);
  EXPECT_LT(needed, 24u);
  EXPECT_FALSE(fs::exists(path("out")));
  expect_no_temp_files();

  o.memory_budget_bytes = needed << 20;
  auto baked = bake(o);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  const Manifest small = written_manifest(path("out"), baked.value());
  ASSERT_EQ(small.nodes.size(), 1u);
  EXPECT_EQ(small.nodes[0].source_triangles, 3'000u);

  BakeOptions large = o;
  large.output = path("large");
  large.memory_budget_bytes = std::uint64_t{2} << 30;
  auto reference = bake(large);
  ASSERT_TRUE(reference.ok()) << reference.status().message();
  std::map<std::string, std::string> files = tree_files(path("out")), expected = tree_files(path("large"));
  files.erase("manifest.json");
  expected.erase("manifest.json");
  EXPECT_EQ(files, expected);
  EXPECT_EQ(manifest_to_json(without_run_details(small)),
            manifest_to_json(without_run_details(written_manifest(path("large"), reference.value()))));
}

TEST_F(BakeTest, AMeshWithoutTrianglesIsRefusedAndTheEarlierTreeKept) {
  // Such a tree would be refused by every command that reads trees, and would have replaced
  // the good one.
  ASSERT_TRUE(bake(options("out")).ok());
  const auto before = tree_files(path("out"));
  std::ofstream(path("empty.ply")) << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                      "property float y\nproperty float z\nelement face 0\n"
                                      "property list uchar int vertex_indices\nend_header\n0 0 0\n";
  BakeOptions o = options("out");
  o.input = path("empty.ply");
  auto r = bake(o);
  ASSERT_EQ(r.status().code(), ErrorCode::bad_input);
  EXPECT_NE(r.status().message().find("empty.ply: the mesh has no triangles (1 vertices, 0 faces)"),
            std::string::npos)
      << r.status().message();
  EXPECT_TRUE(tree_files(path("out")) == before);
  expect_no_temp_files();
}

TEST_F(BakeTest, EveryFaceTwiceSimplifiesLikeEveryFaceOnce) {
  // Exported assets sometimes hold every face twice. The copies cancel in pairs under the mod-2
  // output rule unless the simplifier drops the repeats first: without that, no node of this
  // input got a second LOD and the root kept all 2 x 20K triangles.
  samplegen::SampleSpec spec;
  spec.shape = samplegen::Shape::rock;
  spec.triangles = 20'000;
  spec.layout = {true, false, false};
  Result<NodeMesh> mesh = samplegen::generate_sample_mesh(spec);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  std::vector<std::uint32_t> twice = mesh->indices;
  twice.insert(twice.end(), mesh->indices.begin(), mesh->indices.end());
  PlyWriteOptions ply;
  ply.layout = mesh->layout;
  ASSERT_TRUE(write_ply(path("once.ply"), ply, mesh->vertices, mesh->indices).ok());
  ASSERT_TRUE(write_ply(path("twice.ply"), ply, mesh->vertices, twice).ok());
  auto root_coarsest = [&](const std::string& name) -> std::size_t {
    BakeOptions o = options(name);
    o.input = path(name + ".ply");
    auto r = bake(o);
    EXPECT_TRUE(r.ok()) << r.status().message();
    auto m = read_manifest(path(name) / "manifest.json");
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (!m.ok() || m->nodes[0].lods.empty()) return 0;
    return m->nodes[0].lods.back().triangles;
  };
  const std::size_t once = root_coarsest("once"), twice_coarsest = root_coarsest("twice");
  EXPECT_GT(once, 0u);
  EXPECT_LE(once, 512u);
  EXPECT_GT(twice_coarsest, 0u);
  EXPECT_LE(twice_coarsest, 512u);
}

// --- the CLI, run as a child process (OCTOLOD_CLI) ---

const char* cli_path() { return std::getenv("OCTOLOD_CLI"); }

// fork + exec of the CLI with `args`; `before_exec` runs in the child.
pid_t spawn_cli(const std::vector<std::string>& args, void (*before_exec)() = nullptr) {
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(cli_path()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (before_exec) before_exec();
    const int devnull = ::open("/dev/null", O_WRONLY);
    ::dup2(devnull, STDOUT_FILENO);
    ::execv(argv[0], argv.data());
    std::_Exit(127);
  }
  return pid;
}

int wait_status(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

// Waits until a bake child has created its temporary directory in `dir` (and a little more).
void wait_for_temp_dir(const fs::path& dir, pid_t pid) {
  const std::string prefix = ".octolod-tmp-" + std::to_string(pid) + "-";
  for (int i = 0; i < 2000; ++i) {
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().rfind(prefix, 0) == 0) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// Sends `sig` to the child `pid` once it has made its temporary directory in `dir` (and a
// little more), and returns how the child ended.
int signal_once_started(pid_t pid, const fs::path& dir, int sig) {
  wait_for_temp_dir(dir, pid);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ::kill(pid, sig);
  return wait_status(pid);
}

std::vector<std::string> bake_args(const fs::path& in, const fs::path& out, const fs::path& work) {
  return {"bake", in.string(), "-o", out.string(), "--work-dir", work.string(), "--memory", "24M",
          "--max-tris", "500", "--threads", "2"};
}

TEST_F(BakeTest, KilledBakeLeavesNothingThatBreaksTheNextRun) {
  ASSERT_NE(cli_path(), nullptr);
  const pid_t pid = spawn_cli(bake_args(large_ply(), path("out"), work()));
  ASSERT_GT(pid, 0);
  const int status = signal_once_started(pid, work(), SIGKILL);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the bake finished before it was killed";
  EXPECT_FALSE(fs::exists(path("out")));
  EXPECT_FALSE(temp_entries(work()).empty()) << "SIGKILL cannot be cleaned up after";

  const pid_t again = spawn_cli(bake_args(large_ply(), path("out"), work()));
  const int again_status = wait_status(again);
  ASSERT_TRUE(WIFEXITED(again_status));
  EXPECT_EQ(WEXITSTATUS(again_status), 0);
  EXPECT_TRUE(read_manifest(path("out") / "manifest.json").ok());
  expect_no_temp_files();  // the dead bake's directories were removed too
}

TEST_F(BakeTest, InterruptedBakeRemovesItsTemporaryFilesAndDiesBySignal) {
  ASSERT_NE(cli_path(), nullptr);
  for (const int sig : {SIGINT, SIGTERM}) {
    const int status = signal_once_started(spawn_cli(bake_args(large_ply(), path("out"), work())), work(), sig);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the bake finished before the signal";
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_FALSE(fs::exists(path("out")));
    expect_no_temp_files();
  }
}

// `octolod sample` stages its file the same way: a large sample interrupted leaves neither it
// nor a temporary behind (it used to leave an 80-97 MB "<output>.tmp-*" file).
TEST_F(BakeTest, InterruptedSampleLeavesNothingBehind) {
  ASSERT_NE(cli_path(), nullptr);
  const int status = signal_once_started(
      spawn_cli({"sample", "--shape", "rock", "--triangles", "200M", "-o", path("big.ply").string()}), dir_, SIGINT);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the sample finished before the signal";
  EXPECT_EQ(WTERMSIG(status), SIGINT);
  EXPECT_FALSE(fs::exists(path("big.ply")));
  expect_no_temp_files();
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

// Files of the 60K rock's tree over 64 KiB (its upper nodes' LOD 0s) cannot be written.
void limit_file_size() {
  ::signal(SIGXFSZ, SIG_IGN);  // writes past the limit fail with EFBIG instead of killing
  rlimit limit{64 << 10, 64 << 10};
  ::setrlimit(RLIMIT_FSIZE, &limit);
}

TEST_F(BakeTest, CliExitCodesForWriteFailureBadInputAndUnwritableOutput) {
  ASSERT_NE(cli_path(), nullptr);
  // Writes refused by the system (file size limit): exit 4, nothing left behind.
  int status = wait_status(spawn_cli(bake_args(small_ply(), path("out"), work()), limit_file_size));
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 4);
  EXPECT_FALSE(fs::exists(path("out")));
  expect_no_temp_files();

  std::ofstream(path("bad.ply")) << "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n";
  status = wait_status(spawn_cli(bake_args(path("bad.ply"), path("out"), work())));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ofstream(path("file")) << "x";
  status = wait_status(spawn_cli(bake_args(small_ply(), path("file") / "out", work())));
  EXPECT_EQ(WEXITSTATUS(status), 4);
  expect_no_temp_files();

  // A LOD ratio outside [0.1, 0.5]: a usage error before anything is written; inside, the
  // manifest records it.
  std::vector<std::string> args = bake_args(small_ply(), path("out"), work());
  args.insert(args.end(), {"--lod-ratio", "0.7"});
  status = wait_status(spawn_cli(args));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_FALSE(fs::exists(path("out")));
  args.back() = "0.3";
  status = wait_status(spawn_cli(args));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  auto manifest = read_manifest(path("out") / "manifest.json");
  ASSERT_TRUE(manifest.ok()) << manifest.status().message();
  EXPECT_EQ(manifest->parameters.lod_ratio, 0.3);
  status = wait_status(spawn_cli({"--json", "info", path("out").string()}));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  status = wait_status(spawn_cli({"info", path("missing").string()}));
  EXPECT_EQ(WEXITSTATUS(status), 4);
}

// The 60K rock in one root leaf, far over the cap of --memory 24M (the bake's 16 MiB after the
// program's share): built streaming (exit 0), a root whose LOD 1 fits the in-memory cap, no
// temporary file left.
// Where stderr_to_file sends a spawned CLI's stderr.
std::string stderr_path;
void stderr_to_file() {
  const int fd = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(fd, STDERR_FILENO);
}

// ... and says so: the leaf's steep LOD step and what avoids it.
TEST_F(BakeTest, CliBakesALeafAtMaxDepthOverTheCapStreaming) {
  ASSERT_NE(cli_path(), nullptr);
  std::vector<std::string> args = bake_args(small_ply(), path("out"), work());
  args.insert(args.end(), {"--max-depth", "0"});
  stderr_path = path("stderr.txt").string();
  const int status = wait_status(spawn_cli(args, stderr_to_file));
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  auto m = read_manifest(path("out") / "manifest.json");
  ASSERT_TRUE(m.ok()) << m.status().message();
  ASSERT_EQ(m->nodes.size(), 1u);
  EXPECT_EQ(m->nodes[0].lods[0].triangles, m->input_triangles);
  ASSERT_GE(m->nodes[0].lods.size(), 2u);
  const std::uint64_t cap = max_depth_leaf_triangles((std::uint64_t{24} << 20) - kCliProgramBytes, m->layout, 500);
  EXPECT_LE(m->nodes[0].lods[1].triangles, cap);
  EXPECT_NE(read_bytes(path("stderr.txt"))
                .find("1 leaf at --max-depth 0 held more triangles than --memory lets a leaf simplify in memory (the "
                      "largest " + std::to_string(m->input_triangles) + "): built streaming, with a LOD 1 of at most " +
                      std::to_string(cap) + " triangles"),
            std::string::npos)
      << read_bytes(path("stderr.txt"));
  fs::remove(path("stderr.txt"));
  expect_no_temp_files();
}

}  // namespace
}  // namespace octolod::bake
