// Buffered sequential record files for the out-of-core soup stage (seed 4.2): POSIX read/write
// in large blocks, no stdio double buffering, errors named by file and errno.
#include "record_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace octolod::bake {
namespace {

// The injected fault (ScopedIoFault): which operation, how many bytes still succeed, what errno.
enum : int { kNoFault = 0, kWriteFault = 1, kReadFault = 2 };
std::atomic<int> g_fault_op{kNoFault};
std::atomic<std::int64_t> g_fault_bytes_left{0};
std::atomic<int> g_fault_errno{0};

// True when the fault fires for an operation of `bytes` bytes (errno is set).
bool fault_fires(int op, std::size_t bytes) {
  if (g_fault_op.load(std::memory_order_relaxed) != op) return false;
  const auto n = static_cast<std::int64_t>(bytes);
  if (g_fault_bytes_left.fetch_sub(n) >= n) return false;
  errno = g_fault_errno.load();
  return true;
}

Status os_error(const char* what, const std::filesystem::path& path, int error) {
  return io_error(std::string(what) + " '" + path.string() + "': " + std::strerror(error));
}

std::size_t whole_records(std::size_t buffer_bytes, std::size_t record_bytes) {
  return std::max<std::size_t>(1, buffer_bytes / record_bytes) * record_bytes;
}

}  // namespace

ScopedIoFault::ScopedIoFault(Op op, std::uint64_t after_bytes, int error)
    : after_bytes_(after_bytes) {
  assert(g_fault_op.load() == kNoFault && "ScopedIoFault instances do not nest");
  g_fault_bytes_left.store(static_cast<std::int64_t>(after_bytes));
  g_fault_errno.store(error);
  g_fault_op.store(op == Op::write ? kWriteFault : kReadFault);
}

ScopedIoFault::~ScopedIoFault() { g_fault_op.store(kNoFault); }

std::uint64_t ScopedIoFault::bytes_seen() const {
  return static_cast<std::uint64_t>(static_cast<std::int64_t>(after_bytes_) -
                                    g_fault_bytes_left.load());
}

// ---------------------------------------------------------------------------------------------
// RecordWriter

