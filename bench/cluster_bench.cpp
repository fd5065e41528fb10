// Benchmark of the per-node simplification (seed 3.5, 4.4, 3.5.3): build_lods (a leaf's whole
// LOD chain with the default grid method) on generated rock and city nodes, in input triangles
// per second, and one step (to half the triangles) split into its phases: preparation (weld,
// position ids, boundary), grid resolution search, clustering, conservative Hausdorff bound.
//
//   cluster_bench [--repeat N] [triangles...]     default: 2000 20000 200000, repeat 3
//
// A node here is the whole sample (its cell = the sample's bounds) cut in half at x = centre,
// the left half: a real octree node with a locked boundary on the cut. Best of N runs. The chain
// is timed in wall and process CPU time (single-threaded: on a loaded machine CPU time is the
// fair number). Last, the attribute solve of one output wedge (minimize_free_block) in ns, for
// m = 2 (uv), 3 (normal), 8 (every attribute) free coordinates: random full-rank blocks (the
// LDL^T path nearly every wedge takes) and rank-deficient ones (the eigen-decomposition path),
// 1,024 blocks in cache.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "cluster.h"
#include "error_bound.h"
#include "quadric.h"
#include "octolod/bake/simplify.h"
#include "octolod/formats/node_file.h"
#include "octolod/samplegen/sample_generator.h"

namespace {

using namespace octolod;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  std::exit(1);
}

NodeMesh make_sample(samplegen::Shape shape, std::uint64_t triangles) {
  samplegen::SampleSpec spec;
  spec.shape = shape;
  spec.triangles = triangles;
  Result<NodeMesh> mesh = samplegen::generate_sample_mesh(spec);
  if (!mesh.ok()) fail(mesh.status().message());
  return std::move(mesh.value());
}

// The triangles whose centroid has x < split (vertices compacted), and its cell.
struct Node {
  NodeMesh mesh;
  Bounds cell;
};
Node left_half(const NodeMesh& mesh) {
  const Bounds bounds = mesh.bounds();
  const float split = 0.5f * (bounds.min[0] + bounds.max[0]);
  const std::size_t stride = mesh.layout.floats();
  Node node;
  node.cell = bounds;
  node.cell.max[0] = split;
  node.mesh.layout = mesh.layout;
  std::vector<std::uint32_t> remap(mesh.vertex_count(), std::numeric_limits<std::uint32_t>::max());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    float x = 0.0f;
    for (int k = 0; k < 3; ++k) x += mesh.vertices[mesh.indices[3 * t + static_cast<std::size_t>(k)] * stride];
    if (x / 3.0f >= split) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.indices[3 * t + static_cast<std::size_t>(k)];
      if (remap[v] == std::numeric_limits<std::uint32_t>::max()) {
        remap[v] = static_cast<std::uint32_t>(node.mesh.vertex_count());
        node.mesh.vertices.insert(node.mesh.vertices.end(), mesh.vertices.begin() + static_cast<std::ptrdiff_t>(v * stride),
                                  mesh.vertices.begin() + static_cast<std::ptrdiff_t>((v + 1) * stride));
      }
      node.mesh.indices.push_back(remap[v]);
    }
  }
  return node;
}

