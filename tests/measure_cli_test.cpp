// measure_cli_tests: the measuring commands run as a child process (OCTOLOD_CLI) — extract,
// eval, reference and compare: their numbers on fixtures with known answers, their files, their
// JSON, their exit codes and messages on bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"

namespace octolod {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("octolod_measure_cli_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

struct CliRun {
  int code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs `octolod <arguments>` through the shell, capturing stdout and stderr.
CliRun run_cli(const TempDir& dir, const std::string& arguments) {
  const fs::path err_file = dir / "stderr.txt";
  CliRun run;
  FILE* pipe = ::popen((std::string(std::getenv("OCTOLOD_CLI")) + " " + arguments + " 2>" +
                        err_file.string())
                           .c_str(),
                       "r");
  if (pipe == nullptr) return run;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) run.out.append(buffer, n);
  const int status = ::pclose(pipe);
  run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err_file);
  run.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return run;
}

#define SKIP_WITHOUT_CLI() \
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set"

// A `cells` x `cells` grid over [0,1]^2 at z = height, normals +z, colour and uv from (x, y).
NodeMesh plane(int cells, float height) {
  NodeMesh m;
  m.layout = {true, true, true};
  for (int y = 0; y <= cells; ++y)
    for (int x = 0; x <= cells; ++x) {
      const float u = static_cast<float>(x) / static_cast<float>(cells);
      const float v = static_cast<float>(y) / static_cast<float>(cells);
      m.vertices.insert(m.vertices.end(), {u, v, height, 0, 0, 1, u, v, 0.5f, u, v});
    }
  auto id = [&](int x, int y) { return static_cast<std::uint32_t>(y * (cells + 1) + x); };
  for (int y = 0; y < cells; ++y)
    for (int x = 0; x < cells; ++x)
      m.indices.insert(m.indices.end(), {id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y),
                                         id(x + 1, y + 1), id(x, y + 1)});
  return m;
}

void write_mesh(const fs::path& path, const NodeMesh& mesh,
                PlyColorType color_type = PlyColorType::float32) {
  PlyWriteOptions options;
  options.layout = mesh.layout;
  options.color_type = color_type;
  ASSERT_TRUE(write_ply(path, options, mesh.vertices, mesh.indices).ok()) << path;
}

NodeMesh read_mesh(const fs::path& path) {
  Result<PlyMesh> ply = read_ply(path);
  EXPECT_TRUE(ply.ok()) << ply.status().message();
  NodeMesh m;
  if (!ply.ok()) return m;
  m.layout = ply->info.layout;
  m.vertices = ply->vertices;
  m.indices = ply->triangles;
  return m;
}

// Edges (vertex index pairs, either direction) used by one triangle only: holes or cracks. 0 for
// a closed mesh whose shared vertices are welded. (Non-manifold edges, used by 4 triangles where
// a cluster folds two sheets together, are not openings and are not counted.)
std::size_t open_edges(const NodeMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    for (std::size_t c = 0; c < 3; ++c) {
      std::uint32_t a = m.indices[3 * t + c], b = m.indices[3 * t + (c + 1) % 3];
      if (b < a) std::swap(a, b);
      ++uses[{a, b}];
    }
  std::size_t open = 0;
  for (const auto& [edge, count] : uses) open += count == 1;
  return open;
}

// --- eval --------------------------------------------------------------------------------------

TEST(EvalCli, PlaneAgainstPlaneShiftedByDReportsD) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  const float d = 0.125f;
  write_mesh(dir / "a.ply", plane(8, 0.0f));
  write_mesh(dir / "b.ply", plane(5, d));  // another tessellation of the shifted plane
  const CliRun run = run_cli(dir, "--json eval " + (dir / "a.ply").string() + " " +
                                      (dir / "b.ply").string() + " --samples 20000");
  ASSERT_EQ(run.code, 0) << run.err;
  const json r = json::parse(run.out);
  for (const char* side : {"a_to_b", "b_to_a", "two_sided"}) {
    EXPECT_NEAR(r[side]["mean"].get<double>(), d, 1e-6) << side;
    EXPECT_NEAR(r[side]["rms"].get<double>(), d, 1e-6) << side;
    EXPECT_NEAR(r[side]["max"].get<double>(), d, 1e-6) << side;
    EXPECT_NEAR(r[side]["max_relative"].get<double>(), d / std::sqrt(2.0), 1e-6) << side;
    // the attributes are the same linear fields on both
    EXPECT_NEAR(r[side]["normal_max_degrees"].get<double>(), 0.0, 1e-3) << side;
    EXPECT_NEAR(r[side]["color_rms"].get<double>(), 0.0, 1e-5) << side;
    EXPECT_NEAR(r[side]["uv_rms"].get<double>(), 0.0, 1e-5) << side;
  }
  EXPECT_EQ(r["a_to_b"]["samples"], 20000);
  EXPECT_EQ(r["a"]["triangles"], 128);
  EXPECT_EQ(r["b"]["triangles"], 50);
  EXPECT_NEAR(r["diagonal"].get<double>(), std::sqrt(2.0), 1e-6);

  // the human report carries the same numbers
  const CliRun text =
      run_cli(dir, "eval " + (dir / "a.ply").string() + " " + (dir / "b.ply").string());
  ASSERT_EQ(text.code, 0);
  EXPECT_NE(text.out.find("Hausdorff 0.125"), std::string::npos) << text.out;
  EXPECT_TRUE(text.err.empty()) << "no progress on stderr without --progress or a terminal";
}

