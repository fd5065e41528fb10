// The finished nodes' LOD records, kept in a work file from the moment a node's chain is done
// until the manifest is written (bake_pipeline.cpp). Held in memory as NodeLods with their file
// names, they were about 1 KB of RSS per node to the end of the bake: 219 MiB for the 212K nodes
// of a 100M-triangle rock at --memory 64M. The log holds 8 bytes per node (its record's offset).
//
// A record is the node's bounds and, per LOD, its triangles, vertices, error and bytes; file
// names are not stored, LOD i of the node in directory d is lod_file_name(d, i) (tree_paths.h),
// as the LOD stage writes them. Native byte order: the file lives only as long as the bake.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "lod_tree.h"
#include "octolod/bake/temp_file.h"
#include "octolod/formats/status.h"
#include "record_file.h"

namespace octolod::bake {

class NodeLodsLog {
 public:
  // A new, empty log in `work_dir` (the system temporary directory when empty).
  static Result<NodeLodsLog> create(const std::filesystem::path& work_dir);
  NodeLodsLog(NodeLodsLog&& other) noexcept;
  NodeLodsLog& operator=(NodeLodsLog&& other) noexcept;
  NodeLodsLog(const NodeLodsLog&) = delete;
  NodeLodsLog& operator=(const NodeLodsLog&) = delete;
  ~NodeLodsLog();  // removes the file

  // Records node `node`'s LODs (at most kMaxLods; file names ignored) and bounds, once per
  // node, in any order, until finish(). Errors: io naming the file.
  Status append(std::int32_t node, const NodeLods& lods);
  // Flushes the records; read() only after it. Errors: io naming the file.
  Status finish();

  // Whether `node` was appended.
  bool has(std::int32_t node) const;
  // The record of an appended node, its files named after `dir` (its directory, tree_paths.h).
  // Errors: io naming the file and the offset (the file was cut or is not the log's).
  Result<NodeLods> read(std::int32_t node, std::string_view dir) const;

  // More LODs than any chain has (LodOptions::max_lods is 16 by default).
  static constexpr std::uint32_t kMaxLods = 1024;

 private:
  NodeLodsLog() = default;

  TempFile file_;
  std::optional<RecordWriter> writer_;  // until finish()
  int fd_ = -1;                         // for read(), after finish()
  std::vector<std::uint64_t> offsets_;  // by node; kAbsent when not appended
};

}  // namespace octolod::bake
