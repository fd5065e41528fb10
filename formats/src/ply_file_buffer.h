// Sequential, bounded reading of a PLY file (seed 4.2.1: "read the model in portions"): one
// fixed buffer (64 KiB by default) refilled with large fread calls, and absolute byte offsets so
// error messages can say where the data went wrong. Never allocates after open().
#pragma once

#include <cassert>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <sys/stat.h>

#include "octolod/formats/input_file.h"
#include "octolod/formats/status.h"

namespace octolod::ply {

class FileBuffer {
 public:
  static constexpr std::size_t kDefaultCapacity = std::size_t{64} << 10;

  FileBuffer() = default;
  FileBuffer(const FileBuffer&) = delete;
  FileBuffer& operator=(const FileBuffer&) = delete;
  ~FileBuffer() {
    if (file_ != nullptr) std::fclose(file_);
  }

  // Opens `path` for reading; io error (naming the file) when it cannot be opened or sized.
  Status open(const std::filesystem::path& path, std::size_t capacity = kDefaultCapacity) {
    assert(file_ == nullptr && "FileBuffer::open called twice");
    path_ = path.string();
    OCTOLOD_RETURN_IF_ERROR(check_input_file(path, "the PLY"));  // before opening: a FIFO would block
    file_ = std::fopen(path_.c_str(), "rb");
    if (file_ == nullptr) return io_error(path_ + ": cannot open: " + std::strerror(errno));
    // the size of the file opened, not of whatever the path names by now
    struct stat opened {};
    if (fstat(fileno(file_), &opened) != 0) return io_error(path_ + ": cannot read file size: " + std::strerror(errno));
    file_size_ = static_cast<std::uint64_t>(opened.st_size);
    // Our own buffer is the only one: stdio buffering would copy every byte twice.
    std::setvbuf(file_, nullptr, _IONBF, 0);
    capacity_ = capacity;
    buffer_ = std::make_unique<char[]>(capacity_);
    return {};
  }

  const std::string& path() const { return path_; }
  std::uint64_t file_size() const { return file_size_; }
  std::size_t capacity() const { return capacity_; }

  // Unread buffered bytes; valid until the next fill() or skip().
  const char* data() const { return buffer_.get() + begin_; }
  std::size_t available() const { return end_ - begin_; }
  // Absolute file offset of data()[0].
  std::uint64_t offset() const { return file_pos_ - (end_ - begin_); }
  // True when the file has no more bytes beyond the buffered ones.
  bool exhausted() const { return eof_; }

  void consume(std::size_t n) {
    assert(n <= available());
    begin_ += n;
  }

  // Makes at least min(want, capacity()) bytes available unless the file ends first; a short
  // result at end of file is not an error (callers compare available() with what they need).
  Status fill(std::size_t want) {
    if (available() >= want || eof_) return {};
    if (want > capacity_) want = capacity_;
    if (begin_ != 0) {
      std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
      end_ -= begin_;
      begin_ = 0;
    }
    while (end_ < want && !eof_) {
      const std::size_t got = std::fread(buffer_.get() + end_, 1, capacity_ - end_, file_);
      if (got == 0) {
        if (std::ferror(file_)) return io_error(path_ + ": read failed: " + std::strerror(errno));
        eof_ = true;
      }
      end_ += got;
      file_pos_ += got;
    }
    return {};
  }

  // Consumes `n` bytes, seeking over what is not buffered. Skipping past the end of the file is
  // not an error here: offset() then exceeds file_size() and the caller reports truncation.
  Status skip(std::uint64_t n) {
    if (n <= available()) {
      begin_ += static_cast<std::size_t>(n);
      return {};
    }
    n -= available();
    begin_ = end_ = 0;
    if (fseeko(file_, static_cast<off_t>(n), SEEK_CUR) != 0)
      return io_error(path_ + ": seek failed: " + std::strerror(errno));
    file_pos_ += n;
    eof_ = file_pos_ >= file_size_;
    return {};
  }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0;
  std::unique_ptr<char[]> buffer_;
  std::size_t capacity_ = 0;
  std::size_t begin_ = 0;  // first unread byte in buffer_
  std::size_t end_ = 0;    // one past the last buffered byte
  std::uint64_t file_pos_ = 0;  // file offset of buffer_[end_]
  bool eof_ = false;
};

}  // namespace octolod::ply
