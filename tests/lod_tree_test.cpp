// The bake's LOD hierarchy (seed 3.5.3, 5.3.2; docs/design.md stage 5; issue 4 "Checked by"):
// every node has a LOD chain, any mix of node LODs that covers a closed model is closed (no
// crack), every stored error bounds the measured distance from the node's original triangles,
// and the tree is the same for any thread count.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "octolod/bake/bake.h"
#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/ply_writer.h"
#include "octolod/measure/triangle_bvh.h"
#include "octolod/samplegen/sample_generator.h"
#include "lod_tree.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

// Sanitized and unoptimized builds run the same checks on smaller inputs (CI time).
#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
constexpr std::uint64_t kScale = 5;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr std::uint64_t kScale = 5;
#else
constexpr std::uint64_t kScale = 1;
#endif
#else
constexpr std::uint64_t kScale = 1;
#endif

// A baked tree with every node's LOD meshes loaded.
struct LoadedTree {
  Manifest manifest;
  std::vector<std::vector<NodeMesh>> lods;  // by node, finest first
};

LoadedTree load_tree(const fs::path& dir) {
  LoadedTree t;
  auto m = read_manifest(dir / "manifest.json");
  EXPECT_TRUE(m.ok()) << m.status().message();
  if (!m.ok()) return t;
  t.manifest = std::move(m).value();
  for (const NodeInfo& n : t.manifest.nodes) {
    t.lods.emplace_back();
    for (const LodInfo& l : n.lods) {
      auto mesh = read_node_file(dir / l.file);
      EXPECT_TRUE(mesh.ok()) << mesh.status().message();
      t.lods.back().push_back(mesh.ok() ? std::move(mesh).value() : NodeMesh{});
    }
  }
  return t;
}

// Inputs generated once for the suite: a closed rock, a city (closed boxes on a ground quad), an
// open terrain, and a 200K rock for the error bounds.
class LodTreeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("octolod-lod-tree-test-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "work");
    samplegen::SampleSpec spec;
    spec.shape = samplegen::Shape::rock;
    spec.triangles = 60'000 / kScale;
    ASSERT_TRUE(samplegen::write_sample_ply(spec, rock_ply()).ok());
    spec.shape = samplegen::Shape::city;
    spec.triangles = 60'000 / kScale;
    ASSERT_TRUE(samplegen::write_sample_ply(spec, city_ply()).ok());
    spec.shape = samplegen::Shape::terrain;
    spec.triangles = 60'000 / kScale;
    ASSERT_TRUE(samplegen::write_sample_ply(spec, terrain_ply()).ok());
    spec.shape = samplegen::Shape::rock;
    spec.triangles = 200'000 / kScale;
    spec.seed = 7;
    ASSERT_TRUE(samplegen::write_sample_ply(spec, big_rock_ply()).ok());
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  static fs::path rock_ply() { return root_ / "rock.ply"; }
  static fs::path city_ply() { return root_ / "city.ply"; }
  static fs::path terrain_ply() { return root_ / "terrain.ply"; }
  static fs::path big_rock_ply() { return root_ / "rock200k.ply"; }

  // Bakes `input` into a fresh directory named `name`.
  static BakeOptions options(const fs::path& input, const std::string& name) {
    BakeOptions o;
    o.input = input;
    o.output = root_ / name;
    o.max_tris = static_cast<std::uint32_t>(1000 / kScale);
    o.max_depth = 8;
    o.memory_budget_bytes = 24 << 20;  // max_tris 1000 needs 19 MiB
    o.work_dir = root_ / "work";
    o.threads = 2;
    return o;
  }
  static LoadedTree bake_and_load(const BakeOptions& o) {
    auto r = bake(o);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return load_tree(o.output);
  }

  static fs::path root_;
};

fs::path LodTreeTest::root_;

// The length of the model's bounding box diagonal, model units.
// --- the chains ---