TEST(EvalCli, AttributesOnlyOnOneSideAreNotCompared) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_mesh(dir / "a.ply", plane(4, 0.0f));
  NodeMesh bare;
  bare.layout = {};
  const NodeMesh full = plane(4, 0.0f);
  for (std::size_t v = 0; v < full.vertex_count(); ++v)
    bare.vertices.insert(bare.vertices.end(), full.vertices.begin() + static_cast<long>(v * 11),
                         full.vertices.begin() + static_cast<long>(v * 11 + 3));
  bare.indices = full.indices;
  write_mesh(dir / "b.ply", bare);
  const CliRun run = run_cli(dir, "--json eval " + (dir / "a.ply").string() + " " +
                                      (dir / "b.ply").string() + " --samples 5000");
  ASSERT_EQ(run.code, 0) << run.err;
  const json r = json::parse(run.out);
  EXPECT_LT(r["two_sided"]["max"].get<double>(), 1e-6);
  EXPECT_FALSE(r["two_sided"].contains("normal_mean_degrees"));
  EXPECT_FALSE(r["two_sided"].contains("color_rms"));
}

TEST(EvalCli, BadInputsExitWithCodeAndFileName) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_mesh(dir / "good.ply", plane(2, 0.0f));
  const std::string good = (dir / "good.ply").string();
  // truncated binary body
  {
    std::ifstream in(dir / "good.ply", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir / "cut.ply", std::ios::binary) << bytes.substr(0, bytes.size() - 7);
  }
  CliRun run = run_cli(dir, "eval " + good + " " + (dir / "cut.ply").string());
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("cut.ply"), std::string::npos) << run.err;
  // no faces at all
  std::ofstream(dir / "points.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                       "property float y\nproperty float z\nend_header\n0 0 0\n";
  run = run_cli(dir, "eval " + (dir / "points.ply").string() + " " + good);
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("points.ply: the mesh has no triangles"), std::string::npos) << run.err;
  // zero area: every triangle degenerate
  std::ofstream(dir / "flat.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                     "property float y\nproperty float z\nelement face 1\n"
                                     "property list uchar int vertex_indices\nend_header\n"
                                     "0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n";
  run = run_cli(dir, "eval " + good + " " + (dir / "flat.ply").string());
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("flat.ply"), std::string::npos) << run.err;
  // missing file: I/O
  run = run_cli(dir, "eval " + good + " " + (dir / "missing.ply").string());
  EXPECT_EQ(run.code, 4);
  EXPECT_NE(run.err.find("missing.ply"), std::string::npos) << run.err;
  // usage
  EXPECT_EQ(run_cli(dir, "eval " + good).code, 1);
  EXPECT_EQ(run_cli(dir, "eval " + good + " " + good + " --samples lots").code, 1);
  // counts a typo makes huge (-1 wraps to 2^64 - 1): usage errors, not exhausted memory or threads
  for (const char* option : {"--samples -1", "--samples 1e12", "--threads 100000", "--picture-scale nan"})
    EXPECT_EQ(run_cli(dir, "eval " + good + " " + good + " " + option).code, 1) << option;
}

// --- extract -----------------------------------------------------------------------------------

