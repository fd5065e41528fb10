// Metro-style evaluation (Cignoni, Rocchini, Scopigno 1998): area-weighted surface sampling of
// each mesh, exact closest-point distance to the other (TriangleBvh), attribute deviation at the
// samples.
//
// Determinism: sample k of a direction is a pure function of (seed, direction, k) — a
// counter-based generator (SplitMix64 finalizer over the counter, as in Salmon et al. 2011,
// "Parallel random numbers: as easy as 1, 2, 3") — and partial sums are kept per fixed chunk of
// samples and added in chunk order, so the report does not depend on the thread count.
//
// Sampling is stratified by area: sample k lands at cumulative area (k + r_k) / N * total, so
// every triangle gets floor or ceil of its area share (Metro's "similar triangles" sampling
// without its per-triangle loop), and uniformly inside its triangle by the square-root
// barycentric warp.
#include "octolod/measure/metro.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include <glm/ext/vector_double3.hpp>
#include <glm/geometric.hpp>

#include "mesh_check.h"
#include "octolod/measure/triangle_bvh.h"

namespace octolod::measure {
namespace {

constexpr std::uint64_t kChunkSamples = 4096;
constexpr std::uint64_t kAutoSamplesPerTriangle = 10;
constexpr std::uint64_t kAutoMinSamples = 100'000;
constexpr std::uint64_t kAutoMaxSamples = 1'000'000;
constexpr double kDegreesPerRadian = 57.29577951308232;

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Uniform in [0, 1) from (key, counter).
double uniform01(std::uint64_t key, std::uint64_t counter) {
  return static_cast<double>(mix64(key ^ mix64(counter)) >> 11) * 0x1.0p-53;
}

// One mesh, ready to be sampled (cumulative areas) and queried (hierarchy).
struct Surface {
  const NodeMesh* mesh = nullptr;
  TriangleBvh bvh;
  std::vector<double> cumulative_area;  // [t] = area of triangles 0..t
  double area = 0.0;

  glm::vec3 position(std::uint32_t v) const {
    const float* f = mesh->vertices.data() + std::size_t{v} * mesh->layout.floats();
    return {f[0], f[1], f[2]};
  }
  // Attribute of `width` floats at float `offset`, interpolated on triangle t.
  glm::vec3 interpolate(std::uint32_t t, glm::vec3 bary, std::uint32_t offset, int width) const {
    const std::uint32_t stride = mesh->layout.floats();
    glm::vec3 out(0.0f);
    for (int c = 0; c < 3; ++c) {
      const float* f = mesh->vertices.data() +
                       std::size_t{mesh->indices[3 * std::size_t{t} + static_cast<std::size_t>(c)]} * stride +
                       offset;
      for (int k = 0; k < width; ++k) out[k] += bary[c] * f[k];
    }
    return out;
  }
};

void prepare_areas(Surface& s) {
  const NodeMesh& m = *s.mesh;
  s.cumulative_area.resize(m.triangle_count());
  double total = 0.0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    glm::dvec3 a(s.position(m.indices[3 * t])), b(s.position(m.indices[3 * t + 1])),
        c(s.position(m.indices[3 * t + 2]));
    total += 0.5 * glm::length(glm::cross(b - a, c - a));
    s.cumulative_area[t] = total;
  }
  s.area = total;
}

// Sums over a run of samples; added in chunk order for determinism.
struct Partial {
  std::uint64_t samples = 0;
  double sum = 0.0, sum2 = 0.0, max = 0.0;
  glm::vec3 max_at{0.0f}, max_closest{0.0f};  // the first sample at `max`, its closest point
  std::uint64_t normal_samples = 0;
  double normal_sum = 0.0, normal_max = 0.0;
  double color_sum2 = 0.0, uv_sum2 = 0.0;