// Every node of the tree baked into `dir` has LOD files as its manifest lists them, each at most
// `ratio` times the triangles of the one before and no less wrong; internal nodes are no finer
// and no less wrong than the children's LODs they come from; the root ends in a coarse LOD.
void expect_chains(const LoadedTree& t, const fs::path& dir, double ratio) {
  const Manifest& m = t.manifest;
  ASSERT_GT(m.nodes.size(), 9u);
  EXPECT_EQ(m.parameters.method, "grid");
  EXPECT_EQ(m.parameters.lod_ratio, ratio);
  std::size_t internal = 0;
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const NodeInfo& n = m.nodes[i];
    ASSERT_FALSE(n.lods.empty()) << "node '" << n.path << "' has no LOD";
    for (std::size_t k = 0; k < n.lods.size(); ++k) {
      const LodInfo& l = n.lods[k];
      const NodeMesh& mesh = t.lods[i][k];
      EXPECT_EQ(l.file, (n.path.empty() ? "" : n.path + "/") + "lod" + std::to_string(k) + ".olod");
      EXPECT_EQ(mesh.triangle_count(), l.triangles);
      EXPECT_EQ(mesh.vertex_count(), l.vertices);
      EXPECT_EQ(fs::file_size(dir / l.file), l.bytes);
      EXPECT_TRUE(std::isfinite(l.error));
      Bounds b = n.bounds;
      b.extend(mesh.bounds());
      EXPECT_EQ(b, n.bounds) << "LOD " << k << " of '" << n.path << "' sticks out of its bounds";
      if (k > 0) {
        // Each step keeps at most `ratio` of the triangles (build_lods' reduction), and errors
        // accumulate.
        EXPECT_LE(l.triangles, std::floor(ratio * n.lods[k - 1].triangles)) << n.path << " LOD " << k;
        EXPECT_GE(l.error, n.lods[k - 1].error) << n.path << " LOD " << k;
      }
    }
    if (n.is_leaf()) {
      EXPECT_EQ(n.lods[0].error, 0.0);
      EXPECT_EQ(n.lods[0].triangles, n.source_triangles);
      continue;
    }
    ++internal;
    // An internal node is simplified from one LOD per child (choose_merged_lods), each at least
    // as coarse as the child's LOD 0: its error is at least the largest of those LODs' errors,
    // and its finest LOD has at most as many triangles as their LOD 0s together.
    std::uint64_t finest = 0;
    double children_error = 0;
    for (std::int32_t c : n.children) {
      if (c < 0) continue;
      const NodeInfo& child = m.nodes[static_cast<std::size_t>(c)];
      finest += child.lods.front().triangles;
      children_error = std::max(children_error, child.lods.front().error);
    }
    EXPECT_GE(n.lods[0].error, children_error) << n.path;
    EXPECT_LE(n.lods[0].triangles, finest) << n.path;
  }
  EXPECT_GT(internal, 0u);
  // The nodes below the root stop their chains at node_min_triangles: a LOD is only followed by
  // a coarser one while it has more.
  const std::uint32_t node_min = LodTreeOptions{}.node_min_triangles;
  for (std::size_t i = 1; i < m.nodes.size(); ++i)
    for (std::size_t k = 1; k < m.nodes[i].lods.size(); ++k)
      EXPECT_GT(m.nodes[i].lods[k - 1].triangles, node_min) << m.nodes[i].path << " LOD " << k;
  // The root continues into a coarse chain, while it has more than the root's minimum, down to
  // what a distant rock costs: a few hundred triangles. (Its LOD 0 may already be there: at a
  // low ratio the children's steps are large and the sanitized builds' rock is small.)
  const NodeInfo& root = m.nodes[0];
  const std::uint32_t root_min = LodOptions{}.min_triangles;
  for (std::size_t k = 1; k < root.lods.size(); ++k)
    EXPECT_GT(root.lods[k - 1].triangles, root_min) << "root LOD " << k;
  EXPECT_LE(root.lods.back().triangles, 2u * root_min);
  EXPECT_GT(root.lods.back().error, 0.0);
}

TEST_F(LodTreeTest, EveryNodeHasAChainWhoseErrorsGrowAsItsTrianglesShrink) {
  const BakeOptions o = options(rock_ply(), "chains");
  const LoadedTree t = bake_and_load(o);
  expect_chains(t, o.output, 0.5);
  EXPECT_GE(t.manifest.nodes[0].lods.size(), 2u) << "the root has no coarse chain";
}

// A lower lod_ratio steps each chain down faster: fewer LODs, fewer bytes, the same leaves.
TEST_F(LodTreeTest, ALowerLodRatioGivesShorterChainsOfLargerSteps) {
  BakeOptions o = options(rock_ply(), "quarter-chains");
  o.lod_ratio = 0.25;
  const LoadedTree quarter = bake_and_load(o);
  expect_chains(quarter, o.output, 0.25);
  const LoadedTree half = bake_and_load(options(rock_ply(), "half-chains"));
  ASSERT_EQ(half.manifest.nodes.size(), quarter.manifest.nodes.size());
  std::size_t half_lods = 0, quarter_lods = 0;
  std::uint64_t half_bytes = 0, quarter_bytes = 0;
  for (std::size_t i = 0; i < half.manifest.nodes.size(); ++i) {
    const NodeInfo &h = half.manifest.nodes[i], &q = quarter.manifest.nodes[i];
    EXPECT_EQ(h.path, q.path);
    if (h.is_leaf()) {
      EXPECT_EQ(h.lods.front().triangles, q.lods.front().triangles) << h.path;
    }
    half_lods += h.lods.size(), quarter_lods += q.lods.size();
    for (const LodInfo& l : h.lods) half_bytes += l.bytes;
    for (const LodInfo& l : q.lods) quarter_bytes += l.bytes;
  }
  EXPECT_LT(quarter_lods, half_lods);
  EXPECT_LT(quarter_bytes, 0.8 * static_cast<double>(half_bytes));
}

// A LOD of a positions-only mesh with one vertex per two triangles: 18 bytes per triangle
// ((triangles / 2 * 3 floats + 3 * triangles indices) * 4), so the bounds below are 18x the
// triangle sums.
LodInfo lod(std::uint32_t triangles) {
  LodInfo l;
  l.triangles = triangles;
  l.vertices = triangles / 2;
  return l;
}

TEST(ChooseMergedLods, TakesTheFinestLodsThatFitCoarseningTheLargestFirst) {
  const std::vector<std::vector<LodInfo>> children{
      {lod(1000), lod(500), lod(250)},
      {lod(400), lod(200)},
      {lod(1200)},  // no coarser LOD
  };
  using Chosen = std::vector<std::size_t>;
  const VertexLayout layout;  // positions only
  const auto choose = [&](std::size_t triangles) { return choose_merged_lods(children, layout, 18 * triangles); };
  EXPECT_EQ(lod_mesh_bytes(lod(1000), layout), 18000u);
  // everything fits: every child's LOD 0
  EXPECT_EQ(choose(2600), (Chosen{0, 0, 0}));
  // one short: the largest child that has a coarser LOD (the first; not the third) moves
  EXPECT_EQ(choose(2599), (Chosen{1, 0, 0}));
  EXPECT_EQ(choose(2100), (Chosen{1, 0, 0}));
  // still the first (500 > 400), then the second (400 > 250, the first is at its coarsest)
  EXPECT_EQ(choose(2099), (Chosen{2, 0, 0}));
  EXPECT_EQ(choose(1849), (Chosen{2, 1, 0}));
  // nothing fits: every child at its coarsest
  EXPECT_EQ(choose(0), (Chosen{2, 1, 0}));
}

