// Morton (Z-order) codes of triangle centroids in the octree's root cube (seed 3.4, 4.3: the
// octree is built from the soup sorted by cell, so every node is one contiguous key range).
//
// A key holds `max_depth` levels of 3 bits, the coarsest level in the most significant triple;
// within a triple bit 0 = upper x half, bit 1 = upper y half, bit 2 = upper z half, the octant
// numbering of octolod/formats/manifest.h. The node at depth k containing a key is identified by
// its prefix `key >> 3 * (max_depth - k)`, which is also the path of octants from the root.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

#include "octolod/formats/bounds.h"

namespace octolod::bake {

// Deepest octree supported: 21 levels x 3 bits fit in a 64-bit key.
inline constexpr std::uint32_t kMaxOctreeDepth = 21;

// Spreads the low 21 bits of v so bit i lands on bit 3i.
constexpr std::uint64_t spread_bits_3(std::uint64_t v) {
  v &= 0x1fffffu;
  v = (v | (v << 32)) & 0x001f00000000ffffull;
  v = (v | (v << 16)) & 0x001f0000ff0000ffull;
  v = (v | (v << 8)) & 0x100f00f00f00f00full;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
  v = (v | (v << 2)) & 0x1249249249249249ull;
  return v;
}

constexpr std::uint64_t morton_encode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return spread_bits_3(x) | (spread_bits_3(y) << 1) | (spread_bits_3(z) << 2);
}

// The octree's root cube: an axis-aligned cube (model units) holding every vertex.
struct RootCube {
  std::array<double, 3> origin{0, 0, 0};  // minimum corner
  double size = 1;                        // edge length, > 0

  // The cube around `bounds`: the bounds' minimum corner (moved down by a hair) and their
  // largest extent enlarged by one part in 2^20, so points on the bounds' maximum faces
  // quantize into the last cell rather than onto its far face. Empty or flat bounds give a
  // non-zero size.
  static RootCube around(const Bounds& bounds) {
    RootCube cube;
    if (bounds.empty()) return cube;
    double extent = 0;
    for (std::size_t a = 0; a < 3; ++a)
      extent = std::max(extent, static_cast<double>(bounds.max[a]) - bounds.min[a]);
    const double magnitude = bounds.largest_magnitude();
    // Float positions are only precise to ~1e-7 of their magnitude: keep the margin above it.
    const double margin = std::max(extent, magnitude) * 0x1p-20 + 0x1p-100;
    for (std::size_t a = 0; a < 3; ++a) cube.origin[a] = static_cast<double>(bounds.min[a]) - margin;
    cube.size = extent + 2 * margin;
    return cube;
  }

  // The cell at `depth` whose octant path is `prefix` (see the top of this file), as float
  // bounds. Computed from the root every time, so a child's cell lies inside its parent's.
  Bounds cell(std::uint64_t prefix, std::uint32_t depth) const {
    std::uint32_t c[3] = {0, 0, 0};
    for (std::uint32_t k = 0; k < depth; ++k) {
      const auto octant = static_cast<std::uint32_t>(prefix >> (3 * (depth - 1 - k))) & 7u;
      for (std::size_t a = 0; a < 3; ++a) c[a] = (c[a] << 1) | ((octant >> a) & 1u);
    }
    const double cell_size = std::ldexp(size, -static_cast<int>(depth));
    Bounds b;
    for (std::size_t a = 0; a < 3; ++a) {
      b.min[a] = static_cast<float>(origin[a] + c[a] * cell_size);
      b.max[a] = static_cast<float>(origin[a] + (c[a] + 1.0) * cell_size);
    }
    return b;
  }
};

// Maps centroids to keys of `depth` levels (0..kMaxOctreeDepth) in `cube`.
class MortonQuantizer {
 public:
  MortonQuantizer(const RootCube& cube, std::uint32_t depth)
      : origin_(cube.origin),
        scale_(std::ldexp(1.0, static_cast<int>(depth)) / cube.size),
        last_(depth == 0 ? 0 : (std::uint32_t{1} << depth) - 1) {
    for (std::size_t a = 0; a < 3; ++a) origin3_[a] = 3 * origin_[a];
    third_scale_ = scale_ / 3;
  }

  // Key of the point p (model units); points outside the cube clamp to its border cells, NaN
  // coordinates to the lower one.
  std::uint64_t key(const double p[3]) const {
    return encode((p[0] - origin_[0]) * scale_, (p[1] - origin_[1]) * scale_,
                  (p[2] - origin_[2]) * scale_);
  }
  // The cell coordinates key() gives p, one per axis.
  std::array<std::uint32_t, 3> cells(const double p[3]) const {
    return {cell((p[0] - origin_[0]) * scale_), cell((p[1] - origin_[1]) * scale_),
            cell((p[2] - origin_[2]) * scale_)};
  }
  std::uint32_t last_cell() const { return last_; }
  // Key of the mean of three points given their sum `s` (the division folded into the scale).
  std::uint64_t key_of_mean3(const double s[3]) const {
    return encode((s[0] - origin3_[0]) * third_scale_, (s[1] - origin3_[1]) * third_scale_,
                  (s[2] - origin3_[2]) * third_scale_);
  }

