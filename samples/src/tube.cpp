// The tube: a thin closed torus, 1 unit wide and 1,000 units long around its centre circle, the
// part thinner than the bake's grid cells (a pipe, a pole, a cable). The surface of revolution
// p(theta, phi) = (R + r cos phi) e(theta) + r sin phi y, e(theta) = (cos theta, 0, sin theta),
// sampled on a rings x segments grid whose quads are about square; the normal is exact,
// cos phi e(theta) + sin phi y (radial from the centre circle). No noise: the shape is the same
// for every seed, which only picks the paint colour.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include "shape_generator.h"
#include "turn_trig.h"
#include "value_noise.h"

namespace octolod::samplegen {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kLength = 1000.0;                      // centre circle's length, model units
constexpr double kMajorRadius = kLength / (2.0 * kPi);  // centre circle's radius, ~159.15
constexpr double kRadius = 0.5;                         // tube radius, model units
constexpr double kUvUnit = 10.0;        // model units of centre line per u repeat
constexpr double kStripePitch = 100.0;  // model units of centre line per stripe
constexpr double kStripeWidth = 10.0;   // model units
constexpr std::uint64_t kRoundSegments = 8;  // fewest segments for a round look (an octagon)
constexpr std::uint32_t kPaintTag = 0x500;

struct Grid {
  std::uint64_t segments = 3;  // quads around the tube
  std::uint64_t rings = 3;     // quads along the centre circle
};

// Square quads need segments / rings = 2 pi r / L, i.e. segments = sqrt(N pi r / L)
// (= sqrt(N / 636.6); 10 at 64K, 40 at 1M, 1,253 at a billion), at least kRoundSegments, fewer
// only where 3 rings would not fit (N < 48: a triangular prism ring at N = 16). Rings are the
// nearest count to N / (2 segments), so the count is off by at most `segments` triangles.
Grid grid_for(std::uint64_t triangles) {
  const auto square = static_cast<std::uint64_t>(
      std::floor(std::sqrt(static_cast<double>(triangles) * kPi * kRadius / kLength) + 0.5));
  const std::uint64_t fewest =
      std::min(kRoundSegments, std::max<std::uint64_t>(3, triangles / 6));
  const std::uint64_t segments = std::max(square, fewest);
  const std::uint64_t rings =
      std::max<std::uint64_t>(3, (triangles + segments) / (2 * segments));
  return {segments, rings};
}

class TubeGenerator final : public ShapeGenerator {
 public:
  explicit TubeGenerator(const SampleSpec& spec)
      : layout_(spec.layout), grid_(grid_for(spec.triangles)) {
    const std::uint32_t seed = derive_seed(spec.seed, kPaintTag);
    constexpr double kPalette[5][3] = {{0.78, 0.20, 0.15}, {0.93, 0.62, 0.12}, {0.20, 0.42, 0.72},
                                       {0.24, 0.52, 0.30}, {0.52, 0.53, 0.56}};
    const int pick = std::min(4, static_cast<int>(hash_unit(seed, 0) * 5.0));
    const double brightness = 0.85 + 0.3 * hash_unit(seed, 1);
    for (int a = 0; a < 3; ++a) paint_[a] = clamp01(kPalette[pick][a] * brightness);
  }

  SampleCounts counts() const override {
    return {(grid_.rings + 1) * (grid_.segments + 1), 2 * grid_.rings * grid_.segments};
  }

  // Ring-major: vertex (i, j), ring i at theta = i / rings turns, segment j at
  // phi = j / segments turns, is j + i * (segments + 1). Ring i = rings repeats ring 0 and
  // segment j = segments repeats segment 0 (same angles, same bits) with the wrapped uv.
  void vertices(std::uint64_t first, std::size_t count, float* out) const override {
    const std::uint64_t stride = grid_.segments + 1;
    std::uint64_t i = first / stride, j = first % stride;
    for (std::size_t done = 0; done < count; ++i, j = 0) {
      const SinCos theta = sincos_turns(static_cast<double>(i % grid_.rings) /
                                        static_cast<double>(grid_.rings));
      for (; j < stride && done < count; ++j, ++done)
        out = put_vertex(layout_, vertex(i, theta, j), out);
    }
  }

  // Quad (i, j) with corners a = (i, j), b = (i, j+1), c = (i+1, j), d = (i+1, j+1) is
  // (a, b, c), (b, d, c): dp/dphi x dp/dtheta points outward, so these are counter-clockwise
  // seen from outside.
  void next_triangles(std::size_t count, std::uint32_t* out) override {
    quads_.next(count, out, [](bool second, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
                               std::uint32_t* t) {
      if (!second) t[0] = a, t[1] = b, t[2] = c;
      else t[0] = b, t[1] = d, t[2] = c;
    });
  }


 private:
  VertexAttributes vertex(std::uint64_t i, const SinCos& theta, std::uint64_t j) const {
    const SinCos phi = sincos_turns(static_cast<double>(j % grid_.segments) /
                                    static_cast<double>(grid_.segments));
    VertexAttributes v{};
    const double from_axis = kMajorRadius + kRadius * phi.cos;  // distance from the y axis
    v.position[0] = from_axis * theta.cos;
    v.position[1] = kRadius * phi.sin;
    v.position[2] = from_axis * theta.sin;
    v.normal[0] = phi.cos * theta.cos;
    v.normal[1] = phi.sin;
    v.normal[2] = phi.cos * theta.sin;

    // Painted, with a light band kStripeWidth long every kStripePitch along the centre line
    // (from the wrapped ring, so the seam copies match).
    const double along = kLength * static_cast<double>(i % grid_.rings) /
                         static_cast<double>(grid_.rings);
    const bool stripe = along - kStripePitch * std::floor(along / kStripePitch) < kStripeWidth;
    constexpr double kStripe[3] = {0.94, 0.94, 0.90};
    for (int a = 0; a < 3; ++a) v.color[a] = stripe ? kStripe[a] : paint_[a];

    // u: kUvUnit model units of centre line per repeat (0..100); v: 0..1 around from the outer
    // equator, upwards first.
    v.uv[0] = kLength / kUvUnit * static_cast<double>(i) / static_cast<double>(grid_.rings);
    v.uv[1] = static_cast<double>(j) / static_cast<double>(grid_.segments);
    return v;
  }

  VertexLayout layout_;
  Grid grid_;
  double paint_[3] = {};           // the seed's colour, 0..1
  QuadGridTriangles quads_{grid_.segments};  // rows are rings
};

}  // namespace

std::unique_ptr<ShapeGenerator> make_tube(const SampleSpec& spec) {
  return std::make_unique<TubeGenerator>(spec);
}

}  // namespace octolod::samplegen
