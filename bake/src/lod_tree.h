// The LOD hierarchy of a bake (seed 3.5.3, 5.3.2; docs/design.md stages 5 and 7), built while
// the octree stream hands out its leaves:
//
//   leaf      its triangles are indexed (node_index.h) and become LOD 0 (the original, error 0);
//             build_lods continues the chain from it. A leaf too large for memory
//             (add_streamed_leaf) is built from its record file instead (streamed_leaf.h);
//             its LOD 0 is only in its file, which its parent reads when it merges it
//   internal  once the stream has left its key range (all its children are known) and every
//             child's chain is done: merge_meshes of one LOD per child (choose_merged_lods: the
//             finest ones whose meshes fit LodTreeOptions::merge_bytes together, a leaf's
//             original triangles when they do), in octant order, with input error = the max of
//             those LODs' errors; build_lods from there. Bottom-up whatever the tree's balance.
//             When the chosen LODs exceed twice merge_bytes (their locked boundaries near the
//             root of a large model), they go to a record file and the node's LODs are built
//             streaming from it instead (streamed_leaf.h, merged_children), memory bounded by
//             merge_bytes rather than by the model.
//
// Why the finest LODs that fit: every node keeps the boundary it shares with other nodes at the
// original resolution (crack-freedom for any cut, simplify.h), so a uniform cut through many small nodes spends most
// of its triangles on locked boundary fans (on a 1M rock, 38% of a 10% cut's triangles and 60%
// of a 1% cut's touched a locked edge when parents merged their children's second LODs). Merging
// the finest LODs makes a parent's LOD 0 about twice a child's, so the nodes near the root hold
// the finer LODs and a coarse uniform cut is a few large nodes with few locked edges. The
// clustering holds its whole input, so the merged input is bounded: near the root (and on
// inputs that hardly simplify, a city's separate boxes) children hand coarser LODs instead.
//
// The root's chain ends at LodOptions::min_triangles (a distant asset's few hundred triangles),
// every other node's at LodTreeOptions::node_min_triangles, or where its locked boundary stops
// the halving: the nodes near the root (large, few locked edges) continue into a coarse chain,
// the small ones below them stop where their parent's LOD 0 takes over. The root
// locks nothing (LodOptions::lock_boundary): it has no neighbour to meet, and its boundary is
// the mesh's own border (an open surface's: a 1M terrain's root stopped at 5,654 triangles of
// fans into its full-resolution border, it now goes on to 147, its border held in place by
// border quadrics). The other nodes keep only the boundary edges another node's triangle can
// reach (LodOptions::neighbours, from LodTreeOptions::longest_input_edge) and simplify the
// mesh's own border elsewhere, with border quadrics as well. Errors
// accumulate along the chains (simplify.h), so every stored error is conservative with respect
// to the original triangles of the node's region.
//
// Node work runs on the worker threads and on the caller (while the leaf queue is full and in
// finish()): ready internal nodes first, heaviest first (El-Sana & Varshney: octree cells
// processed in parallel, heaviest first), then leaves in stream order, so no small leaf holds
// up its parent (and the siblings' kept LODs) for long. A node's files depend only on its own input, which depends only on the
// input mesh and the options: the output is the same for any thread count and schedule.
//
// Memory: the leaves waiting for a thread (queue_bytes), the node work in flight (work_bytes: a
// node starts only while the running nodes' node_work_bytes estimates fit beside its own; an
// internal node's input is at most twice merge_bytes of mesh), and the children's finest LODs
// kept for their pending parents up to keep_bytes; past that, or when the parent merges a coarser one, the
// parent reads the child's file (identical bytes). A finished node's records go to a work file
// (node_lods_log.h, its offset in another) and its scheduler slot is dropped: nothing stays per
// node.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string_view>
#include <vector>

#include "morton.h"
#include "octolod/bake/simplify.h"
#include "octolod/bake/temp_file.h"
#include "octolod/formats/manifest.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"
#include "octree_build.h"

