// The bake's LOD hierarchy, scheduled bottom-up on the worker threads while the octree stream
// runs (seed 3.5.3, 5.3.2), see lod_tree.h.
#include "lod_tree.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <system_error>
#include <thread>
#include <unordered_map>
#include <utility>

#include <sys/stat.h>

#include "node_index.h"
#include "node_lods_log.h"
#include "octolod/bake/soup.h"
#include "octolod/formats/node_file.h"
#include "streamed_leaf.h"
#include "octolod/bake/temp_dir.h"
#include "tree_paths.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::size_t mesh_bytes(const NodeMesh& mesh) {
  return (mesh.vertices.size() + mesh.indices.size()) * sizeof(float);
}

// LodOptions::neighbours from the input's longest edge: a third of it (NeighbourReach), with
// room for rounding: the node cells are the cube's cells rounded to float (an ulp of the
// coordinates), the centroids summed in double.
NeighbourReach neighbours(double longest_input_edge, const RootCube& cube) {
  double magnitude = cube.size;
  for (const double origin : cube.origin) magnitude = std::max(magnitude, std::abs(origin) + cube.size);
  return {longest_input_edge / 3.0 * (1.0 + 1e-6) + 1e-6 * magnitude, cube.cell(0, 0)};
}

// A finished child as its parent sees it: its chain, and its LOD 0 while kept in memory.
struct ChildLod {
  bool present = false;
  std::vector<LodInfo> lods;  // finest first
  bool in_memory = false;     // LOD 0 is in `mesh`; every other LOD is read from its file
  bool spilled = false;       // LOD 0 was not kept because the kept bytes were full
  NodeMesh mesh;
  std::size_t bytes = 0;      // counted in the kept bytes while in memory
};

// What a parent collects from its children as they finish.
struct Pending {
  std::array<ChildLod, 8> child;  // by octant
  Bounds bounds;                  // their subtrees' bounds
};

// The scheduler's view of one octree node, from its creation until it is delivered (the open
// nodes of the tree, not all of them): its shape, which the log records (prefix and depth name
// its directory and cell; triangles are a leaf's own, then its delivered children's), and the
// counts; a pending parent's children's results hang off it until the parent's task takes them.
struct Slot {
  NodeShape shape;
  std::uint32_t done = 0;    // children whose chains are complete
  std::uint64_t child_triangles = 0;
  bool closed = false;       // internal node whose children are all known
  // Allocated by the first delivery, taken by the node's task: only pending parents hold one
  // (a tree of 100M triangles has 212K nodes).
  std::unique_ptr<Pending> pending;

  // An internal node is ready once it is closed and every child it has is done.
  bool ready() const {
    return closed && done == static_cast<std::uint32_t>(std::count_if(shape.children.begin(), shape.children.end(),
                                                                      [](std::int32_t c) { return c >= 0; }));
  }
};

// The LODs an internal node merges: one index per present child into its chain (octant order),
// their lod_mesh_bytes and their largest error.
struct MergePlan {
  std::vector<std::size_t> chosen;
  std::size_t bytes = 0;
  double input_error = 0;
};

struct Task {
  std::int32_t node = -1;
  std::uint64_t weight = 0;  // input triangles
  std::size_t work = 0;      // node_work_bytes within LodTreeOptions::work_bytes; 0 without a limit
  MergePlan merge;           // an internal node's, planned when it became ready
  std::vector<std::byte> records;  // a leaf's soup records; empty for an internal node
  TempFile streamed;               // a streamed leaf's records instead (add_streamed_leaf)
  bool leaf = false;
};

// Max-heap order. Internal nodes first, heaviest first (they free their children's kept LODs
// and their chains are the long tail near the root); leaves in stream order (node indices grow
// with it), so a small leaf is never passed over for long: its parent, and every kept sibling
// LOD, waits for it.
bool later(const Task& a, const Task& b) {
  if (a.leaf != b.leaf) return a.leaf;
  if (!a.leaf && a.weight != b.weight) return a.weight < b.weight;
  return a.node > b.node;
}

