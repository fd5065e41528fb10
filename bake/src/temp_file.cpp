// Temporary file ownership for the bake's out-of-core stages (seed 4.2).
#include "octolod/bake/temp_file.h"

#include <unistd.h>

#include <atomic>
#include <string>
#include <system_error>

namespace octolod::bake {

void TempFile::remove() {
  if (path_.empty()) return;
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
  path_.clear();
}

TempFile make_temp_file(const std::filesystem::path& dir, std::string_view purpose) {
  static std::atomic<std::uint64_t> counter{0};
  std::filesystem::path base = dir;
  if (base.empty()) {
    std::error_code ec;
    base = std::filesystem::temp_directory_path(ec);
    if (ec) base = "/tmp";
  }
  std::string name = "octolod-" + std::to_string(::getpid()) + "-" +
                     std::to_string(counter.fetch_add(1)) + "-" + std::string(purpose) + ".tmp";
  return TempFile(base / name);
}

}  // namespace octolod::bake