// Expects the same nodes with the same LODs (meshes, errors, bounds); returns the LODs compared.
std::size_t expect_identical_trees(const LoadedTree& a, const LoadedTree& b, const std::string& what) {
  EXPECT_EQ(a.manifest.nodes.size(), b.manifest.nodes.size()) << what;
  if (a.manifest.nodes.size() != b.manifest.nodes.size()) return 0;
  std::size_t lods = 0;
  for (std::size_t i = 0; i < a.manifest.nodes.size(); ++i) {
    const NodeInfo& x = a.manifest.nodes[i];
    const NodeInfo& y = b.manifest.nodes[i];
    EXPECT_EQ(x.lods.size(), y.lods.size()) << what << ": " << x.path;
    if (x.lods.size() != y.lods.size()) continue;
    for (std::size_t k = 0; k < x.lods.size(); ++k) {
      EXPECT_EQ(x.lods[k].error, y.lods[k].error) << what << ": " << x.path << " LOD " << k;
      EXPECT_EQ(x.lods[k].triangles, y.lods[k].triangles);
      EXPECT_TRUE(a.lods[i][k] == b.lods[i][k]) << what << ": " << x.path << " LOD " << k;
      ++lods;
    }
    EXPECT_EQ(x.bounds, y.bounds);
  }
  return lods;
}

TEST_F(LodTreeTest, OneAndTwoThreadsWriteIdenticalLodTreesWithEitherMethod) {
  for (const ClusterMethod method : {ClusterMethod::grid, ClusterMethod::bade2006}) {
    const std::string name(method_name(method));
    BakeOptions one = options(rock_ply(), "one-" + name);
    one.threads = 1;
    one.method = method;
    BakeOptions two = options(rock_ply(), "two-" + name);
    two.threads = 2;
    two.method = method;
    ASSERT_TRUE(bake(one).ok());
    ASSERT_TRUE(bake(two).ok());
    const LoadedTree a = load_tree(one.output);
    const LoadedTree b = load_tree(two.output);
    EXPECT_EQ(a.manifest.parameters.method, name);
    const std::size_t lods = expect_identical_trees(a, b, name);
    // (bade2006's fan rarely halves a small node: its chains may be one LOD long)
    if (method == ClusterMethod::grid) {
      EXPECT_GT(lods, a.manifest.nodes.size()) << "chains longer than one LOD were compared";
    }
  }
}

// --- cracks ---

using Position = std::array<std::uint32_t, 3>;  // exact float bits

struct PositionHash {
  std::size_t operator()(const Position& p) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::uint32_t v : p) h = (h ^ v) * 0xff51afd7ed558ccdull;
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
};

// The edges of `meshes`, merged by exact position, that exactly one triangle uses, each as its
// two positions in ascending order; sorted.
std::vector<std::pair<Position, Position>> open_edges(const std::vector<const NodeMesh*>& meshes) {
  std::unordered_map<Position, std::uint32_t, PositionHash> ids;
  std::vector<Position> positions;
  std::unordered_map<std::uint64_t, std::uint32_t> uses;
  for (const NodeMesh* mesh : meshes) {
    const std::size_t stride = mesh->layout.floats();
    for (std::size_t t = 0; t < mesh->triangle_count(); ++t) {
      std::uint32_t corner[3];
      for (std::size_t c = 0; c < 3; ++c) {
        const float* v = &mesh->vertices[mesh->indices[3 * t + c] * stride];
        const Position p{std::bit_cast<std::uint32_t>(v[0]), std::bit_cast<std::uint32_t>(v[1]),
                         std::bit_cast<std::uint32_t>(v[2])};
        auto [it, added] = ids.try_emplace(p, static_cast<std::uint32_t>(positions.size()));
        if (added) positions.push_back(p);
        corner[c] = it->second;
      }
      for (std::size_t e = 0; e < 3; ++e) {
        const std::uint32_t a = corner[e], b = corner[(e + 1) % 3];
        ++uses[(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b)];
      }
    }
  }
  std::vector<std::pair<Position, Position>> open;
  for (const auto& [key, count] : uses) {
    if (count != 1) continue;
    Position a = positions[key >> 32], b = positions[key & 0xffffffffu];
    if (b < a) std::swap(a, b);
    open.emplace_back(a, b);
  }
  std::sort(open.begin(), open.end());
  return open;
}

// A random frontier of the tree: at each node either one of its LODs (always at a leaf) or
// its children. Returns the chosen meshes; `covered` sums the chosen nodes' source triangles.
void random_cut(const LoadedTree& t, std::size_t node, std::mt19937_64& rng,
                std::vector<const NodeMesh*>& cut, std::uint64_t& covered) {
  const NodeInfo& n = t.manifest.nodes[node];
  if (!n.lods.empty() && (n.is_leaf() || std::bernoulli_distribution(0.35)(rng))) {
    const std::size_t lod = std::uniform_int_distribution<std::size_t>(0, n.lods.size() - 1)(rng);
    cut.push_back(&t.lods[node][lod]);
    covered += n.source_triangles;
    return;
  }
  for (std::int32_t c : n.children)
    if (c >= 0) random_cut(t, static_cast<std::size_t>(c), rng, cut, covered);
}

