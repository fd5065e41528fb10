// The bake pipeline (docs/design.md stages 2-7; seed 3.4, 3.5.3, 4.3): soup, Morton sort and
// streaming octree with the LOD hierarchy built on worker threads meanwhile (lod_tree.h),
// manifest, atomic publication. See
// octolod/bake/bake.h for the contract.
#include "octolod/bake/bake.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "bucket_sort.h"
#include "error_bound.h"
#include "morton.h"
#include "octolod/bake/external_sort.h"
#include "octolod/bake/soup.h"
#include "octolod/formats/ply_reader.h"
#include "lod_tree.h"
#include "node_lods_log.h"
#include "octolod/formats/node_file.h"
#include "octree_build.h"
#include "page_array.h"
#include "radix_sort.h"
#include "peak_rss.h"
#include "record_file.h"
#include "streamed_leaf.h"
#include "octolod/bake/temp_dir.h"
#include "tree_paths.h"
#include "tree_texture.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

Status interrupted() { return io_error("bake interrupted by a signal"); }

// Sort key of soup records: the Morton code of the triangle's centroid (morton.h), without the
// bits equal for every centroid (VaryingKeyBits: the same order, fewer key bits).
SortKeyFn centroid_morton_key(const MortonQuantizer& quantizer, const VaryingKeyBits& varying, VertexLayout layout) {
  const std::size_t record_bytes = soup_record_bytes(layout);
  return [quantizer, varying, layout, record_bytes](std::span<const std::byte> records,
                                                    std::span<std::uint64_t> keys) {
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::byte* record = records.data() + i * record_bytes;
      float corner[3][3];
      for (int c = 0; c < 3; ++c)
        std::memcpy(corner[c], record + soup_corner_offset(layout, c), sizeof corner[c]);
      keys[i] = varying.compact(centroid_key(quantizer, corner[0], corner[1], corner[2]));
    }
  };
}

// The longest edge of the triangle with corners a, b, c (positions), model units.
double triangle_longest_edge(const float* a, const float* b, const float* c) {
  auto length2 = [](const float* p, const float* q) {
    double sum = 0;
    for (int i = 0; i < 3; ++i) sum += (static_cast<double>(p[i]) - q[i]) * (static_cast<double>(p[i]) - q[i]);
    return sum;
  };
  return std::sqrt(std::max({length2(a, b), length2(b, c), length2(c, a)}));
}

// How the budget is divided in the octree stage: the sort gets what the leaf buffers and the
// node work leave.
struct OctreeBudget {
  std::size_t io_bytes = 0;     // the soup file reader's buffer
  std::size_t queue_bytes = 0;  // leaves waiting for a thread
  std::size_t keep_bytes = 0;   // children's LODs held for their parents (lod_tree.h)
  std::size_t merge_bytes = 0;  // an internal node's merged input (LodTreeOptions::merge_bytes); 0 for a one-leaf tree
  std::size_t work_bytes = 0;   // node work in flight (LodTreeOptions::work_bytes)
  std::uint64_t sort_bytes = 0;
};

// Node work threads besides the caller, for `threads` in all (the caller works too).
unsigned lod_workers(unsigned threads) { return threads > 1 ? threads - 1 : 0; }

// What each thread past the second holds beyond its nodes' estimates (node_work_bytes, measured
// on two threads): the free memory its malloc arena keeps (glibc trims an arena's top only past
// 128 KiB) and its stack's touched pages. Measured as the growth of the 1M rock's peak RSS at
// --memory 64M: 14 MiB from 2 to 128 threads (110 KiB per thread), 2.3 MiB more at 256, when the
// node work limit leaves the extra threads idle (--method none: no growth).
constexpr std::uint64_t kNodeThreadBytes = 128 << 10;
constexpr std::uint64_t kThreadsInTheEstimates = 2;

// The input's triangle count when the budget is divided before it is known.
constexpr std::uint64_t kUnknownTriangles = std::numeric_limits<std::uint64_t>::max();

