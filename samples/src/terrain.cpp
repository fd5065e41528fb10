// The terrain: an open heightfield on a regular grid, height = H * s(fbm(x, z)) with
// s(F) = F + F^2 / 2 (flatter valleys, sharper peaks; Musgrave's fBm terrains, "Texturing and
// Modeling", ch. 16). Normals come from the analytic gradient, so they are exact and cost no
// neighbour lookups; colour follows height and slope.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>

#include "shape_generator.h"
#include "value_noise.h"

namespace octolod::samplegen {
namespace {

constexpr double kWidth = 100.0;       // x extent, model units
constexpr double kHeight = 14.0;       // height scale, model units
constexpr double kFrequency = 0.04;    // noise cells per model unit (4 across the width)
constexpr double kSamplesPerCell = 3;  // grid steps across the finest noise cell (no aliasing)
constexpr std::uint32_t kHeightTag = 0x300;

struct Grid {
  std::uint64_t columns = 1;  // quads along x
  std::uint64_t rows = 1;     // quads along z
};

// columns * rows quads with 2 * columns * rows as close to `triangles` as possible, near square.
Grid grid_for(std::uint64_t triangles) {
  const double side = std::sqrt(static_cast<double>(triangles) / 2.0);
  const auto widest = static_cast<std::uint64_t>(std::ceil(side));
  const auto narrowest = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(side * 0.5));
  Grid best;
  std::uint64_t best_error = ~std::uint64_t{0};
  for (std::uint64_t columns = widest; columns >= narrowest; --columns) {
    const std::uint64_t rows = std::max<std::uint64_t>(1, (triangles + columns) / (2 * columns));
    const std::uint64_t made = 2 * columns * rows;
    const std::uint64_t error = made > triangles ? made - triangles : triangles - made;
    if (error < best_error) {
      best = {columns, rows};
      best_error = error;
    }
    if (error == 0 || columns == 1) break;
  }
  return best;
}

class TerrainGenerator final : public ShapeGenerator {
 public:
  explicit TerrainGenerator(const SampleSpec& spec)
      : layout_(spec.layout),
        grid_(grid_for(spec.triangles)),
        spacing_(kWidth / static_cast<double>(grid_.columns)),
        height_(resolvable_octaves(1.0 / kFrequency, spacing_, kSamplesPerCell), spec.seed,
                kHeightTag) {}

  SampleCounts counts() const override {
    return {(grid_.columns + 1) * (grid_.rows + 1), 2 * grid_.columns * grid_.rows};
  }

  // Row-major: vertex (i, j) at x = i * spacing, z = j * spacing is i + j * (columns + 1).
  void vertices(std::uint64_t first, std::size_t count, float* out) const override {
    std::uint64_t i = first % (grid_.columns + 1), j = first / (grid_.columns + 1);
    for (std::size_t k = 0; k < count; ++k) {
      out = put_vertex(layout_, vertex(i, j), out);
      if (++i > grid_.columns) {
        i = 0;
        ++j;
      }
    }
  }

  // Quad (i, j) with corners a = (i, j), b = (i+1, j), c = (i, j+1), d = (i+1, j+1) is
  // (a, c, b), (b, c, d): counter-clockwise seen from +y.
  void next_triangles(std::size_t count, std::uint32_t* out) override {
    quads_.next(count, out, [](bool second, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
                               std::uint32_t* t) {
      if (!second) t[0] = a, t[1] = c, t[2] = b;
      else t[0] = b, t[1] = c, t[2] = d;
    });
  }


 private:
  VertexAttributes vertex(std::uint64_t i, std::uint64_t j) const {
    const double x = static_cast<double>(i) * spacing_, z = static_cast<double>(j) * spacing_;
    const Noise2 f = height_(x * kFrequency, z * kFrequency);
    const double shaped = f.value + 0.5 * f.value * f.value;
    const double slope_scale = kHeight * (1.0 + f.value) * kFrequency;  // d height / d F * dF/dx
    const double hx = slope_scale * f.dx, hz = slope_scale * f.dy;

    VertexAttributes v{};
    v.position[0] = x;
    v.position[1] = kHeight * shaped;
    v.position[2] = z;
    const double inverse_length = 1.0 / std::sqrt(hx * hx + 1.0 + hz * hz);
    v.normal[0] = -hx * inverse_length;
    v.normal[1] = inverse_length;
    v.normal[2] = -hz * inverse_length;

    // Height ramp: sand, grass, forest, rock, snow; steep ground shows rock whatever its height.
    const double t = clamp01(0.5 + shaped * 0.8);
    constexpr double kStops[5][3] = {{0.76, 0.70, 0.50},
                                     {0.35, 0.55, 0.22},
                                     {0.18, 0.36, 0.16},
                                     {0.45, 0.42, 0.40},
                                     {0.95, 0.95, 0.97}};
    const double position = t * 4.0;
    const int stop = std::min(3, static_cast<int>(position));
    const double within = position - stop;
    const double steep = clamp01((1.0 - v.normal[1] - 0.15) * 4.0);
    for (int a = 0; a < 3; ++a)
      v.color[a] =
          clamp01(mix(mix(kStops[stop][a], kStops[stop + 1][a], within), kStops[3][a], steep));

    v.uv[0] = x / kWidth;
    v.uv[1] = z / kWidth;
    return v;
  }

  VertexLayout layout_;
  Grid grid_;
  double spacing_;  // model units between grid lines, both directions
  Fbm height_;
  QuadGridTriangles quads_{grid_.columns};
};

}  // namespace

std::unique_ptr<ShapeGenerator> make_terrain(const SampleSpec& spec) {
  return std::make_unique<TerrainGenerator>(spec);
}

}  // namespace octolod::samplegen
