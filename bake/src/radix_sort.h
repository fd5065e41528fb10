// Stable LSD radix sort of 64-bit keys carrying a 32-bit payload: the external sort's runs and
// the in-memory octree's triangles.
#pragma once

#include <cstddef>
#include <cstdint>

namespace octolod::bake {

// Sorts `order` by `keys` (parallel arrays of n entries, n < 2^32), stably: equal keys keep
// their order. One histogram pass, 8-bit digits, digits that do not vary are skipped, input
// that is already sorted returns at once. keys_tmp / order_tmp are scratch arrays of n entries;
// the sorted result ends in keys / order, whose pointers may have been swapped with the
// scratch ones (the caller owns all four arrays either way).
void radix_sort(std::uint64_t*& keys, std::uint32_t*& order, std::uint64_t*& keys_tmp,
                std::uint32_t*& order_tmp, std::size_t n);

}  // namespace octolod::bake