  void add(const Partial& o) {
    // the max and where it is together; on equal ones the earlier run's place stays
    if (o.samples > 0 && (samples == 0 || o.max > max)) {
      max = o.max;
      max_at = o.max_at;
      max_closest = o.max_closest;
    }
    samples += o.samples;
    sum += o.sum;
    sum2 += o.sum2;
    normal_samples += o.normal_samples;
    normal_sum += o.normal_sum;
    normal_max = std::max(normal_max, o.normal_max);
    color_sum2 += o.color_sum2;
    uv_sum2 += o.uv_sum2;
  }
};

struct Direction {
  const Surface* from;
  const Surface* to;
  std::uint64_t samples;
  std::uint64_t key;  // generator key: seed and direction
};

// Samples [first, last) of `dir`.
Partial sample_range(const Direction& dir, VertexLayout compared, std::uint64_t first,
                     std::uint64_t last) {
  const Surface& from = *dir.from;
  const Surface& to = *dir.to;
  const NodeMesh& fm = *from.mesh;
  Partial out;
  const double scale = from.area / static_cast<double>(dir.samples);
  // Previous sample and its distance: by the triangle inequality d(p) <= d(prev) + |p - prev|,
  // a bound that lets the hierarchy prune almost everything for neighbouring samples.
  glm::vec3 prev_point(0.0f);
  float prev_distance = -1.0f;
  for (std::uint64_t k = first; k < last; ++k) {
    // pick the triangle by stratified cumulative area
    double target = (static_cast<double>(k) + uniform01(dir.key, 3 * k)) * scale;
    auto it = std::upper_bound(from.cumulative_area.begin(), from.cumulative_area.end(), target);
    if (it == from.cumulative_area.end()) --it;
    const auto t = static_cast<std::uint32_t>(it - from.cumulative_area.begin());
    // uniform point inside it
    double s = std::sqrt(uniform01(dir.key, 3 * k + 1));
    double r = uniform01(dir.key, 3 * k + 2);
    glm::vec3 bary(static_cast<float>(1.0 - s), static_cast<float>(s * (1.0 - r)),
                   static_cast<float>(s * r));
    glm::vec3 p = bary.x * from.position(fm.indices[3 * std::size_t{t}]) +
                  bary.y * from.position(fm.indices[3 * std::size_t{t} + 1]) +
                  bary.z * from.position(fm.indices[3 * std::size_t{t} + 2]);

    TriangleBvh::Hit hit;
    if (prev_distance >= 0.0f) {
      float bound = (prev_distance + glm::length(p - prev_point)) * 1.001f + 1e-30f;
      hit = to.bvh.closest(p, bound);
    }
    if (!hit.found()) hit = to.bvh.closest(p);
    prev_point = p;
    prev_distance = hit.distance;

    const double d = hit.distance;
    if (out.samples == 0 || d > out.max) out.max = d, out.max_at = p, out.max_closest = hit.point;
    ++out.samples;
    out.sum += d;
    out.sum2 += d * d;

    if (compared.normal) {
      glm::vec3 na = from.interpolate(t, bary, VertexLayout::normal_offset(), 3);
      glm::vec3 nb = to.interpolate(hit.triangle, hit.barycentric, VertexLayout::normal_offset(), 3);
      if (glm::length(na) > 0.0f && glm::length(nb) > 0.0f) {
        // atan2(|a x b|, a . b) needs no normalization and, unlike acos of the cosine, stays
        // accurate near 0 degrees (parallel normals give exactly 0)
        const glm::dvec3 a(na), b(nb);
        const double degrees =
            std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)) * kDegreesPerRadian;
        ++out.normal_samples;
        out.normal_sum += degrees;
        out.normal_max = std::max(out.normal_max, degrees);
      }
    }
    if (compared.color) {
      glm::vec3 diff = from.interpolate(t, bary, fm.layout.color_offset(), 3) -
                       to.interpolate(hit.triangle, hit.barycentric, to.mesh->layout.color_offset(), 3);
      out.color_sum2 += glm::dot(diff, diff);
    }
    if (compared.uv) {
      glm::vec3 diff = from.interpolate(t, bary, fm.layout.uv_offset(), 2) -
                       to.interpolate(hit.triangle, hit.barycentric, to.mesh->layout.uv_offset(), 2);
      out.uv_sum2 += glm::dot(diff, diff);
    }
  }
  return out;
}

