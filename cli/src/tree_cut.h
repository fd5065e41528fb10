// Uniform cuts of a baked tree: which LOD of which node covers each part of the model when the
// whole model is drawn at one error target or at one octree depth — what `extract` writes and
// `compare` measures. (The runtime's view-dependent selection lives in octolod::runtime.)
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"

namespace octolod::cli {

struct CutEntry {
  std::uint32_t node = 0;  // index into Manifest::nodes
  std::uint32_t lod = 0;   // index into NodeInfo::lods
  friend bool operator==(const CutEntry&, const CutEntry&) = default;
};

// Per node, top-down: the coarsest LOD whose error <= max_error (model units); otherwise its
// children; a leaf with no such LOD uses its finest. Every original triangle is covered once.
std::vector<CutEntry> uniform_error_cut(const Manifest& manifest, double max_error);

// Nodes at `depth` (and leaves above it), each with its finest LOD; nodes without LODs are
// replaced by their children.
std::vector<CutEntry> depth_cut(const Manifest& manifest, std::uint32_t depth);

// Sum of the cut's triangles and its largest stored error.
struct CutSummary {
  std::uint64_t triangles = 0;
  double max_error = 0;
};
CutSummary summarize_cut(const Manifest& manifest, std::span<const CutEntry> cut);

// Loads every entry's node file from the tree at `root`. Errors: those of read_node_file, and
// check_node_lod's when a file is not what the manifest says (layout, counts).
Result<std::vector<NodeMesh>> load_cut(const std::filesystem::path& root, const Manifest& manifest,
                                       std::span<const CutEntry> cut);

// The cut as one mesh, as the runtime draws it: the entries' node files in cut order,
// concatenated, with vertices whose records (position and attributes) are bit-identical welded
// into one (bake::merge_meshes). A cut is crack-free because neighbouring nodes keep their shared
// boundary vertices bit-identical, so after welding the seams between nodes are shared vertices.
// The layout is the manifest's. Errors: load_cut's.
Result<NodeMesh> load_cut_mesh(const std::filesystem::path& root, const Manifest& manifest,
                               std::span<const CutEntry> cut);

}  // namespace octolod::cli