// What a finished node hands back to the scheduler.
struct NodeDone {
  NodeLods lods;
  // LOD 0, which the parent merges when it fits its merge_bytes; empty for a streamed leaf,
  // whose LOD 0 the parent reads from its file
  NodeMesh finest;
  bool streamed = false;  // an internal node built by run_streamed_internal
};

// A thread's reusable buffers.
struct Scratch {
  NodeIndexer indexer;
};

Status interrupted() { return io_error("bake interrupted by a signal"); }

// node_work_bytes = kNodeWorkFixed + kNodeWorkPerInputByte x input: the measurements in
// lod_tree.h with some headroom (the fixed part covers small nodes' tables).
constexpr std::size_t kNodeWorkFixed = 256 << 10;
constexpr std::size_t kNodeWorkPerInputByte = 11;
// The node work of a streamed node (its memory is bounded by its own limits, not its input):
// it runs alone.
constexpr std::size_t kRunsAlone = std::numeric_limits<std::size_t>::max();

}  // namespace

class LodTreeBuilder::Impl {
 public:
  explicit Impl(LodTreeOptions options)
      : options_(std::move(options)),
        merge_bytes_(options_.merge_bytes ? options_.merge_bytes : 2 * options_.queue_bytes) {
    for (unsigned i = 0; i < options_.workers; ++i) threads_.emplace_back([this] { work(); });
  }
  ~Impl() { stop(); }

  Status add_leaf(std::int32_t node, const OctreeNodes& nodes,
                  std::vector<std::byte>&& records, TempFile streamed) {
    std::unique_lock lock(mutex_);
    if (!error_.ok()) return error_;
    OCTOLOD_RETURN_IF_ERROR(open_log());
    register_nodes(nodes);
    close_off_path(node, nodes);
    Task task;
    task.node = node;
    task.leaf = true;
    task.weight = nodes[static_cast<std::size_t>(node)].triangles;
    Slot& s = slot(node);
    s.shape.leaf = true;
    s.shape.triangles = task.weight;
    ++stats_.leaves;
    stats_.depth = std::max(stats_.depth, s.shape.depth);
    if (!streamed.empty()) {
      ++stats_.streamed_leaves;
      stats_.largest_streamed_leaf = std::max(stats_.largest_streamed_leaf, task.weight);
    }
    task.work = streamed.empty() ? leaf_work_bytes(records.size()) : kRunsAlone;  // a streamed leaf runs alone
    queued_bytes_ += records.size();
    task.records = std::move(records);
    task.streamed = std::move(streamed);
    push(std::move(task));
    // Without workers the caller does everything now; with them, it runs node work itself
    // rather than let the queue grow past queue_bytes.
    while (error_.ok()) {
      if (threads_.empty()) {
        if (heap_.empty()) break;
      } else if (queued_bytes_ <= options_.queue_bytes) {
        break;
      } else if (!can_start()) {
        space_.wait(lock);
        continue;
      }
      run_one(lock, caller_scratch_);
    }
    return error_;
  }

  Status finish(const OctreeNodes& nodes,
                const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    {
      std::unique_lock lock(mutex_);
      OCTOLOD_RETURN_IF_ERROR(open_log());
      register_nodes(nodes);
      while (!open_.empty()) {
        close(open_.back());
        open_.pop_back();
      }
      total_nodes_ = nodes.size();
      work_.notify_all();
      // The caller works too until nothing is left. Every condition is checked again after
      // the lock was released (run_one, progress), so no completion is missed.
      std::uint64_t reported = ~std::uint64_t{0};
      while (error_.ok() && completed_ < total_nodes_) {
        if (can_start()) {
          run_one(lock, caller_scratch_);
        } else if (progress && reported != completed_) {
          reported = completed_;
          lock.unlock();
          progress(reported, total_nodes_);
          lock.lock();
        } else {
          space_.wait(lock);
        }
      }
    }
    stop();
    std::lock_guard lock(mutex_);
    if (error_.ok()) error_ = log_->finish();
    if (error_.ok() && progress) progress(completed_, total_nodes_);
    return error_;
  }

  NodeLodsLog take_results() { return std::move(*log_); }
  const LodTreeStats& stats() const { return stats_; }