// The finest cut: every leaf's original triangles, i.e. the input.
std::vector<const NodeMesh*> leaf_cut(const LoadedTree& t) {
  std::vector<const NodeMesh*> cut;
  for (std::size_t i = 0; i < t.manifest.nodes.size(); ++i)
    if (t.manifest.nodes[i].is_leaf()) cut.push_back(&t.lods[i][0]);
  return cut;
}

void expect_random_cuts_add_no_open_edge(const LoadedTree& t, bool input_closed) {
  const auto input_open = open_edges(leaf_cut(t));
  if (input_closed) {
    EXPECT_EQ(input_open.size(), 0u) << "the input is not closed";
  }
  std::mt19937_64 rng(2026);
  std::size_t coarser_than_leaves = 0;
  for (int i = 0; i < 100; ++i) {
    std::vector<const NodeMesh*> cut;
    std::uint64_t covered = 0;
    random_cut(t, 0, rng, cut, covered);
    ASSERT_EQ(covered, t.manifest.input_triangles) << "cut " << i << " does not cover the model";
    std::size_t triangles = 0;
    for (const NodeMesh* mesh : cut) triangles += mesh->triangle_count();
    coarser_than_leaves += triangles < t.manifest.input_triangles;
    // A cut of one LOD covering the model is the root's, which meets no other node: it
    // simplifies the model's own border (lod_tree.h), so on an open input its open edges are
    // the border simplified, not the input's (on a closed input it must stay closed like any
    // cut).
    if (cut.size() == 1 && !input_closed) continue;
    const auto open = open_edges(cut);
    EXPECT_EQ(open.size(), input_open.size()) << "cut " << i << " (" << cut.size() << " LODs)";
    EXPECT_TRUE(open == input_open) << "cut " << i << " opened or closed edges";
    if (open != input_open) break;
  }
  EXPECT_GT(coarser_than_leaves, 90u) << "the cuts should mostly be simplified";
}

// The edges of a mesh as pairs of exact positions (ascending), with how many triangles use each.
std::map<std::pair<Position, Position>, std::uint32_t> edge_uses(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  auto position = [&](std::uint32_t v) {
    const float* f = &mesh.vertices[v * stride];
    return Position{std::bit_cast<std::uint32_t>(f[0]), std::bit_cast<std::uint32_t>(f[1]),
                    std::bit_cast<std::uint32_t>(f[2])};
  };
  std::map<std::pair<Position, Position>, std::uint32_t> uses;
  for (std::size_t c = 0; c < mesh.indices.size(); ++c) {
    Position a = position(mesh.indices[c]), b = position(mesh.indices[c % 3 == 2 ? c - 2 : c + 1]);
    if (b < a) std::swap(a, b);
    if (a != b) ++uses[{a, b}];
  }
  return uses;
}

// Every original edge two leaves share (one original triangle in each) is in every LOD of every
// node that holds one of the two leaves but not the other: whichever LODs a cut takes on either
// side, both have it, so no cut opens there. On a closed input this is what keeps every cut
// closed; on an open one, whose own border the nodes simplify (NeighbourReach), it is the only
// way to tell a crack from the border. Returns the number of shared edges checked.
std::size_t expect_shared_edges_kept(const LoadedTree& t) {
  const Manifest& m = t.manifest;
  std::map<std::pair<Position, Position>, std::vector<std::size_t>> leaves_of;
  for (std::size_t i = 0; i < m.nodes.size(); ++i)
    if (m.nodes[i].is_leaf())
      for (const auto& [edge, count] : edge_uses(t.lods[i][0]))
        if (count == 1) leaves_of[edge].push_back(i);
  std::map<std::pair<std::size_t, std::size_t>, std::map<std::pair<Position, Position>, std::uint32_t>> lod_edges;
  auto path_to_root = [&](std::size_t node) {
    std::vector<std::size_t> path;
    for (auto n = static_cast<std::int32_t>(node); n >= 0; n = m.nodes[static_cast<std::size_t>(n)].parent)
      path.push_back(static_cast<std::size_t>(n));
    return path;
  };
  std::size_t checked = 0, missing = 0;
  for (const auto& [edge, leaves] : leaves_of) {
    if (leaves.size() != 2) continue;  // the mesh's own border (1), or non-manifold
    ++checked;
    const std::vector<std::size_t> a = path_to_root(leaves[0]), b = path_to_root(leaves[1]);
    for (const auto* side : {&a, &b}) {
      const auto* other = side == &a ? &b : &a;
      for (const std::size_t node : *side) {
        if (std::find(other->begin(), other->end(), node) != other->end()) break;  // a common ancestor
        for (std::size_t k = 0; k < m.nodes[node].lods.size(); ++k) {
          auto [it, added] = lod_edges.try_emplace({node, k});
          if (added) it->second = edge_uses(t.lods[node][k]);
          if (it->second.count(edge) == 0 && ++missing <= 5)
            ADD_FAILURE() << "node '" << m.nodes[node].path << "' LOD " << k << " lost an edge it shares";
        }
      }
    }
  }
  EXPECT_EQ(missing, 0u);
  return checked;
}