// A baked tree by hand, positions only:
//
//   root  lod0: both halves (4 triangles, error 0.01)   lod1: one quad (2 triangles, error 0.5)
//   ├── octant 0 "0": the left square  x in [0,1] (2 triangles, error 0)
//   └── octant 1 "1": the right square x in [1,2] (2 triangles, error 0)
//
// The two children share the edge x = 1 with bit-identical vertices.
NodeMesh square(float x0) {
  NodeMesh m;
  m.vertices = {x0, 0, 0, x0 + 1, 0, 0, x0 + 1, 1, 0, x0, 1, 0};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

void write_tree(const fs::path& root) {
  Manifest manifest;
  auto add_lod = [&](NodeInfo& node, const NodeMesh& mesh, double error, const std::string& file) {
    fs::create_directories((root / file).parent_path());
    ASSERT_TRUE(write_node_file(root / file, mesh).ok());
    node.lods.push_back({static_cast<std::uint32_t>(mesh.triangle_count()),
                         static_cast<std::uint32_t>(mesh.vertex_count()), error,
                         fs::file_size(root / file), file});
    node.bounds.extend(mesh.bounds());
  };
  NodeMesh both = square(0.0f);  // root lod0: the two squares, shared edge welded
  both.vertices.insert(both.vertices.end(), {2, 0, 0, 2, 1, 0});
  both.indices.insert(both.indices.end(), {1, 4, 5, 1, 5, 2});
  NodeMesh coarse;
  coarse.vertices = {0, 0, 0, 2, 0, 0, 2, 1, 0, 0, 1, 0};
  coarse.indices = {0, 1, 2, 0, 2, 3};
  NodeInfo top;
  top.cell = {{0, 0, 0}, {2, 2, 2}};
  top.children[0] = 1;
  top.children[1] = 2;
  top.source_triangles = 4;
  add_lod(top, both, 0.01, "lod0.olod");
  add_lod(top, coarse, 0.5, "lod1.olod");
  NodeInfo left;
  left.path = "0";
  left.depth = 1;
  left.parent = 0;
  left.cell = {{0, 0, 0}, {1, 1, 1}};
  left.source_triangles = 2;
  NodeInfo right = left;
  right.path = "1";
  right.cell = {{1, 0, 0}, {2, 1, 1}};
  add_lod(left, square(0.0f), 0.0, "0/lod0.olod");
  add_lod(right, square(1.0f), 0.0, "1/lod0.olod");
  manifest.nodes = {top, left, right};
  for (const NodeInfo& n : manifest.nodes) manifest.bounds.extend(n.bounds);
  manifest.input_triangles = 4;
  ASSERT_TRUE(write_manifest(root / std::string(kManifestFileName), manifest).ok());
}

TEST(ExtractCli, LevelZeroIsTheRootLod) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_tree(dir / "tree");
  const CliRun run = run_cli(dir, "--json extract " + (dir / "tree").string() + " --level 0 -o " +
                                      (dir / "cut.ply").string());
  ASSERT_EQ(run.code, 0) << run.err;
  Result<NodeMesh> root = read_node_file(dir / "tree" / "lod0.olod");
  ASSERT_TRUE(root.ok());
  EXPECT_EQ(read_mesh(dir / "cut.ply"), root.value());
  const json r = json::parse(run.out);
  EXPECT_EQ(r["triangles"], 4);
  EXPECT_EQ(r["node_lods"], 1);
  EXPECT_EQ(r["lods"][0]["node"], "");
  EXPECT_EQ(r["lods"][0]["lod"], 0);
}

// A level below the tree's deepest node is a mistake, not a request for the leaves: refused
// (usage, nothing written), naming the deepest level; the deepest level itself is the leaves.
TEST(ExtractCli, LevelDeeperThanTheTreeIsRefused) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_tree(dir / "tree");
  const std::string out = (dir / "cut.ply").string();
  const CliRun deep = run_cli(dir, "extract " + (dir / "tree").string() + " --level 2 -o " + out);
  EXPECT_EQ(deep.code, 1) << deep.err;
  EXPECT_NE(deep.err.find("--level 2: the deepest level of " + (dir / "tree").string() + " is 1"), std::string::npos)
      << deep.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  const CliRun leaves = run_cli(dir, "--json extract " + (dir / "tree").string() + " --level 1 -o " + out);
  ASSERT_EQ(leaves.code, 0) << leaves.err;
  EXPECT_EQ(json::parse(leaves.out)["node_lods"], 2);
}