 private:
  Slot& slot(std::int32_t node) {
    const auto it = slots_.find(node);
    assert(it != slots_.end() && "a node's slot lives until it is delivered");
    return it->second;
  }

  // The node records' log, on the first call. Under the lock.
  Status open_log() {
    if (log_) return {};
    auto log = NodeLodsLog::create(options_.work_dir);
    if (!log.ok()) return log.status();
    log_.emplace(std::move(log).value());
    return {};
  }

  // Slots for the nodes the builder created since the last call (their parent, prefix and depth
  // never change once created). Under the lock.
  void register_nodes(const OctreeNodes& nodes) {
    for (std::size_t i = registered_; i < nodes.size(); ++i) {
      const OctreeNode& n = nodes[i];
      Slot s;
      s.shape.prefix = n.prefix;
      s.shape.parent = n.parent;
      s.shape.depth = n.depth;
      slots_.emplace(static_cast<std::int32_t>(i), std::move(s));
      if (n.parent >= 0) {  // registered before it: a lower index
        slot(n.parent).shape.children[n.prefix & 7u] = static_cast<std::int32_t>(i);
      }
    }
    registered_ = nodes.size();
  }

  // Keys arrive in order: the internal nodes on the previous leaf's path that are not on this
  // leaf's path have received all their children. Under the lock.
  void close_off_path(std::int32_t leaf, const OctreeNodes& nodes) {
    std::vector<std::int32_t> path;
    for (std::int32_t p = nodes[static_cast<std::size_t>(leaf)].parent; p >= 0;
         p = nodes[static_cast<std::size_t>(p)].parent)
      path.push_back(p);
    std::reverse(path.begin(), path.end());
    std::size_t common = 0;
    while (common < open_.size() && common < path.size() && open_[common] == path[common])
      ++common;
    while (open_.size() > common) {
      close(open_.back());
      open_.pop_back();
    }
    open_ = std::move(path);
  }

  void close(std::int32_t node) {
    Slot& s = slot(node);
    s.closed = true;
    if (s.ready()) push_internal(node);
  }

  void push_internal(std::int32_t node) {
    const Slot& s = slot(node);
    Task task;
    task.node = node;
    task.weight = s.child_triangles;
    if (options_.build_lods && s.pending) task.merge = plan_merge(s.pending->child);
    task.work = merges_streaming(task.merge) ? kRunsAlone : node_work_bytes(task.merge.bytes);
    push(std::move(task));
  }

  void push(Task task) {
    // accounted only against a limit; a node whose work reaches the limit runs alone
    task.work = options_.work_bytes > 0 ? std::min(task.work, options_.work_bytes) : 0;
    heap_.push_back(std::move(task));
    std::push_heap(heap_.begin(), heap_.end(), later);
    work_.notify_one();
  }

  // Whether the heaviest ready node may start: its node work fits beside the running ones' in
  // work_bytes, or nothing runs. Under the lock.
  bool can_start() const {
    return !heap_.empty() && (running_work_ == 0 || heap_.front().work <= options_.work_bytes - running_work_);
  }

  // Pops the heaviest ready node and runs it with the lock released. Under the lock.
  void run_one(std::unique_lock<std::mutex>& lock, Scratch& scratch) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    Task task = std::move(heap_.back());
    heap_.pop_back();
    running_work_ += task.work;
    Slot& s = slot(task.node);
    const std::string dir = node_path(s.shape.prefix, s.shape.depth);
    const Bounds cell = options_.cube.cell(s.shape.prefix, s.shape.depth);
    std::unique_ptr<Pending> taken = std::move(s.pending);
    std::array<ChildLod, 8> children;
    Bounds below;  // the children's subtrees
    if (taken) {
      children = std::move(taken->child);
      below = taken->bounds;
    }
    taken.reset();
    lock.unlock();