TEST_F(LodTreeTest, RandomCutsOfAClosedRockHaveNoOpenEdge) {
  const LoadedTree t = bake_and_load(options(rock_ply(), "rock-cuts"));
  expect_random_cuts_add_no_open_edge(t, true);
  EXPECT_GT(expect_shared_edges_kept(t), 100u);
}

TEST_F(LodTreeTest, RandomCutsOfACityAddNoOpenEdge) {
  // The city's boxes are closed; its ground quad's outline is the only open boundary.
  const LoadedTree t = bake_and_load(options(city_ply(), "city-cuts"));
  expect_random_cuts_add_no_open_edge(t, false);
}

TEST_F(LodTreeTest, RandomCutsOfABade2006RockHaveNoOpenEdge) {
  BakeOptions o = options(rock_ply(), "rock-cuts-bade");
  o.method = ClusterMethod::bade2006;
  const LoadedTree t = bake_and_load(o);
  expect_random_cuts_add_no_open_edge(t, true);
}

// --- error bounds ---

// Points of a mesh's surface: its vertices and four interior points per triangle.
void surface_samples(const NodeMesh& mesh, std::vector<glm::vec3>& out) {
  const std::size_t stride = mesh.layout.floats();
  auto at = [&](std::uint32_t v) {
    const float* f = &mesh.vertices[v * stride];
    return glm::vec3(f[0], f[1], f[2]);
  };
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) out.push_back(at(static_cast<std::uint32_t>(v)));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const glm::vec3 a = at(mesh.indices[3 * t]), b = at(mesh.indices[3 * t + 1]),
                    c = at(mesh.indices[3 * t + 2]);
    out.push_back((a + b + c) / 3.0f);
    out.push_back(a * (2.0f / 3) + b * (1.0f / 6) + c * (1.0f / 6));
    out.push_back(a * (1.0f / 6) + b * (2.0f / 3) + c * (1.0f / 6));
    out.push_back(a * (1.0f / 6) + b * (1.0f / 6) + c * (2.0f / 3));
  }
}

// What expect_stored_errors_bound measured.
struct ErrorCheck {
  std::size_t checked = 0;     // node LODs
  std::size_t simplified = 0;  // of them with a positive stored error
  double tightest = 0;         // largest measured / stored ratio
};

// Every node LOD's stored error bounds the distance from the node's original triangles (the
// samples of its leaves' LOD 0) to that LOD.
ErrorCheck expect_stored_errors_bound(const LoadedTree& t) {
  const Manifest& m = t.manifest;
  ErrorCheck check;
  // Samples of each node's region, the original triangles of its leaves: children follow their
  // parents, so a backward sweep appends every node's samples to its parent's.
  std::vector<std::vector<glm::vec3>> samples(m.nodes.size());
  for (std::size_t i = m.nodes.size(); i-- > 0;) {
    if (m.nodes[i].is_leaf()) surface_samples(t.lods[i][0], samples[i]);
    if (m.nodes[i].parent >= 0) {
      auto& parent = samples[static_cast<std::size_t>(m.nodes[i].parent)];
      parent.insert(parent.end(), samples[i].begin(), samples[i].end());
    }
  }
  const double diagonal = m.bounds.diagonal();
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    for (std::size_t k = 0; k < m.nodes[i].lods.size(); ++k) {
      const NodeMesh& lod = t.lods[i][k];
      const double stored = m.nodes[i].lods[k].error;
      EXPECT_TRUE(std::isfinite(stored));
      const measure::TriangleBvh bvh(lod.vertices, lod.layout.floats(), lod.indices);
      // float distances: allow their rounding, a few ulps of the model's size
      const double slack = diagonal * 1e-6;
      double measured = 0;
      std::size_t violations = 0;
      for (const glm::vec3& p : samples[i]) {
        const auto hit = bvh.closest(p, static_cast<float>(stored + slack));
        if (hit.found()) {
          measured = std::max(measured, static_cast<double>(hit.distance));
        } else {
          ++violations;
          measured = std::max(measured, static_cast<double>(bvh.closest(p).distance));
        }
      }
      EXPECT_EQ(violations, 0u) << "node '" << m.nodes[i].path << "' LOD " << k << ": measured "
                                << measured << " > stored " << stored;
      ++check.checked;
      if (stored > 0) {
        ++check.simplified;
        check.tightest = std::max(check.tightest, measured / stored);
      }
    }
  }
  return check;
}

TEST_F(LodTreeTest, StoredErrorsBoundTheDistanceFromTheOriginalTriangles) {
  BakeOptions o = options(big_rock_ply(), "bounds");
  o.max_tris = static_cast<std::uint32_t>(2000 / kScale);
  o.memory_budget_bytes = 48 << 20;  // max_tris 2000 needs 35 MiB
  const LoadedTree t = bake_and_load(o);
  const Manifest& m = t.manifest;
  ASSERT_FALSE(m.nodes.empty());
  const ErrorCheck check = expect_stored_errors_bound(t);
  // Not vacuous: most LODs other than the leaves' originals (all that small leaves have,
  // lod_tree.h node_min_triangles) are simplified, some bound is within 5x of what is measured,
  // and even the root's coarsest (a few hundred triangles, errors accumulated over every level)
  // bounds less than half the model's size.
  const auto leaves = static_cast<std::size_t>(
      std::count_if(m.nodes.begin(), m.nodes.end(), [](const NodeInfo& n) { return n.is_leaf(); }));
  EXPECT_GT(check.simplified, (check.checked - leaves) / 2);
  const double diagonal = m.bounds.diagonal();
  EXPECT_GT(check.tightest, 0.2);
  EXPECT_LT(m.nodes[0].lods.back().error, 0.5 * diagonal);
  std::printf("[ info ] %zu node LODs checked, max measured/stored error %.3f, root coarsest "
              "%u triangles error %.4g (diagonal %.4g)\n",
              check.checked, check.tightest, m.nodes[0].lods.back().triangles,
              m.nodes[0].lods.back().error, diagonal);
}