// Bytes after a binary PLY's last element are ignored, as other readers do (some writers pad),
// but said: more than padding usually means element counts that are too small. bake and eval
// warn with the count and go on; a file without them gets no warning.
TEST(BakeCli, WarnsOfBytesAfterTheLastElement) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_mesh(dir / "clean.ply", plane(4, 0.0f));
  fs::copy_file(dir / "clean.ply", dir / "padded.ply");
  std::ofstream(dir / "padded.ply", std::ios::binary | std::ios::app) << "3 0 1 2\n";  // 8 bytes
  const std::string warning = "warning: " + (dir / "padded.ply").string() + ": 8 bytes after the last element were ignored";
  const CliRun clean = run_cli(dir, "bake " + (dir / "clean.ply").string() + " -o " + (dir / "clean").string());
  ASSERT_EQ(clean.code, 0) << clean.err;
  EXPECT_EQ(clean.err.find("warning"), std::string::npos) << clean.err;
  const CliRun baked = run_cli(dir, "bake " + (dir / "padded.ply").string() + " -o " + (dir / "padded").string());
  ASSERT_EQ(baked.code, 0) << baked.err;
  EXPECT_NE(baked.err.find(warning), std::string::npos) << baked.err;
  const CliRun measured = run_cli(dir, "eval " + (dir / "padded.ply").string() + " " + (dir / "clean.ply").string());
  ASSERT_EQ(measured.code, 0) << measured.err;
  EXPECT_NE(measured.err.find(warning), std::string::npos) << measured.err;
}

// Positions are floats: a model far from the origin (here 1 unit across, 4 million units out,
// where floats are 0.25 apart) bakes, and the bake says so on stderr; at the origin it does not.
TEST(BakeCli, WarnsWhenFloatsAreCoarseFarFromTheOrigin) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  const NodeMesh grid = plane(4, 0.0f);
  NodeMesh near;
  near.indices = grid.indices;
  for (std::size_t v = 0; v < grid.vertex_count(); ++v)
    near.vertices.insert(near.vertices.end(), &grid.vertices[v * 11], &grid.vertices[v * 11] + 3);
  NodeMesh far = near;
  for (std::size_t i = 0; i < far.vertices.size(); i += 3) far.vertices[i] += 4.0e6f;
  write_mesh(dir / "near.ply", near);
  write_mesh(dir / "far.ply", far);
  const CliRun quiet = run_cli(dir, "bake " + (dir / "near.ply").string() + " -o " + (dir / "near").string());
  ASSERT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.err.find("warning"), std::string::npos) << quiet.err;
  const CliRun warned = run_cli(dir, "bake " + (dir / "far.ply").string() + " -o " + (dir / "far").string());
  ASSERT_EQ(warned.code, 0) << warned.err;
  EXPECT_NE(warned.err.find("warning: " + (dir / "far.ply").string() + ": coordinates reach 4e+06"), std::string::npos)
      << warned.err;
  EXPECT_NE(warned.err.find("0.25 apart"), std::string::npos) << warned.err;
  EXPECT_NE(warned.err.find("recentre"), std::string::npos) << warned.err;
}

