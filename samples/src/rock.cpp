// The rock: a closed, star-shaped, noise-displaced ellipsoid. A latitude/longitude sphere whose
// ring k (polar angle pi k / n) has m_k ~ circumference segments, so triangles stay near
// equilateral up to the poles; neighbouring rings are zipped by merging their longitudes (the
// classic contour-stitching walk of Fuchs, Kedem & Uselton 1977, with exact integer comparisons).
// Surface: radius r(d) = 1 + A fbm(f d) along the unit direction d; its normal is exact:
// n ~ d - grad_t r / r (grad_t: tangential part of r's gradient), then scaled to the ellipsoid
// by the inverse-transpose of the axis scale.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "shape_generator.h"
#include "turn_trig.h"
#include "value_noise.h"

namespace octolod::samplegen {
namespace {

constexpr double kAmplitude = 0.3;               // radial displacement, fraction of the radius
constexpr double kFrequency = 1.3;               // noise cells per unit of direction
constexpr double kScale[3] = {1.0, 0.72, 0.86};  // ellipsoid axes: a rock, not a ball
constexpr double kSamplesPerCell = 3;  // ring steps across the finest noise cell (no aliasing)
constexpr std::uint32_t kShapeTag = 0x100;
constexpr std::uint32_t kTintTag = 0x200;

// Ring sizes m_1..m_{n-1} summing to exactly `segments`, each >= 3, proportional to
// sin(polar angle) so that quads are about square (there are n bands of pi/n each).
std::vector<std::uint64_t> ring_sizes(std::uint64_t triangles) {
  const std::uint64_t segments = triangles / 2;  // 2 * sum(m_k) triangles in total
  const double pi = 3.14159265358979323846;
  auto n = static_cast<std::uint64_t>(
      std::floor(std::sqrt(pi * static_cast<double>(triangles) / 8.0) + 0.5));
  n = std::max<std::uint64_t>(n, 2);
  while (n > 2 && 3 * (n - 1) > segments) --n;

  std::vector<double> weight(n - 1);
  double weight_sum = 0;
  for (std::uint64_t k = 1; k < n; ++k) {
    weight[k - 1] = sincos_turns(static_cast<double>(k) / static_cast<double>(2 * n)).sin;
    weight_sum += weight[k - 1];
  }
  std::vector<std::uint64_t> m(n - 1);
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const double ideal = static_cast<double>(segments) * weight[i] / weight_sum;
    m[i] = std::max<std::uint64_t>(3, static_cast<std::uint64_t>(std::floor(ideal + 0.5)));
    sum += m[i];
  }
  // Rounding leaves sum a little off: add or remove one segment per ring, equator first, where
  // rings are largest and one segment matters least.
  std::vector<std::size_t> order(m.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  const double middle = static_cast<double>(m.size() - 1) / 2.0;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::fabs(static_cast<double>(a) - middle) < std::fabs(static_cast<double>(b) - middle);
  });
  while (sum != segments) {
    for (std::size_t i : order) {
      if (sum < segments) {
        ++m[i];
        ++sum;
      } else if (sum > segments && m[i] > 3) {
        --m[i];
        --sum;
      }
      if (sum == segments) break;
    }
  }
  return m;
}

class RockGenerator final : public ShapeGenerator {
 public:
  explicit RockGenerator(const SampleSpec& spec)
      : layout_(spec.layout),
        m_(ring_sizes(spec.triangles)),
        rings_(m_.size()),
        // Ring spacing is pi / n radians on the unit sphere, the space the noise lives in.
        shape_(resolvable_octaves(1.0 / kFrequency,
                                  3.14159265358979323846 / static_cast<double>(rings_ + 1),
                                  kSamplesPerCell),
               spec.seed, kShapeTag),
        tint_(2, spec.seed, kTintTag) {
    // Vertex order: north pole, rings 1..n-1 (m_k + 1 vertices each: j = m_k repeats j = 0 with
    // u = 1), south pole.
    ring_start_.resize(rings_ + 2);
    ring_start_[1] = 1;
    for (std::size_t k = 1; k <= rings_; ++k) ring_start_[k + 1] = ring_start_[k] + m_[k - 1] + 1;
    std::uint64_t segments = 0;
    for (std::uint64_t s : m_) segments += s;
    counts_ = {ring_start_[rings_ + 1] + 1, 2 * segments};
  }

  SampleCounts counts() const override { return counts_; }

  void vertices(std::uint64_t first, std::size_t count, float* out) const override {
    // The ring holding `first`: the last ring starting at or before it.
    std::size_t ring = static_cast<std::size_t>(
        std::upper_bound(ring_start_.begin(), ring_start_.end(), first) - ring_start_.begin() - 1);
    std::uint64_t j = first - ring_start_[ring];
    for (std::size_t done = 0; done < count; ++ring, j = 0) {
      // Ring 0 and ring n are the poles: one vertex each.
      const std::uint64_t ring_vertices = ring == 0 || ring > rings_ ? 1 : m_[ring - 1] + 1;
      const SinCos polar =
          sincos_turns(static_cast<double>(ring) / static_cast<double>(2 * (rings_ + 1)));
      for (; j < ring_vertices && done < count; ++j, ++done)
        out = put_vertex(layout_, vertex(ring, polar, j), out);
    }
  }