    const std::size_t record_bytes = task.records.size();
    const auto start = Clock::now();
    // the root has no neighbours to meet: its boundary is the mesh's own border
    LodOptions lod = options_.lod;
    lod.lock_boundary = s.shape.depth > 0;
    lod.neighbours = neighbours(options_.longest_input_edge, options_.cube);
    // every internal node's input is simplified down to the root's limit, its chain only to its own
    lod.input_min_triangles = options_.lod.min_triangles;
    if (s.shape.depth > 0) lod.min_triangles = options_.node_min_triangles;
    Result<NodeDone> done = task.leaf ? run_leaf(task, dir, cell, lod, scratch)
                                      : run_internal(children, task.merge, dir, cell, lod);
    std::size_t released = 0;
    std::uint64_t rereads = 0;
    for (ChildLod& c : children) {
      if (c.present && c.in_memory) released += c.bytes;
      if (c.spilled) ++rereads;
      c = {};
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();

    lock.lock();
    running_work_ -= task.work;
    stats_.work_seconds += seconds;
    stats_.reread_lods += rereads;
    kept_bytes_ -= released;
    queued_bytes_ -= record_bytes;
    if (!done.ok()) {
      if (error_.ok()) error_ = done.status();
    } else if (error_.ok()) {
      stats_.streamed_internal_nodes += done->streamed;
      done->lods.bounds.extend(below);
      deliver(task.node, std::move(done).value());
    }
    space_.notify_all();
    work_.notify_all();
  }

  // `lod`: the node's chain options (LodOptions::lock_boundary set for it; include_input is
  // set here).
  Result<NodeDone> run_leaf(Task& task, const std::string& dir, const Bounds& cell, const LodOptions& lod,
                            Scratch& scratch) {
    if (cleanup_signal_received()) return interrupted();
    if (!task.streamed.empty()) {
      OCTOLOD_RETURN_IF_ERROR(make_directory(dir));  // its LOD 0 is written while it streams
      return run_streamed_leaf(task, dir, cell, lod);
    }
    NodeMesh mesh;
    scratch.indexer.index(task.records, options_.layout, mesh);
    task.records = {};  // the queue's bytes are given back in run_one
    if (!options_.build_lods) {
      std::vector<Lod> lods(1);
      lods[0].mesh = std::move(mesh);
      return write_lods(dir, lods);
    }
    LodOptions o = lod;
    o.include_input = true;
    auto lods = build_lods(std::move(mesh), 0.0, cell, o);
    if (!lods.ok()) return lods.status();
    return write_lods(dir, lods.value());
  }

  Result<NodeDone> run_streamed_leaf(Task& task, const std::string& dir, const Bounds& cell, const LodOptions& lod) {
    StreamedLeafOptions o;
    o.layout = options_.layout;
    o.cell = cell;
    o.build_lods = options_.build_lods;
    o.lod = lod;  // its lock_boundary: for the chain after LOD 1 (which keeps the boundary)
    o.chunk_triangles = options_.streamed_chunk_triangles;
    o.max_lod1_triangles = options_.streamed_max_lod1_triangles;
    o.work_dir = options_.work_dir;
    o.sort_budget_bytes = options_.streamed_sort_bytes;
    auto built = build_streamed_leaf(task.streamed.path(), options_.root, dir, o);
    task.streamed.remove();
    if (!built.ok()) return built.status();
    auto done = write_lods(dir, built->coarser, 1);
    if (!done.ok()) return done.status();
    done->lods.lods.insert(done->lods.lods.begin(), built->lod0);
    done->lods.bounds.extend(built->lod0_bounds);
    done->finest = {};
    return done;
  }

  // Whether an internal node's merge is too large for memory: then it is built streaming
  // (run_streamed_internal), alone.
  bool merges_streaming(const MergePlan& plan) const { return plan.bytes > kStreamedMergeFactor * merge_bytes_; }

  // An internal node's MergePlan: choose_merged_lods over its present children.
  MergePlan plan_merge(const std::array<ChildLod, 8>& children) const {
    std::vector<std::vector<LodInfo>> chains;
    for (const ChildLod& c : children)
      if (c.present) chains.push_back(c.lods);
    MergePlan plan;
    plan.chosen = choose_merged_lods(chains, options_.layout, merge_bytes_);
    std::size_t next = 0;
    for (const ChildLod& c : children) {
      if (!c.present) continue;
      const LodInfo& lod = c.lods[plan.chosen[next++]];
      plan.input_error = std::max(plan.input_error, lod.error);
      plan.bytes += lod_mesh_bytes(lod, options_.layout);
    }
    return plan;
  }

