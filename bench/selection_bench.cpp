// selection_bench: per-frame cost of StreamingTree::update() (selection, fallbacks, paging and
// prefetch decisions; loads run between frames, outside the timing) on a synthetic octree: the
// cells of a sphere shell of radius --shell refined to --depth, every node with two LODs
// (depth 8: shell 0.8 -> 263,585 nodes, shell 0.5 -> ~100K). Cameras orbit the model at 5, 2.5,
// 1.5 and 1.19 shell radii; prints per orbit the p50/p99/max of FrameStats::selection_ms (wall
// time of update(), the quantity `octolod walk` reports) and of selection_cpu_ms (cpu_*: the
// update thread's CPU time, the same without preemption by other processes).
// Target (issue 5): p99 <= 0.2 ms per frame on ~100K nodes.
//
//   selection_bench [--depth 8] [--shell 0.8] [--frames 2000] [--budget-mb 512]
//   (NOPREFETCH=1: prefetch off)
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/runtime/streaming_tree.h"
#include "percentile.h"

namespace {

using namespace octolod;
using namespace octolod::runtime;

constexpr std::uint32_t kTriangles[2] = {256, 64};

// `triangles` triangles in a strip along the diagonal of `b`.
NodeMesh strip_mesh(const Bounds& b, std::uint32_t triangles) {
  NodeMesh mesh;
  for (std::uint32_t v = 0; v < triangles + 2; ++v) {
    const float t = static_cast<float>(v) / static_cast<float>(triangles + 1);
    for (std::size_t a = 0; a < 3; ++a) mesh.vertices.push_back(b.min[a] + t * (b.max[a] - b.min[a]));
  }
  for (std::uint32_t t = 0; t < triangles; ++t) mesh.indices.insert(mesh.indices.end(), {t, t + 1, t + 2});
  return mesh;
}

bool touches_shell(const Bounds& b, float shell) {
  float near2 = 0, far2 = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    const float lo = b.min[a], hi = b.max[a];
    const float n = std::max({lo, 0.0f, -hi});
    const float f = std::max(std::abs(lo), std::abs(hi));
    near2 += n * n;
    far2 += f * f;
  }
  return near2 <= shell * shell && far2 >= shell * shell;
}

Manifest shell_octree(std::uint32_t max_depth, float shell) {
  Manifest m;
  m.bounds.min = {-1, -1, -1};
  m.bounds.max = {1, 1, 1};
  NodeInfo root;
  root.cell = root.bounds = m.bounds;
  m.nodes.push_back(root);
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    if (m.nodes[i].depth >= max_depth) continue;
    for (std::uint32_t octant = 0; octant < 8; ++octant) {
      NodeInfo child;
      child.depth = m.nodes[i].depth + 1;
      child.parent = static_cast<std::int32_t>(i);
      for (std::size_t a = 0; a < 3; ++a) {
        const float lo = m.nodes[i].cell.min[a], hi = m.nodes[i].cell.max[a], mid = 0.5f * (lo + hi);
        child.cell.min[a] = ((octant >> a) & 1u) ? mid : lo;
        child.cell.max[a] = ((octant >> a) & 1u) ? hi : mid;
      }
      if (!touches_shell(child.cell, shell)) continue;
      child.bounds = child.cell;
      m.nodes[i].children[octant] = static_cast<std::int32_t>(m.nodes.size());
      m.nodes.push_back(child);
    }
  }
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    NodeInfo& n = m.nodes[i];
    const double edge = n.cell.max[0] - n.cell.min[0];
    for (std::uint32_t l = 0; l < 2; ++l) {
      LodInfo lod;
      lod.triangles = kTriangles[l];
      lod.vertices = kTriangles[l] + 2;
      lod.error = l == 0 ? (n.is_leaf() ? 0.0 : 0.01 * edge) : 0.04 * edge;
      lod.bytes = node_file_size(strip_mesh(n.bounds, kTriangles[l]));
      lod.file = std::to_string(i) + "/" + std::to_string(l);
      n.lods.push_back(lod);
    }
  }
  return m;
}