// `input_triangles`: the input's triangle count, or kUnknownTriangles. No leaf holds more than
// the input, and no internal node merges more than the input's mesh (its triangles with three
// vertices each), so a small input needs less than max_tris says.
Result<OctreeBudget> divide_octree_budget(const BakeOptions& options, VertexLayout layout,
                                          unsigned workers, std::uint64_t input_triangles) {
  // One leaf's records. The octree pass holds a candidate and a replay of one. Node work in
  // flight is limited to the largest node's estimate (lod_tree.h, max_node_work_bytes: an
  // internal node merging up to twice merge_bytes, ~24 MB with the defaults, or a leaf at
  // max_depth as large as the budget keeps in memory, a quarter of it), which the threads
  // share; without LODs a thread holds a leaf's records.
  const std::uint64_t leaf_triangles = std::min<std::uint64_t>(options.max_tris, input_triangles);
  const std::uint64_t leaf = (leaf_triangles + 1) * soup_record_bytes(layout);
  OctreeBudget b;
  b.io_bytes = static_cast<std::size_t>(
      std::clamp<std::uint64_t>(options.memory_budget_bytes / 16, 4096, std::uint64_t{1} << 20));
  b.queue_bytes = static_cast<std::size_t>(2 * leaf);
  // Children's LODs kept for their parents: what is pending is one level's closed siblings per
  // depth of the current path, usually a few leaves' worth; beyond it parents re-read files.
  b.keep_bytes = static_cast<std::size_t>(
      options.lods ? std::max(2 * leaf, options.memory_budget_bytes / 16) : 0);
  const std::uint64_t threads = workers + 1;  // the caller works too
  b.merge_bytes = 2 * b.queue_bytes;
  // the cap is above any merge of this input, so it decides nothing (the tree does not depend
  // on the input's size being known); an input of at most max_tris is one leaf, which merges
  // nothing
  if (input_triangles <= options.max_tris)
    b.merge_bytes = 0;
  else if (input_triangles != kUnknownTriangles)
    b.merge_bytes = static_cast<std::size_t>(std::min<std::uint64_t>(
        b.merge_bytes, input_triangles * (3 * layout.bytes() + 3 * sizeof(std::uint32_t))));
  const std::uint64_t largest_leaf =
      std::min(max_depth_leaf_triangles(options.memory_budget_bytes, layout, options.max_tris), input_triangles) *
      soup_record_bytes(layout);
  const std::uint64_t work =
      options.lods ? max_node_work_bytes(b.merge_bytes, static_cast<std::size_t>(largest_leaf)) : threads * leaf;
  if (options.lods) b.work_bytes = static_cast<std::size_t>(work);
  const std::uint64_t thread_bytes =
      options.lods && threads > kThreadsInTheEstimates ? (threads - kThreadsInTheEstimates) * kNodeThreadBytes : 0;
  const std::uint64_t reserve =
      b.io_bytes + (workers ? b.queue_bytes : 0) + b.keep_bytes + work + 2 * leaf + thread_bytes;
  // the sort keeps at least a quarter of the budget
  if (reserve > options.memory_budget_bytes - options.memory_budget_bytes / 4) {
    // reserve <= fixed + budget / 16 (the io buffer at its largest, the kept LODs at theirs)
    // with the node work at its floor (the largest internal node or leaf of max_tris), so any
    // budget of at least 16/11 x fixed passes, or 16/7 x (fixed - floor) where a quarter of the
    // budget for a leaf at max_depth is the larger node work
    const std::uint64_t floor = max_node_work_bytes(b.merge_bytes, static_cast<std::size_t>(leaf));
    const std::uint64_t rest = (std::uint64_t{1} << 20) + (workers ? b.queue_bytes : 0) + 4 * leaf + thread_bytes;
    const std::uint64_t fixed = std::max(16 * (rest + floor) / 11, 16 * (rest + leaf_work_bytes(0)) / 7);
    return usage_error("memory budget of " + std::to_string((options.memory_budget_bytes + options.program_bytes) >> 20) +
                       " MiB is too small for --max-tris " + std::to_string(options.max_tris) +
                       " with layout " + layout.describe() + " on " + std::to_string(threads) +
                       (threads == 1 ? " thread" : " threads") +
                       (input_triangles != kUnknownTriangles
                            ? " and an input of " + std::to_string(input_triangles) + " triangles"
                            : std::string()) +
                       ": a budget of " +
                       std::to_string(((fixed + options.program_bytes) >> 20) + 1) +
                       " MiB suffices (the exact threshold can be a few MiB lower; a smaller --max-tris needs less)");
  }
  b.sort_bytes = options.memory_budget_bytes - reserve;
  return b;
}

// A leaf at max_depth, which cannot split, may cost up to 1 / kMaxDepthLeafShare of the budget
// in the LOD stage: that many triangles (max_depth_leaf_triangles, at kLeafWorkPerRecordByte,
// lod_tree.h) are handed out in memory, a larger leaf is spilled to a record file and built
// streaming (streamed_leaf.h: LOD 1 of at most that many triangles and its chain cost about
// what an in-memory leaf of that size does, the chunks it reads its records in a fraction of
// that; it runs alone). The node work reserve covers that share (divide_octree_budget).
constexpr std::uint64_t kMaxDepthLeafShare = 4;
// A streamed leaf's sorts (its records by triangle id, its repeated faces, its edges) take 1 / this
// of the budget, one at a time.
constexpr std::uint64_t kStreamedSortShare = 16;
// A streamed leaf reads its records in chunks of this many leaves of max_depth_leaf_triangles:
// a chunk costs about 3 records per triangle (records, indexed mesh, hash slots), a fifth of
// an in-memory leaf's 16, and larger chunks store fewer vertices twice in LOD 0 (1M rock at
// --memory 16M --max-depth 0: 942K vertices in chunks of 1 cap, 574K in memory).
constexpr std::uint64_t kStreamedChunkLeaves = 4;

// Sorted records into `builder` with their Morton keys: the sort's keys are compact
// (VaryingKeyBits), expanded here a fixed chunk at a time.
Status push_with_full_keys(OctreeBuilder& builder, std::span<const std::byte> records,
                           std::span<const std::uint64_t> keys, const VaryingKeyBits& varying,
                           std::size_t record_bytes) {
  if (varying.keeps_every_bit()) return builder.push(records, keys);
  constexpr std::size_t kChunk = 4096;
  std::array<std::uint64_t, kChunk> full;  // 32 KiB of stack
  for (std::size_t first = 0; first < keys.size(); first += kChunk) {
    const std::size_t n = std::min(kChunk, keys.size() - first);
    for (std::size_t i = 0; i < n; ++i) full[i] = varying.expand(keys[first + i]);
    OCTOLOD_RETURN_IF_ERROR(builder.push(records.subspan(first * record_bytes, n * record_bytes),
                                         std::span<const std::uint64_t>(full.data(), n)));
  }
  return {};
}

// The soup's way into the octree sort (SoupOptions::sink). When the soup stage leaves room
// for a sorter beside it (its out-of-core path keeps about half the budget free), the records
// go straight into that sorter's stage and the soup is never written as a file. Otherwise (the in-core path holds the whole budget) they go to a soup file, read into a
// sorter with the full sort budget once the soup stage has freed its memory.
class OctreeInput {
 public:
  // `input_triangles`: as divide_octree_budget's (known here only when the early check counted)
  OctreeInput(const BakeOptions& options, fs::path work, unsigned threads, std::uint64_t input_triangles)
      : options_(options), work_(std::move(work)), threads_(threads), input_triangles_(input_triangles) {}