namespace octolod::bake {

// What the LOD stage produced for one node.
struct NodeLods {
  Bounds bounds;              // tight bounds of the node's LODs and its subtree's, model units
  std::vector<LodInfo> lods;  // finest first, files relative to the tree root
};

class NodeLodsLog;

struct LodTreeOptions {
  std::filesystem::path root;  // the tree being written: node files go to root / node path
  VertexLayout layout;         // of the leaves' soup records
  RootCube cube;               // the octree's root cube (node cells)
  // false: leaves get only LOD 0 (their original triangles), internal nodes no LOD.
  bool build_lods = true;
  // Method, min_triangles (the root's chain's, and every internal node's first step's: its
  // input_min_triangles), reduction, max_lods of every chain (include_input, lock_boundary and
  // input_min_triangles are set per node).
  LodOptions lod;
  // Where the chain of a node other than the root stops (its LodOptions::min_triangles). A
  // parent's LOD 0 is about as fine as its children's LOD 1, so a child's coarser LODs are only
  // drawn where the parent cannot be (a sibling needs more detail), and a draw call of fewer
  // than about a thousand triangles costs mostly its fixed overhead. 1024 instead of 256 (1M rock,
  // --memory 64M): bake 4.7 -> 3.5 s, 5,336 -> 3,009 node LODs (most leaves keep only their
  // original triangles); 16 of the 18 uniform cuts of six rock seeds at 10/3/1% identical, the
  // other two closer to the reference; the runtime's walks at 2 px drew 0.2-1.3% more
  // triangles. At 2048: 2.75 s, 1-4% more triangles drawn (docs/benchmarks.md).
  std::uint32_t node_min_triangles = 1024;
  // The longest edge of any input triangle, model units: every node below the root keeps only
  // the boundary edges within a third of it of its cell's faces (LodOptions::neighbours), which
  // are all it can share with other nodes; the mesh's own border deeper inside is simplified
  // where that pays (SimplifyOptions::neighbours). Infinity (unknown): every node keeps its
  // whole boundary.
  double longest_input_edge = std::numeric_limits<double>::infinity();
  unsigned workers = 0;         // threads besides the caller; 0: the caller does all node work
  std::size_t queue_bytes = 0;  // leaf records waiting for a thread (one leaf always fits)
  std::size_t keep_bytes = 0;   // children's LODs kept in memory for their parents
  // Upper bound of an internal node's merged input in NodeMesh bytes (lod_mesh_bytes), unless
  // its children's coarsest LODs alone exceed it. It must not depend on the memory budget (the
  // tree does not): 0 means 2 x queue_bytes, which the bake sets to two leaves' soup records
  // (max_tris and the layout), ~1 MiB with the defaults: 1M rock / city peak RSS at --memory
  // 64M 74 / 63 MiB; at twice that the city's was 92 MiB, over the budget + 24 MiB.
  std::size_t merge_bytes = 0;
  // Node work in flight: the sum of the running nodes' node_work_bytes stays within it, except
  // that a node always runs when no other does (so one whose estimate exceeds it, a streamed
  // node's included, runs alone). 0: no limit. The bake reserves max_node_work_bytes.
  std::size_t work_bytes = 0;
  // Leaves handed out as record files (add_streamed_leaf, streamed_leaf.h): triangles held in
  // memory at once, their LOD 1's limit, the edge sort's memory and temporary directory.
  std::uint64_t streamed_chunk_triangles = 1 << 16;
  std::uint64_t streamed_max_lod1_triangles = 1 << 14;
  std::uint64_t streamed_sort_bytes = 4 << 20;
  std::filesystem::path work_dir;  // the streamed leaves' and the node records' work files
};

// Bytes of the NodeMesh of a LOD: its vertex floats and its indices.
std::size_t lod_mesh_bytes(const LodInfo& lod, VertexLayout layout);

// An internal node's work, its heap high-water mark, estimated from its merged LODs
// (lod_mesh_bytes) in bytes. The simplifier's working set (the prepared node, clustering,
// quadrics, wedge tables, the LOD chain, the error bound's arrays) is at most ~11 times its
// input: measured per node (heap of the thread, 1M and 10M rock, 60K city at --max-tris 500 and
// 2000) 5-10x (10.4x at 300 KB, 7.2x at 1.1 MB, 4.9x at 1.9 MB of merged input); on the 100M
// rock some mid-size internal nodes up to 1.1x 256 KiB + 10x their input, hence 11.
std::size_t node_work_bytes(std::size_t input_bytes);
// A leaf's node work from its soup records, per record byte: the records, the indexed NodeMesh,
// the simplifier's arrays and the LOD chain. Measured as the slope of peak RSS (/usr/bin/time
// -v) between one leaf of 100K and one of 400K triangles (--max-depth 0, --memory 16M): rocks
// 4.4 (every attribute, 0.5 vertices per triangle) to 9.2 (positions only) records per
// triangle, a city's boxes 13.6 (every attribute, 2 vertices per triangle; 15.0 at --memory 4G,
// the in-memory octree's mesh included); bade2006 a third to a half of that. The worst with
// some headroom (a leaf at max_depth may be that large); leaves of max_tris take far less
// (2.8x for a rock's, 9x for a city's).
inline constexpr std::size_t kLeafWorkPerRecordByte = 16;
// kNodeWorkFixed + kLeafWorkPerRecordByte x a leaf's record bytes.
std::size_t leaf_work_bytes(std::size_t record_bytes);
// The largest node work of a tree with these limits: an internal node merges in memory up to
// kStreamedMergeFactor x merge_bytes (more is built streaming); a leaf holds at most
// leaf_record_bytes of records in memory (larger ones are built streaming, alone). What the
// bake reserves for node work (work_bytes).
std::size_t max_node_work_bytes(std::size_t merge_bytes, std::size_t leaf_record_bytes);
// Merged input past this many merge_bytes is built streaming (lod_tree.cpp, run_streamed_internal).
inline constexpr std::size_t kStreamedMergeFactor = 2;

// Which LOD of each child an internal node merges (an index into each child's chain, finest
// first): every child's finest LOD when their lod_mesh_bytes sum to at most merge_bytes;
// otherwise, one step at a time, the child whose chosen LOD has the most bytes (the first of
// equals) moves to its next coarser LOD until the sum fits or every child is at its coarsest.
// Depends only on the chains: the same on any thread and schedule. Every chain non-empty.
std::vector<std::size_t> choose_merged_lods(const std::vector<std::vector<LodInfo>>& children,
                                            VertexLayout layout, std::size_t merge_bytes);

struct LodTreeStats {
  double work_seconds = 0;  // node work summed over threads (indexing, LOD chains, files)
  std::uint64_t leaves = 0;
  std::uint32_t depth = 0;  // of the deepest leaf
  // children's LODs 0 a parent re-read from their files because the kept bytes were full (a
  // parent that merges a coarser LOD always reads its file)
  std::uint64_t reread_lods = 0;
  std::uint64_t peak_kept_bytes = 0;
  // internal nodes built streaming because their children's LODs were too large to merge in
  // memory (lod_tree.cpp, run_streamed_internal)
  std::uint64_t streamed_internal_nodes = 0;
  // leaves at max_depth too large for memory, built streaming (add_streamed_leaf), and the
  // triangles of the largest
  std::uint64_t streamed_leaves = 0;
  std::uint64_t largest_streamed_leaf = 0;
};

class LodTreeBuilder {
 public:
  explicit LodTreeBuilder(LodTreeOptions options);
  ~LodTreeBuilder();
  LodTreeBuilder(const LodTreeBuilder&) = delete;
  LodTreeBuilder& operator=(const LodTreeBuilder&) = delete;

  // The octree stream's next leaf (OctreeBuilder's LeafFn, key order); `nodes` is the builder's
  // tree so far. Returns once the leaf is queued; while the queue holds more than queue_bytes,
  // the caller runs node work itself or waits. The first error of any node work ends the build.
  Status add_leaf(std::int32_t node, const OctreeNodes& nodes,
                  std::vector<std::byte>&& records);
  // The same for a leaf too large for memory (OctreeBuilder's MaxDepthLeafSpill): its soup
  // records ordered by triangle id in `records` (removed once built), its LODs built streaming
  // (streamed_leaf.h); it counts nothing against queue_bytes.
  Status add_streamed_leaf(std::int32_t node, const OctreeNodes& nodes,
                           TempFile records);
  // After OctreeBuilder::finish(): the remaining node work, on the caller and the workers.
  // `progress(done, total)` is called on the caller as nodes complete. The first error.
  Status finish(const OctreeNodes& nodes,
                const std::function<void(std::uint64_t, std::uint64_t)>& progress);

  // Every node's record (its bounds include its subtree's), by node index: complete after a
  // successful finish(), which flushed it. Moves the log out of the builder.
  NodeLodsLog take_results();
  const LodTreeStats& stats() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace octolod::bake
