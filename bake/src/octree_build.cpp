// One streaming pass over the Morton-sorted soup decides the octree and hands out its leaves
// (seed 3.4, 4.3), see octree_build.h.
#include "octree_build.h"

#include <cassert>
#include <cstring>
#include <utility>

#include "morton.h"

namespace octolod::bake {

std::string OctreeNode::path() const {
  std::string p;
  for (std::uint32_t k = 0; k < depth; ++k) {
    if (!p.empty()) p += '/';
    p += static_cast<char>('0' + ((prefix >> (3 * (depth - 1 - k))) & 7u));
  }
  return p;
}

OctreeBuilder::OctreeBuilder(std::uint32_t max_tris, std::uint32_t max_depth,
                             std::size_t record_bytes, std::size_t tie_offset, LeafFn on_leaf)
    : max_tris_(max_tris),
      max_depth_(max_depth),
      record_bytes_(record_bytes),
      tie_offset_(tie_offset),
      on_leaf_(std::move(on_leaf)) {
  assert(max_depth <= kMaxOctreeDepth && "max_depth above kMaxOctreeDepth: keys would overflow");
  assert(max_tris >= 1 && "max_tris must be at least 1");
  assert((record_bytes == 0 || tie_offset + 4 <= record_bytes) && "tie_offset outside the record");
}

Status OctreeBuilder::push(std::span<const std::byte> records,
                           std::span<const std::uint64_t> keys) {
  assert(records.size() == keys.size() * record_bytes_);
  for (std::size_t i = 0; i < keys.size(); ++i)
    OCTOLOD_RETURN_IF_ERROR(add(records.data() + i * record_bytes_, keys[i]));
  return {};
}

Status OctreeBuilder::add(const std::byte* record, std::uint64_t key) {
  if (candidate_ >= 0) {
    const OctreeNode& c = nodes_[static_cast<std::size_t>(candidate_)];
    if (prefix_of(key, c.depth) == c.prefix) {
      buffer_.insert(buffer_.end(), record, record + record_bytes_);
      buffer_keys_.push_back(key);
      if (c.depth < max_depth_ && buffer_keys_.size() > max_tris_) return split_candidate();
      return {};
    }
    OCTOLOD_RETURN_IF_ERROR(close_candidate());
  }
  // The deepest split node on the key's path; the key opens a new candidate below it.
  while (!open_.empty()) {
    const OctreeNode& n = nodes_[static_cast<std::size_t>(open_.back())];
    if (prefix_of(key, n.depth) == n.prefix) break;
    open_.pop_back();
  }
  OctreeNode node;
  if (open_.empty()) {
    assert(nodes_.empty() && "a key outside the root: keys must have max_depth levels");
  } else {
    const std::int32_t parent = open_.back();
    OctreeNode& p = nodes_[static_cast<std::size_t>(parent)];
    node.depth = p.depth + 1;
    node.prefix = prefix_of(key, node.depth);
    node.parent = parent;
    const std::uint32_t octant = static_cast<std::uint32_t>(node.prefix & 7u);
    assert(p.children[octant] < 0 && "keys are not sorted");
    p.children[octant] = static_cast<std::int32_t>(nodes_.size());
  }
  candidate_ = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back(node);
  return add(record, key);
}

// The candidate holds more than max_tris: it becomes a split node and its records are replayed
// into its children (one of which may split again, recursively, at most max_depth times).
Status OctreeBuilder::split_candidate() {
  open_.push_back(candidate_);
  candidate_ = -1;
  std::vector<std::byte> records = std::move(buffer_);
  std::vector<std::uint64_t> keys = std::move(buffer_keys_);
  buffer_ = {};
  buffer_keys_ = {};
  buffer_.reserve(records.size());
  buffer_keys_.reserve(keys.size());
  return push(records, keys);
}

// Insertion sort of each run of equal keys by the tie value: the runs are short (triangles of
// one finest cell) and usually in order already, which costs one comparison per record.
void OctreeBuilder::order_equal_keys() {
  const std::size_t rb = record_bytes_;
  std::byte* records = buffer_.data();
  auto tie = [&](std::size_t i) {
    std::uint32_t v;
    std::memcpy(&v, records + i * rb + tie_offset_, sizeof v);
    return v;
  };
  std::vector<std::byte> moving(rb);
  for (std::size_t i = 1; i < buffer_keys_.size(); ++i) {
    const std::uint64_t key = buffer_keys_[i];
    const std::uint32_t t = tie(i);
    if (buffer_keys_[i - 1] != key || tie(i - 1) <= t) continue;
    std::memcpy(moving.data(), records + i * rb, rb);
    std::size_t j = i;
    for (; j > 0 && buffer_keys_[j - 1] == key && tie(j - 1) > t; --j)
      std::memcpy(records + j * rb, records + (j - 1) * rb, rb);
    std::memcpy(records + j * rb, moving.data(), rb);
  }
}

Status OctreeBuilder::close_candidate() {
  if (record_bytes_ > 0) order_equal_keys();
  OctreeNode& c = nodes_[static_cast<std::size_t>(candidate_)];
  c.leaf = true;
  c.triangles = buffer_keys_.size();
  const std::int32_t leaf = candidate_;
  candidate_ = -1;
  std::vector<std::byte> records = std::move(buffer_);
  buffer_ = {};
  buffer_keys_.clear();
  return on_leaf_(leaf, std::move(records));
}

Status OctreeBuilder::finish() {
  if (candidate_ >= 0) OCTOLOD_RETURN_IF_ERROR(close_candidate());
  open_.clear();
  // Children follow their parents: one backward sweep sums the subtrees.
  for (std::size_t i = nodes_.size(); i-- > 1;) {
    const OctreeNode& n = nodes_[i];
    nodes_[static_cast<std::size_t>(n.parent)].triangles += n.triangles;
  }
  return {};
}

}  // namespace octolod::bake
