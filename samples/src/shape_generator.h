// The interface each shape implements for SampleStream (sample_generator.cpp): exact counts up
// front, vertices by index range (pure and const, so ranges can be generated in parallel), then
// triangles produced sequentially; all into caller-owned memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "octolod/formats/vertex_layout.h"
#include "octolod/samplegen/sample_generator.h"

namespace octolod::samplegen {

class ShapeGenerator {
 public:
  virtual ~ShapeGenerator() = default;
  virtual SampleCounts counts() const = 0;
  // Writes vertices [first, first + count) (layout.floats() floats each), within counts().
  // Thread-safe: a pure function of the spec and the indices.
  virtual void vertices(std::uint64_t first, std::size_t count, float* out) const = 0;
  // Writes the next `count` triangles (3 indices each); never more than remain.
  virtual void next_triangles(std::size_t count, std::uint32_t* out) = 0;
};

// The triangles of a grid of quads `width` wide (width + 1 vertices per row, rows one after the
// other), two per quad, quad after quad along each row. The quad's corners: a, b = a + 1 (next
// along the row), c = a + width + 1 (the next row), d = c + 1; `wind(second, a, b, c, d, out)`
// writes the quad's first or second triangle to out[0..3).
class QuadGridTriangles {
 public:
  explicit QuadGridTriangles(std::uint64_t width) : width_(width) {}
  template <typename Wind>
  void next(std::size_t count, std::uint32_t* out, Wind wind) {
    const std::uint64_t stride = width_ + 1;
    for (std::size_t k = 0; k < count; ++k, out += 3) {
      const auto a = static_cast<std::uint32_t>(column_ + row_ * stride);
      const auto c = static_cast<std::uint32_t>(a + stride);
      wind(second_, a, a + 1, c, c + 1, out);
      if (second_ && ++column_ == width_) {
        column_ = 0;
        ++row_;
      }
      second_ = !second_;
    }
  }

 private:
  std::uint64_t width_;
  std::uint64_t column_ = 0, row_ = 0;  // quad cursor
  bool second_ = false;                 // next triangle is the quad's second
};

// Construction is cheap (no generation): O(sqrt(N)) for the rock's ring table and the terrain's
// grid search, O(1) for the city and the tube.
// spec.triangles is already within [kMinTriangles, kMaxTriangles].
std::unique_ptr<ShapeGenerator> make_rock(const SampleSpec& spec);
std::unique_ptr<ShapeGenerator> make_terrain(const SampleSpec& spec);
std::unique_ptr<ShapeGenerator> make_city(const SampleSpec& spec);
std::unique_ptr<ShapeGenerator> make_tube(const SampleSpec& spec);

// Writes one vertex in VertexLayout order, skipping absent attributes; returns the next slot.
struct VertexAttributes {
  double position[3];
  double normal[3];
  double color[3];
  double uv[2];
};
inline float* put_vertex(const VertexLayout& layout, const VertexAttributes& v, float* out) {
  for (double x : v.position) *out++ = static_cast<float>(x);
  if (layout.normal)
    for (double x : v.normal) *out++ = static_cast<float>(x);
  if (layout.color)
    for (double x : v.color) *out++ = static_cast<float>(x);
  if (layout.uv)
    for (double x : v.uv) *out++ = static_cast<float>(x);
  return out;
}

inline double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }
inline double mix(double a, double b, double t) { return a + (b - a) * t; }

}  // namespace octolod::samplegen
