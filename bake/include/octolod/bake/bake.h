// The bake: a PLY mesh of any size becomes an on-disk LOD octree directory (docs/design.md
// stages 1-6; seed 3.3-3.5, 4.2-4.4):
//
//   soup      the PLY becomes one self-contained record per triangle (octolod/bake/soup.h)
//   octree    the soup is sorted by the Morton code of each triangle's centroid in the model's
//             bounding cube (an external bucket sort, bucket_sort.h; the soup stage's records
//             go straight into it, no soup file), and one streaming pass over the sorted
//             records decides the tree (a node splits while it holds more than max_tris
//             triangles and is shallower than max_depth) and hands every leaf its contiguous
//             run of triangles, by (key, triangle id). When the indexed mesh fits the budget
//             the keys are sorted in memory instead and the leaves gathered from the mesh
//   lods      meanwhile, on worker threads, heaviest ready node first: each leaf is indexed
//             (exact vertex dedup) into its LOD 0 (the original triangles, error 0) and a chain
//             of simplifications (simplify.h); every internal node, once its children are done,
//             simplifies the merge of their first simplified LODs; nodes near the root continue
//             into a coarse chain down to about 256 triangles. Files lod<i>.olod, finest first,
//             each with a conservative error in model units.
//   manifest  manifest.json at the root (octolod/formats/manifest.h)
//
// Output: OUT_DIR/manifest.json and one directory per node, children in sub-directories "0".."7"
// by octant (docs/formats.md). The tree is built in a temporary sibling directory of OUT_DIR and
// renamed into place only when complete: a failed or interrupted bake leaves no OUT_DIR (or the
// previous one, untouched) and no temporary file.
//
// The output depends only on the input and (max_tris, max_depth, lods, method, lod_ratio): not on the
// budget, the thread count or the work directory (the manifest's parameters, stage_seconds and
// stats aside), except for the leaves at max_depth larger than max_depth_leaf_triangles of the
// budget, whose LODs are built streaming in chunks of that size (see max_depth below).
//
// Memory: the soup stage, then the octree sort, the leaf queue, the node work in flight (as
// many nodes at once as their estimated working sets fit the reserve for the largest one) and
// the children's LODs kept for their parents share the budget less program_bytes; kept LODs
// beyond their share are re-read from their files by the parent. Peak RSS stays within the
// budget (with program_bytes covering the program's own footprint); the node work reserve
// covers a leaf at max_depth as large as a quarter of the budget can simplify in memory
// (max_depth_leaf_triangles), and a larger one is built streaming from a temporary file,
// alone, within that quarter.
// Nothing is held per octree node: a finished node's record waits in a work file (its offset
// in another) until the manifest is written node by node from it, and of the octree only the
// open path is held. An
// internal node whose children's LODs are too large to merge in memory (near the root of a
// large model) is clustered streaming from a file of them, like an oversize leaf.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string_view>

#include "octolod/bake/simplify.h"
#include "octolod/formats/manifest.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::bake {

// Called from the bake's calling thread: stage is "split", "dereference 0..2" (the soup), "sort"
// (the octree's run formation), "octree" (the streaming pass; `done` of `total` triangles),
// "lods" (the node work left after the stream; `done` of `total` nodes).
using BakeProgressFn =
    std::function<void(std::string_view stage, std::uint64_t done, std::uint64_t total)>;

