// FileSource and MemorySource: the two NodeSources the runtime ships with.
#include "octolod/runtime/node_source.h"

#include "octolod/formats/node_file.h"

namespace octolod::runtime {

Result<std::vector<std::byte>> FileSource::read(std::string_view file, std::uint64_t expected_bytes) const {
  return read_node_file_bytes(root_ / std::filesystem::path(file), expected_bytes);
}

void MemorySource::put(std::string file, std::vector<std::byte> bytes) {
  std::lock_guard lock(mutex_);
  files_[std::move(file)] = std::move(bytes);
}

Result<std::vector<std::byte>> MemorySource::read(std::string_view file, std::uint64_t expected_bytes) const {
  std::lock_guard lock(mutex_);
  ++total_reads_;
  auto count = reads_.find(file);
  if (count == reads_.end()) count = reads_.emplace(std::string(file), 0).first;
  ++count->second;
  auto it = files_.find(file);
  if (it == files_.end()) return io_error(std::string(file) + ": no such file in memory source");
  OCTOLOD_RETURN_IF_ERROR(check_node_file_size(file, it->second.size(), expected_bytes));
  return it->second;
}

std::uint64_t MemorySource::read_count(std::string_view file) const {
  std::lock_guard lock(mutex_);
  auto it = reads_.find(file);
  return it == reads_.end() ? 0 : it->second;
}

std::uint64_t MemorySource::total_reads() const {
  std::lock_guard lock(mutex_);
  return total_reads_;
}

}  // namespace octolod::runtime
