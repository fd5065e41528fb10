// The city: a ground plane and one box building per 12 x 12 lot, taller towards the centre.
// Flat shaded like a game asset: each box face has its own 4 vertices carrying the face normal,
// so normals (and uvs) are discontinuous at every box edge, the hard case for attribute-aware
// simplification. The ground is split into 1..6 strips so the triangle count hits N or N - 1.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include "shape_generator.h"
#include "value_noise.h"

namespace octolod::samplegen {
namespace {

constexpr double kLot = 12.0;     // lot pitch, model units
constexpr double kUvUnit = 10.0;  // model units per texture repeat
constexpr std::uint32_t kBoxTag = 0x400;
constexpr std::uint64_t kBoxVertices = 24;
constexpr std::uint64_t kBoxTriangles = 12;

// Corners of a box are numbered by bits (x, y, z): 0 = min, 1 = max. Each face lists its
// corners counter-clockwise seen from outside, then its outward normal.
struct Face {
  int corners[4];
  double normal[3];
};
constexpr Face kFaces[6] = {
    {{5, 1, 3, 7}, {1, 0, 0}},  {{0, 4, 6, 2}, {-1, 0, 0}}, {{4, 5, 7, 6}, {0, 0, 1}},
    {{1, 0, 2, 3}, {0, 0, -1}}, {{6, 7, 3, 2}, {0, 1, 0}},  {{0, 1, 5, 4}, {0, -1, 0}},
};

struct Box {
  double min[3];
  double max[3];
  double color[3];
};

class CityGenerator final : public ShapeGenerator {
 public:
  explicit CityGenerator(const SampleSpec& spec)
      : layout_(spec.layout), seed_(derive_seed(spec.seed, kBoxTag)) {
    boxes_ = std::max<std::uint64_t>(1, (spec.triangles - 2) / kBoxTriangles);
    strips_ = std::clamp<std::uint64_t>((spec.triangles - kBoxTriangles * boxes_) / 2, 1, 6);
    columns_ = static_cast<std::uint64_t>(std::ceil(std::sqrt(static_cast<double>(boxes_))));
    while (columns_ * columns_ < boxes_) ++columns_;
    rows_ = (boxes_ + columns_ - 1) / columns_;
  }

  SampleCounts counts() const override {
    return {ground_vertices() + kBoxVertices * boxes_, 2 * strips_ + kBoxTriangles * boxes_};
  }

  void vertices(std::uint64_t first, std::size_t count, float* out) const override {
    std::uint64_t current_box = ~std::uint64_t{0};
    Box box{};
    for (std::uint64_t vertex = first; vertex < first + count; ++vertex) {
      if (vertex < ground_vertices()) {
        out = put_vertex(layout_, ground_vertex(vertex), out);
        continue;
      }
      const std::uint64_t local = vertex - ground_vertices();
      if (local / kBoxVertices != current_box) {
        current_box = local / kBoxVertices;
        box = make_box(current_box);
      }
      out = put_vertex(layout_, box_vertex(box, (local % kBoxVertices) / 4, local % 4), out);
    }
  }

  void next_triangles(std::size_t count, std::uint32_t* out) override {
    for (std::size_t k = 0; k < count; ++k, ++triangle_, out += 3) {
      if (triangle_ < 2 * strips_) {
        // Strip s: corners 2s, 2s+2 at z = 0 and 2s+1, 2s+3 at the far edge; up is +y.
        const auto s = static_cast<std::uint32_t>(triangle_ / 2);
        if (triangle_ % 2 == 0)
          out[0] = 2 * s, out[1] = 2 * s + 1, out[2] = 2 * s + 2;
        else
          out[0] = 2 * s + 2, out[1] = 2 * s + 1, out[2] = 2 * s + 3;
        continue;
      }
      const std::uint64_t local = triangle_ - 2 * strips_;
      const std::uint64_t face_first = ground_vertices() + (local / kBoxTriangles) * kBoxVertices +
                                       (local % kBoxTriangles) / 2 * 4;
      const auto f = static_cast<std::uint32_t>(face_first);
      if (local % 2 == 0)
        out[0] = f, out[1] = f + 1, out[2] = f + 2;
      else
        out[0] = f, out[1] = f + 2, out[2] = f + 3;
    }
  }