struct BakeOptions {
  std::filesystem::path input;   // PLY file
  std::filesystem::path output;  // OUT_DIR: must not exist, or be empty, or hold an earlier bake
  // A node splits while it holds more than this many triangles (seed 3.4). Smaller leaves mean
  // more nodes, more files and a finer LOD cut; larger ones fewer files but coarser paging.
  // Memory: about (max_tris + 1) soup records per leaf in flight (the input's triangles when
  // fewer: an input smaller than four such leaves is budgeted for its own size). At least 1.
  std::uint32_t max_tris = 2000;
  // Deepest level (root = 0), at most 21. A leaf at max_depth cannot split, so it keeps all
  // its triangles; one holding more than max_depth_leaf_triangles(memory_budget_bytes, layout,
  // max_tris) is spilled to a temporary file and built streaming (memory bounded by
  // that cap, not by the leaf): LOD 0 its original triangles, stored per chunk of four times
  // that many (a vertex shared by two chunks is stored twice), LOD 1 a vertex clustering of at
  // most that many triangles (and half the leaf) with the leaf's boundary kept and attributes per
  // wedge (a cell's corners grouped by their attributes, so seams are not averaged across),
  // the rest of the chain from LOD 1: a coarser
  // first step than an in-memory leaf's halving; raise max_depth for dense models when that
  // matters.
  std::uint32_t max_depth = 10;
  // Cap on the process's memory: program_bytes for what is not the bake's, the rest for the
  // bake's buffers together (soup stage, octree sort, leaf buffers, node work in flight,
  // children's LODs kept for their parents, a leaf at max_depth larger than max_tris + 1, in
  // memory or streamed). Larger budgets mean fewer sorted runs and merges and, once the
  // vertices fit in half of it, the in-core soup path. At least program_bytes + kMinBakeBudget,
  // and enough for max_tris (the bake says how much when it is not; about 38 MiB with every
  // attribute at max_tris 2000, most of it for the largest node's simplification). The bake
  // counts its own buffers; the process's RSS also holds what the allocator keeps of freed ones.
  // With glibc, the CLI calls mallopt(M_ARENA_MAX, 2) and mallopt(M_MMAP_THRESHOLD, 1 MiB)
  // before bake() (cli/src/cmd_bake.cpp: without them the 10M rock at 16M peaked 6.5 MiB higher,
  // the 100M rock at 64M 5.1 MiB higher); a caller who wants the CLI's peaks does the same (they
  // are process-wide, so the library leaves that choice to it).
  std::uint64_t memory_budget_bytes = std::uint64_t{64} << 20;
  // The part of memory_budget_bytes the process holds besides the bake (its code, libraries,
  // thread stacks): the CLI sets kCliProgramBytes so that its --memory caps the whole
  // process's peak RSS; 0 for a caller whose budget is the bake's own.
  std::uint64_t program_bytes = 0;
  // Where the temporary files go (inside a fresh ".octolod-tmp-*" directory); empty: next to
  // the output. Needs room for about two soups (3 x vertex bytes + 4 per triangle, twice).
  std::filesystem::path work_dir;
  // Threads for the sorts and the node work; 0 = hardware concurrency, or fewer when the memory
  // budget cannot hold that many threads (each past the second reserves 128 KiB; the manifest
  // records the count used). A count given here that the budget cannot hold is refused (usage).
  // The output does not depend on it.
  unsigned threads = 0;
  // Take the soup stage's out-of-core path even when the vertices would fit (tests, benchmarks).
  bool force_out_of_core = false;
  // In core, when the indexed mesh fits in the budget with 36 bytes per triangle to spare (its
  // 12 bytes of indices, keys and triangle ids with their sort scratch): sort the triangles by
  // cell in memory and gather each leaf's records from the mesh instead of producing the soup
  // and sorting it (same output, several times faster). false: always the soup path (tests
  // compare the two).
  bool in_memory_octree = true;
  // Install the SIGINT/SIGTERM cleanup (temp_dir.h): on a signal the temporary directories are
  // removed and the process dies by that signal. For programs; libraries embedding the bake
  // may prefer their own handling.
  bool cleanup_on_signal = false;
  // Build the LOD hierarchy (lod_tree: leaves from their original triangles, internal nodes
  // from their children's first simplified LODs, coarse chains near the root). false: the
  // leaves hold only their original triangles (lod0) and internal nodes have no LOD.
  bool lods = true;
  // Clustering operator of every simplification step (simplify.h). The output depends on it.
  ClusterMethod method = ClusterMethod::grid;
  // Each LOD of a node's chain has at most this fraction of the previous LOD's triangles (and
  // a streamed leaf's LOD 1 of its input's), in [kMinLodRatio, kMaxLodRatio]. Lower: fewer
  // LODs, a faster bake and fewer bytes, with larger steps between the LODs a runtime chooses
  // from (docs/benchmarks.md, "The LOD ratio"). The output depends on it.
  double lod_ratio = 0.5;
  BakeProgressFn progress;
};