  void next_triangles(std::size_t count, std::uint32_t* out) override {
    for (std::size_t i = 0; i < count; ++i, out += 3) next_triangle(out);
  }

 private:
  // Vertex j of ring k (k = 0: north pole, k = n: south pole) at polar angle k / 2n turns.
  VertexAttributes vertex(std::uint64_t ring, const SinCos& polar, std::uint64_t j) const {
    const double n = static_cast<double>(rings_ + 1);
    const bool pole = ring == 0 || ring > rings_;
    const std::uint64_t m = pole ? 1 : m_[ring - 1];
    // j = m is the seam copy of j = 0: the same angle, hence the same bits.
    const SinCos azimuth = sincos_turns(static_cast<double>(j % m) / static_cast<double>(m));
    const double d[3] = {polar.sin * azimuth.cos, polar.cos, polar.sin * azimuth.sin};

    const Noise3 f = shape_(d[0] * kFrequency, d[1] * kFrequency, d[2] * kFrequency);
    const double r = 1.0 + kAmplitude * f.value;
    const double g[3] = {kAmplitude * kFrequency * f.dx, kAmplitude * kFrequency * f.dy,
                         kAmplitude * kFrequency * f.dz};
    const double g_dot_d = g[0] * d[0] + g[1] * d[1] + g[2] * d[2];

    VertexAttributes v{};
    double normal_length_sq = 0;
    for (int a = 0; a < 3; ++a) {
      v.position[a] = d[a] * r * kScale[a];
      v.normal[a] = (d[a] - (g[a] - g_dot_d * d[a]) / r) / kScale[a];
      normal_length_sq += v.normal[a] * v.normal[a];
    }
    const double inverse_length = 1.0 / std::sqrt(normal_length_sq);
    for (double& x : v.normal) x *= inverse_length;

    // Darker in the hollows, lighter on the bumps, with a low-frequency lichen tint.
    const double height = clamp01(0.5 + 0.8 * f.value);
    const double lichen = clamp01(1.5 * tint_(d[0] * 2.0, d[1] * 2.0, d[2] * 2.0).value);
    const double dark[3] = {0.26, 0.23, 0.21}, light[3] = {0.64, 0.60, 0.54},
                 moss[3] = {0.42, 0.48, 0.27};
    for (int a = 0; a < 3; ++a)
      v.color[a] = clamp01(mix(mix(dark[a], light[a], height), moss[a], 0.7 * lichen));

    v.uv[0] = pole ? 0.5 : static_cast<double>(j) / static_cast<double>(m);
    v.uv[1] = 1.0 - static_cast<double>(ring) / n;
    return v;
  }

  // Band 0: the north fan around ring 1; band b in 1..n-2: ring b zipped to ring b+1;
  // band n-1: the south fan around ring n-1. Winding is counter-clockwise seen from outside.
  void next_triangle(std::uint32_t* t) {
    const std::size_t bands = rings_ + 1;
    auto index = [&](std::size_t ring, std::uint64_t j) {
      return static_cast<std::uint32_t>(ring_start_[ring] + j);
    };
    if (band_ == 0) {
      t[0] = 0;
      t[1] = index(1, a_ + 1);
      t[2] = index(1, a_);
      if (++a_ == m_[0]) next_band();
    } else if (band_ == bands - 1) {
      t[0] = index(rings_, a_);
      t[1] = index(rings_, a_ + 1);
      t[2] = static_cast<std::uint32_t>(counts_.vertices - 1);
      if (++a_ == m_[rings_ - 1]) next_band();
    } else {
      const std::uint64_t ma = m_[band_ - 1], mb = m_[band_];
      // Advance on the ring whose next vertex has the smaller longitude: (a+1)/ma <= (b+1)/mb.
      const bool advance_a = b_ == mb || (a_ < ma && (a_ + 1) * mb <= (b_ + 1) * ma);
      t[0] = index(band_, a_);
      if (advance_a) {
        t[1] = index(band_, a_ + 1);
        t[2] = index(band_ + 1, b_);
        ++a_;
      } else {
        t[1] = index(band_ + 1, b_ + 1);
        t[2] = index(band_ + 1, b_);
        ++b_;
      }
      if (a_ == ma && b_ == mb) next_band();
    }
  }

  void next_band() {
    ++band_;
    a_ = 0;
    b_ = 0;
  }

  VertexLayout layout_;
  std::vector<std::uint64_t> m_;  // segments of rings 1..n-1 (m_[k-1] for ring k)
  std::size_t rings_;             // n - 1
  Fbm shape_;
  Fbm tint_;
  std::vector<std::uint64_t> ring_start_;  // first vertex of ring k (0: north pole)
  SampleCounts counts_;
  // Triangle cursor: band, position on its upper (a) and lower (b) ring.
  std::size_t band_ = 0;
  std::uint64_t a_ = 0;
  std::uint64_t b_ = 0;
};

}  // namespace

std::unique_ptr<ShapeGenerator> make_rock(const SampleSpec& spec) {
  return std::make_unique<RockGenerator>(spec);
}

}  // namespace octolod::samplegen
