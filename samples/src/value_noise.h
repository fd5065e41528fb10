// Integer-hash value noise with analytic derivatives (quintic interpolation, as in Perlin's
// "Improving noise", 2002, and Quilez's derivative formulation) and fractal Brownian motion on
// top. Only integer hashing and + - * / floor: the same bits on every platform and compiler
// (std::*_distribution is implementation-defined and is never used here).
#pragma once

#include <cassert>
#include <cmath>
#include <cstdint>

namespace octolod::samplegen {

// A bijective 32-bit mixer (Wellons' "lowbias32"): every input bit affects every output bit.
inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

// Folds a 64-bit user seed and a stream tag (octave, purpose) into one 32-bit noise seed.
inline std::uint32_t derive_seed(std::uint64_t seed, std::uint32_t tag) {
  const auto lo = static_cast<std::uint32_t>(seed);
  const auto hi = static_cast<std::uint32_t>(seed >> 32);
  return hash32(lo ^ hash32(hi ^ hash32(tag + 0x9e3779b9u)));
}

// Uniform in [0, 1) from a hash of an integer tuple.
inline double hash_unit(std::uint32_t seed, std::uint32_t a, std::uint32_t b = 0) {
  return static_cast<double>(hash32(a ^ hash32(b ^ hash32(seed))) >> 8) * (1.0 / 16777216.0);
}

// Lattice values in [-1, 1], hashed one axis at a time (z, then y, then x) so that the corners
// of a cell share the inner hashes: 6 hashes per 2D cell, 14 per 3D cell instead of 12 and 24.
inline std::uint32_t lattice_hash(std::uint32_t inner, std::int32_t coordinate,
                                  std::uint32_t prime) {
  return hash32(static_cast<std::uint32_t>(coordinate) * prime ^ inner);
}
inline double lattice_value(std::uint32_t hash) {
  return static_cast<double>(hash >> 8) * (2.0 / 16777216.0) - 1.0;
}
constexpr std::uint32_t kPrimeX = 0x8da6b343u, kPrimeY = 0xd8163841u, kPrimeZ = 0xcb1ab31fu;

struct Noise2 {
  double value = 0;
  double dx = 0, dy = 0;
};
struct Noise3 {
  double value = 0;
  double dx = 0, dy = 0, dz = 0;
};

namespace detail {
struct Axis {
  std::int32_t cell;
  double w;   // quintic weight 6u^5 - 15u^4 + 10u^3
  double dw;  // its derivative 30u^2 (u - 1)^2
};
// Coordinates must stay within +-2^30 (they do: every caller feeds bounded domains).
inline Axis axis(double x) {
  const double f = std::floor(x);
  const double u = x - f;
  return {static_cast<std::int32_t>(f), u * u * u * (u * (u * 6.0 - 15.0) + 10.0),
          30.0 * u * u * (u - 1.0) * (u - 1.0)};
}
}  // namespace detail

// Value noise in [-1, 1] and its gradient.
inline Noise2 value_noise(double x, double y, std::uint32_t seed) {
  const detail::Axis ax = detail::axis(x), ay = detail::axis(y);
  const std::uint32_t y0 = lattice_hash(seed, ay.cell, kPrimeY);
  const std::uint32_t y1 = lattice_hash(seed, ay.cell + 1, kPrimeY);
  const double a = lattice_value(lattice_hash(y0, ax.cell, kPrimeX));
  const double b = lattice_value(lattice_hash(y0, ax.cell + 1, kPrimeX));
  const double c = lattice_value(lattice_hash(y1, ax.cell, kPrimeX));
  const double d = lattice_value(lattice_hash(y1, ax.cell + 1, kPrimeX));
  const double k1 = b - a, k2 = c - a, k4 = a - b - c + d;
  return {a + k1 * ax.w + k2 * ay.w + k4 * ax.w * ay.w, ax.dw * (k1 + k4 * ay.w),
          ay.dw * (k2 + k4 * ax.w)};
}

inline Noise3 value_noise(double x, double y, double z, std::uint32_t seed) {
  const detail::Axis ax = detail::axis(x), ay = detail::axis(y), az = detail::axis(z);
  const std::int32_t i = ax.cell, j = ay.cell, k = az.cell;
  const std::uint32_t z0 = lattice_hash(seed, k, kPrimeZ), z1 = lattice_hash(seed, k + 1, kPrimeZ);
  const std::uint32_t y0z0 = lattice_hash(z0, j, kPrimeY), y1z0 = lattice_hash(z0, j + 1, kPrimeY);
  const std::uint32_t y0z1 = lattice_hash(z1, j, kPrimeY), y1z1 = lattice_hash(z1, j + 1, kPrimeY);
  auto corner = [&](std::uint32_t yz, std::int32_t cell_x) {
    return lattice_value(lattice_hash(yz, cell_x, kPrimeX));
  };
  const double a = corner(y0z0, i), b = corner(y0z0, i + 1), c = corner(y1z0, i),
               d = corner(y1z0, i + 1), e = corner(y0z1, i), f = corner(y0z1, i + 1),
               g = corner(y1z1, i), h = corner(y1z1, i + 1);
  const double k1 = b - a, k2 = c - a, k3 = e - a, k4 = a - b - c + d, k5 = a - c - e + g,
               k6 = a - b - e + f, k7 = -a + b + c - d + e - f - g + h;
  const double u = ax.w, v = ay.w, w = az.w;
  return {a + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w,
          ax.dw * (k1 + k4 * v + k6 * w + k7 * v * w), ay.dw * (k2 + k5 * w + k4 * u + k7 * w * u),
          az.dw * (k3 + k6 * u + k5 * v + k7 * u * v)};
}

// Fractal Brownian motion: `octaves` layers, frequency x2 and amplitude x0.5 per layer, each
// with its own seed, divided by 2 (the amplitude sum of infinitely many layers) so the result
// stays in (-1, 1) and adding octaves adds detail without changing the coarse shape.
class Fbm {
 public:
  static constexpr int kMaxOctaves = 12;

