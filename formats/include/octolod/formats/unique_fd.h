// An owned POSIX file descriptor: closed when its owner is destroyed or given another; moving
// hands it over (the moved-from one owns none). Lets classes that hold files default their moves.
// Shared by the libraries that write their own files (formats' writers, bake's record files).
#pragma once

#include <unistd.h>

#include <utility>

namespace octolod {

class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}  // takes `fd` (-1: none)
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.release()) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept {
    if (this != &other) reset(other.release());
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() { reset(); }

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  // Gives the descriptor up without closing it: for callers that close it themselves to see
  // close(2)'s result.
  int release() { return std::exchange(fd_, -1); }
  // Closes the one held (its close(2) result is lost) and takes `fd`.
  void reset(int fd = -1) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }

 private:
  int fd_ = -1;
};

}  // namespace octolod