Deviation to_deviation(const Partial& p, VertexLayout compared, double diagonal) {
  Deviation d;
  d.samples = p.samples;
  d.compared = compared;
  if (p.samples == 0) return d;
  const auto n = static_cast<double>(p.samples);
  d.mean = p.sum / n;
  d.rms = std::sqrt(p.sum2 / n);
  d.max = p.max;
  d.mean_relative = d.mean / diagonal;
  d.rms_relative = d.rms / diagonal;
  d.max_relative = d.max / diagonal;
  for (glm::length_t k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    d.max_at[i] = p.max_at[k], d.max_closest[i] = p.max_closest[k];
  }
  if (compared.normal && p.normal_samples > 0) {
    d.normal_mean_degrees = p.normal_sum / static_cast<double>(p.normal_samples);
    d.normal_max_degrees = p.normal_max;
  }
  if (compared.color) d.color_rms = std::sqrt(p.color_sum2 / n);
  if (compared.uv) d.uv_rms = std::sqrt(p.uv_sum2 / n);
  return d;
}

std::uint64_t sample_count(const MetroOptions& options, const NodeMesh& from) {
  if (options.samples > 0) return options.samples;
  return std::clamp<std::uint64_t>(kAutoSamplesPerTriangle * from.triangle_count(), kAutoMinSamples,
                                   kAutoMaxSamples);
}

}  // namespace

Result<MetroReport> evaluate(const NodeMesh& a, const NodeMesh& b, const MetroOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  OCTOLOD_RETURN_IF_ERROR(check_mesh(a, "mesh a"));
  OCTOLOD_RETURN_IF_ERROR(check_mesh(b, "mesh b"));
  if (a.indices.empty()) return bad_input_error("mesh a: the mesh has no triangles");
  if (b.indices.empty()) return bad_input_error("mesh b: the mesh has no triangles");

  MetroReport report;
  report.threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());

  // both hierarchies at once, one per thread when there are two
  Surface sa, sb;
  sa.mesh = &a;
  sb.mesh = &b;
  auto prepare = [](Surface& s) {
    s.bvh = TriangleBvh(s.mesh->vertices, s.mesh->layout.floats(), s.mesh->indices);
    prepare_areas(s);
  };
  if (report.threads > 1) {
    std::thread helper(prepare, std::ref(sb));
    prepare(sa);
    helper.join();
  } else {
    prepare(sa);
    prepare(sb);
  }
  if (!(sa.area > 0.0)) return bad_input_error("mesh a: the surface has zero area");
  if (!(sb.area > 0.0)) return bad_input_error("mesh b: the surface has zero area");
  report.area_a = sa.area;
  report.area_b = sb.area;
  report.diagonal = a.bounds().diagonal();

  const VertexLayout compared{a.layout.normal && b.layout.normal, a.layout.color && b.layout.color,
                              a.layout.uv && b.layout.uv};
  const Direction directions[2] = {
      {&sa, &sb, sample_count(options, a), mix64(options.seed) ^ 0xA5A5A5A5A5A5A5A5ull},
      {&sb, &sa, sample_count(options, b), mix64(options.seed) ^ 0x5A5A5A5A5A5A5A5Aull}};

  // chunks of both directions in one work list, claimed by the threads in any order
  struct Chunk {
    int direction;
    std::uint64_t first, last;
  };
  std::vector<Chunk> chunks;
  for (int d = 0; d < 2; ++d)
    for (std::uint64_t first = 0; first < directions[d].samples; first += kChunkSamples)
      chunks.push_back({d, first, std::min(first + kChunkSamples, directions[d].samples)});
  std::vector<Partial> partials(chunks.size());
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1, std::memory_order_relaxed)) < chunks.size();)
      partials[i] = sample_range(directions[chunks[i].direction], compared, chunks[i].first,
                                 chunks[i].last);
  };
  std::vector<std::thread> helpers;
  for (unsigned i = 1; i < report.threads; ++i) helpers.emplace_back(work);
  work();
  for (std::thread& t : helpers) t.join();

  Partial sums[2], both;
  for (std::size_t i = 0; i < chunks.size(); ++i) sums[chunks[i].direction].add(partials[i]);
  both.add(sums[0]);
  both.add(sums[1]);
  report.a_to_b = to_deviation(sums[0], compared, report.diagonal);
  report.b_to_a = to_deviation(sums[1], compared, report.diagonal);
  report.two_sided = to_deviation(both, compared, report.diagonal);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace octolod::measure
