// Temporary files of the bake (seed 4.2: the vertex file, the triangle index file, sorted runs and
// the triangle soup all live on disk only while the bake needs them). A TempFile owns one path
// and removes the file when destroyed, so every early error return cleans up after itself.
#pragma once

#include <filesystem>
#include <string_view>

namespace octolod::bake {

class TempFile {
 public:
  TempFile() = default;
  // Takes ownership of `path` (which need not exist yet).
  explicit TempFile(std::filesystem::path path) : path_(std::move(path)) {}
  ~TempFile() { remove(); }
  TempFile(TempFile&& other) noexcept : path_(std::move(other.path_)) { other.path_.clear(); }
  TempFile& operator=(TempFile&& other) noexcept {
    if (this != &other) {
      remove();
      path_ = std::move(other.path_);
      other.path_.clear();
    }
    return *this;
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  bool empty() const { return path_.empty(); }
  // Deletes the file now (ignoring a missing file) and forgets the path.
  void remove();
  // Gives up ownership: the file stays, the caller must remove it.
  std::filesystem::path release() {
    std::filesystem::path p = std::move(path_);
    path_.clear();
    return p;
  }

 private:
  std::filesystem::path path_;
};

// A fresh, unique path in `dir` (the system temporary directory when empty) named
// "octolod-<pid>-<n>-<purpose>.tmp"; nothing is created.
TempFile make_temp_file(const std::filesystem::path& dir, std::string_view purpose);

}  // namespace octolod::bake