 private:
  // Cell coordinates t (in cells from the origin) to the key: floor, clamped to the cube.
  std::uint64_t encode(double t0, double t1, double t2) const {
    return morton_encode(cell(t0), cell(t1), cell(t2));
  }
  std::uint32_t cell(double t) const {
    // For t > 0 truncation is floor; NaN fails t > 0.
    return !(t > 0) ? 0u : t >= last_ ? last_ : static_cast<std::uint32_t>(t);
  }

  std::array<double, 3> origin_;
  std::array<double, 3> origin3_;
  double scale_;
  double third_scale_;
  std::uint32_t last_;
};

// The key bits that vary among points of a box, and keys without the others: the octree's
// bucket sort distributes by a key's top bits, and a flat model (a city 60 units high and 3,500
// wide) has the same upper y bits everywhere, so each of them would halve the buckets used and
// make every bucket too large for memory, to be distributed again. Only the upper levels of an
// axis can be constant (a prefix of its cell coordinate), so a compact key is those levels'
// varying bits followed by the lower levels' bits as they are. Keys of points of the box keep
// their order and their equality: every bit dropped is the same in all of them.
class VaryingKeyBits {
 public:
  // For `quantizer`'s keys of `depth` levels of points inside `bounds` (model units), including
  // centroids of triangles with corners inside it: the box's cells are widened by one cell on
  // each side for the rounding of a centroid's computation.
  VaryingKeyBits(const MortonQuantizer& quantizer, std::uint32_t depth, const Bounds& bounds)
      : key_bits_(3 * depth) {
    const double lo[3] = {bounds.min[0], bounds.min[1], bounds.min[2]};
    const double hi[3] = {bounds.max[0], bounds.max[1], bounds.max[2]};
    const auto low_cells = quantizer.cells(lo), high_cells = quantizer.cells(hi);
    std::uint32_t constant_levels[3];
    std::uint32_t top_levels = 0;  // levels with a constant bit
    for (std::size_t a = 0; a < 3; ++a) {
      const std::uint32_t first = low_cells[a] == 0 ? 0 : low_cells[a] - 1;
      const std::uint32_t last = std::min(high_cells[a] + 1, quantizer.last_cell());
      constant_levels[a] = bounds.empty() ? 0 : depth - static_cast<std::uint32_t>(std::bit_width(first ^ last));
      top_levels = std::max(top_levels, constant_levels[a]);
    }
    low_bits_ = 3 * (depth - top_levels);
    std::uint64_t varying = (std::uint64_t{1} << low_bits_) - 1;
    for (std::uint32_t level = 0; level < top_levels; ++level) {
      for (std::uint32_t a = 3; a-- > 0;) {
        if (level < constant_levels[a]) continue;
        const auto position = static_cast<std::uint8_t>(3 * (depth - 1 - level) + a);
        top_positions_[top_count_++] = position;
        varying |= std::uint64_t{1} << position;
      }
    }
    const std::uint64_t all = (std::uint64_t{1} << (3 * depth)) - 1;  // depth <= 21
    constant_ = morton_encode(low_cells[0], low_cells[1], low_cells[2]) & all & ~varying;
  }

  // Bits of a compact key.
  unsigned bits() const { return low_bits_ + top_count_; }
  // No bit is constant: compact and expand are the identity.
  bool keeps_every_bit() const { return bits() == key_bits_; }
  std::uint64_t compact(std::uint64_t key) const {
    std::uint64_t top = 0;
    for (std::uint32_t i = 0; i < top_count_; ++i) top = (top << 1) | ((key >> top_positions_[i]) & 1u);
    return (top << low_bits_) | (key & low_mask());
  }
  // The key `compact` made `compacted` of.
  std::uint64_t expand(std::uint64_t compacted) const {
    std::uint64_t key = constant_ | (compacted & low_mask());
    for (std::uint32_t i = 0; i < top_count_; ++i)
      key |= ((compacted >> (low_bits_ + top_count_ - 1 - i)) & 1u) << top_positions_[i];
    return key;
  }

 private:
  std::uint64_t low_mask() const { return (std::uint64_t{1} << low_bits_) - 1; }  // low_bits_ <= 63

  unsigned key_bits_;                           // of a key: 3 * depth
  unsigned low_bits_ = 0;                       // the lower levels' bits, all kept
  std::array<std::uint8_t, 3 * kMaxOctreeDepth> top_positions_{};  // the upper levels' varying
  std::uint32_t top_count_ = 0;                 // bits, most significant first
  std::uint64_t constant_ = 0;                  // the bits dropped, as every key has them
};

// Sort key of a triangle: the key of its centroid, the mean of its corners' positions (model
// units) taken in double precision.
inline std::uint64_t centroid_key(const MortonQuantizer& quantizer, const float* a,
                                  const float* b, const float* c) {
  double sum[3];
  for (int i = 0; i < 3; ++i) sum[i] = static_cast<double>(a[i]) + b[i] + c[i];
  return quantizer.key_of_mean3(sum);
}

}  // namespace octolod::bake