  Fbm(int octaves, std::uint64_t seed, std::uint32_t tag) : octaves_(octaves) {
    assert(octaves >= 1 && octaves <= kMaxOctaves && "Fbm: 1..kMaxOctaves octaves");
    for (int o = 0; o < octaves; ++o)
      seeds_[o] = derive_seed(seed, tag + static_cast<std::uint32_t>(o));
  }

  Noise2 operator()(double x, double y) const {
    Noise2 sum;
    double amplitude = 0.5, frequency = 1;
    for (int o = 0; o < octaves_; ++o) {
      const Noise2 n = value_noise(x * frequency, y * frequency, seeds_[o]);
      sum.value += amplitude * n.value;
      sum.dx += amplitude * frequency * n.dx;
      sum.dy += amplitude * frequency * n.dy;
      amplitude *= 0.5;
      frequency *= 2.0;
    }
    return sum;
  }

  Noise3 operator()(double x, double y, double z) const {
    Noise3 sum;
    double amplitude = 0.5, frequency = 1;
    for (int o = 0; o < octaves_; ++o) {
      const Noise3 n = value_noise(x * frequency, y * frequency, z * frequency, seeds_[o]);
      sum.value += amplitude * n.value;
      sum.dx += amplitude * frequency * n.dx;
      sum.dy += amplitude * frequency * n.dy;
      sum.dz += amplitude * frequency * n.dz;
      amplitude *= 0.5;
      frequency *= 2.0;
    }
    return sum;
  }

 private:
  int octaves_;
  std::uint32_t seeds_[kMaxOctaves] = {};
};

// Octaves whose finest noise cell still spans `min_samples` grid steps, so the mesh resolves its
// detail instead of aliasing it: the largest o with 2^(o-1) <= base_cell / (min_samples * step),
// clamped to [2, Fbm::kMaxOctaves]. Finer meshes get more octaves over the same coarse shape.
inline int resolvable_octaves(double base_cell, double step, double min_samples) {
  int octaves = 1;
  double cell = base_cell;
  while (octaves < Fbm::kMaxOctaves && cell * 0.5 >= min_samples * step) {
    cell *= 0.5;
    ++octaves;
  }
  return octaves < 2 ? 2 : octaves;
}

}  // namespace octolod::samplegen