TEST(BakeCli, DoublePositionsFarFromTheOriginBakeAsNearOnes) {
  // A bumpy 16 x 16 grid near the origin (floats), and the same written as double positions
  // 4,000 km out, where floats are 0.25 apart and the unit square would collapse to a few points.
  // Baked relative to its first vertex (exactly the offset here), the far one gives the near
  // one's node files; extract and export put it back where it was, eval measures it there.
  SKIP_WITHOUT_CLI();
  TempDir dir;
  NodeMesh near = plane(16, 0.0f);
  for (std::size_t v = 0; v < near.vertex_count(); ++v) {
    float* p = &near.vertices[v * 11];
    p[2] = 0.05f * std::sin(9.0f * p[0] + 0.5f) * std::cos(7.0f * p[1] + 0.25f);  // never -0, which + 4e6 - 4e6 makes +0
  }
  write_mesh(dir / "near.ply", near);
  const std::array<double, 3> offset{4.0e6, -5.0e5, 0.0};
  PlyWriteOptions far_options;
  far_options.layout = near.layout;
  far_options.color_type = PlyColorType::float32;
  far_options.position_origin = offset;
  ASSERT_TRUE(write_ply(dir / "far.ply", far_options, near.vertices, near.indices).ok());
  const std::string lods = " --max-tris 100";
  const CliRun near_bake = run_cli(dir, "bake " + (dir / "near.ply").string() + " -o " + (dir / "near").string() + lods);
  ASSERT_EQ(near_bake.code, 0) << near_bake.err;
  const CliRun far_bake = run_cli(dir, "bake " + (dir / "far.ply").string() + " -o " + (dir / "far").string() + lods);
  ASSERT_EQ(far_bake.code, 0) << far_bake.err;
  EXPECT_EQ(far_bake.err.find("warning"), std::string::npos) << far_bake.err;
  Result<Manifest> near_tree = read_tree_manifest(dir / "near"), far_tree = read_tree_manifest(dir / "far");
  ASSERT_TRUE(near_tree.ok() && far_tree.ok());
  EXPECT_EQ(near_tree->origin, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_EQ(far_tree->origin, offset);
  ASSERT_EQ(far_tree->nodes.size(), near_tree->nodes.size());
  ASSERT_GT(far_tree->nodes.size(), 1u);
  for (std::size_t n = 0; n < near_tree->nodes.size(); ++n) {
    ASSERT_EQ(far_tree->nodes[n].lods.size(), near_tree->nodes[n].lods.size());
    for (const LodInfo& lod : near_tree->nodes[n].lods) {
      std::ifstream a(dir / "near" / lod.file, std::ios::binary), b(dir / "far" / lod.file, std::ios::binary);
      EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {}))
          << lod.file;
    }
  }
  // the cut in the input's coordinates: double positions, the offset added back
  const CliRun extracted = run_cli(dir, "extract " + (dir / "far").string() + " --level 0 -o " + (dir / "cut.ply").string());
  ASSERT_EQ(extracted.code, 0) << extracted.err;
  PlyReadOptions framed;
  framed.position_origin = offset;
  Result<PlyMesh> cut = read_ply(dir / "cut.ply", framed);
  ASSERT_TRUE(cut.ok()) << cut.status().message();
  EXPECT_TRUE(cut->info.double_positions);
  const CliRun eval = run_cli(dir, "--json eval " + (dir / "far.ply").string() + " " + (dir / "cut.ply").string());
  ASSERT_EQ(eval.code, 0) << eval.err;
  const json distances = json::parse(eval.out);
  EXPECT_LE(distances["two_sided"]["max"].get<double>(), far_tree->nodes[0].lods[0].error + 1e-6);
  EXPECT_GT(distances["two_sided"]["max_at"][0].get<double>(), offset[0] - 1.0);  // where, out there
  const CliRun exported = run_cli(dir, "export " + (dir / "far").string() + " --level 0 -o " + (dir / "cut.gltf").string());
  ASSERT_EQ(exported.code, 0) << exported.err;
  std::ifstream gltf(dir / "cut.gltf");
  const json document = json::parse(gltf);
  const auto translation = document["nodes"][0]["translation"].get<std::array<double, 3>>();
  EXPECT_EQ(translation, offset);
}

// `info`'s stats line: counts and bytes with every digit, seconds to six significant digits.
TEST(InfoCli, StatsPrintCountsWholeAndSecondsShort) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_tree(dir / "tree");
  const fs::path file = dir / "tree" / std::string(kManifestFileName);
  Result<Manifest> manifest = read_manifest(file);
  ASSERT_TRUE(manifest.ok()) << manifest.status().message();
  manifest->stats = {{"peak_rss_bytes", 19337216.0}, {"node_work_seconds", 0.34460257999999999}};
  ASSERT_TRUE(write_manifest(file, manifest.value()).ok());
  const CliRun run = run_cli(dir, "info " + (dir / "tree").string());
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find(" node_work_seconds 0.344603 peak_rss_bytes 19337216\n"), std::string::npos)
      << run.out;
}

