// FileSource and MemorySource: the two NodeSources the runtime ships with.
#include "octolod/runtime/node_source.h"

#include <cerrno>
#include <cstdio>
#include <memory>
#include <system_error>

namespace octolod::runtime {

Result<std::vector<std::byte>> FileSource::read(std::string_view file) const {
  const std::filesystem::path path = root_ / std::filesystem::path(file);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) {
    return io_error(path.string() + ": cannot open: " +
                    std::generic_category().message(errno));
  }
  std::vector<std::byte> bytes;
  std::byte chunk[1 << 16];
  for (;;) {
    const std::size_t got = std::fread(chunk, 1, sizeof chunk, f.get());
    bytes.insert(bytes.end(), chunk, chunk + got);
    if (got < sizeof chunk) break;
  }
  if (std::ferror(f.get())) return io_error(path.string() + ": read failed");
  return bytes;
}

void MemorySource::put(std::string file, std::vector<std::byte> bytes) {
  std::lock_guard lock(mutex_);
  files_[std::move(file)] = std::move(bytes);
}

Result<std::vector<std::byte>> MemorySource::read(std::string_view file) const {
  std::lock_guard lock(mutex_);
  ++total_reads_;
  auto count = reads_.find(file);
  if (count == reads_.end()) count = reads_.emplace(std::string(file), 0).first;
  ++count->second;
  auto it = files_.find(file);
  if (it == files_.end()) return io_error(std::string(file) + ": no such file in memory source");
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