  // SoupOptions::sink_start: the cube, the budget's division, and where the records go.
  Status start(const SoupSinkStart& soup) {
    layout_ = soup.layout;
    cube_ = RootCube::around(soup.bounds);
    const MortonQuantizer quantizer(cube_, options_.max_depth);
    varying_.emplace(quantizer, options_.max_depth, soup.bounds);
    key_ = centroid_morton_key(quantizer, *varying_, layout_);
    auto budget = divide_octree_budget(options_, layout_, workers(), input_triangles_);
    if (!budget.ok()) return budget.status();
    budget_ = budget.value();
    const std::size_t record_bytes = soup_record_bytes(layout_);
    if (soup.free_budget_bytes >= budget_.sort_bytes / 4) {
      auto sorter = create_sorter(std::min(soup.free_budget_bytes, budget_.sort_bytes));
      if (!sorter.ok()) return sorter.status();
      sorter_ = std::move(sorter).value();
      return {};
    }
    file_ = make_temp_file(work_, "soup");
    auto writer = RecordWriter::create(file_.path(), record_bytes, budget_.io_bytes);
    if (!writer.ok()) return writer.status();
    writer_.emplace(std::move(writer).value());
    return {};
  }

  // SoupOptions::sink.
  Status push(std::span<const std::byte> records) {
    if (cleanup_signal_received()) return interrupted();
    const std::size_t record_bytes = soup_record_bytes(layout_);
    for (std::size_t offset = 0; offset + record_bytes <= records.size(); offset += record_bytes) {
      float corner[3][3];
      for (int c = 0; c < 3; ++c)
        std::memcpy(corner[c], records.data() + offset + soup_corner_offset(layout_, c), sizeof corner[c]);
      longest_edge_ = std::max(longest_edge_, triangle_longest_edge(corner[0], corner[1], corner[2]));
    }
    if (sorter_) return sorter_->push(records);
    return writer_->append(records.data(), records.size() / soup_record_bytes(layout_));
  }

  // After the soup stage: the sorter, holding every record and finished (input distributed).
  // `progress(done)` counts the records read back from the soup file, if one was written.
  Result<RecordSorter*> finish(const std::function<void(std::uint64_t)>& progress) {
    if (writer_) OCTOLOD_RETURN_IF_ERROR(read_back(progress));
    OCTOLOD_RETURN_IF_ERROR(sorter_->finish());
    return sorter_.get();
  }

  const RootCube& cube() const { return cube_; }
  // The Morton key bits of the sort's keys (after start()).
  const VaryingKeyBits& key_bits() const { return *varying_; }
  // The longest edge of the triangles pushed so far (all of them once the soup stage is done).
  double longest_edge() const { return longest_edge_; }
  const OctreeBudget& budget() const { return budget_; }
  unsigned workers() const { return lod_workers(threads_); }
  bool streamed() const { return file_.empty(); }  // no soup file was written
  const fs::path& work() const { return work_; }

 private:
  Result<std::unique_ptr<RecordSorter>> create_sorter(std::uint64_t budget) const {
    SortOptions sort_options;
    sort_options.memory_budget_bytes = budget;
    sort_options.work_dir = work_;
    sort_options.threads = threads_;
    // Morton keys have 3 bits per level: a bucket (MSD radix) sort, no merge. Once the soup
    // stage is done it may take the octree stage's whole sort budget.
    return create_bucket_sorter(soup_record_bytes(layout_), key_, varying_->bits(), sort_options, budget_.sort_bytes);
  }

  Status read_back(const std::function<void(std::uint64_t)>& progress) {
    OCTOLOD_RETURN_IF_ERROR(writer_->finish());
    writer_.reset();
    auto sorter = create_sorter(budget_.sort_bytes);
    if (!sorter.ok()) return sorter.status();
    sorter_ = std::move(sorter).value();
    const std::size_t record_bytes = soup_record_bytes(layout_);
    auto reader = RecordReader::open(file_.path(), record_bytes, budget_.io_bytes);
    if (!reader.ok()) return reader.status();
    std::uint64_t done = 0;
    for (;;) {
      if (cleanup_signal_received()) return interrupted();
      auto block = reader->read();
      if (!block.ok()) return block.status();
      if (block->empty()) break;
      OCTOLOD_RETURN_IF_ERROR(sorter_->push(block.value()));
      done += block->size() / record_bytes;
      progress(done);
    }
    file_.remove();  // every record is in the sorter's runs now: free the disk
    return {};
  }

  const BakeOptions& options_;
  fs::path work_;
  unsigned threads_;
  std::uint64_t input_triangles_;
  VertexLayout layout_;
  RootCube cube_;
  std::optional<VaryingKeyBits> varying_;  // which bits of the Morton keys key_ keeps
  SortKeyFn key_;
  OctreeBudget budget_;
  std::unique_ptr<RecordSorter> sorter_;
  double longest_edge_ = 0;
  TempFile file_;
  std::optional<RecordWriter> writer_;
};

