// measure_bench: TriangleBvh build and closest-point throughput, and Metro-style evaluation time
// (Cignoni, Rocchini, Scopigno 1998), on procedural rocks of 100K and 1M triangles.
//   measure_bench [triangles...]      default: 100000 1000000
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "octolod/formats/node_file.h"
#include "octolod/measure/metro.h"
#include "octolod/measure/triangle_bvh.h"
#include "octolod/samplegen/sample_generator.h"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

octolod::NodeMesh make_rock(std::uint64_t triangles, std::uint64_t seed) {
  octolod::samplegen::SampleSpec spec;
  spec.shape = octolod::samplegen::Shape::rock;
  spec.triangles = triangles;
  spec.seed = seed;
  octolod::Result<octolod::NodeMesh> mesh = octolod::samplegen::generate_sample_mesh(spec);
  if (!mesh.ok()) {
    std::fprintf(stderr, "error: %s\n", mesh.status().message().c_str());
    std::exit(1);
  }
  return std::move(mesh.value());
}

// Points near the surface: random triangles' centroids pushed off by up to `offset` model units
// along each axis, in random order (no coherence between consecutive queries).
std::vector<glm::vec3> near_surface_points(const octolod::NodeMesh& mesh, std::size_t count,
                                           float offset) {
  std::mt19937 rng(42);
  std::uniform_int_distribution<std::size_t> pick(0, mesh.triangle_count() - 1);
  std::uniform_real_distribution<float> jitter(-offset, offset);
  std::vector<glm::vec3> points(count);
  const std::uint32_t stride = mesh.layout.floats();
  for (glm::vec3& p : points) {
    std::size_t t = pick(rng);
    glm::vec3 c(0.0f);
    for (int k = 0; k < 3; ++k) {
      const float* f = mesh.vertices.data() + std::size_t{mesh.indices[3 * t + static_cast<std::size_t>(k)]} * stride;
      c += glm::vec3(f[0], f[1], f[2]) / 3.0f;
    }
    p = c + glm::vec3(jitter(rng), jitter(rng), jitter(rng));
  }
  return points;
}

void bench_bvh(const octolod::NodeMesh& mesh) {
  auto start = Clock::now();
  octolod::measure::TriangleBvh bvh(mesh.vertices, mesh.layout.floats(), mesh.indices);
  double build = seconds_since(start);
  std::printf("bvh   %9zu tris  build %.3f s (%.2f Mtris/s, 1 thread)\n", mesh.triangle_count(),
              build, static_cast<double>(mesh.triangle_count()) / build / 1e6);
  // offsets: ~1 edge length of a 1M-triangle rock (0.005), and of a 100K one (0.016), and far
  for (float offset : {0.005f, 0.016f, 0.1f}) {
    std::vector<glm::vec3> points = near_surface_points(mesh, 1'000'000, offset);
    start = Clock::now();
    double checksum = 0;
    for (const glm::vec3& p : points) checksum += bvh.closest(p).distance;
    double query = seconds_since(start);
    std::printf("      queries offset <= %.3f: %.2f Mqueries/s (1 thread, random order, mean "
                "distance %.5f)\n",
                static_cast<double>(offset), static_cast<double>(points.size()) / query / 1e6,
                checksum / static_cast<double>(points.size()));
  }
}

void bench_metro(const octolod::NodeMesh& a, const octolod::NodeMesh& b) {
  octolod::measure::MetroOptions options;
  auto start = Clock::now();
  octolod::Result<octolod::measure::MetroReport> report = octolod::measure::evaluate(a, b, options);
  double seconds = seconds_since(start);
  if (!report.ok()) {
    std::fprintf(stderr, "error: %s\n", report.status().message().c_str());
    std::exit(1);
  }
  const octolod::measure::MetroReport& r = report.value();
  std::printf("metro %9zu vs %9zu tris  %.3f s  (%llu + %llu samples, %u threads)  two-sided "
              "mean %.3g rms %.3g max %.3g (model units)\n",
              a.triangle_count(), b.triangle_count(), seconds,
              static_cast<unsigned long long>(r.a_to_b.samples),
              static_cast<unsigned long long>(r.b_to_a.samples), r.threads, r.two_sided.mean,
              r.two_sided.rms, r.two_sided.max);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::uint64_t> sizes;
  for (int i = 1; i < argc; ++i) sizes.push_back(std::strtoull(argv[i], nullptr, 10));
  if (sizes.empty()) sizes = {100'000, 1'000'000};
  for (std::uint64_t n : sizes) {
    octolod::NodeMesh fine = make_rock(n, 1);
    bench_bvh(fine);
    // against the same rock at a tenth of the resolution (a coarse LOD of it)
    octolod::NodeMesh coarse = make_rock(std::max<std::uint64_t>(n / 10, 16), 1);
    bench_metro(fine, coarse);
  }
  return 0;
}