TEST_F(LodTreeTest, AnOpenTerrainsNodesKeepTheirSeamsAndSimplifyTheirBorder) {
  // A terrain's border edges are used by one triangle, like the edges a node shares with its
  // neighbours; the nodes keep only the boundary edges a neighbour's triangle can reach
  // (NeighbourReach: within a third of the longest input edge of a face of their cell with other
  // cells behind it), so the border can be simplified at every level (where that pays: simplify.h),
  // held in place by the border quadrics. The root's children keep few of the original border edges in their
  // coarsest LODs (before: every one of them), every edge two leaves share stays in every node
  // between them, and every stored error still bounds the measured distance.
  const LoadedTree t = bake_and_load(options(terrain_ply(), "terrain"));
  const Manifest& m = t.manifest;
  ASSERT_GT(m.nodes.size(), 9u);
  EXPECT_LE(m.nodes[0].lods.back().triangles, 256u);
  // the terrain's own border: the edges one original triangle uses
  std::map<std::pair<Position, Position>, std::uint32_t> original;
  for (std::size_t i = 0; i < m.nodes.size(); ++i)
    if (m.nodes[i].is_leaf())
      for (const auto& [edge, count] : edge_uses(t.lods[i][0])) original[edge] += count;
  std::map<std::pair<Position, Position>, std::uint32_t> coarsest;
  for (std::int32_t c : m.nodes[0].children)
    if (c >= 0) coarsest.merge(edge_uses(t.lods[static_cast<std::size_t>(c)].back()));
  std::size_t border = 0, border_kept = 0;
  for (const auto& [edge, count] : original)
    if (count == 1) ++border, border_kept += coarsest.count(edge);
  const std::size_t shared = expect_shared_edges_kept(t);
  const ErrorCheck errors = expect_stored_errors_bound(t);
  std::printf("[ info ] terrain %llu tris: %zu edges shared between leaves kept; the root's children's coarsest "
              "LODs keep %zu of its %zu border edges; %zu node LODs' errors checked\n",
              static_cast<unsigned long long>(m.input_triangles), shared, border_kept, border, errors.checked);
  EXPECT_GT(shared, 100u);
  EXPECT_GT(border, 100u);
  EXPECT_LT(border_kept * 4, border) << "the root's children keep the terrain's border";
}

// --- internal nodes built streaming ---

// Near the root of a large model every child's coarsest LOD keeps its locked boundary at the
// original resolution, so the LODs its parent merges can be far larger than merge_bytes (103K
// triangles for the root of a 100M rock); such a parent is built streaming from a record file
// of them (lod_tree.cpp, run_streamed_internal). A small max_tris on the city (boxes cut by
// many node boundaries) forces it on small inputs: cuts through those nodes stay crack-free,
// their errors bound the original surface, and the tree is the same for any thread count and
// budget.
TEST_F(LodTreeTest, InternalNodesTooLargeToMergeAreBuiltStreamingCrackFreeAndBounded) {
  BakeOptions o = options(city_ply(), "streamed-internal");
  o.max_tris = static_cast<std::uint32_t>(50 / kScale);
  auto baked = bake(o);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  const double streamed = baked->header.stats.at("lod_streamed_internal_nodes");
  EXPECT_GT(streamed, 0.0);
  const LoadedTree t = load_tree(o.output);
  expect_random_cuts_add_no_open_edge(t, false);
  const ErrorCheck check = expect_stored_errors_bound(t);  // every streamed LOD is simplified
  EXPECT_GE(static_cast<double>(check.simplified), streamed);

  BakeOptions other = o;
  other.output = root_ / "streamed-internal-other";
  other.threads = 1;
  other.memory_budget_bytes = std::uint64_t{256} << 20;
  ASSERT_TRUE(bake(other).ok());
  // every node has a LOD (sanitized builds, max_tris 10: mostly one each)
  EXPECT_GE(expect_identical_trees(t, load_tree(other.output), "1 thread, 256M"), t.manifest.nodes.size());
}

// --- streamed leaves ---

// Every triangle of `mesh` as its three vertex records, in the mesh's order.
std::vector<std::vector<float>> triangle_records(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  std::vector<std::vector<float>> triangles(mesh.triangle_count());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (std::size_t c = 0; c < 3; ++c) {
      const float* v = &mesh.vertices[mesh.indices[3 * t + c] * stride];
      triangles[t].insert(triangles[t].end(), v, v + stride);
    }
  return triangles;
}

// A rock half the size of rock_ply(), generated on first use: the streamed-leaf tests bake it
// twice or more under sanitizers.
fs::path streamed_rock_ply(const fs::path& dir) {
  const fs::path ply = dir / "rock-streamed.ply";
  if (!fs::exists(ply)) {
    samplegen::SampleSpec spec;
    spec.shape = samplegen::Shape::rock;
    spec.triangles = 30'000 / kScale;
    EXPECT_TRUE(samplegen::write_sample_ply(spec, ply).ok());
  }
  return ply;
}