LodTreeOptions lod_tree_options(const BakeOptions& options, VertexLayout layout,
                                const RootCube& cube, double longest_input_edge, const fs::path& root,
                                unsigned workers, const OctreeBudget& budget, const fs::path& work) {
  LodTreeOptions o;
  o.root = root;
  o.layout = layout;
  o.cube = cube;
  o.longest_input_edge = longest_input_edge;
  o.build_lods = options.lods;
  o.lod.method = options.method;
  o.lod.reduction = options.lod_ratio;
  o.workers = workers;
  o.queue_bytes = budget.queue_bytes;
  o.keep_bytes = budget.keep_bytes;
  o.merge_bytes = budget.merge_bytes;
  o.work_bytes = budget.work_bytes;
  o.streamed_max_lod1_triangles = max_depth_leaf_triangles(options.memory_budget_bytes, layout, options.max_tris);
  o.streamed_chunk_triangles = kStreamedChunkLeaves * o.streamed_max_lod1_triangles;
  o.streamed_sort_bytes = options.memory_budget_bytes / kStreamedSortShare;
  o.work_dir = work;
  return o;
}

// Where the OctreeBuilder puts a leaf at max_depth over max_depth_leaf_triangles: its records
// go to a LeafRecordSpill (`records(count)` appends them when the builder has only keys), the
// finished file to the LOD tree.
MaxDepthLeafSpill max_depth_leaf_spill(const BakeOptions& options, VertexLayout layout,
                                       LeafRecordSpill& spill, LodTreeBuilder& lod_tree,
                                       OctreeBuilder* const& builder,
                                       std::function<Status(std::size_t count)> records = {}) {
  MaxDepthLeafSpill s;
  s.triangles = max_depth_leaf_triangles(options.memory_budget_bytes, layout, options.max_tris);
  s.append = [&spill, records](const OctreeNode&, std::span<const std::byte> bytes,
                               std::size_t count) {
    return records ? records(count) : spill.append(bytes);
  };
  s.finish = [&spill, &lod_tree, &builder](std::int32_t node) -> Status {
    if (cleanup_signal_received()) return interrupted();
    auto file = spill.finish();
    if (!file.ok()) return file.status();
    return lod_tree.add_streamed_leaf(node, builder->nodes(), std::move(file).value());
  };
  return s;
}

struct OctreeResult {
  RootCube cube;
  OctreeNodes nodes;
  std::optional<NodeLodsLog> lods;  // every node's record
  LodTreeStats lod_stats;
  SortStats sort;
  unsigned sort_key_bits = 0; // the Morton key bits the sort used (VaryingKeyBits); 0 without one
  bool soup_streamed = false; // the soup went straight into the sorter, no soup file
  double sort_seconds = 0;    // the sort's input left after the soup stage (reading the soup
                              // file back when one was written, the last distribution)
  double stream_seconds = 0;  // buckets read and sorted + tree decision, node work overlapping
  double lod_seconds = 0;     // the node work left when the stream ended (wall)
};

// lods: the node work still queued and the upper levels, which wait for their children. Moves
// the tree and its LODs into `result`.
Status finish_lod_tree(const BakeOptions& options, LodTreeBuilder& lod_tree,
                       OctreeBuilder& builder, OctreeResult& result) {
  const auto start = Clock::now();
  OCTOLOD_RETURN_IF_ERROR(
      lod_tree.finish(builder.nodes(), [&](std::uint64_t nodes_done, std::uint64_t total) {
        if (options.progress) options.progress("lods", nodes_done, total);
      }));
  result.lod_seconds = seconds_since(start);
  result.nodes = std::move(builder.nodes());
  result.lods.emplace(lod_tree.take_results());
  result.lod_stats = lod_tree.stats();
  return {};
}

// Streams the Morton-sorted soup through the OctreeBuilder, leaves written into `root` (seed
// 3.4, 4.3).
Result<OctreeResult> build_octree(const BakeOptions& options, const SoupResult& soup,
                                  OctreeInput& input, const fs::path& root) {
  OctreeResult result;
  result.cube = input.cube();
  result.soup_streamed = input.streamed();
  const std::size_t record_bytes = soup_record_bytes(soup.layout);
  const unsigned workers = input.workers();
  const OctreeBudget& budget = input.budget();
  auto progress = [&](std::string_view stage, std::uint64_t done) {
    if (options.progress) options.progress(stage, done, soup.triangle_count);
  };

  // sort: what input distribution is left
  auto start = Clock::now();
  auto finished = input.finish([&](std::uint64_t done) { progress("sort", done); });
  if (!finished.ok()) return finished.status();
  RecordSorter& sorter = *finished.value();
  result.sort_seconds = seconds_since(start);

  // octree: one pass over the sorted stream decides the tree and hands out the leaves, whose
  // LOD chains (and then their parents') are built meanwhile (lod_tree.h)
  start = Clock::now();
  LodTreeBuilder lod_tree(
      lod_tree_options(options, soup.layout, result.cube, input.longest_edge(), root, workers, budget, input.work()));
  OctreeBuilder* builder_ptr = nullptr;
  LeafRecordSpill spill(input.work(), soup.layout, budget.io_bytes,
                        options.memory_budget_bytes / kStreamedSortShare);
  OctreeBuilder builder(options.max_tris, options.max_depth, record_bytes,
                        soup_triangle_id_offset(soup.layout),
                        [&](std::int32_t node, std::vector<std::byte>&& records) {
                          if (cleanup_signal_received()) return interrupted();
                          return lod_tree.add_leaf(node, builder_ptr->nodes(), std::move(records));
                        },
                        max_depth_leaf_spill(options, soup.layout, spill, lod_tree, builder_ptr));
  builder_ptr = &builder;
  builder.forget_finished_nodes();  // the LOD log keeps what the manifest needs of them
  std::uint64_t done = 0;
  Status streamed;
  for (;;) {
    if (cleanup_signal_received()) {
      streamed = interrupted();
      break;
    }
    auto block = sorter.next();
    if (!block.ok()) {
      streamed = block.status();
      break;
    }
    if (block->empty()) break;
    streamed = push_with_full_keys(builder, block.value(), sorter.keys(), input.key_bits(), record_bytes);
    if (!streamed.ok()) break;
    done += block->size() / record_bytes;
    progress("octree", done);
  }
  if (streamed.ok()) streamed = builder.finish();
  OCTOLOD_RETURN_IF_ERROR(streamed);
  result.sort = sorter.stats();
  result.sort_key_bits = input.key_bits().bits();
  result.stream_seconds = seconds_since(start);
  OCTOLOD_RETURN_IF_ERROR(finish_lod_tree(options, lod_tree, builder, result));
  return result;
}

