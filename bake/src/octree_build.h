// The on-disk octree's shape, decided in one streaming pass over the soup sorted by centroid
// Morton code (seed 3.4, 4.3; docs/design.md stage 3).
//
// The seed re-reads every triangle once per level to split the nodes of that level (I/O grows
// with N x depth). Here the soup is sorted once by Morton key (external sort), which makes
// every node a contiguous run of the sorted stream, and the tree is decided while that stream
// passes by: a node whose triangles are still arriving is a *candidate* whose records are
// buffered (runs of the stream appended at once); when it collects more than max_tris it
// splits: its buffer, sorted, is one run per child, every child but the last is complete and
// settled at once (split again or handed out as a leaf), the last becomes the candidate. When
// the stream leaves the candidate's key range it is a leaf and its records go to the caller.
// Memory: one candidate buffer of at most max_tris + 1 records and a copy of a settled leaf.
// A candidate at max_depth cannot split, so it would keep everything its cell gets: once the
// stream brings it more than a MaxDepthLeafSpill's cap, its records (the buffered ones, then
// every later run of its cell) go to the spill instead of the buffer, and the leaf is handed
// out to the spill (its buffer never holds more than the cap's records).
//
// Rules (seed 3.4): a node splits while it holds more than max_tris triangles and its depth is
// below max_depth; each triangle belongs to exactly one leaf, the one whose cell holds its
// centroid; empty octants get no node.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "octolod/formats/status.h"

namespace octolod::bake {

// A node's children are the nodes whose parent it is, octant = prefix & 7.
struct OctreeNode {
  std::uint64_t prefix = 0;  // octant path from the root, 3 bits per level (morton.h)
  std::uint64_t triangles = 0;  // in the subtree (complete after finish())
  std::int32_t parent = -1;  // index into OctreeBuilder::nodes(), -1 for the root
  std::uint32_t depth = 0;   // root = 0
  bool leaf = false;

  // "" for the root, else the octants from the root joined by '/': "3/5".
  std::string path() const;
};

// The tree's nodes by index (creation order: parents first, depth-first). size() counts every
// node created; which are held depends on the builder (OctreeBuilder::forget_finished_nodes).
class OctreeNodes {
 public:
  std::size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  bool holds(std::size_t i) const { return held_.count(i) != 0; }
  std::size_t held() const { return held_.size(); }
  const OctreeNode& operator[](std::size_t i) const { return held_.at(i); }
  OctreeNode& operator[](std::size_t i) { return held_.at(i); }
  const OctreeNode& back() const { return held_.at(count_ - 1); }
  void push_back(const OctreeNode& node) { held_.emplace(count_++, node); }
  void forget(std::size_t i) { held_.erase(i); }

 private:
  std::unordered_map<std::size_t, OctreeNode> held_;
  std::size_t count_ = 0;
};

// Receives a finished leaf: its node index and its records in leaf order (ownership passes).
using LeafFn = std::function<Status(std::int32_t node, std::vector<std::byte>&& records)>;

// Where a leaf at max_depth goes when it holds more than `triangles` (the most a leaf handed
// out in memory may hold; at least max_tris + 1 always stay in memory: a split's child at
// max_depth may hold all of its parent's records). When the stream brings such a candidate
// more, append(node, records, count) receives its buffered records, then every later run of
// its cell as it arrives (stream order: equal keys are NOT ordered by the tie value, the
// receiver orders them; `records` empty when record_bytes is 0), and finish(node) ends the
// leaf (OctreeNode::triangles set) instead of LeafFn. An error either returns ends the build.
struct MaxDepthLeafSpill {
  std::uint64_t triangles = std::numeric_limits<std::uint64_t>::max();
  std::function<Status(const OctreeNode& node, std::span<const std::byte> records,
                       std::size_t count)> append;
  std::function<Status(std::int32_t node)> finish;
};

class OctreeBuilder {
 public:
  // max_depth <= kMaxOctreeDepth (morton.h), max_tris >= 1; keys pushed must have max_depth
  // levels. on_leaf is called from push()/finish(), in key order; an error it returns ends the
  // build with that error. record_bytes 0 decides the tree from the keys alone: leaves get no
  // records, and a leaf's triangles are the next OctreeNode::triangles keys of the stream.
  // The tree (nodes(), leaves and their order) depends on the keys only. Leaf order: by key,
  // equal keys by the u32 at byte `tie_offset` of the record (the triangle id), so a leaf's
  // records do not depend on the order equal keys arrived in. `spill` only decides where a
  // leaf's records go, it never changes the tree; its default keeps every leaf in memory.
  OctreeBuilder(std::uint32_t max_tris, std::uint32_t max_depth, std::size_t record_bytes,
                std::size_t tie_offset, LeafFn on_leaf, MaxDepthLeafSpill spill = {});

  // The next records of the sorted stream and their keys (keys.size() records, non-decreasing
  // keys across all calls).
  Status push(std::span<const std::byte> records, std::span<const std::uint64_t> keys);
  // Ends the stream: the last candidate becomes a leaf, subtree counts are summed.
  Status finish();

  // Parents precede their children; children in octant order (depth-first, key order).
  const OctreeNodes& nodes() const { return nodes_; }
  OctreeNodes& nodes() { return nodes_; }
  // From now on a node is dropped from nodes() once finished and handed on: a leaf after its
  // LeafFn or spill finish returned, a split node once the stream has left it (every node is
  // created before its subtree's leaves are handed out, so a consumer that looks at the new
  // nodes in each LeafFn call sees each one). What stays held is the open path; OctreeNode::
  // triangles of a split node is then never summed (finish() does that for a tree held whole).
  // A tree of 100M triangles has 212K nodes.
  void forget_finished_nodes() { forget_ = true; }

 private:
  void open_candidate(std::uint64_t key);
  std::int32_t new_child(std::int32_t parent, std::uint64_t key);
  Status split_candidate_while_full();
  Status settle(std::int32_t node, std::size_t begin, std::size_t end);
  Status close_candidate();
  Status spill_run(const OctreeNode& candidate, std::span<const std::byte> records,
                   std::size_t count);
  Status hand_out_leaf(std::int32_t node, std::vector<std::byte>&& records,
                       std::span<const std::uint64_t> keys);
  // Node `node` is finished and handed on: dropped under forget_finished_nodes().
  void finished(std::int32_t node);
  void order_equal_keys(std::vector<std::byte>& records, std::span<const std::uint64_t> keys) const;
  std::uint64_t prefix_of(std::uint64_t key, std::uint32_t depth) const {
    return key >> (3 * (max_depth_ - depth));
  }

  std::uint32_t max_tris_;
  std::uint32_t max_depth_;
  std::size_t record_bytes_;
  std::size_t tie_offset_;
  LeafFn on_leaf_;
  MaxDepthLeafSpill spill_;  // spill_.triangles >= max_tris_ + 1
  OctreeNodes nodes_;
  std::vector<std::int32_t> open_;  // split nodes on the current key's path, root first
  std::int32_t candidate_ = -1;     // the node whose records are being buffered
  std::vector<std::byte> buffer_;   // the candidate's records
  std::vector<std::uint64_t> buffer_keys_;
  std::uint64_t spilled_ = 0;  // records of the candidate given to the spill (0: not spilling)
  bool forget_ = false;        // forget_finished_nodes()
};

}  // namespace octolod::bake