// The range of BakeOptions::lod_ratio: at most half (each LOD halves the triangles at least),
// at least a tenth (coarser steps leave a runtime little to choose from).
inline constexpr double kMinLodRatio = 0.1;
inline constexpr double kMaxLodRatio = 0.5;

// "grid" / "bade2006": the names of the CLI's --method and of the manifest's parameters.method.
std::string_view method_name(ClusterMethod method);
// The method named `name`; nullopt for an unknown name.
std::optional<ClusterMethod> parse_method(std::string_view name);

inline constexpr std::uint64_t kMinBakeBudget = std::uint64_t{1} << 20;
// What the octolod CLI holds before a bake starts, rounded up: its code and libraries
// (OpenMesh, Draco, OSMesa, ...) resident, 6.9 MiB measured idle, and the bake's thread
// stacks.
inline constexpr std::uint64_t kCliProgramBytes = std::uint64_t{8} << 20;

// The most triangles a leaf at max_depth may hold under a budget of memory_budget_bytes with
// vertices of `layout`, never fewer than max_tris + 1 (a leaf that small is always built in
// memory): a quarter of the budget at
// about 16 soup records of memory per triangle (its records, indexed mesh, simplification
// arrays and LOD chain, measured on leaves of up to 400K triangles). The node work reserve
// holds that quarter (the sort's share gives it up where it is larger than the largest
// internal node's); a larger leaf is built streaming in chunks of this many triangles. Depends
// only on its arguments: the cap decides how a leaf is built, never the tree.
std::uint64_t max_depth_leaf_triangles(std::uint64_t memory_budget_bytes, VertexLayout layout,
                                       std::uint32_t max_tris);

struct BakeReport {
  // OUT_DIR/manifest.json as written, without its nodes (`nodes` is empty: a large tree's nodes
  // are never held together; read_tree_manifest(OUT_DIR) has them)
  Manifest header;
  std::uint64_t lods = 0;        // node LODs of the whole tree
  std::uint32_t root_coarsest_triangles = 0;  // what the whole model costs from far away
  std::uint64_t nodes = 0;
  std::uint64_t leaves = 0;
  std::uint32_t depth = 0;       // deepest leaf
  std::uint64_t bytes = 0;       // node files + manifest
  bool soup_in_core = false;     // which soup path ran
  bool octree_in_memory = false; // the octree came from the in-memory mesh (in_memory_octree)
  std::uint64_t sort_runs = 0;   // sorted runs the octree sort wrote (0: in core)
  std::uint64_t peak_rss_bytes = 0;
  // Bytes after the input's last element, ignored (PlyInfo::trailing_bytes): worth a warning,
  // since more than padding usually means element counts in the header that are too small.
  std::uint64_t input_trailing_bytes = 0;
  // Why the texture the input's TextureFile comment names was not copied into the tree
  // (Manifest::texture stays empty): no UVs, a path outside the input's directory, no such file.
  // Empty when it was copied or none was named.
  std::string texture_warning;
  // Leaves at max_depth that held more triangles than the budget lets a leaf simplify in memory,
  // built streaming: their LOD 1 has at most streamed_lod1_triangles (set when there are any), a
  // steep step down from their LOD 0 for a runtime. A larger max_depth splits such leaves.
  std::uint64_t streamed_leaves = 0;
  std::uint64_t largest_streamed_leaf_triangles = 0;
  std::uint64_t streamed_lod1_triangles = 0;
};

// Bakes options.input into options.output (see the top of this file). Errors: usage for bad
// options (max_tris 0, max_depth > 21, budget below kMinBakeBudget or too small for max_tris
// and the threads, an output that is a file or a non-empty foreign directory, an input inside
// it), bad_input for an input without faces, the PLY reader's bad_input / unsupported / io
// naming the file, io for any refused write (out of space included) naming the path. On error
// nothing is published and every temporary file is gone.
Result<BakeReport> bake(const BakeOptions& options);

}  // namespace octolod::bake