 private:
  std::uint64_t ground_vertices() const { return 2 * (strips_ + 1); }

  VertexAttributes ground_vertex(std::uint64_t index) const {
    const double x_extent = kLot * static_cast<double>(columns_);
    const double z_extent = kLot * static_cast<double>(rows_);
    VertexAttributes v{};
    v.position[0] = x_extent * static_cast<double>(index / 2) / static_cast<double>(strips_);
    v.position[2] = index % 2 == 0 ? 0.0 : z_extent;
    v.normal[1] = 1.0;
    v.color[0] = 0.30, v.color[1] = 0.32, v.color[2] = 0.30;
    v.uv[0] = v.position[0] / kUvUnit;
    v.uv[1] = v.position[2] / kUvUnit;
    return v;
  }

  // Box b stands on lot (b mod columns, b / columns): a random footprint inside the lot's
  // 10 x 10 buildable area, a height growing towards the city centre, rounded to 3-unit floors.
  Box make_box(std::uint64_t b) const {
    const auto id = static_cast<std::uint32_t>(b);
    const auto high = static_cast<std::uint32_t>(b >> 32);
    auto random = [&](std::uint32_t what) { return hash_unit(seed_ ^ high, id, what); };
    const double column = static_cast<double>(b % columns_),
                 row = static_cast<double>(b / columns_);
    const double dx = (column + 0.5) / static_cast<double>(columns_) - 0.5;
    const double dz = (row + 0.5) / static_cast<double>(rows_) - 0.5;
    const double downtown = clamp01(1.0 - std::sqrt(dx * dx + dz * dz) * 1.6);

    Box box{};
    const double width = 4.0 + 6.0 * random(0), depth = 4.0 + 6.0 * random(1);
    box.min[0] = column * kLot + 1.0 + (10.0 - width) * random(2);
    box.min[2] = row * kLot + 1.0 + (10.0 - depth) * random(3);
    box.max[0] = box.min[0] + width;
    box.max[2] = box.min[2] + depth;
    const double height = 3.0 + (6.0 + 51.0 * downtown * downtown) * random(4);
    box.max[1] = 3.0 * std::ceil(height / 3.0);

    constexpr double kPalette[6][3] = {{0.62, 0.60, 0.57}, {0.72, 0.66, 0.55}, {0.55, 0.30, 0.24},
                                       {0.40, 0.50, 0.60}, {0.80, 0.80, 0.78}, {0.35, 0.36, 0.38}};
    const int pick = std::min(5, static_cast<int>(random(5) * 6.0));
    const double brightness = 0.85 + 0.3 * random(6);
    for (int a = 0; a < 3; ++a) box.color[a] = clamp01(kPalette[pick][a] * brightness);
    return box;
  }

  static VertexAttributes box_vertex(const Box& box, std::uint64_t face, std::uint64_t corner) {
    const Face& f = kFaces[face];
    VertexAttributes v{};
    const int bits = f.corners[corner];
    for (int a = 0; a < 3; ++a) {
      v.position[a] = (bits >> a) & 1 ? box.max[a] : box.min[a];
      v.normal[a] = f.normal[a];
      v.color[a] = box.color[a];
    }
    // uv spans the face: corner 0 is (0, 0), corner 2 is (face width, face height) / kUvUnit.
    auto extent = [&](int from, int to) {
      double length = 0;
      for (int a = 0; a < 3; ++a)
        if (((from ^ to) >> a) & 1) length += box.max[a] - box.min[a];
      return length / kUvUnit;
    };
    const double u = extent(f.corners[0], f.corners[1]), w = extent(f.corners[0], f.corners[3]);
    v.uv[0] = corner == 1 || corner == 2 ? u : 0.0;
    v.uv[1] = corner >= 2 ? w : 0.0;
    return v;
  }

  VertexLayout layout_;
  std::uint32_t seed_;
  std::uint64_t boxes_ = 1;
  std::uint64_t strips_ = 1;    // ground quads
  std::uint64_t columns_ = 1;   // lots along x
  std::uint64_t rows_ = 1;      // lots along z
  std::uint64_t triangle_ = 0;  // cursor
};

}  // namespace

std::unique_ptr<ShapeGenerator> make_city(const SampleSpec& spec) {
  return std::make_unique<CityGenerator>(spec);
}

}  // namespace octolod::samplegen