// Largest circular distance between an output vertex's u and the u of the nearest corner of the
// input triangle closest to it, over the output vertices between the polar caps (v within 0.08
// of 0 or 1: there the longitudes meet). The rock's u is the longitude / 2 pi and jumps from 1
// back to 0 at longitude 0, where the generator duplicates the vertices: an output vertex that
// keeps one side of that seam stays within about a cell's span of u of the input next to it,
// one whose cell averaged both sides is near 0.5 away from both.
double worst_u_drift(const NodeMesh& input, const NodeMesh& output) {
  const std::size_t stride = input.layout.floats(), u = input.layout.uv_offset();
  const measure::TriangleBvh bvh(input.vertices, input.layout.floats(), input.indices);
  double worst = 0.0;
  for (std::size_t v = 0; v < output.vertex_count(); ++v) {
    const float* vertex = &output.vertices[v * stride];
    if (vertex[u + 1] < 0.08f || vertex[u + 1] > 0.92f) continue;
    const glm::vec3 p(vertex[0], vertex[1], vertex[2]);
    const auto hit = bvh.closest(p);
    const float* nearest = nullptr;
    float nearest_distance = 0.0f;
    for (std::size_t k = 0; k < 3; ++k) {
      const float* corner = &input.vertices[input.indices[3 * std::size_t{hit.triangle} + k] * stride];
      const glm::vec3 offset = glm::vec3(corner[0], corner[1], corner[2]) - p;
      const float d = offset.x * offset.x + offset.y * offset.y + offset.z * offset.z;
      if (!nearest || d < nearest_distance) nearest = corner, nearest_distance = d;
    }
    const double d = std::fabs(double(vertex[u]) - nearest[u]);
    worst = std::max(worst, std::min(d, 1.0 - d));
  }
  return worst;
}

// At --max-depth 0 and 1 under a small budget every leaf is over the in-memory cap and is built
// streaming: LOD 0 holds exactly the leaf's triangles (those of the same leaf baked in memory
// under a large budget, in the same order), LOD 1 at most the cap and half the leaf, every
// stored error bounds the measured distance from the leaf's triangles, and random cuts mixing
// streamed leaves with their neighbours and parents add no open edge (at depth 0, every LOD
// of the root is closed).
TEST_F(LodTreeTest, LeavesOverTheCapAreStreamedWithinItAndStayCrackFreeAndBounded) {
  // (sanitized builds: depth 1 only, the same code with more leaves and cuts between them)
  const std::vector<std::uint32_t> depths = kScale == 1 ? std::vector<std::uint32_t>{0, 1} : std::vector<std::uint32_t>{1};
  for (const std::uint32_t depth : depths) {
    BakeOptions o = options(streamed_rock_ply(root_), "streamed-" + std::to_string(depth));
    o.max_depth = depth;
    // every leaf over the cap (1083 triangles; 216 sanitized): a small budget, and leaves
    // small enough for its node work
    o.max_tris = static_cast<std::uint32_t>(300 / kScale);
    o.memory_budget_bytes = (9 << 20) / kScale;
    const LoadedTree t = bake_and_load(o);
    BakeOptions in_memory = o;  // for its leaves' LOD 0
    in_memory.output = root_ / ("in-memory-" + std::to_string(depth));
    in_memory.memory_budget_bytes = std::uint64_t{256} << 20;
    in_memory.lods = false;
    const LoadedTree r = bake_and_load(in_memory);
    const Manifest& m = t.manifest;
    ASSERT_EQ(m.nodes.size(), r.manifest.nodes.size());
    const std::uint64_t cap = max_depth_leaf_triangles(o.memory_budget_bytes, m.layout, o.max_tris);
    ASSERT_LT(cap, max_depth_leaf_triangles(in_memory.memory_budget_bytes, m.layout, o.max_tris));
    const double diagonal = m.bounds.diagonal();
    std::size_t streamed = 0;
    for (std::size_t i = 0; i < m.nodes.size(); ++i) {
      const NodeInfo& n = m.nodes[i];
      if (!n.is_leaf()) continue;
      ASSERT_GT(n.source_triangles, cap) << n.path;
      ++streamed;
      EXPECT_TRUE(triangle_records(t.lods[i][0]) == triangle_records(r.lods[i][0])) << n.path;
      EXPECT_EQ(n.lods[0].triangles, n.source_triangles);
      EXPECT_EQ(n.lods[0].error, 0.0);
      ASSERT_GE(n.lods.size(), 2u) << n.path;
      EXPECT_LE(n.lods[1].triangles, cap) << n.path;
      EXPECT_LE(n.lods[1].triangles, n.source_triangles / 2) << n.path;
      std::vector<glm::vec3> samples;
      surface_samples(t.lods[i][0], samples);
      for (std::size_t k = 1; k < n.lods.size(); ++k) {
        const NodeMesh& lod = t.lods[i][k];
        EXPECT_EQ(lod.triangle_count(), n.lods[k].triangles);
        const measure::TriangleBvh bvh(lod.vertices, lod.layout.floats(), lod.indices);
        const double bound = n.lods[k].error + diagonal * 1e-6;
        std::size_t violations = 0;
        for (const glm::vec3& p : samples) violations += !bvh.closest(p, static_cast<float>(bound)).found();
        EXPECT_EQ(violations, 0u) << n.path << " LOD " << k << " error " << n.lods[k].error;
      }
      EXPECT_LT(n.lods[1].error, 0.1 * diagonal) << n.path;
      // LOD 1's wedges keep the sides of the uv seam apart (streamed_leaf.h)
      EXPECT_LT(worst_u_drift(t.lods[i][0], t.lods[i][1]), 0.2) << n.path;
    }
    EXPECT_EQ(streamed, depth == 0 ? 1u : 8u);
    if (depth == 0) {  // one node: every LOD is a cut
      for (const NodeMesh& lod : t.lods[0]) EXPECT_TRUE(open_edges({&lod}).empty());
    } else {
      expect_random_cuts_add_no_open_edge(t, true);
    }
  }
}