void run(samplegen::Shape shape, std::uint64_t triangles, int repeat) {
  const Node node = left_half(make_sample(shape, triangles));
  const double input = static_cast<double>(node.mesh.triangle_count());

  double chain_best = std::numeric_limits<double>::infinity();
  double chain_cpu_best = chain_best;
  std::vector<bake::Lod> lods;
  for (int r = 0; r < repeat; ++r) {
    const auto start = Clock::now();
    const std::clock_t cpu_start = std::clock();
    auto result = bake::build_lods(node.mesh, 0.0, node.cell, {});
    chain_cpu_best = std::min(chain_cpu_best, static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
    chain_best = std::min(chain_best, seconds_since(start));
    if (!result.ok()) fail(result.status().message());
    lods = std::move(result.value());
  }

  // one step (input -> half) by phases, and the error bound with and without the clustering's
  // hints (the BVH path is what the bound would cost without them)
  const auto target = node.mesh.triangle_count() / 2;
  double prepare_best = std::numeric_limits<double>::infinity(), search_best = prepare_best,
         cluster_best = prepare_best, bound_best = prepare_best, bvh_best = prepare_best;
  std::size_t step_triangles = 0;
  for (int r = 0; r < repeat; ++r) {
    auto start = Clock::now();
    const bake::PreparedNode prepared = bake::prepare_node(node.mesh, node.cell);
    prepare_best = std::min(prepare_best, seconds_since(start));
    start = Clock::now();
    const bake::Clustering clustering = bake::adaptive_grid_clustering(prepared, target, bake::SearchCount::surviving);
    search_best = std::min(search_best, seconds_since(start));
    start = Clock::now();
    const bake::ClusteredMesh clustered = bake::build_clustered_mesh(prepared.mesh(), prepared.face_normal, clustering, prepared.origin);
    cluster_best = std::min(cluster_best, seconds_since(start));
    step_triangles = clustered.mesh.triangle_count();
    start = Clock::now();
    const double bound = bake::hausdorff_upper_bound(prepared.mesh(), clustered.mesh, clustered.hints());
    bound_best = std::min(bound_best, seconds_since(start));
    if (r == 0) {
      start = Clock::now();
      const double bvh_bound = bake::hausdorff_upper_bound(prepared.mesh(), clustered.mesh);
      bvh_best = std::min(bvh_best, seconds_since(start));
      std::printf("      step bound %.6f (hinted) vs %.6f (BVH queries)\n", bound, bvh_bound);
    }
  }
  const double step_best = prepare_best + search_best + cluster_best + bound_best;

  std::printf("%-5s %8.0f tris  chain: %2zu LODs (last %6zu tris) %8.2f ms wall %8.2f ms CPU  %6.2f M tris/s (CPU) | step to %zu: "
              "%7.2f ms %6.2f M tris/s = prepare %.2f + search %.2f + cluster %.2f + bound %.2f ms "
              "(BVH bound %.2f ms)\n",
              std::string(samplegen::to_string(shape)).c_str(), input, lods.size(),
              lods.back().mesh.triangle_count(), chain_best * 1e3, chain_cpu_best * 1e3, input / chain_cpu_best / 1e6,
              step_triangles,
              step_best * 1e3, input / step_best / 1e6, prepare_best * 1e3, search_best * 1e3, cluster_best * 1e3,
              bound_best * 1e3, bvh_best * 1e3);
}

// Nanoseconds per minimize_free_block over `blocks` (free_block_doubles(m) each), best of 3.
double solve_nanoseconds(int m, const std::vector<double>& blocks) {
  const std::size_t size = bake::free_block_doubles(m), count = blocks.size() / size;
  std::vector<double> mean(static_cast<std::size_t>(m), 0.0), out(static_cast<std::size_t>(m));
  constexpr int kRounds = 512;
  double best = std::numeric_limits<double>::infinity(), sink = 0.0;
  for (int r = 0; r < 3; ++r) {
    const auto start = Clock::now();
    for (int round = 0; round < kRounds; ++round)
      for (std::size_t b = 0; b < count; ++b) {
        bake::minimize_free_block(m, &blocks[b * size], mean.data(), out.data());
        sink += out[0];
      }
    best = std::min(best, seconds_since(start));
  }
  if (!(sink == sink)) fail("attribute solve: not a number");
  return best * 1e9 / (static_cast<double>(kRounds) * static_cast<double>(count));
}

// Random symmetric positive semi-definite free blocks of m coordinates: sums of `rank` outer
// products, plus the identity times `ridge` (full rank when ridge > 0), then a random right-hand side.
std::vector<double> random_blocks(int m, int rank, double ridge) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto n = static_cast<std::size_t>(m);
  std::vector<double> blocks;
  for (int b = 0; b < 1024; ++b) {
    std::vector<double> matrix(n * n, 0.0), v(n);
    for (int r = 0; r < rank; ++r) {
      for (double& x : v) x = uniform(rng);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) matrix[i * n + j] += v[i] * v[j];
    }
    for (std::size_t i = 0; i < n; ++i) matrix[i * n + i] += ridge;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i; j < n; ++j) blocks.push_back(matrix[i * n + j]);
    for (std::size_t i = 0; i < n; ++i) blocks.push_back(uniform(rng));
  }
  return blocks;
}

void run_solves() {
  for (const int m : {2, 3, 8})
    std::printf("attribute solve, m = %d: %6.1f ns full rank, %7.1f ns rank %d\n", m,
                solve_nanoseconds(m, random_blocks(m, m, 1.0)), solve_nanoseconds(m, random_blocks(m, m - 1, 0.0)), m - 1);
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 3;
  std::vector<std::uint64_t> sizes;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--repeat" && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
      continue;
    }
    auto count = samplegen::parse_triangle_count(arg);
    if (!count.ok()) fail(count.status().message());
    sizes.push_back(count.value());
  }
  if (sizes.empty()) sizes = {2'000, 20'000, 200'000};
  for (const samplegen::Shape shape : {samplegen::Shape::rock, samplegen::Shape::city})
    for (const std::uint64_t size : sizes) run(shape, size, repeat);
  run_solves();
  return 0;
}