// info on a PLY file reads its header alone and says what a bake keeps: the attributes and
// where they come from (a colour per face, UVs per corner replacing the vertices' own), the
// textures named, and every property and element it skips. A PLY it cannot read fails as bake
// would, naming the file and line.
TEST(InfoCli, PlyFileShowsWhatIsKeptFromWhereAndWhatIsSkipped) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  const fs::path ply = dir / "scan.ply";
  std::ofstream(ply) << "ply\nformat ascii 1.0\ncomment TextureFile scan.jpg\n"
                        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "property float u\nproperty float v\nproperty float quality\n"
                        "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n"
                        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int texnumber\n"
                        "element camera 1\nproperty float focal\nend_header\n"
                        "0 0 0 0 0 1\n1 0 0 1 0 1\n0 1 0 0 1 1\n3 0 1 2 6 0 0 1 0 0 1 255 0 0 0\n35\n";
  const CliRun as_json = run_cli(dir, "--json info " + ply.string());
  ASSERT_EQ(as_json.code, 0) << as_json.err;
  const json info = json::parse(as_json.out);
  EXPECT_EQ(info.at("layout"), "position,color,uv");
  EXPECT_EQ(info.at("colors"), "face");
  EXPECT_EQ(info.at("color_type"), "uchar");
  EXPECT_EQ(info.at("uvs"), "corner");
  EXPECT_EQ(info.at("vertices"), 3);
  EXPECT_EQ(info.at("faces"), 1);
  EXPECT_EQ(info.at("texture_files"), json::array({"scan.jpg"}));
  EXPECT_EQ(info.at("skipped"),
            json::array({"vertex.u", "vertex.v", "vertex.quality", "face.texnumber", "element camera"}));
  const CliRun text = run_cli(dir, "info " + ply.string());
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("colours     per face (uchar)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("skipped     vertex.u, vertex.v, vertex.quality, face.texnumber, element camera\n"),
            std::string::npos)
      << text.out;

  const CliRun missing = run_cli(dir, "info " + (dir / "scna.ply").string());
  EXPECT_EQ(missing.code, 4);
  EXPECT_NE(missing.err.find("'" + (dir / "scna.ply").string() + "' does not exist (info takes a baked tree's "
                                                                 "directory or a PLY file)"),
            std::string::npos)
      << missing.err;
  std::ofstream(dir / "bad.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n";
  const CliRun bad = run_cli(dir, "info " + (dir / "bad.ply").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find((dir / "bad.ply").string() + ": line 3: element 'vertex' has no property 'x'"),
            std::string::npos)
      << bad.err;
}

TEST(ExtractCli, ErrorCutUsesOnlyLodsWithinTheTargetAndWeldsSeams) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  write_tree(dir / "tree");
  const std::string tree = (dir / "tree").string(), out = (dir / "cut.ply").string();
  struct Case {
    const char* error;
    std::size_t triangles, vertices, open_edges;
    double max_error;
  };
  // 0: the leaves, whose shared edge welds (8 -> 6 vertices; unwelded, the edge x = 1 would be
  // two open edges); 0.1: root lod0; 1: root lod1. A 2x1 rectangle of 4 triangles has 6
  // boundary edges, the single quad 4.
  for (const Case& c :
       {Case{"0", 4, 6, 6, 0.0}, Case{"0.1", 4, 6, 6, 0.01}, Case{"1", 2, 4, 4, 0.5}}) {
    const CliRun run = run_cli(dir, std::string("--json extract ") + tree + " --error " + c.error +
                                        " -o " + out + " --ascii");
    ASSERT_EQ(run.code, 0) << run.err;
    const json r = json::parse(run.out);
    EXPECT_EQ(r["triangles"], c.triangles) << c.error;
    EXPECT_EQ(r["vertices"], c.vertices) << c.error;
    EXPECT_EQ(r["max_error"], c.max_error) << c.error;
    EXPECT_LE(r["max_error"].get<double>(), std::stod(c.error));
    const NodeMesh mesh = read_mesh(out);
    EXPECT_EQ(mesh.triangle_count(), c.triangles);
    EXPECT_EQ(mesh.vertex_count(), c.vertices);
    EXPECT_EQ(open_edges(mesh), c.open_edges) << c.error;
  }
}

TEST(ExtractCli, UsageAndBrokenTreeErrors) {
  SKIP_WITHOUT_CLI();
  TempDir dir;
  const std::string tree = (dir / "tree").string(), out = (dir / "cut.ply").string();
  EXPECT_EQ(run_cli(dir, "extract " + tree + " --level 0 -o " + out).code, 4);  // no manifest
  write_tree(dir / "tree");
  EXPECT_EQ(run_cli(dir, "extract " + tree + " -o " + out).code, 1);
  EXPECT_EQ(run_cli(dir, "extract " + tree + " --error 1 --level 0 -o " + out).code, 1);
  EXPECT_EQ(run_cli(dir, "extract " + tree + " --error -2 -o " + out).code, 1);
  // the root's lod1 copied over its lod0: a valid file, but not the one the manifest lists (its
  // size already says so, before it is read)
  fs::copy_file(dir / "tree" / "lod0.olod", dir / "lod0.kept");
  fs::copy_file(dir / "tree" / "lod1.olod", dir / "tree" / "lod0.olod", fs::copy_options::overwrite_existing);
  CliRun swapped = run_cli(dir, "extract " + tree + " --level 0 -o " + out);
  EXPECT_EQ(swapped.code, 2);
  EXPECT_NE(swapped.err.find("lod0.olod: 120 bytes, the manifest says 156"), std::string::npos) << swapped.err;
  EXPECT_FALSE(fs::exists(out));
  fs::copy_file(dir / "lod0.kept", dir / "tree" / "lod0.olod", fs::copy_options::overwrite_existing);
  // a corrupted node file: bad input, named, and no output file
  {
    std::fstream f(dir / "tree" / "1" / "lod0.olod", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(60);
    f.put('\x7f');
  }
  const CliRun run = run_cli(dir, "extract " + tree + " --level 1 -o " + out);
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("lod0.olod"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));
}

