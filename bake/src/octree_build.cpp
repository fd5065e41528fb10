// One streaming pass over the Morton-sorted soup decides the octree and hands out its leaves
// (seed 3.4, 4.3), see octree_build.h.
#include "octree_build.h"

#include <cassert>
#include <algorithm>
#include <cstring>
#include <utility>

#include "morton.h"
#include "tree_paths.h"

namespace octolod::bake {

std::string OctreeNode::path() const { return node_path(prefix, depth); }

OctreeBuilder::OctreeBuilder(std::uint32_t max_tris, std::uint32_t max_depth,
                             std::size_t record_bytes, std::size_t tie_offset, LeafFn on_leaf,
                             MaxDepthLeafSpill spill)
    : max_tris_(max_tris),
      max_depth_(max_depth),
      record_bytes_(record_bytes),
      tie_offset_(tie_offset),
      on_leaf_(std::move(on_leaf)),
      spill_(std::move(spill)) {
  spill_.triangles = std::max<std::uint64_t>(spill_.triangles, std::uint64_t{max_tris} + 1);
  assert(((spill_.append && spill_.finish) ||
          spill_.triangles == std::numeric_limits<std::uint64_t>::max()) &&
         "a MaxDepthLeafSpill with a limit needs its append and finish functions");
  assert(max_depth <= kMaxOctreeDepth && "max_depth above kMaxOctreeDepth: keys would overflow");
  assert(max_tris >= 1 && "max_tris must be at least 1");
  assert((record_bytes == 0 || tie_offset + 4 <= record_bytes) && "tie_offset outside the record");
}

Status OctreeBuilder::push(std::span<const std::byte> records,
                           std::span<const std::uint64_t> keys) {
  assert(records.size() == keys.size() * record_bytes_);
  std::size_t i = 0;
  while (i < keys.size()) {
    if (candidate_ < 0) open_candidate(keys[i]);
    const OctreeNode& c = nodes_[static_cast<std::size_t>(candidate_)];
    if (prefix_of(keys[i], c.depth) != c.prefix) {  // the stream left the candidate's cell
      OCTOLOD_RETURN_IF_ERROR(close_candidate());
      continue;
    }
    // The run of keys in the candidate's cell (the stream is sorted), appended at once, up to
    // the record that makes it split (so the buffer never holds more than max_tris + 1). At
    // max_depth the whole run; once it takes the candidate over the spill's cap, the buffer
    // and every later run go to the spill.
    std::size_t limit = keys.size();
    if (c.depth < max_depth_) limit = std::min(limit, i + (max_tris_ + 1 - buffer_keys_.size()));
    std::size_t j = i;
    while (j < limit && prefix_of(keys[j], c.depth) == c.prefix) ++j;
    if (c.depth == max_depth_ &&
        (spilled_ > 0 || buffer_keys_.size() + (j - i) > spill_.triangles)) {
      if (spilled_ == 0 && !buffer_keys_.empty()) {
        OCTOLOD_RETURN_IF_ERROR(spill_run(c, buffer_, buffer_keys_.size()));
        buffer_ = {};
        buffer_keys_ = {};
      }
      OCTOLOD_RETURN_IF_ERROR(
          spill_run(c, records.subspan(i * record_bytes_, (j - i) * record_bytes_), j - i));
      i = j;
      continue;
    }
    buffer_.insert(buffer_.end(), records.data() + i * record_bytes_,
                   records.data() + j * record_bytes_);
    buffer_keys_.insert(buffer_keys_.end(), keys.begin() + static_cast<std::ptrdiff_t>(i),
                        keys.begin() + static_cast<std::ptrdiff_t>(j));
    OCTOLOD_RETURN_IF_ERROR(split_candidate_while_full());
    i = j;
  }
  return {};
}

// A new candidate for `key`: a child of the deepest split node on the key's path.
void OctreeBuilder::open_candidate(std::uint64_t key) {
  while (!open_.empty()) {
    const OctreeNode& n = nodes_[static_cast<std::size_t>(open_.back())];
    if (prefix_of(key, n.depth) == n.prefix) break;
    finished(open_.back());
    open_.pop_back();
  }
  if (open_.empty()) {
    assert(nodes_.empty() && "a key outside the root: keys must have max_depth levels");
    nodes_.push_back(OctreeNode{});
    candidate_ = 0;
    return;
  }
  candidate_ = new_child(open_.back(), key);
}

std::int32_t OctreeBuilder::new_child(std::int32_t parent, std::uint64_t key) {
  OctreeNode node;
  const OctreeNode& p = nodes_[static_cast<std::size_t>(parent)];
  node.depth = p.depth + 1;
  node.prefix = prefix_of(key, node.depth);
  node.parent = parent;
  assert((!nodes_.holds(nodes_.size() - 1) || nodes_.back().parent != parent ||
          nodes_.back().prefix < node.prefix) && "keys are not sorted");
  const auto index = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back(node);
  return index;
}

// While the candidate holds more than max_tris and may split: it becomes a split node on the
// open path; its buffer, sorted, is a run per child. Every child but the last is complete
// (later keys are larger) and is settled now; the last becomes the candidate.
Status OctreeBuilder::split_candidate_while_full() {
  for (;;) {
    const OctreeNode& c = nodes_[static_cast<std::size_t>(candidate_)];
    if (c.depth >= max_depth_ || buffer_keys_.size() <= max_tris_) return {};
    const std::int32_t parent = candidate_;
    const std::uint32_t depth = c.depth + 1;
    open_.push_back(parent);
    std::size_t begin = 0;
    for (;;) {
      std::size_t end = begin + 1;
      const std::uint64_t prefix = prefix_of(buffer_keys_[begin], depth);
      while (end < buffer_keys_.size() && prefix_of(buffer_keys_[end], depth) == prefix) ++end;
      const std::int32_t child = new_child(parent, buffer_keys_[begin]);
      if (end == buffer_keys_.size()) {  // the last child: the candidate, its run moved forward
        buffer_.erase(buffer_.begin(),
                      buffer_.begin() + static_cast<std::ptrdiff_t>(begin * record_bytes_));
        buffer_keys_.erase(buffer_keys_.begin(),
                           buffer_keys_.begin() + static_cast<std::ptrdiff_t>(begin));
        candidate_ = child;
        break;
      }
      OCTOLOD_RETURN_IF_ERROR(settle(child, begin, end));
      begin = end;
    }
  }
}

// A complete node holding the buffer's entries [begin, end): split while over max_tris, else a
// leaf with a copy of its records.
Status OctreeBuilder::settle(std::int32_t node, std::size_t begin, std::size_t end) {
  const std::uint32_t depth = nodes_[static_cast<std::size_t>(node)].depth;
  if (depth < max_depth_ && end - begin > max_tris_) {
    for (std::size_t first = begin; first < end;) {
      std::size_t last = first + 1;
      const std::uint64_t prefix = prefix_of(buffer_keys_[first], depth + 1);
      while (last < end && prefix_of(buffer_keys_[last], depth + 1) == prefix) ++last;
      OCTOLOD_RETURN_IF_ERROR(settle(new_child(node, buffer_keys_[first]), first, last));
      first = last;
    }
    finished(node);
    return {};
  }
  std::vector<std::byte> records(buffer_.begin() + static_cast<std::ptrdiff_t>(begin * record_bytes_),
                                 buffer_.begin() + static_cast<std::ptrdiff_t>(end * record_bytes_));
  return hand_out_leaf(node, std::move(records),
                       std::span<const std::uint64_t>(buffer_keys_.data() + begin, end - begin));
}

Status OctreeBuilder::hand_out_leaf(std::int32_t node, std::vector<std::byte>&& records,
                                    std::span<const std::uint64_t> keys) {
  OctreeNode& n = nodes_[static_cast<std::size_t>(node)];
  n.leaf = true;
  n.triangles = keys.size();
  if (record_bytes_ > 0) order_equal_keys(records, keys);
  OCTOLOD_RETURN_IF_ERROR(on_leaf_(node, std::move(records)));
  finished(node);
  return {};
}

// Insertion sort of each run of equal keys by the tie value: the runs are short (triangles of
// one finest cell) and usually in order already, which costs one comparison per record.
void OctreeBuilder::order_equal_keys(std::vector<std::byte>& records_vector,
                                     std::span<const std::uint64_t> keys) const {
  const std::size_t rb = record_bytes_;
  std::byte* records = records_vector.data();
  auto tie = [&](std::size_t i) {
    std::uint32_t v;
    std::memcpy(&v, records + i * rb + tie_offset_, sizeof v);
    return v;
  };
  std::vector<std::byte> moving(rb);
  for (std::size_t i = 1; i < keys.size(); ++i) {
    const std::uint64_t key = keys[i];
    const std::uint32_t t = tie(i);
    if (keys[i - 1] != key || tie(i - 1) <= t) continue;
    std::memcpy(moving.data(), records + i * rb, rb);
    std::size_t j = i;
    for (; j > 0 && keys[j - 1] == key && tie(j - 1) > t; --j)
      std::memcpy(records + j * rb, records + (j - 1) * rb, rb);
    std::memcpy(records + j * rb, moving.data(), rb);
  }
}

Status OctreeBuilder::spill_run(const OctreeNode& candidate, std::span<const std::byte> records,
                                std::size_t count) {
  spilled_ += count;
  return spill_.append(candidate, records, count);
}

Status OctreeBuilder::close_candidate() {
  const std::int32_t leaf = candidate_;
  candidate_ = -1;
  if (spilled_ > 0) {
    OctreeNode& n = nodes_[static_cast<std::size_t>(leaf)];
    n.leaf = true;
    n.triangles = spilled_;
    spilled_ = 0;
    OCTOLOD_RETURN_IF_ERROR(spill_.finish(leaf));
    finished(leaf);
    return {};
  }
  std::vector<std::byte> records = std::move(buffer_);
  buffer_ = {};
  Status handed = hand_out_leaf(leaf, std::move(records), buffer_keys_);
  buffer_keys_.clear();
  return handed;
}

void OctreeBuilder::finished(std::int32_t node) {
  if (forget_) nodes_.forget(static_cast<std::size_t>(node));
}

Status OctreeBuilder::finish() {
  if (candidate_ >= 0) OCTOLOD_RETURN_IF_ERROR(close_candidate());
  if (forget_) {
    for (std::int32_t node : open_) finished(node);
    open_.clear();
    return {};
  }
  open_.clear();
  // Children follow their parents: one backward sweep sums the subtrees.
  for (std::size_t i = nodes_.size(); i-- > 1;) {
    const OctreeNode& n = nodes_[i];
    nodes_[static_cast<std::size_t>(n.parent)].triangles += n.triangles;
  }
  return {};
}

}  // namespace octolod::bake