// The in-memory octree (SoupMeshSink): when the indexed mesh fits in the budget, each
// triangle's centroid key is computed from the vertex array, the (key, triangle id) pairs are
// sorted in memory, the tree is decided from the keys alone, and each leaf's soup records are
// gathered straight from the mesh: no soup records are produced or sorted externally. The
// leaves are the records path's: by (key, triangle id) (OctreeBuilder's leaf order).

// Keys handed to the OctreeBuilder per push (and progress granularity).
constexpr std::size_t kMeshKeyBlock = 1 << 14;

// Whether the in-memory octree takes a mesh of this shape: the mesh (vertex array, 12 bytes
// per triangle) and the keys and triangle ids with their radix scratch fit in what the node
// work leaves of the budget.
bool mesh_octree_fits(const BakeOptions& options, unsigned workers, VertexLayout layout,
                      std::uint64_t vertices, std::uint64_t triangles) {
  auto budget = divide_octree_budget(options, layout, workers, triangles);
  if (!budget.ok()) return false;
  const std::uint64_t bytes =
      vertices * layout.bytes() +
      triangles * (12 + 2 * (sizeof(std::uint64_t) + sizeof(std::uint32_t)));
  return bytes <= budget->sort_bytes;
}

// The mesh's triangles in leaf order: ids[i] with its centroid key keys[i]; the longest edge of
// any of them.
struct MeshOrder {
  PageArray<std::uint64_t> keys;
  PageArray<std::uint32_t> ids;
  double longest_edge = 0;
};

MeshOrder sort_mesh_triangles(const BakeOptions& options, unsigned threads, const SoupMesh& mesh,
                              const RootCube& cube) {
  const std::size_t floats = mesh.layout.floats();
  const std::size_t n = mesh.triangles.size() / 3;
  const MortonQuantizer quantizer(cube, options.max_depth);
  MeshOrder sorted{PageArray<std::uint64_t>(n), PageArray<std::uint32_t>(n)};
  auto compute = [&](std::size_t begin, std::size_t end, double& longest) {
    for (std::size_t t = begin; t < end; ++t) {
      const std::uint32_t* v = mesh.triangles.data() + 3 * t;
      const float* a = mesh.vertices.data() + std::size_t{v[0]} * floats;
      const float* b = mesh.vertices.data() + std::size_t{v[1]} * floats;
      const float* c = mesh.vertices.data() + std::size_t{v[2]} * floats;
      sorted.keys[t] = centroid_key(quantizer, a, b, c);
      sorted.ids[t] = static_cast<std::uint32_t>(t);
      longest = std::max(longest, triangle_longest_edge(a, b, c));
    }
  };
  double longest[2] = {0, 0};
  if (threads > 1 && n >= (1u << 16)) {
    std::thread helper(compute, n / 2, n, std::ref(longest[1]));
    compute(0, n / 2, longest[0]);
    helper.join();
  } else {
    compute(0, n, longest[0]);
  }
  {
    // By key, then triangle id: the ids start in triangle order and the sort is stable.
    MeshOrder scratch{PageArray<std::uint64_t>(n), PageArray<std::uint32_t>(n)};
    std::uint64_t* keys = sorted.keys.get();
    std::uint32_t* ids = sorted.ids.get();
    std::uint64_t* keys_tmp = scratch.keys.get();
    std::uint32_t* ids_tmp = scratch.ids.get();
    radix_sort(keys, ids, keys_tmp, ids_tmp, n);
    if (keys != sorted.keys.get()) std::swap(sorted, scratch);  // keep the result, free the rest
  }
  sorted.longest_edge = std::max(longest[0], longest[1]);
  return sorted;
}

