// The manifest: manifest.json at the root of a baked tree. It describes the whole octree (node
// directories, bounds, LODs with their triangle counts, errors, sizes and files) so a runtime can
// plan everything before loading a single payload. JSON, versioned; see docs/formats.md.
//
// Octants: child i of a node covers the half-open sub-cube selected by bit 0 = upper x half,
// bit 1 = upper y half, bit 2 = upper z half. Child directories are named "0".."7".
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "octolod/formats/bounds.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod {

inline constexpr std::uint32_t kManifestVersion = 1;
inline constexpr std::string_view kManifestFileName = "manifest.json";

struct LodInfo {
  std::uint32_t triangles = 0;
  std::uint32_t vertices = 0;
  // Conservative geometric error in model units: an upper bound on the distance from any point
  // of the original surface this node covers to this LOD. 0 for the original triangles.
  double error = 0.0;
  std::uint64_t bytes = 0;  // size of `file`
  std::string file;         // node file, relative to the tree root, '/'-separated
};

struct NodeInfo {
  std::string path;            // directory relative to the root, "" for the root, else "3/5"
  std::uint32_t depth = 0;     // root = 0
  std::int32_t parent = -1;    // index into Manifest::nodes, -1 for the root
  std::array<std::int32_t, 8> children{-1, -1, -1, -1, -1, -1, -1, -1};  // by octant
  Bounds cell;                 // the octree cube this node owns (centroid assignment)
  Bounds bounds;               // tight bounds of its triangles (may stick out of `cell`)
  std::uint64_t source_triangles = 0;  // original triangles in this subtree
  std::vector<LodInfo> lods;   // finest first; a leaf's lods[0] is its original triangles

  std::uint8_t child_mask() const {
    std::uint8_t m = 0;
    for (int i = 0; i < 8; ++i)
      if (children[static_cast<std::size_t>(i)] >= 0) m = static_cast<std::uint8_t>(m | (1u << i));
    return m;
  }
  bool is_leaf() const { return child_mask() == 0; }
};

struct BakeParameters {
  std::string input;            // input file name as given
  std::uint32_t max_tris = 0;
  std::uint32_t max_depth = 0;
  std::uint64_t memory_budget_bytes = 0;
  std::uint32_t threads = 0;
  std::string method;           // clustering method, "" when no LODs were built
  // Each LOD of a chain has at most this fraction of the previous LOD's triangles (bake
  // --lod-ratio), in (0, 1). Absent in manifests of bakes before 2026-12-04: 0.5.
  double lod_ratio = 0.5;
};

struct Manifest {
  std::uint32_t version = kManifestVersion;
  VertexLayout layout;
  // Where the tree's (0, 0, 0) lies in the input's coordinates (model units, double): every
  // position of the tree (bounds, cells, node files) is relative to it. Zeros unless the input's
  // positions were recentred before rounding to float (double positions: PlyReadOptions); a
  // runtime places the tree at this point, exporters add it back. Absent in manifests of bakes
  // before 2026-12-02: zeros.
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  // The image the layout's uv index, relative to the tree's root ('/'-separated, never ".."):
  // the input's texture (its PLY's TextureFile comment), copied into the tree by the bake. UVs are
  // as in the input: (0, 0) is the image's lower-left corner, v up (OpenGL's and MeshLab's
  // convention; glTF's v is 1 - v). Empty when the input named none (written only when set).
  std::string texture;
  Bounds bounds;                        // tight bounds of the model
  std::uint64_t input_vertices = 0;
  std::uint64_t input_triangles = 0;    // after fan triangulation, degenerate ones included
  BakeParameters parameters;
  std::map<std::string, double> stage_seconds;  // wall time per bake stage
  std::map<std::string, double> stats;          // other numbers (peak RSS bytes, ...)
  std::vector<NodeInfo> nodes;          // nodes[0] is the root; parents precede children

  // A texture the meshes can show: one is named and the layout has UVs to index it.
  bool has_texture() const { return !texture.empty() && layout.uv; }
};

std::string manifest_to_json(const Manifest& manifest);
// The manifest's "parameters" object as compact JSON text (the same keys and values the manifest
// holds), for tools that report a tree's bake parameters.
std::string bake_parameters_to_json(const BakeParameters& parameters);
// bad_input naming `name` unless `manifest` is a tree: nodes (at least the root) whose parents
// precede them, parent/child links consistent and in range, depths one below the parent's, LOD
// files and the texture relative and without "..", errors not negative or NaN, at least a node file header's
// bytes (kNodeFileHeaderBytes). Every reader below checks it; a
// manifest built in code is checked by StreamingTree::open.
Status validate_manifest(const Manifest& manifest, std::string_view name);
// Parses and validates (validate_manifest).
Result<Manifest> manifest_from_json(std::string_view text, std::string_view name);

// write_manifest writes atomically (temporary sibling + rename).
Status write_manifest(const std::filesystem::path& path, const Manifest& manifest);
// A tree's nodes produced one at a time, in index order (index 0 .. count - 1, each once), for
// writers that do not hold them all (a 100M-triangle bake has 212K nodes).
using ManifestNodeFn = std::function<Result<NodeInfo>(std::size_t index)>;
// write_manifest of `header` (its `nodes` ignored) with the `node_count` nodes `node` produces:
// the same text as write_manifest of the whole Manifest. The first error of `node` ends the
// write and is returned; nothing is left at `path` then.
Status write_manifest(const std::filesystem::path& path, const Manifest& header,
                      std::size_t node_count, const ManifestNodeFn& node);
Result<Manifest> read_manifest(const std::filesystem::path& path);
// read_manifest of the manifest.json at the root of a baked tree (the OUT_DIR of a bake).
Result<Manifest> read_tree_manifest(const std::filesystem::path& tree_root);

// bad_input naming `name` (the node file) unless `mesh`, loaded from lod.file, is what `lod` of
// a tree of `layout` says: that layout and lod.triangles / lod.vertices. Catches a node file
// swapped for another LOD's and an edited manifest, whose counts a runtime budgets memory by.
Status check_node_lod(const NodeMesh& mesh, const LodInfo& lod, const VertexLayout& layout, std::string_view name);

}  // namespace octolod