  Result<NodeDone> run_internal(std::array<ChildLod, 8>& children, const MergePlan& plan,
                                const std::string& dir, const Bounds& cell, const LodOptions& lod) {
    if (cleanup_signal_received()) return interrupted();
    if (!options_.build_lods) return NodeDone{};
    if (merges_streaming(plan)) {
      auto streamed = run_streamed_internal(children, plan.chosen, plan.input_error, dir, cell, lod);
      if (!streamed.ok() || !streamed->lods.lods.empty()) return streamed;
    }
    std::vector<const NodeMesh*> meshes;
    std::size_t next = 0;
    for (ChildLod& c : children) {
      if (!c.present) continue;
      OCTOLOD_RETURN_IF_ERROR(load_chosen(c, plan.chosen[next++]));
      meshes.push_back(&c.mesh);
    }
    NodeMesh merged = merge_meshes(meshes);
    for (ChildLod& c : children) c.mesh = {};
    LodOptions o = lod;
    o.include_input = false;
    auto lods = build_lods(std::move(merged), plan.input_error, cell, o);
    if (!lods.ok()) return lods.status();
    return write_lods(dir, lods.value());
  }

  // Child c's LOD `index` in c.mesh: its kept LOD 0 (left in place), else read from its file.
  Status load_chosen(ChildLod& c, std::size_t index) const {
    if (c.in_memory && index == 0) return {};
    auto read = read_node_file(options_.root / c.lods[index].file, c.lods[index].bytes);
    if (!read.ok()) return read.status();
    c.mesh = std::move(read).value();
    return {};
  }

  // An internal node whose children's chosen LODs are too large to merge and simplify in memory
  // (near the root of a large model, where every child's coarsest LOD keeps its locked boundary
  // at the original resolution: 103K triangles for the root of a 100M rock): their triangles go
  // to a record file, one child at a time, and the node's LODs are built streaming from it
  // (streamed_leaf.h, merged_children). No LOD when even that cannot simplify them (the caller
  // then merges in memory).
  Result<NodeDone> run_streamed_internal(std::array<ChildLod, 8>& children,
                                         const std::vector<std::size_t>& chosen, double input_error,
                                         const std::string& dir, const Bounds& cell, const LodOptions& lod) {
    TempFile records = make_temp_file(options_.work_dir, "merged-children");
    const std::size_t record_bytes = soup_record_bytes(options_.layout);
    {
      auto writer = RecordWriter::create(records.path(), record_bytes, std::size_t{1} << 20);
      if (!writer.ok()) return writer.status();
      std::vector<std::byte> record(record_bytes);
      std::uint32_t id = 0;  // octant order: the file is the same on any schedule
      std::size_t next = 0;
      for (ChildLod& c : children) {
        if (!c.present) continue;
        const std::size_t index = chosen[next++];
        OCTOLOD_RETURN_IF_ERROR(load_chosen(c, index));
        for (std::size_t t = 0; t < c.mesh.triangle_count(); ++t) {
          store_soup_record(record.data(), options_.layout, c.mesh.vertices.data(), &c.mesh.indices[3 * t], id++);
          OCTOLOD_RETURN_IF_ERROR(writer->append(record.data(), 1));
        }
        if (!(c.in_memory && index == 0)) c.mesh = {};  // a kept LOD 0 stays for the fallback
      }
      OCTOLOD_RETURN_IF_ERROR(writer->finish());
    }
    // LOD 1 at most the triangles of a merge_bytes mesh (about one vertex per triangle at these
    // levels), read in chunks of that many: like the leaves' limits, but not from the budget,
    // so the tree stays independent of it (merge_bytes, lod_tree.h)
    const std::uint64_t limit = std::max<std::uint64_t>(
        1, merge_bytes_ / (sizeof(float) * (options_.layout.floats() + 3)));
    StreamedLeafOptions o;
    o.layout = options_.layout;
    o.cell = cell;
    o.lod = lod;  // its lock_boundary: for the chain after LOD 1 (which keeps the boundary)
    o.chunk_triangles = limit;
    o.max_lod1_triangles = limit;
    o.work_dir = options_.work_dir;
    o.sort_budget_bytes = options_.streamed_sort_bytes;
    o.merged_children = true;
    o.input_error = input_error;
    auto built = build_streamed_leaf(records.path(), options_.root, dir, o);
    records.remove();
    if (!built.ok()) return built.status();
    if (built->coarser.empty()) return NodeDone{};
    auto done = write_lods(dir, built->coarser);
    if (done.ok()) done->streamed = true;
    return done;
  }