Result<OctreeResult> build_octree_from_mesh(const BakeOptions& options, unsigned threads,
                                            const SoupMesh& mesh, const fs::path& root,
                                            const fs::path& work) {
  OctreeResult result;
  result.cube = RootCube::around(mesh.bounds);
  const unsigned workers = lod_workers(threads);
  const std::size_t n = mesh.triangles.size() / 3;
  auto budget = divide_octree_budget(options, mesh.layout, workers, n);
  if (!budget.ok()) return budget.status();

  // sort: keys computed and sorted in memory
  auto start = Clock::now();
  const MeshOrder sorted = sort_mesh_triangles(options, threads, mesh, result.cube);
  result.sort.records = n;
  result.sort.in_core = true;
  result.sort_seconds = seconds_since(start);
  if (cleanup_signal_received()) return interrupted();

  // octree: the tree from the keys alone; each leaf's records gathered from the mesh
  start = Clock::now();
  LodTreeBuilder lod_tree(
      lod_tree_options(options, mesh.layout, result.cube, sorted.longest_edge, root, workers, budget.value(), work));
  const std::size_t record_bytes = soup_record_bytes(mesh.layout);
  std::size_t next_leaf = 0;  // first entry of `sorted` in the next leaf
  // The soup records of the next `count` triangles of `sorted`.
  auto gather = [&](std::size_t count) {
    std::vector<std::byte> records(count * record_bytes);
    std::byte* out = records.data();
    for (std::size_t i = next_leaf; i < next_leaf + count; ++i, out += record_bytes) {
      const std::uint32_t t = sorted.ids[i];
      store_soup_record(out, mesh.layout, mesh.vertices.data(),
                        mesh.triangles.data() + 3 * std::size_t{t}, t);
    }
    next_leaf += count;
    return records;
  };
  LeafRecordSpill spill(work, mesh.layout, budget->io_bytes,
                        options.memory_budget_bytes / kStreamedSortShare);
  OctreeBuilder* builder_ptr = nullptr;
  OctreeBuilder builder(
      options.max_tris, options.max_depth, 0, 0,
      [&](std::int32_t node, std::vector<std::byte>&&) -> Status {
        if (cleanup_signal_received()) return interrupted();
        const auto& nodes = builder_ptr->nodes();
        return lod_tree.add_leaf(node, nodes, gather(nodes[static_cast<std::size_t>(node)].triangles));
      },
      max_depth_leaf_spill(options, mesh.layout, spill, lod_tree, builder_ptr,
                           [&](std::size_t count) { return spill.append(gather(count)); }));
  builder_ptr = &builder;
  builder.forget_finished_nodes();  // the LOD log keeps what the manifest needs of them
  for (std::size_t first = 0; first < n; first += kMeshKeyBlock) {
    const std::size_t m = std::min(kMeshKeyBlock, n - first);
    OCTOLOD_RETURN_IF_ERROR(
        builder.push({}, std::span<const std::uint64_t>(sorted.keys.get() + first, m)));
    if (options.progress) options.progress("octree", first + m, n);
  }
  OCTOLOD_RETURN_IF_ERROR(builder.finish());
  result.stream_seconds = seconds_since(start);
  OCTOLOD_RETURN_IF_ERROR(finish_lod_tree(options, lod_tree, builder, result));
  return result;
}
// The manifest without its nodes: the input, the parameters and the model's bounds.
Result<Manifest> manifest_header(const BakeOptions& options, unsigned threads,
                                 const SoupResult& soup, const OctreeResult& octree) {
  Manifest m;
  m.layout = soup.layout;
  m.origin = soup.origin;
  m.input_vertices = soup.vertex_count;
  m.input_triangles = soup.triangle_count;
  m.parameters.input = options.input.string();
  m.parameters.max_tris = options.max_tris;
  m.parameters.max_depth = options.max_depth;
  m.parameters.memory_budget_bytes = options.memory_budget_bytes + options.program_bytes;
  m.parameters.threads = threads;
  m.parameters.method = options.lods ? std::string(method_name(options.method)) : "";
  m.parameters.lod_ratio = options.lod_ratio;
  auto root = octree.lods->read(0);
  if (!root.ok()) return root.status();
  m.bounds = root->lods.bounds;  // the subtree's: the whole model's
  return m;
}

// Node `index` of the manifest, from its record in the LOD log.
Result<NodeInfo> manifest_node(const OctreeResult& octree, std::size_t index) {
  NodeInfo n;
  auto logged = octree.lods->read(static_cast<std::int32_t>(index));
  if (!logged.ok()) return logged.status();
  const NodeShape& shape = logged->shape;
  n.path = node_path(shape.prefix, shape.depth);
  n.depth = shape.depth;
  n.parent = shape.parent;
  n.children = shape.children;
  n.cell = octree.cube.cell(shape.prefix, shape.depth);
  n.source_triangles = shape.triangles;
  n.bounds = logged->lods.bounds;
  n.lods = std::move(logged->lods.lods);
  // the stored errors bound distances measured in float too (error_bound.h): the margin once, of
  // the root's cell for every node, so that a parent's errors stay at or above its children's
  const double margin = float_measurement_margin(octree.cube.cell(0, 0));
  for (LodInfo& lod : n.lods)
    if (lod.error > 0.0) lod.error += margin;
  return n;
}

// Writes the manifest of the bake to `path` node by node (nodes are read back from the LOD log,
// never held together) and counts the report's LODs and bytes.
Status write_bake_manifest(const fs::path& path, const Manifest& header,
                           const OctreeResult& octree, BakeReport& report) {
  return write_manifest(path, header, octree.nodes.size(), [&](std::size_t i) -> Result<NodeInfo> {
    Result<NodeInfo> n = manifest_node(octree, i);
    if (!n.ok()) return n;
    report.lods += n->lods.size();
    for (const LodInfo& l : n->lods) report.bytes += l.bytes;
    if (i == 0 && !n->lods.empty()) report.root_coarsest_triangles = n->lods.back().triangles;
    return n;
  });
}

Status check_options(const BakeOptions& options) {
  if (options.max_tris < 1) return usage_error("max_tris must be at least 1");
  if (options.max_depth > kMaxOctreeDepth) {
    return usage_error("max_depth " + std::to_string(options.max_depth) + " is above the limit of " +
                       std::to_string(kMaxOctreeDepth));
  }
  if (options.memory_budget_bytes < options.program_bytes + kMinBakeBudget) {
    const std::uint64_t minimum = options.program_bytes + kMinBakeBudget;
    return usage_error("memory budget of " + std::to_string(options.memory_budget_bytes) +
                       " bytes is below the minimum of " + std::to_string(minimum) + " bytes (" +
                       std::to_string((minimum + (1u << 20) - 1) >> 20) + " MiB)");
  }
  if (!(options.lod_ratio >= kMinLodRatio && options.lod_ratio <= kMaxLodRatio)) {
    char text[120];
    std::snprintf(text, sizeof text, "lod_ratio %g is outside [%g, %g]", options.lod_ratio, kMinLodRatio,
                  kMaxLodRatio);
    return usage_error(text);
  }
  if (options.output.empty()) return usage_error("no output directory given");
  OCTOLOD_RETURN_IF_ERROR(check_replaceable(options.output));
  // the published tree replaces the whole output directory: an input inside it would be deleted
  std::error_code input_ec, output_ec;
  const fs::path input = fs::weakly_canonical(options.input, input_ec);
  const fs::path output = fs::weakly_canonical(options.output, output_ec);
  if (!input_ec && !output_ec && std::mismatch(output.begin(), output.end(), input.begin(), input.end()).first == output.end())
    return usage_error("input '" + options.input.string() + "' lies inside the output directory '" +
                       options.output.string() + "', which the bake replaces whole: move it or choose another -o");
  return {};
}