// A streamed leaf's files depend only on the input and the budget: the same with 1 and 2
// threads and from the records path (no in-memory octree).
TEST_F(LodTreeTest, StreamedLeavesAreTheSameForAnyThreadCountAndOctreePath) {
  BakeOptions one = options(streamed_rock_ply(root_), "streamed-one");
  one.max_depth = 1;
  one.max_tris = static_cast<std::uint32_t>(300 / kScale);
  one.memory_budget_bytes = (9 << 20) / kScale;
  one.threads = 1;
  BakeOptions two = one;
  two.output = root_ / "streamed-two";
  two.threads = 2;
  two.in_memory_octree = false;
  const LoadedTree a = bake_and_load(one);
  const LoadedTree b = bake_and_load(two);
  EXPECT_EQ(a.manifest.stats.at("octree_in_memory"), 1.0);
  EXPECT_EQ(b.manifest.stats.at("octree_in_memory"), 0.0);
  ASSERT_EQ(a.manifest.nodes.size(), b.manifest.nodes.size());
  for (std::size_t i = 0; i < a.manifest.nodes.size(); ++i) {
    ASSERT_EQ(a.lods[i].size(), b.lods[i].size()) << a.manifest.nodes[i].path;
    for (std::size_t k = 0; k < a.lods[i].size(); ++k) {
      EXPECT_TRUE(a.lods[i][k] == b.lods[i][k]) << a.manifest.nodes[i].path << " LOD " << k;
      EXPECT_EQ(a.manifest.nodes[i].lods[k].error, b.manifest.nodes[i].lods[k].error);
    }
  }
}

// A face the input holds twice would cancel under the clustering's mod-2 rule, and its edges,
// used twice, would hide from the streamed boundary search (edges used an odd number of times):
// a streamed leaf builds its LODs from every face once (repeated_records.h). The rock with
// every third face repeated (after all the faces, shuffled, a third of them from another
// corner in the same cyclic order) bakes the same streamed leaves' LODs as the rock itself, but
// for LOD 0, which keeps the repeats, and its random cuts stay crack-free.
TEST_F(LodTreeTest, StreamedLeavesBuildTheirLodsFromEveryRepeatedFaceOnce) {
  samplegen::SampleSpec spec;
  spec.shape = samplegen::Shape::rock;
  spec.triangles = 30'000 / kScale;
  const Result<NodeMesh> rock = samplegen::generate_sample_mesh(spec);
  ASSERT_TRUE(rock.ok()) << rock.status().message();
  std::vector<std::uint32_t> repeated = rock->indices;
  std::vector<std::uint32_t> faces;
  for (std::uint32_t t = 0; t < rock->triangle_count(); t += 3) faces.push_back(t);
  std::shuffle(faces.begin(), faces.end(), std::mt19937(7));
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) repeated.push_back(rock->indices[3 * std::size_t{faces[i]} + (i + k) % 3]);
  PlyWriteOptions write;
  write.layout = rock->layout;
  ASSERT_TRUE(write_ply(root_ / "rock-once.ply", write, rock->vertices, rock->indices).ok());
  ASSERT_TRUE(write_ply(root_ / "rock-repeated.ply", write, rock->vertices, repeated).ok());

  BakeOptions once = options(root_ / "rock-once.ply", "repeats-once");
  once.max_depth = 1;
  once.max_tris = static_cast<std::uint32_t>(300 / kScale);
  once.memory_budget_bytes = (9 << 20) / kScale;  // every leaf over the cap, as above
  BakeOptions twice = once;
  twice.input = root_ / "rock-repeated.ply";
  twice.output = root_ / "repeats-twice";
  const LoadedTree a = bake_and_load(once);
  const LoadedTree b = bake_and_load(twice);
  const std::uint64_t cap = max_depth_leaf_triangles(once.memory_budget_bytes, a.manifest.layout, once.max_tris);
  ASSERT_EQ(a.manifest.nodes.size(), b.manifest.nodes.size());
  std::size_t leaves = 0;
  for (std::size_t i = 0; i < a.manifest.nodes.size(); ++i) {
    const NodeInfo& n = a.manifest.nodes[i];
    const NodeInfo& m = b.manifest.nodes[i];
    if (!n.is_leaf()) continue;
    ++leaves;
    ASSERT_GT(n.source_triangles, cap) << n.path;
    EXPECT_GT(m.lods[0].triangles, n.lods[0].triangles) << n.path;
    ASSERT_GE(n.lods.size(), 2u) << n.path;
    ASSERT_EQ(m.lods.size(), n.lods.size()) << n.path;
    for (std::size_t k = 1; k < n.lods.size(); ++k) {
      EXPECT_TRUE(b.lods[i][k] == a.lods[i][k]) << n.path << " LOD " << k;
      EXPECT_EQ(m.lods[k].error, n.lods[k].error) << n.path << " LOD " << k;
    }
  }
  EXPECT_EQ(leaves, 8u);
  expect_random_cuts_add_no_open_edge(b, true);
}

}  // namespace
}  // namespace octolod::bake
