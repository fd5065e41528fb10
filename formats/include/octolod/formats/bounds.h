// Axis-aligned box in model units.
#pragma once

#include <algorithm>
#include <array>
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
    for (int i = 0; i < 3; ++i) {
      min[i] = std::min(min[i], p[i]);
      max[i] = std::max(max[i], p[i]);
    }
  }
  void extend(const Bounds& b) {
    for (int i = 0; i < 3; ++i) {
      min[i] = std::min(min[i], b.min[i]);
      max[i] = std::max(max[i], b.max[i]);
    }
  }
  bool contains(const float* p) const {
    for (int i = 0; i < 3; ++i)
      if (p[i] < min[i] || p[i] > max[i]) return false;
    return true;
  }
  friend bool operator==(const Bounds&, const Bounds&) = default;
};

}  // namespace octolod
