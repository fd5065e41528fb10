// Buffered sequential files of fixed-size binary records: the vertex file, the triangle index
// file, sorted runs and the soup (seed 4.2: every out-of-core stage reads and writes whole files
// front to back in large blocks). Records are raw native (little-endian) bytes, no header.
//
// Every failure is an io Status naming the file and the operating system's reason (including
// "No space left on device"); an injectable fault (ScopedIoFault) lets tests simulate them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

#include "octolod/formats/status.h"
#include "octolod/formats/unique_fd.h"
#include "page_array.h"

namespace octolod::bake {

// Appends records to a new (truncated) file through a buffer of `buffer_bytes` (rounded down to
// whole records, at least one record).
class RecordWriter {
 public:
  static Result<RecordWriter> create(const std::filesystem::path& path, std::size_t record_bytes,
                                     std::size_t buffer_bytes);
  RecordWriter(RecordWriter&&) noexcept = default;
  RecordWriter& operator=(RecordWriter&&) noexcept = default;
  // Destroyed, it closes the file without flushing: call finish() to keep the data.

  // Copies `count` records.
  Status append(const std::byte* records, std::size_t count);
  // Writes the runs of whole records `runs` (in order) straight from the caller's memory with
  // writev(2), after what is buffered: no copy through the buffer.
  Status append_runs(std::span<const std::span<const std::byte>> runs);
  // Room for between 1 and `max_records` records in the buffer (flushing first when it is
  // full); fill a prefix and commit() it. Valid until the next call on the writer.
  Result<std::span<std::byte>> reserve(std::size_t max_records);
  void commit(std::size_t records);
  // Flushes and closes; the writer is unusable afterwards.
  Status finish();

  std::uint64_t records_written() const { return records_; }
  std::size_t record_bytes() const { return record_bytes_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  RecordWriter() = default;
  Status flush();

  std::filesystem::path path_;
  UniqueFd fd_;
  std::size_t record_bytes_ = 0;
  PageArray<std::byte> buffer_;
  std::size_t capacity_ = 0;  // bytes, a multiple of record_bytes_
  std::size_t used_ = 0;      // bytes
  std::uint64_t records_ = 0;
};

// Reads a file of records front to back through a buffer of `buffer_bytes` (rounded down to
// whole records, at least one record). A file whose size is not a multiple of the record size
// is an io error (it was truncated or is not ours).
class RecordReader {
 public:
  static Result<RecordReader> open(const std::filesystem::path& path, std::size_t record_bytes,
                                   std::size_t buffer_bytes);
  RecordReader(RecordReader&&) noexcept = default;
  RecordReader& operator=(RecordReader&&) noexcept = default;

  // The next up to `max_records` records (at least one unless the file is exhausted, then
  // empty). Valid until the next call on the reader.
  Result<std::span<const std::byte>> read(std::size_t max_records = SIZE_MAX);
  // Reads the next min(records_left(), dst.size() / record_bytes()) records straight into
  // `dst`, bypassing the buffer (which must be empty: no read() since open, or its records all
  // taken); returns how many.
  Result<std::size_t> read_into(std::span<std::byte> dst);

  std::uint64_t record_count() const { return total_; }
  std::uint64_t records_left() const { return total_ - consumed_; }
  std::size_t record_bytes() const { return record_bytes_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  RecordReader() = default;
  Status refill();
  Status read_fully(std::byte* dst, std::size_t bytes);

  std::filesystem::path path_;
  UniqueFd fd_;
  std::size_t record_bytes_ = 0;
  PageArray<std::byte> buffer_;
  std::size_t capacity_ = 0;  // bytes, a multiple of record_bytes_
  std::size_t begin_ = 0;     // bytes of the buffer already handed out
  std::size_t end_ = 0;       // bytes of the buffer filled
  std::uint64_t total_ = 0;     // records in the file
  std::uint64_t consumed_ = 0;  // records handed out
};

// Test hook: while alive, the RecordWriter (op write) or RecordReader (op read) system calls of
// the whole process fail with `error` once `after_bytes` more bytes have passed through them.
// Install it before starting the work under test; instances do not nest.
class ScopedIoFault {
 public:
  enum class Op { write, read };
  ScopedIoFault(Op op, std::uint64_t after_bytes, int error);
  ~ScopedIoFault();
  // Bytes the hooked system calls have passed (or tried to) since construction.
  std::uint64_t bytes_seen() const;
  ScopedIoFault(const ScopedIoFault&) = delete;
  ScopedIoFault& operator=(const ScopedIoFault&) = delete;

 private:
  std::uint64_t after_bytes_;
};

}  // namespace octolod::bake
