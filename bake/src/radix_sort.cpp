// Stable LSD radix sort of keys with a payload (radix_sort.h).
#include "radix_sort.h"

#include <array>
#include <utility>
#include <vector>

namespace octolod::bake {

void radix_sort(std::uint64_t*& keys, std::uint32_t*& order, std::uint64_t*& keys_tmp,
                std::uint32_t*& order_tmp, std::size_t n) {
  if (n < 2) return;
  bool sorted = true;
  for (std::size_t i = 1; i < n && sorted; ++i) sorted = keys[i - 1] <= keys[i];
  if (sorted) return;

  std::vector<std::array<std::uint32_t, 256>> counts(8, std::array<std::uint32_t, 256>{});
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t k = keys[i];
    for (int d = 0; d < 8; ++d) ++counts[static_cast<std::size_t>(d)][(k >> (8 * d)) & 255u];
  }
  for (int d = 0; d < 8; ++d) {
    auto& count = counts[static_cast<std::size_t>(d)];
    const int shift = 8 * d;
    if (count[(keys[0] >> shift) & 255u] == n) continue;  // this digit is the same everywhere
    std::uint32_t offset = 0;
    for (auto& c : count) {
      const std::uint32_t next = offset + c;
      c = offset;
      offset = next;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t k = keys[i];
      const std::uint32_t pos = count[(k >> shift) & 255u]++;
      keys_tmp[pos] = k;
      order_tmp[pos] = order[i];
    }
    std::swap(keys, keys_tmp);
    std::swap(order, order_tmp);
  }
}

}  // namespace octolod::bake