  Status make_directory(const std::string& dir) const {
    if (dir.empty()) return {};
    // Usually only the last component is missing: one mkdir(2), no stat of every component.
    const fs::path path = options_.root / dir;
    if (::mkdir(path.c_str(), 0777) == 0 || errno == EEXIST) return {};
    std::error_code ec;
    fs::create_directories(path, ec);
    if (ec) {
      return io_error("cannot create node directory '" + path.string() + "': " + ec.message());
    }
    return {};
  }

  // Writes lod<first + i>.olod for every LOD; the first is handed to the parent.
  Result<NodeDone> write_lods(const std::string& dir, std::vector<Lod>& lods,
                              std::size_t first = 0) const {
    OCTOLOD_RETURN_IF_ERROR(make_directory(dir));
    NodeDone done;
    for (std::size_t i = 0; i < lods.size(); ++i) {
      const NodeMesh& mesh = lods[i].mesh;
      const std::string file = lod_file_name(dir, first + i);
      OCTOLOD_RETURN_IF_ERROR(write_node_file(options_.root / file, mesh));
      LodInfo info;
      info.triangles = static_cast<std::uint32_t>(mesh.triangle_count());
      info.vertices = static_cast<std::uint32_t>(mesh.vertex_count());
      info.error = lods[i].error;
      info.bytes = node_file_size(mesh);
      info.file = file;
      done.lods.bounds.extend(mesh.bounds());
      done.lods.lods.push_back(std::move(info));
    }
    if (!lods.empty()) done.finest = std::move(lods.front().mesh);
    return done;
  }

  // A node's chain is complete: record it and hand it to the parent (LOD 0 in memory while the
  // kept bytes allow), which becomes ready with its last child. Under the lock.
  void deliver(std::int32_t node, NodeDone done) {
    ++completed_;
    const auto done_slot = slots_.find(node);
    const NodeShape shape = done_slot->second.shape;
    slots_.erase(done_slot);
    const std::int32_t parent = shape.parent;
    const auto octant = static_cast<std::size_t>(shape.prefix & 7u);
    const bool has_lod = options_.build_lods && !done.lods.lods.empty();
    error_ = log_->append(node, shape, done.lods);
    if (!error_.ok() || parent < 0) return;
    Slot& p = slot(parent);
    ++p.done;
    p.shape.triangles += shape.triangles;
    if (!p.pending) p.pending = std::make_unique<Pending>();
    p.pending->bounds.extend(done.lods.bounds);
    if (has_lod) {
      ChildLod& c = p.pending->child[octant];
      c.present = true;
      c.lods = std::move(done.lods.lods);
      p.child_triangles += c.lods.front().triangles;
      const std::size_t bytes = mesh_bytes(done.finest);
      // a LOD 0 larger than a whole merged input is only merged where nothing coarser exists:
      // not worth keeping (nor a streamed leaf's, which is only in its file)
      if (bytes <= merge_bytes_ && !done.finest.indices.empty()) {
        c.spilled = kept_bytes_ + bytes > options_.keep_bytes;
        if (!c.spilled) {
          c.in_memory = true;
          c.bytes = bytes;
          c.mesh = std::move(done.finest);
          kept_bytes_ += bytes;
          stats_.peak_kept_bytes = std::max<std::uint64_t>(stats_.peak_kept_bytes, kept_bytes_);
        }
      }
    }
    if (p.ready()) push_internal(parent);
  }

