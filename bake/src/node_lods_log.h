// The finished nodes' records, kept in a work file from the moment a node's chain is done
// until the manifest is written (bake_pipeline.cpp): what the manifest says of the node. Held
// in memory as NodeLods with their file names, they were about 1 KB of RSS per node to the end
// of the bake: 219 MiB for the 212K nodes of a 100M-triangle rock at --memory 64M; the octree's
// nodes held for the manifest were another 64 bytes each. The log holds nothing per node in
// memory: each record's offset goes to a second work file, at the node's index.
//
// A record is the node's place in the tree (NodeShape), its bounds and, per LOD, its triangles,
// vertices, error and bytes; file names are not stored, LOD i of the node is
// lod_file_name(node_path(prefix, depth), i) (tree_paths.h), as the LOD stage writes them.
// Native byte order: the file lives only as long as the bake.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>

#include "lod_tree.h"
#include "octolod/bake/temp_file.h"
#include "octolod/formats/status.h"
#include "octolod/formats/unique_fd.h"
#include "record_file.h"

namespace octolod::bake {

// A node's place in the octree (octree_build.h's OctreeNode and its children).
struct NodeShape {
  std::uint64_t prefix = 0;     // octant path from the root (morton.h)
  std::uint64_t triangles = 0;  // in the subtree
  std::int32_t parent = -1;
  std::uint32_t depth = 0;
  std::array<std::int32_t, 8> children{-1, -1, -1, -1, -1, -1, -1, -1};  // by octant
  bool leaf = false;

  bool operator==(const NodeShape&) const = default;
};

// One node as the log gives it back.
struct LoggedNode {
  NodeShape shape;
  NodeLods lods;  // files named after the node's directory
};

class NodeLodsLog {
 public:
  // A new, empty log in `work_dir` (the system temporary directory when empty).
  static Result<NodeLodsLog> create(const std::filesystem::path& work_dir);
  NodeLodsLog(NodeLodsLog&&) noexcept = default;
  NodeLodsLog& operator=(NodeLodsLog&&) noexcept = default;
  // Destroyed, it removes its files.

  // Records node `node`'s shape, LODs (at most kMaxLods; file names ignored) and bounds, once
  // per node, in any order, until finish(). Errors: io naming the file.
  Status append(std::int32_t node, const NodeShape& shape, const NodeLods& lods);
  // Flushes the records; read() only after it. Errors: io naming the file.
  Status finish();

  // Whether `node` was appended.
  bool has(std::int32_t node) const;
  // The record of an appended node. Errors: io naming the file and the offset (the file was
  // cut or is not the log's).
  Result<LoggedNode> read(std::int32_t node) const;

  // More LODs than any chain has (LodOptions::max_lods is 16 by default).
  static constexpr std::uint32_t kMaxLods = 1024;

 private:
  NodeLodsLog() = default;

  // The offset of node i's record + 1 at byte 8 i of the index file (0, or past its end: not
  // appended).
  Result<std::uint64_t> stored_offset(std::int32_t node) const;

  // (destroyed in reverse: each descriptor is closed before its file is removed)
  TempFile file_;
  std::optional<RecordWriter> writer_;  // until finish()
  UniqueFd fd_;                         // for read(), after finish()
  TempFile index_file_;
  UniqueFd index_fd_;
};

}  // namespace octolod::bake