// Inputs whose header declares fewer faces than this many leaves of max_tris have their
// triangles counted when the budget is too small for max_tris: below about four leaves the
// input's own size bounds the leaves and the merged inputs (divide_octree_budget).
constexpr std::uint64_t kSmallInputLeaves = 4;

// Triangles of a PLY after its polygons are fanned out: one pass over the file.
Result<std::uint64_t> count_triangles(const fs::path& ply) {
  auto reader = PlyReader::open(ply, {});
  if (!reader.ok()) return reader.status();
  std::uint64_t triangles = 0;
  for (;;) {
    auto batch = reader.value()->next();
    if (!batch.ok()) return batch.status();
    if (batch->kind == PlyBatch::Kind::end) return triangles;
    triangles += batch->triangles.size() / 3;
  }
}

Result<BakeReport> run_bake(const BakeOptions& given) {
  const auto start = Clock::now();
  OCTOLOD_RETURN_IF_ERROR(check_options(given));
  // from here on memory_budget_bytes is the bake's own share; program_bytes only names it in
  // messages and the manifest
  BakeOptions options = given;
  options.memory_budget_bytes -= given.program_bytes;
  unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  if (options.cleanup_on_signal) install_signal_cleanup();

  // temporary directories: the staging tree next to the output, the work files
  fs::path output = fs::absolute(options.output).lexically_normal();
  if (!output.has_filename()) output = output.parent_path();  // "out/" names "out"
  const fs::path parent = output.parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    return io_error("cannot write '" + options.output.string() + "': directory '" +
                    parent.string() + "' does not exist");
  }
  const fs::path work_parent = options.work_dir.empty() ? parent : options.work_dir;
  std::uint64_t input_triangles = kUnknownTriangles;
  std::vector<std::string> texture_names;  // the input's TextureFile comments (PlyInfo::texture_files)
  if (!fs::is_directory(work_parent, ec))
    return io_error("work directory '" + work_parent.string() + "' does not exist or is not a directory");
  {
    // a budget too small for max_tris is refused before any work (the header names the layout),
    // unless the input is too small to fill leaves of max_tris: then its triangles are counted
    // (the header's faces may be polygons) and the budget divided for them
    PlyReadOptions header_only;
    header_only.buffer_bytes = 4096;
    auto reader = PlyReader::open(options.input, header_only);
    if (!reader.ok()) return reader.status();
    const PlyInfo& info = reader.value()->info();
    texture_names = info.texture_files;
    // every face gives at least one triangle; a tree without any is refused by every reader of
    // trees, and would replace a good tree in the output directory
    if (info.face_count == 0)
      return bad_input_error(options.input.string() + ": the mesh has no triangles (" +
                             std::to_string(info.vertex_count) + " vertices, 0 faces): nothing to bake");
    auto budget = divide_octree_budget(options, info.layout, lod_workers(threads), kUnknownTriangles);
    if (!budget.ok() && info.face_count < kSmallInputLeaves * std::uint64_t{options.max_tris}) {
      auto triangles = count_triangles(options.input);
      if (!triangles.ok()) return triangles.status();
      input_triangles = triangles.value();
      budget = divide_octree_budget(options, info.layout, lod_workers(threads), input_triangles);
    }
    // a thread count of the machine's gives way to the budget (each thread past the second costs
    // kNodeThreadBytes): a default bake on a many-core machine runs on fewer threads rather than
    // being refused; a count the caller asked for is refused instead
    while (!budget.ok() && options.threads == 0 && threads > 1) {
      --threads;
      budget = divide_octree_budget(options, info.layout, lod_workers(threads), input_triangles);
    }
    if (!budget.ok()) return budget.status();
  }
  remove_stale_temp_dirs(parent);
  if (work_parent != parent) remove_stale_temp_dirs(work_parent);
  auto staging = TempDir::create(parent, "out");
  if (!staging.ok()) return staging.status();
  auto work = TempDir::create(work_parent, "work");
  if (!work.ok()) return work.status();

  BakeReport report;
  {
    // soup
    SoupOptions soup_options;
    soup_options.memory_budget_bytes = options.memory_budget_bytes;
    soup_options.work_dir = work->path();
    soup_options.threads = threads;
    soup_options.order = SoupOrder::any;
    soup_options.force_out_of_core = options.force_out_of_core;
    soup_options.progress = options.progress;
    OctreeInput octree_input(options, work->path(), threads, input_triangles);
    soup_options.sink_start = [&](const SoupSinkStart& soup_start) {
      return octree_input.start(soup_start);
    };
    soup_options.sink = [&](std::span<const std::byte> records) {
      return octree_input.push(records);
    };
    std::optional<OctreeResult> mesh_octree;
    if (options.in_memory_octree) {
      soup_options.mesh_sink.accepts = [&](VertexLayout layout, std::uint64_t vertices,
                                           std::uint64_t triangles) {
        return mesh_octree_fits(options, octree_input.workers(), layout, vertices, triangles);
      };
      soup_options.mesh_sink.consume = [&](const SoupMesh& mesh) -> Status {
        auto built = build_octree_from_mesh(options, threads, mesh, staging->path(), work->path());
        if (!built.ok()) return built.status();
        mesh_octree.emplace(std::move(built).value());
        return {};
      };
    }
    auto soup = build_soup(options.input, soup_options);
    if (!soup.ok()) return soup.status();
    if (cleanup_signal_received()) return interrupted();

    // octree (built already when the soup stage handed over the mesh)
    auto octree = soup->mesh_consumed
                      ? Result<OctreeResult>(std::move(*mesh_octree))
                      : build_octree(options, soup.value(), octree_input, staging->path());
    if (!octree.ok()) return octree.status();

    // manifest
    auto header = manifest_header(options, threads, soup.value(), octree.value());
    if (!header.ok()) return header.status();
    Manifest& manifest = header.value();
    auto texture = copy_tree_texture(options.input, texture_names, manifest.layout.uv, staging->path());
    if (!texture.ok()) return texture.status();
    manifest.texture = texture->file;
    report.texture_warning = texture->warning;
    manifest.stage_seconds["soup"] = soup->seconds.total;
    manifest.stage_seconds["soup.split"] = soup->seconds.split;
    manifest.stage_seconds["soup.sort"] = soup->seconds.sort;
    manifest.stage_seconds["soup.dereference"] = soup->seconds.dereference;
    manifest.stage_seconds["octree.sort"] = octree->sort_seconds;
    manifest.stage_seconds["octree.stream"] = octree->stream_seconds;
    manifest.stage_seconds["octree"] = octree->sort_seconds + octree->stream_seconds;
    manifest.stage_seconds["lods"] = octree->lod_seconds;
    manifest.stats["node_work_seconds"] = octree->lod_stats.work_seconds;
    manifest.stats["lod_rereads"] = static_cast<double>(octree->lod_stats.reread_lods);
    manifest.stats["lod_kept_bytes_peak"] = static_cast<double>(octree->lod_stats.peak_kept_bytes);
    manifest.stats["lod_streamed_internal_nodes"] = static_cast<double>(octree->lod_stats.streamed_internal_nodes);
    manifest.stats["lod_streamed_leaves"] = static_cast<double>(octree->lod_stats.streamed_leaves);
    report.streamed_leaves = octree->lod_stats.streamed_leaves;
    report.largest_streamed_leaf_triangles = octree->lod_stats.largest_streamed_leaf;
    if (report.streamed_leaves > 0)
      report.streamed_lod1_triangles =
          max_depth_leaf_triangles(options.memory_budget_bytes, manifest.layout, options.max_tris);
    report.soup_in_core = soup->in_core;
    report.input_trailing_bytes = soup->input_trailing_bytes;
    report.octree_in_memory = soup->mesh_consumed;
    manifest.stats["octree_in_memory"] = soup->mesh_consumed ? 1 : 0;
    report.sort_runs = octree->sort.runs;
    manifest.stats["soup_in_core"] = soup->in_core ? 1 : 0;
    manifest.stats["soup_far_triangles"] = static_cast<double>(soup->far_triangles);
    manifest.stats["octree_sort_runs"] = static_cast<double>(octree->sort.runs);
    manifest.stats["octree_sort_merge_passes"] = octree->sort.merge_passes;
    manifest.stats["octree_sort_key_bits"] = octree->sort_key_bits;
    manifest.stats["soup_streamed_to_sort"] = octree->soup_streamed ? 1 : 0;
    report.nodes = octree->nodes.size();
    report.leaves = octree->lod_stats.leaves;
    report.depth = octree->lod_stats.depth;
    manifest.stats["nodes"] = static_cast<double>(report.nodes);
    manifest.stats["leaves"] = static_cast<double>(report.leaves);
    report.peak_rss_bytes = peak_rss_bytes();
    manifest.stats["peak_rss_bytes"] = static_cast<double>(report.peak_rss_bytes);
    manifest.stage_seconds["total"] = seconds_since(start);
    const fs::path manifest_path = staging->path() / kManifestFileName;
    OCTOLOD_RETURN_IF_ERROR(write_bake_manifest(manifest_path, manifest, octree.value(), report));
    report.bytes += fs::file_size(manifest_path, ec);
    report.header = std::move(manifest);
  }
  work->remove();

  // publish
  if (cleanup_signal_received()) return interrupted();
  OCTOLOD_RETURN_IF_ERROR(publish_directory(staging->path(), output));
  staging->release();
  return report;
}

}  // namespace

std::string_view method_name(ClusterMethod method) {
  switch (method) {
    case ClusterMethod::grid: return "grid";
    case ClusterMethod::bade2006: return "bade2006";
  }
  return "grid";
}

std::optional<ClusterMethod> parse_method(std::string_view name) {
  for (ClusterMethod m : {ClusterMethod::grid, ClusterMethod::bade2006})
    if (method_name(m) == name) return m;
  return std::nullopt;
}

std::uint64_t max_depth_leaf_triangles(std::uint64_t memory_budget_bytes, VertexLayout layout,
                                       std::uint32_t max_tris) {
  return std::max<std::uint64_t>(memory_budget_bytes / kMaxDepthLeafShare / (kLeafWorkPerRecordByte * soup_record_bytes(layout)),
                                 std::uint64_t{max_tris} + 1);
}

Result<BakeReport> bake(const BakeOptions& options) {
  Result<BakeReport> result = run_bake(options);
  // A signal's cleanup may have made the bake fail (its directories vanished): let the watcher
  // finish and kill the process rather than report that failure.
  if (options.cleanup_on_signal && cleanup_signal_received()) await_signal_cleanup();
  return result;
}

}  // namespace octolod::bake