  void work() {
    Scratch scratch;
    std::unique_lock lock(mutex_);
    for (;;) {
      work_.wait(lock, [&] { return stopping_ || !error_.ok() || can_start(); });
      if (stopping_ || !error_.ok()) return;
      run_one(lock, scratch);
    }
  }

  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    work_.notify_all();
    for (std::thread& t : threads_) t.join();
    threads_.clear();
  }

  const LodTreeOptions options_;
  const std::size_t merge_bytes_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable work_;   // tasks or stop for the workers
  std::condition_variable space_;  // a task finished: queue room, progress, new tasks
  std::vector<Task> heap_;         // ready nodes, heaviest on top
  // by node index, from register_nodes until delivered: the open nodes, not the tree's
  std::unordered_map<std::int32_t, Slot> slots_;
  std::size_t registered_ = 0;     // nodes given a slot so far
  std::vector<std::int32_t> open_; // internal nodes on the last leaf's path, root first
  std::optional<NodeLodsLog> log_;  // every finished node's record
  std::size_t queued_bytes_ = 0;   // records of leaves not yet done
  std::size_t kept_bytes_ = 0;     // children's LODs held for their parents
  std::size_t running_work_ = 0;   // node_work_bytes of the nodes running now
  std::uint64_t completed_ = 0;
  std::uint64_t total_nodes_ = 0;
  bool stopping_ = false;
  Status error_;
  Scratch caller_scratch_;
  LodTreeStats stats_;
};

std::size_t lod_mesh_bytes(const LodInfo& lod, VertexLayout layout) {
  return (std::size_t{lod.vertices} * layout.floats() + 3 * std::size_t{lod.triangles}) * sizeof(float);
}

std::size_t node_work_bytes(std::size_t input_bytes) {
  return kNodeWorkFixed + kNodeWorkPerInputByte * input_bytes;
}

std::size_t leaf_work_bytes(std::size_t record_bytes) {
  return kNodeWorkFixed + kLeafWorkPerRecordByte * record_bytes;
}

std::size_t max_node_work_bytes(std::size_t merge_bytes, std::size_t leaf_record_bytes) {
  return std::max(node_work_bytes(kStreamedMergeFactor * merge_bytes), leaf_work_bytes(leaf_record_bytes));
}

std::vector<std::size_t> choose_merged_lods(const std::vector<std::vector<LodInfo>>& children,
                                            VertexLayout layout, std::size_t merge_bytes) {
  std::vector<std::size_t> chosen(children.size(), 0);
  std::size_t total = 0;
  for (const std::vector<LodInfo>& chain : children) total += lod_mesh_bytes(chain.front(), layout);
  while (total > merge_bytes) {
    std::size_t largest = children.size();
    std::size_t largest_bytes = 0;
    for (std::size_t c = 0; c < children.size(); ++c) {
      const std::size_t bytes = lod_mesh_bytes(children[c][chosen[c]], layout);
      if (chosen[c] + 1 < children[c].size() && (largest == children.size() || bytes > largest_bytes)) {
        largest = c;
        largest_bytes = bytes;
      }
    }
    if (largest == children.size()) break;  // every child at its coarsest
    ++chosen[largest];
    total = total - largest_bytes + lod_mesh_bytes(children[largest][chosen[largest]], layout);
  }
  return chosen;
}

LodTreeBuilder::LodTreeBuilder(LodTreeOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}
LodTreeBuilder::~LodTreeBuilder() = default;

Status LodTreeBuilder::add_leaf(std::int32_t node, const OctreeNodes& nodes,
                                std::vector<std::byte>&& records) {
  return impl_->add_leaf(node, nodes, std::move(records), {});
}

Status LodTreeBuilder::add_streamed_leaf(std::int32_t node, const OctreeNodes& nodes,
                                         TempFile records) {
  return impl_->add_leaf(node, nodes, {}, std::move(records));
}

Status LodTreeBuilder::finish(const OctreeNodes& nodes,
                              const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
  return impl_->finish(nodes, progress);
}

NodeLodsLog LodTreeBuilder::take_results() { return impl_->take_results(); }
const LodTreeStats& LodTreeBuilder::stats() const { return impl_->stats(); }

}  // namespace octolod::bake