// --- reference, compare (on a real bake of a sampled rock) -------------------------------------

// Debug builds (the CI's ASan+UBSan run, where OpenMesh's decimater is ~10x slower) bake a
// smaller rock; every assertion scales with it.
#ifdef NDEBUG
constexpr int kBakedRockTriangles = 20'000;
#else
constexpr int kBakedRockTriangles = 8'000;
#endif

class BakedRock : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
    // positions only: the rock's uv-seam copies then weld, and the rock is closed
    CliRun run = run_cli(dir_, "sample --shape rock --triangles " + std::to_string(kBakedRockTriangles) +
                                   " --attributes none -o " +
                                   input());
    ASSERT_EQ(run.code, 0) << run.err;
    run = run_cli(dir_, "bake " + input() + " -o " + tree() + " --max-tris 1500");
    ASSERT_EQ(run.code, 0) << run.err;
  }
  std::string input() const { return (dir_ / "rock.ply").string(); }
  std::string tree() const { return (dir_ / "tree").string(); }

  TempDir dir_;
};

TEST_F(BakedRock, ReferenceReachesTheCountAndStaysClose) {
  const std::string out = (dir_ / "ref.ply").string();
  const int target = kBakedRockTriangles / 10;
  const CliRun run = run_cli(
      dir_, "--json reference " + input() + " --triangles " + std::to_string(target) + " -o " + out);
  ASSERT_EQ(run.code, 0) << run.err;
  const json r = json::parse(run.out);
  EXPECT_EQ(r["input_triangles"], kBakedRockTriangles);
  EXPECT_LE(r["triangles"].get<int>(), target);
  EXPECT_GE(r["triangles"].get<int>(), target - 2);
  const NodeMesh mesh = read_mesh(out);
  EXPECT_EQ(json(mesh.triangle_count()), r["triangles"]);
  EXPECT_EQ(open_edges(mesh), 0u);

  const CliRun eval = run_cli(dir_, "--json eval " + input() + " " + out);
  ASSERT_EQ(eval.code, 0) << eval.err;
  const json e = json::parse(eval.out);
  // 10% of the triangles of a smooth-ish rock: well under 1% of the diagonal on average
  EXPECT_LT(e["two_sided"]["rms_relative"].get<double>(), 0.005);
  EXPECT_GT(e["two_sided"]["rms_relative"].get<double>(), 0.0);

  EXPECT_EQ(run_cli(dir_, "reference " + input() + " --triangles 0 -o " + out).code, 1);
  EXPECT_EQ(run_cli(dir_, "reference " + (dir_ / "nope.ply").string() + " --triangles 9 -o " + out)
                .code,
            4);
}

TEST_F(BakedRock, CutsAtEveryStoredErrorAreClosed) {
  Result<Manifest> manifest = read_tree_manifest(tree());
  ASSERT_TRUE(manifest.ok());
  std::vector<double> errors{0.0};
  for (const NodeInfo& n : manifest->nodes)
    for (const LodInfo& l : n.lods) errors.push_back(l.error);
  std::sort(errors.begin(), errors.end());
  errors.erase(std::unique(errors.begin(), errors.end()), errors.end());
  const std::string out = (dir_ / "cut.ply").string();
  // every distinct cut, up to 8 of them spread over the ladder
  const std::size_t step = std::max<std::size_t>(1, errors.size() / 8);
  for (std::size_t i = 0; i < errors.size(); i += step) {
    std::ostringstream e;
    e.precision(17);
    e << errors[i];
    const CliRun run = run_cli(dir_, "--json extract " + tree() + " --error " + e.str() + " -o " + out);
    ASSERT_EQ(run.code, 0) << run.err;
    const json r = json::parse(run.out);
    for (const json& lod : r["lods"]) {
      const auto node = std::find_if(manifest->nodes.begin(), manifest->nodes.end(),
                                     [&](const NodeInfo& n) { return n.path == lod["node"]; });
      ASSERT_NE(node, manifest->nodes.end());
      const LodInfo& info = node->lods[lod["lod"].get<std::size_t>()];
      EXPECT_TRUE(info.error <= errors[i] || (node->is_leaf() && lod["lod"] == 0));
    }
    const NodeMesh mesh = read_mesh(out);
    EXPECT_EQ(json(mesh.triangle_count()), r["triangles"]);
    EXPECT_EQ(open_edges(mesh), 0u) << "error " << errors[i];
  }
}

