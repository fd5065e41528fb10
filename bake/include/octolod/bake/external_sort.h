// External k-way merge sort of fixed-size binary records (seed 3.3 and 4.2.2: the triangle soup
// is built by sorting the triangle index file by each corner's vertex id; the octree build sorts
// the soup by cell). The records live in memory only up to the caller's budget:
//
//   1. Run formation: records are gathered into a run buffer sized by the budget; a full buffer
//      is sorted (LSD radix sort on the 64-bit key, two halves on two threads when allowed) and
//      written to a temporary run file. With two threads, after the first run the buffer works
//      as two halves: a helper thread sorts and writes one while the caller fills the other.
//   2. Merge: the runs are merged with the largest fan-in the budget allows (loser tree); only
//      when there are more runs than that are intermediate merge passes made, each merging
//      consecutive runs so the sort stays stable. The final pass is streamed to the caller;
//      with two threads a helper thread merges the next block while the caller works on the
//      last one.
//   3. In-core fast path: when every record fits in the run buffer, one in-memory sort and no
//      temporary file at all.
//
// Stable: records with equal keys keep their input order, so the output is a pure function of
// the input, whatever the budget or thread count. Run files are deleted as soon as they are
// merged, and on every error.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>

#include "octolod/formats/status.h"

namespace octolod::bake {

// Computes the sort keys of `keys.size()` consecutive records starting at `records`
// (records.size() == keys.size() * record_bytes). Called once per batch of records, never per
// record, so an indirect call costs nothing. Must be a pure function of the record bytes; it may
// run on the sorter's helper thread while the caller's thread does other work.
using SortKeyFn = std::function<void(std::span<const std::byte> records,
                                     std::span<std::uint64_t> keys)>;

// The unsigned little-endian 32- or 64-bit integer at byte `offset` of each record.
SortKeyFn sort_key_u32_at(std::size_t offset, std::size_t record_bytes);
SortKeyFn sort_key_u64_at(std::size_t offset, std::size_t record_bytes);

struct SortOptions {
  // Cap on all buffers of the sort together (run buffer with its key arrays, merge input
  // buffers, output buffer and its keys). Larger budgets mean fewer runs and fewer merge passes. At least
  // 16 KiB and room for a few records.
  std::uint64_t memory_budget_bytes = std::uint64_t{64} << 20;
  // Where run files go; the system temporary directory when empty.
  std::filesystem::path work_dir;
  // 1: sort and write runs on the calling thread; 2 or more: also use one helper thread (run
  // halves sorted in parallel, runs written while the caller pushes more, the final merge a
  // block ahead of the caller). The output is identical for any value.
  unsigned threads = 2;
  // Largest buffer per file (bigger blocks stop paying off); smaller when the budget demands.
  std::size_t max_io_buffer_bytes = std::size_t{1} << 20;
};

struct SortStats {
  std::uint64_t records = 0;
  std::uint64_t runs = 0;           // sorted runs written to disk (0: in-core fast path)
  std::uint32_t merge_passes = 0;   // passes over the data after run formation, the final one
                                    // included (0: in-core, 1: a single k-way merge)
  std::uint32_t fan_in = 0;         // most runs merged at once
  std::uint64_t bytes_written = 0;  // to run files
  std::uint64_t bytes_read = 0;     // from run files
  bool in_core = false;
  double seconds = 0;  // wall time spent inside the sorter's calls
};

// Push records, finish(), then pull them back sorted.
class RecordSorter {
 public:
  // usage error when the budget cannot hold the sort's minimal buffers for this record size.
  static Result<std::unique_ptr<RecordSorter>> create(std::size_t record_bytes, SortKeyFn key,
                                                      const SortOptions& options);
  virtual ~RecordSorter() = default;

  // Copies whole records (records.size() a multiple of record_bytes); only before finish().
  // Through reserve() and commit().
  Status push(std::span<const std::byte> records);
  // Zero-copy push: room for between 1 and `max_records` records inside the run buffer (writing
  // a run first when it is full); fill a prefix, then commit() it before any other call.
  virtual Result<std::span<std::byte>> reserve(std::size_t max_records) = 0;
  virtual void commit(std::size_t records) = 0;
  // Ends the input; runs intermediate merge passes if the fan-in demands them.
  virtual Status finish() = 0;
  // The next sorted records (at least one, or empty after the last); only after finish().
  // Valid until the next call.
  virtual Result<std::span<const std::byte>> next() = 0;
  // The sort keys of the records the last next() returned, one per record (computed once,
  // when the records entered the sort). Valid until the next call to next().
  virtual std::span<const std::uint64_t> keys() const = 0;

  // Complete once next() has returned the empty block; while the final merge runs on its
  // helper thread (threads >= 2), read it only before finish() or after the end.
  virtual const SortStats& stats() const = 0;
  virtual std::size_t record_bytes() const = 0;
};

// Sorts the record file `in` into `out` (raw records, no header; `out` is replaced).
Result<SortStats> sort_records(const std::filesystem::path& in, const std::filesystem::path& out,
                               std::size_t record_bytes, SortKeyFn key,
                               const SortOptions& options);

}  // namespace octolod::bake
