// Flat open-addressing hash tables (linear probing, power-of-two capacity sized once for a known
// number of keys) for the per-node simplification's cluster, cluster-triple, position and vertex
// tables, where std::unordered_map's node allocation per entry dominated the run time. They are
// never iterated, so no result depends on a table's internal order.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace octolod::bake {

// Hash of n 32-bit words: the words packed in pairs into 64 bits, folded by an odd multiplier,
// then one finalizer (Stafford's Mix13, as in splitmix64) so that the low bits, which pick a
// slot, depend on every input bit.
inline std::uint64_t hash_words(const std::uint32_t* words, std::size_t n) {
  constexpr std::uint64_t kOdd = 0x9E3779B97F4A7C15ull;
  std::uint64_t h = 0;
  std::size_t i = 0;
  for (; i + 1 < n; i += 2) h = (h ^ (std::uint64_t{words[i]} << 32 | words[i + 1])) * kOdd;
  if (i < n) h = (h ^ words[i]) * kOdd;
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

inline std::size_t table_capacity(std::size_t max_keys) {
  return std::bit_ceil(std::max<std::size_t>(16, 2 * max_keys));  // load factor <= 1/2
}

// Map from W 32-bit words to a 32-bit value. The key whose first word is ~0 is reserved.
template <std::size_t W>
class FlatHashMap {
 public:
  using Key = std::array<std::uint32_t, W>;
  static constexpr std::uint32_t kMissing = ~std::uint32_t{0};

  // Room for `max_keys` distinct keys.
  explicit FlatHashMap(std::size_t max_keys) : mask_(table_capacity(max_keys) - 1), slots_(mask_ + 1) {}

  // The value stored for `key`, after inserting `value` for it when the key is new (`inserted`
  // says which). At most max_keys distinct keys may be inserted.
  std::uint32_t find_or_insert(const Key& key, std::uint32_t value, bool& inserted) {
    for (std::size_t i = hash(key) & mask_;; i = (i + 1) & mask_) {
      Slot& slot = slots_[i];
      if (same(slot.key, key)) {
        inserted = false;
        return slot.value;
      }
      if (slot.key[0] == kMissing) {
        slot.key = key;
        slot.value = value;
        inserted = true;
        return value;
      }
    }
  }

  // The value of `key`, or kMissing.
  std::uint32_t find(const Key& key) const {
    for (std::size_t i = hash(key) & mask_;; i = (i + 1) & mask_) {
      const Slot& slot = slots_[i];
      if (same(slot.key, key)) return slot.value;
      if (slot.key[0] == kMissing) return kMissing;
    }
  }

 private:
  static bool same(const Key& a, const Key& b) {  // a loop, not std::array's memcmp call
    bool equal = true;
    for (std::size_t i = 0; i < W; ++i) equal = equal && a[i] == b[i];
    return equal;
  }
  static std::uint64_t hash(const Key& key) { return hash_words(key.data(), W); }
  struct Slot {
    Key key = make_empty();
    std::uint32_t value = 0;
  };
  static Key make_empty() {
    Key key{};
    key[0] = kMissing;
    return key;
  }
  std::size_t mask_;
  std::vector<Slot> slots_;
};

// Set of ids (e.g. vertex ids) whose identity is decided by the caller's `hash(id)` and
// `equal(id, id)`: finds the first inserted id equal to a new one.
class FlatIdSet {
 public:
  explicit FlatIdSet(std::size_t max_ids) : mask_(table_capacity(max_ids) - 1), slots_(mask_ + 1, kEmpty) {}

  // The id already in the set that equals `id`, or `id` itself after inserting it.
  template <class Hash, class Equal>
  std::uint32_t find_or_insert(std::uint32_t id, const Hash& hash, const Equal& equal) {
    for (std::size_t i = hash(id) & mask_;; i = (i + 1) & mask_) {
      std::uint32_t& slot = slots_[i];
      if (slot == kEmpty) {
        slot = id;
        return id;
      }
      if (equal(slot, id)) return slot;
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t{0};
  std::size_t mask_;
  std::vector<std::uint32_t> slots_;
};

}  // namespace octolod::bake