Result<RecordWriter> RecordWriter::create(const std::filesystem::path& path,
                                          std::size_t record_bytes, std::size_t buffer_bytes) {
  assert(record_bytes > 0 && "RecordWriter: records need at least one byte");
  RecordWriter w;
  w.path_ = path;
  w.record_bytes_ = record_bytes;
  w.capacity_ = whole_records(buffer_bytes, record_bytes);
  w.fd_.reset(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (!w.fd_.valid()) return os_error("cannot create", path, errno);
  w.buffer_ = PageArray<std::byte>(w.capacity_);
  return w;
}

Status RecordWriter::flush() {
  std::size_t done = 0;
  while (done < used_) {
    const std::size_t n = used_ - done;
    ssize_t written = -1;
    if (!fault_fires(kWriteFault, n)) written = ::write(fd_.get(), buffer_.get() + done, n);
    if (written < 0) {
      if (errno == EINTR) continue;
      return os_error("cannot write", path_, errno);
    }
    done += static_cast<std::size_t>(written);
  }
  used_ = 0;
  return {};
}

Status RecordWriter::append_runs(std::span<const std::span<const std::byte>> runs) {
  assert(fd_.valid() && "RecordWriter used after finish()");
  OCTOLOD_RETURN_IF_ERROR(flush());
  constexpr std::size_t kMaxIov = 1024;  // IOV_MAX on Linux
  std::vector<iovec> iov;
  iov.reserve(std::min(runs.size(), kMaxIov));
  for (std::size_t first = 0; first < runs.size(); first += kMaxIov) {
    iov.clear();
    std::size_t bytes = 0;
    for (std::size_t i = first; i < std::min(runs.size(), first + kMaxIov); ++i) {
      assert(runs[i].size() % record_bytes_ == 0 && "RecordWriter::append_runs: partial record");
      iov.push_back(iovec{const_cast<std::byte*>(runs[i].data()), runs[i].size()});
      bytes += runs[i].size();
    }
    records_ += bytes / record_bytes_;
    // Until every byte is out: a short write leaves the rest of its iovec and the later ones.
    std::size_t next = 0;
    while (bytes > 0) {
      ssize_t written = -1;
      if (!fault_fires(kWriteFault, bytes))
        written = ::writev(fd_.get(), iov.data() + next, static_cast<int>(iov.size() - next));
      if (written < 0) {
        if (errno == EINTR) continue;
        return os_error("cannot write", path_, errno);
      }
      bytes -= static_cast<std::size_t>(written);
      for (auto left = static_cast<std::size_t>(written); left > 0;) {
        const std::size_t take = std::min(left, iov[next].iov_len);
        iov[next].iov_base = static_cast<std::byte*>(iov[next].iov_base) + take;
        iov[next].iov_len -= take;
        left -= take;
        if (iov[next].iov_len == 0) ++next;
      }
      while (next < iov.size() && iov[next].iov_len == 0) ++next;
    }
  }
  return {};
}

Status RecordWriter::append(const std::byte* records, std::size_t count) {
  assert(fd_.valid() && "RecordWriter used after finish()");
  std::size_t bytes = count * record_bytes_;
  while (bytes > 0) {
    if (used_ == capacity_) OCTOLOD_RETURN_IF_ERROR(flush());
    const std::size_t n = std::min(bytes, capacity_ - used_);
    std::memcpy(buffer_.get() + used_, records, n);
    used_ += n;
    records += n;
    bytes -= n;
  }
  records_ += count;
  return {};
}

Result<std::span<std::byte>> RecordWriter::reserve(std::size_t max_records) {
  assert(fd_.valid() && "RecordWriter used after finish()");
  if (used_ == capacity_) OCTOLOD_RETURN_IF_ERROR(flush());
  const std::size_t n = std::min(max_records, (capacity_ - used_) / record_bytes_);
  return std::span<std::byte>(buffer_.get() + used_, n * record_bytes_);
}

void RecordWriter::commit(std::size_t records) {
  assert(used_ + records * record_bytes_ <= capacity_ && "RecordWriter::commit beyond reserve()");
  used_ += records * record_bytes_;
  records_ += records;
}

Status RecordWriter::finish() {
  assert(fd_.valid() && "RecordWriter::finish() called twice");
  Status status = flush();
  if (::close(fd_.release()) != 0 && status.ok()) status = os_error("cannot close", path_, errno);
  buffer_.reset();
  return status;
}

// ---------------------------------------------------------------------------------------------
// RecordReader

Result<RecordReader> RecordReader::open(const std::filesystem::path& path,
                                        std::size_t record_bytes, std::size_t buffer_bytes) {
  assert(record_bytes > 0 && "RecordReader: records need at least one byte");
  RecordReader r;
  r.path_ = path;
  r.record_bytes_ = record_bytes;
  r.fd_.reset(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!r.fd_.valid()) return os_error("cannot open", path, errno);
  struct stat st {};
  if (::fstat(r.fd_.get(), &st) != 0) return os_error("cannot stat", path, errno);
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size % record_bytes != 0) {
    return io_error("record file '" + path.string() + "' has " + std::to_string(size) +
                    " bytes, not a multiple of its " + std::to_string(record_bytes) +
                    "-byte records (truncated?)");
  }
  r.total_ = size / record_bytes;
  ::posix_fadvise(r.fd_.get(), 0, 0, POSIX_FADV_SEQUENTIAL);
  // Never more buffer than the file needs.
  const std::uint64_t file_bytes = std::max<std::uint64_t>(size, record_bytes);
  r.capacity_ = whole_records(
      static_cast<std::size_t>(std::min<std::uint64_t>(buffer_bytes, file_bytes)), record_bytes);
  r.buffer_ = PageArray<std::byte>(r.capacity_);
  return r;
}

Status RecordReader::read_fully(std::byte* dst, std::size_t bytes) {
  std::size_t got = 0;
  while (got < bytes) {
    ssize_t n = -1;
    if (!fault_fires(kReadFault, bytes - got)) n = ::read(fd_.get(), dst + got, bytes - got);
    if (n < 0) {
      if (errno == EINTR) continue;
      return os_error("cannot read", path_, errno);
    }
    if (n == 0) {
      return io_error("record file '" + path_.string() + "' ended early: it shrank while read");
    }
    got += static_cast<std::size_t>(n);
  }
  return {};
}

Status RecordReader::refill() {
  // Only called when the buffer is exhausted; fills it with whole records.
  const std::uint64_t left_bytes = (total_ - consumed_) * record_bytes_;
  const std::size_t want =
      static_cast<std::size_t>(std::min<std::uint64_t>(capacity_, left_bytes));
  OCTOLOD_RETURN_IF_ERROR(read_fully(buffer_.get(), want));
  begin_ = 0;
  end_ = want;
  return {};
}

Result<std::size_t> RecordReader::read_into(std::span<std::byte> dst) {
  assert(begin_ == end_ && "RecordReader::read_into with buffered records left");
  const std::size_t n = static_cast<std::size_t>(
      std::min<std::uint64_t>(total_ - consumed_, dst.size() / record_bytes_));
  OCTOLOD_RETURN_IF_ERROR(read_fully(dst.data(), n * record_bytes_));
  consumed_ += n;
  return n;
}

Result<std::span<const std::byte>> RecordReader::read(std::size_t max_records) {
  if (begin_ == end_) {
    if (consumed_ == total_) return std::span<const std::byte>();
    OCTOLOD_RETURN_IF_ERROR(refill());
  }
  const std::size_t n = std::min(max_records, (end_ - begin_) / record_bytes_);
  std::span<const std::byte> out(buffer_.get() + begin_, n * record_bytes_);
  begin_ += n * record_bytes_;
  consumed_ += n;
  return out;
}

}  // namespace octolod::bake
