// Where node LOD files come from. The runtime never opens files itself: it asks a NodeSource,
// so a game can read from a pak file or the network, and tests from memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "octolod/formats/status.h"

namespace octolod::runtime {

class NodeSource {
 public:
  virtual ~NodeSource() = default;
  // The whole content of `file`, a '/'-separated path relative to the tree root as the manifest
  // stores it (LodInfo::file), which the manifest says is `expected_bytes` long (LodInfo::bytes).
  // Called concurrently from loader threads: must be thread-safe. A missing file is an error
  // Result (ErrorCode::io), never an exception. Content of any other size than `expected_bytes`
  // is an error Result too (check_node_file_size: bad_input naming the file and both sizes),
  // found before the content is fetched or allocated where the source can (a file's size, a pak
  // directory entry), so a swapped or corrupt file cannot take more memory than the manifest
  // budgets for it. The runtime treats either failure alike: the LOD is marked bad and an
  // ancestor or other LOD is drawn instead.
  virtual Result<std::vector<std::byte>> read(std::string_view file, std::uint64_t expected_bytes) const = 0;
};

// Reads files below a baked tree's root directory on disk, each in one read
// (read_node_file_bytes: only regular files, so a FIFO or a device in the tree fails its load
// instead of blocking a loader thread or filling memory; the size is checked by fstat before
// the read).
class FileSource final : public NodeSource {
 public:
  explicit FileSource(std::filesystem::path root) : root_(std::move(root)) {}
  Result<std::vector<std::byte>> read(std::string_view file, std::uint64_t expected_bytes) const override;

 private:
  std::filesystem::path root_;
};

// Files held in memory, keyed by their relative path. put() and read() may be called from any
// thread. Counts reads per file so tests can tell a cache hit from a reload.
class MemorySource final : public NodeSource {
 public:
  void put(std::string file, std::vector<std::byte> bytes);
  Result<std::vector<std::byte>> read(std::string_view file, std::uint64_t expected_bytes) const override;
  // How many times read(file, ...) was called (successful or not).
  std::uint64_t read_count(std::string_view file) const;
  std::uint64_t total_reads() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::vector<std::byte>, std::less<>> files_;
  mutable std::map<std::string, std::uint64_t, std::less<>> reads_;
  mutable std::uint64_t total_reads_ = 0;
};

}  // namespace octolod::runtime