TEST_F(BakedRock, CompareReportsEveryCutNextToTheReference) {
  const CliRun run = run_cli(dir_, "--json compare " + input() + " " + tree() + " --samples 20000");
  ASSERT_EQ(run.code, 0) << run.err;
  const json r = json::parse(run.out);
  EXPECT_EQ(r["input_triangles"], kBakedRockTriangles);
  ASSERT_FALSE(r["rows"].empty());
  std::uint64_t previous = ~0ull;
  for (const json& row : r["rows"]) {
    const auto triangles = row["triangles"].get<std::uint64_t>();
    EXPECT_LT(triangles, previous) << "rows go from fine to coarse, no repeats";
    previous = triangles;
    EXPECT_LE(row["stored_max_error"].get<double>(), row["error_target"].get<double>());
    EXPECT_LE(row["reference_triangles"].get<std::uint64_t>(), triangles);
    EXPECT_GE(row["reference_triangles"].get<std::uint64_t>() + 2, triangles);
    EXPECT_DOUBLE_EQ(row["percent_of_input"].get<double>(), 100.0 * static_cast<double>(triangles) / kBakedRockTriangles);
    // the Hausdorff distance bounds the RMS; the stored error bounds what the cut's samples see
    // (one-sided, input -> cut)
    EXPECT_LE(row["rms"].get<double>(), row["hausdorff"].get<double>());
    EXPECT_LE(row["cut"]["a_to_b"]["max"].get<double>(),
              row["stored_max_error"].get<double>() + 1e-6);
    EXPECT_NEAR(row["rms_ratio"].get<double>(),
                row["rms"].get<double>() / row["reference_rms"].get<double>(), 1e-9);
  }

  const CliRun cuts_only = run_cli(dir_, "--json compare " + input() + " " + tree() +
                                             " --samples 5000 --no-reference --errors 0");
  ASSERT_EQ(cuts_only.code, 0) << cuts_only.err;
  const json c = json::parse(cuts_only.out);
  ASSERT_EQ(c["rows"].size(), 1u);
  EXPECT_EQ(c["rows"][0]["triangles"], kBakedRockTriangles);
  EXPECT_LT(c["rows"][0]["hausdorff"].get<double>(), 1e-6);  // error 0: the original triangles
  EXPECT_FALSE(c["rows"][0].contains("reference_rms"));
  EXPECT_TRUE(c["reference_seconds"].is_null());

  const CliRun markdown =
      run_cli(dir_, "compare " + input() + " " + tree() + " --samples 5000 --markdown --errors 0");
  ASSERT_EQ(markdown.code, 0) << markdown.err;
  EXPECT_EQ(markdown.out.rfind("| error target | stored max | triangles |", 0), 0u) << markdown.out;
  EXPECT_NE(markdown.out.find("| 0 | 0 | " + std::to_string(kBakedRockTriangles) + " | 100.00 |"),
            std::string::npos)
      << markdown.out;
}

TEST_F(BakedRock, CompareRejectsAnInputTheTreeWasNotBakedFrom) {
  write_mesh(dir_ / "other.ply", plane(3, 0.0f));
  const CliRun run = run_cli(dir_, "compare " + (dir_ / "other.ply").string() + " " + tree());
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("other.ply has 18 triangles, but the tree"), std::string::npos) << run.err;
  EXPECT_EQ(run_cli(dir_, "compare " + input() + " " + tree() + " --errors 1,x").code, 1);
  EXPECT_EQ(run_cli(dir_, "compare " + input() + " " + tree() + " --fractions 0").code, 1);
  EXPECT_EQ(run_cli(dir_, "compare " + input() + " " + (dir_ / "none").string()).code, 4);
}

}  // namespace
}  // namespace octolod
