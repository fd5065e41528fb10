// Axis-aligned box in model units.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace octolod {

struct Bounds {
  std::array<float, 3> min{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                           std::numeric_limits<float>::max()};
  std::array<float, 3> max{std::numeric_limits<float>::lowest(),
                           std::numeric_limits<float>::lowest(),
                           std::numeric_limits<float>::lowest()};

  bool empty() const { return min[0] > max[0] || min[1] > max[1] || min[2] > max[2]; }
  void extend(const float* p) {
    for (std::size_t i = 0; i < 3; ++i) {
      min[i] = std::min(min[i], p[i]);
      max[i] = std::max(max[i], p[i]);
    }
  }
  void extend(const Bounds& b) {
    for (std::size_t i = 0; i < 3; ++i) {
      min[i] = std::min(min[i], b.min[i]);
      max[i] = std::max(max[i], b.max[i]);
    }
  }
  bool contains(const float* p) const {
    for (std::size_t i = 0; i < 3; ++i)
      if (p[i] < min[i] || p[i] > max[i]) return false;
    return true;
  }
  // Length of the box's diagonal, in double (0 for a point; meaningless when empty).
  double diagonal() const {
    double sum = 0.0;
    for (std::size_t i = 0; i < 3; ++i) {
      const double side = static_cast<double>(max[i]) - min[i];
      sum += side * side;
    }
    return std::sqrt(sum);
  }
  // The largest absolute coordinate of its corners: how far from the origin its floats reach
  // (their spacing there sets the positions' precision). 0 when empty.
  double largest_magnitude() const {
    if (empty()) return 0.0;
    double largest = 0.0;
    for (std::size_t i = 0; i < 3; ++i)
      largest = std::max({largest, std::abs(static_cast<double>(min[i])), std::abs(static_cast<double>(max[i]))});
    return largest;
  }
  friend bool operator==(const Bounds&, const Bounds&) = default;
};

}  // namespace octolod