// Node files made up on demand from the file name "<node>/<lod>": strip_mesh of the node's box.
class SyntheticSource final : public NodeSource {
 public:
  explicit SyntheticSource(const Manifest& m) : manifest_(m) {}
  Result<std::vector<std::byte>> read(std::string_view file, std::uint64_t expected_bytes) const override {
    std::size_t node = 0, lod = 0;
    const auto slash = file.find('/');
    std::from_chars(file.data(), file.data() + slash, node);
    std::from_chars(file.data() + slash + 1, file.data() + file.size(), lod);
    std::vector<std::byte> bytes = encode_node_file(strip_mesh(manifest_.nodes[node].bounds, kTriangles[lod]));
    OCTOLOD_RETURN_IF_ERROR(check_node_file_size(file, bytes.size(), expected_bytes));
    return bytes;
  }

 private:
  const Manifest& manifest_;
};

}  // namespace

int main(int argc, char** argv) {
  std::uint32_t depth = 8, frames = 2000;
  std::uint64_t budget_mb = 512;
  float shell = 0.8f;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--depth")) depth = static_cast<std::uint32_t>(std::stoul(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--frames")) frames = static_cast<std::uint32_t>(std::stoul(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--budget-mb")) budget_mb = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--shell")) shell = std::stof(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: selection_bench [--depth N] [--shell R] [--frames N] [--budget-mb N]\n");
      return 1;
    }
  }
  if (!(shell > 0.0f && shell < 1.0f)) {
    std::fprintf(stderr, "error: --shell must be within (0, 1)\n");
    return 1;
  }
  const Manifest manifest = shell_octree(depth, shell);
  std::printf("synthetic shell octree: depth %u, shell radius %.2f, %zu nodes; %u frames per orbit, budget %llu MiB\n",
              depth, static_cast<double>(shell), manifest.nodes.size(), frames, static_cast<unsigned long long>(budget_mb));
  std::printf("%-8s %8s %8s %8s %8s %9s %9s %9s %9s %9s %9s\n", "orbit_r", "visited", "wanted", "drawn", "tris",
              "p50_ms", "p99_ms", "max_ms", "cpu_p50", "cpu_p99", "cpu_max");

  for (const float orbit : {5.0f, 2.5f, 1.5f, 1.1875f}) {
    const float radius = orbit * shell;
    auto executor = std::make_shared<SynchronousExecutor>();
    StreamingOptions options;
    options.max_resident_bytes = budget_mb << 20;
    options.max_loads_in_flight = 64;
    options.prefetch = std::getenv("NOPREFETCH") == nullptr;
    auto opened = StreamingTree::open(manifest, std::make_shared<SyntheticSource>(manifest), executor, options);
    if (!opened.ok()) {
      std::fprintf(stderr, "error: %s\n", opened.status().message().c_str());
      return 2;
    }
    StreamingTree& tree = *opened.value();
    std::vector<double> ms, cpu_ms;
    double visited = 0, wanted = 0, drawn = 0, triangles = 0;
    const std::uint32_t warmup = 200;
    for (std::uint32_t f = 0; f < warmup + frames; ++f) {
      // One orbit per 1000 frames, slightly inclined, 1080p at 60 degrees.
      const float angle = 6.2831853f * static_cast<float>(f) / 1000.0f;
      const glm::vec3 eye(radius * std::cos(angle), 0.3f * radius, radius * std::sin(angle));
      const Camera camera = make_perspective_camera(eye, glm::vec3(0.0f), glm::vec3(0, 1, 0), 1.0471976f,
                                                    16.0f / 9.0f, 0.01f, 100.0f, 1080.0f);
      const FrameResult& frame = tree.update(camera);
      executor->run_pending();  // loads between frames, not timed
      if (f < warmup) continue;
      ms.push_back(frame.stats.selection_ms);
      cpu_ms.push_back(frame.stats.selection_cpu_ms);
      visited += frame.stats.visited;
      wanted += frame.stats.wanted;
      drawn += frame.stats.drawn_nodes;
      triangles += static_cast<double>(frame.stats.drawn_triangles);
    }
    const double n = static_cast<double>(frames);
    std::printf("%-8.2f %8.0f %8.0f %8.0f %8.0f %9.4f %9.4f %9.4f %9.4f %9.4f %9.4f\n", static_cast<double>(radius),
                visited / n, wanted / n, drawn / n, triangles / n, percentile(ms, 0.5), percentile(ms, 0.99),
                *std::max_element(ms.begin(), ms.end()), percentile(cpu_ms, 0.5), percentile(cpu_ms, 0.99),
                *std::max_element(cpu_ms.begin(), cpu_ms.end()));
  }
  return 0;
}
