// External k-way merge sort of fixed-size records (seed 3.3, 4.2.2). Runs are sorted with a
// stable LSD radix sort on 64-bit keys (one histogram pass, digits that do not vary skipped,
// already-sorted runs detected), merged with a loser tree whose ties go to the earlier run.
#include "octolod/bake/external_sort.h"

#include <algorithm>
#include <cassert>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "octolod/bake/temp_file.h"
#include "page_array.h"
#include "radix_sort.h"
#include "record_file.h"
#include "stopwatch.h"

namespace octolod::bake {
namespace {

constexpr std::uint64_t kMinBudget = 16 * 1024;
constexpr std::size_t kMinBlockBytes = 4096;
// Below this many records a run is sorted on one thread (a thread costs more than it saves).
constexpr std::size_t kParallelSortMin = 1 << 16;
// Bytes per record of the run buffer's key and order arrays (keys + order, each twice).
constexpr std::size_t kRunOverhead = 2 * (sizeof(std::uint64_t) + sizeof(std::uint32_t));

// A range of the run buffer, sorted: one or two sorted halves (sorted on two threads) read out
// in order by a two-way merge.
struct SortedRun {
  const std::byte* records = nullptr;  // first record of the range; order[] indexes from here
  std::size_t record_bytes = 0;
  std::uint64_t* keys[2] = {nullptr, nullptr};
  std::uint32_t* order[2] = {nullptr, nullptr};
  std::size_t size[2] = {0, 0};
  std::size_t cursor[2] = {0, 0};  // read position in each half

  bool exhausted() const { return cursor[0] == size[0] && cursor[1] == size[1]; }

  // Copies up to `max` records in sorted order to `out` (and their keys to `out_keys` unless
  // null); returns how many. Ties between the halves go to the first half (earlier input),
  // which keeps the sort stable.
  std::size_t emit(std::byte* out, std::uint64_t* out_keys, std::size_t max) {
    std::size_t n = 0;
    while (n < max) {
      int h;
      if (cursor[0] == size[0]) {
        if (cursor[1] == size[1]) break;
        h = 1;
      } else if (cursor[1] == size[1]) {
        h = 0;
      } else {
        h = keys[1][cursor[1]] < keys[0][cursor[0]] ? 1 : 0;
      }
      std::memcpy(out + n * record_bytes,
                  records + std::size_t{order[h][cursor[h]]} * record_bytes, record_bytes);
      if (out_keys) out_keys[n] = keys[h][cursor[h]];
      ++cursor[h];
      ++n;
    }
    return n;
  }
};

// The run buffer: records, their keys and sort order (each with radix scratch space).
struct RunBuffer {
  std::size_t record_bytes = 0;
  std::size_t capacity = 0;  // records
  PageArray<std::byte> records;
  PageArray<std::uint64_t> key_storage;    // 2 * capacity
  PageArray<std::uint32_t> order_storage;  // 2 * capacity

  void allocate(std::size_t rb, std::size_t cap) {
    record_bytes = rb;
    capacity = cap;
    records = PageArray<std::byte>(cap * rb);
    key_storage = PageArray<std::uint64_t>(2 * cap);
    order_storage = PageArray<std::uint32_t>(2 * cap);
  }
  void release() {
    records.reset();
    key_storage.reset();
    order_storage.reset();
    capacity = 0;
  }
  std::byte* record(std::size_t i) { return records.get() + i * record_bytes; }

  // Sorts records [begin, begin + count), as two halves on two threads when `two_threads` and
  // the range is large. Touches only that range's slots of the key and order arrays, so two
  // disjoint ranges can be sorted concurrently.
  SortedRun sort(std::size_t begin, std::size_t count, const SortKeyFn& key_fn,
                 bool two_threads) {
    SortedRun run;
    run.records = record(begin);
    run.record_bytes = record_bytes;
    if (count == 0) return run;
    std::uint64_t* k = key_storage.get() + begin;
    std::uint32_t* o = order_storage.get() + begin;
    key_fn(std::span<const std::byte>(run.records, count * record_bytes),
           std::span<std::uint64_t>(k, count));
    for (std::size_t i = 0; i < count; ++i) o[i] = static_cast<std::uint32_t>(i);
    const std::size_t half = (two_threads && count >= kParallelSortMin) ? count / 2 : count;
    run.size[0] = half;
    run.size[1] = count - half;
    std::uint64_t* kt = k + capacity;
    std::uint32_t* ot = o + capacity;
    run.keys[0] = k;
    run.order[0] = o;
    run.keys[1] = k + half;
    run.order[1] = o + half;
    std::uint64_t* kt1 = kt + half;
    std::uint32_t* ot1 = ot + half;
    if (run.size[1] == 0) {
      radix_sort(run.keys[0], run.order[0], kt, ot, run.size[0]);
      return run;
    }
    std::thread helper([&] { radix_sort(run.keys[1], run.order[1], kt1, ot1, run.size[1]); });
    radix_sort(run.keys[0], run.order[0], kt, ot, run.size[0]);
    helper.join();
    return run;
  }
};

// One run being merged: its file, a block of its records and their keys.
struct MergeInput {
  TempFile file;
  std::unique_ptr<RecordReader> reader;
  std::vector<std::uint64_t> keys;
  const std::byte* records = nullptr;
  std::size_t count = 0;  // records in the current block
  std::size_t pos = 0;
  bool done = false;
};

// Loser-tree k-way merge of runs (Knuth 5.4.1). Ties go to the input with the lower index, the
// earlier run, so the merge is stable.
class KWayMerge {
 public:
  Status open(std::vector<TempFile> runs, std::size_t record_bytes, std::size_t block_bytes,
              const SortKeyFn* key_fn, SortStats* stats) {
    record_bytes_ = record_bytes;
    key_fn_ = key_fn;
    stats_ = stats;
    const std::size_t k = runs.size();
    inputs_.resize(k);
    for (std::size_t i = 0; i < k; ++i) {
      MergeInput& in = inputs_[i];
      in.file = std::move(runs[i]);
      auto reader = RecordReader::open(in.file.path(), record_bytes, block_bytes);
      if (!reader.ok()) return reader.status();
      in.reader = std::make_unique<RecordReader>(std::move(reader).value());
      in.keys.resize(std::max<std::size_t>(1, block_bytes / record_bytes));
      OCTOLOD_RETURN_IF_ERROR(refill(in));
    }
    // Build the tree bottom-up: winners of each subtree, losers stored in the nodes.
    tree_.assign(std::max<std::size_t>(k, 1), 0);
    if (k > 1) {
      std::vector<std::uint32_t> winner(2 * k);
      for (std::size_t i = 0; i < k; ++i) winner[k + i] = static_cast<std::uint32_t>(i);
      for (std::size_t node = k - 1; node >= 1; --node) {
        const std::uint32_t a = winner[2 * node];
        const std::uint32_t b = winner[2 * node + 1];
        if (less(a, b)) {
          winner[node] = a;
          tree_[node] = b;
        } else {
          winner[node] = b;
          tree_[node] = a;
        }
      }
      tree_[0] = winner[1];
    }
    return {};
  }

  bool empty() const { return inputs_.empty() || inputs_[tree_[0]].done; }

  // Copies up to `max` records in order to `out` (and their keys to `out_keys` unless null);
  // returns how many (0 only when exhausted).
  Result<std::size_t> emit(std::byte* out, std::uint64_t* out_keys, std::size_t max) {
    std::size_t n = 0;
    const std::size_t k = inputs_.size();
    while (n < max) {
      std::uint32_t w = tree_[0];
      MergeInput& in = inputs_[w];
      if (in.done) break;
      std::memcpy(out + n * record_bytes_, in.records + in.pos * record_bytes_, record_bytes_);
      if (out_keys) out_keys[n] = in.keys[in.pos];
      ++n;
      if (++in.pos == in.count) OCTOLOD_RETURN_IF_ERROR(refill(in));
      // Replay w's path to the root.
      for (std::size_t node = (w + k) / 2; node >= 1; node /= 2) {
        if (less(tree_[node], w)) std::swap(tree_[node], w);
      }
      tree_[0] = w;
    }
    return n;
  }

 private:
  bool less(std::uint32_t a, std::uint32_t b) const {
    const MergeInput& x = inputs_[a];
    const MergeInput& y = inputs_[b];
    if (x.done) return false;
    if (y.done) return true;
    const std::uint64_t ka = x.keys[x.pos];
    const std::uint64_t kb = y.keys[y.pos];
    return ka < kb || (ka == kb && a < b);
  }

  Status refill(MergeInput& in) {
    auto block = in.reader->read(in.keys.size());
    if (!block.ok()) return block.status();
    const std::size_t n = block->size() / record_bytes_;
    if (n == 0) {
      // Consumed: free the buffer and delete the run file right away.
      in.done = true;
      in.reader.reset();
      in.file.remove();
      in.keys = {};
      return {};
    }
    stats_->bytes_read += block->size();
    in.records = block->data();
    in.count = n;
    in.pos = 0;
    (*key_fn_)(block.value(), std::span<std::uint64_t>(in.keys.data(), n));
    return {};
  }

  std::size_t record_bytes_ = 0;
  const SortKeyFn* key_fn_ = nullptr;
  SortStats* stats_ = nullptr;
  std::vector<MergeInput> inputs_;
  std::vector<std::uint32_t> tree_;  // [0] winner, [1..k) losers
};

class ExternalSorter final : public RecordSorter {
 public:
  ExternalSorter(std::size_t record_bytes, SortKeyFn key, const SortOptions& options,
                 std::size_t out_bytes, std::size_t run_capacity)
      : record_bytes_(record_bytes),
        key_(std::move(key)),
        options_(options),
        out_bytes_(out_bytes),
        run_capacity_(run_capacity) {}
  ~ExternalSorter() override {
    if (spiller_.joinable()) spiller_.join();
    stop_merger();
  }
  ExternalSorter(const ExternalSorter&) = delete;
  ExternalSorter& operator=(const ExternalSorter&) = delete;

  Result<std::span<std::byte>> reserve(std::size_t max_records) override {
    assert(state_ == State::input && "RecordSorter::reserve after finish()");
    Stopwatch watch(stats_.seconds);
    if (!run_.records) {
      run_.allocate(record_bytes_, run_capacity_);
      fill_limit_ = run_capacity_;
    }
    if (fill_count_ == fill_limit_) OCTOLOD_RETURN_IF_ERROR(make_room());
    const std::size_t n = std::min(max_records, fill_limit_ - fill_count_);
    return std::span<std::byte>(run_.record(fill_begin_ + fill_count_), n * record_bytes_);
  }

  void commit(std::size_t records) override {
    assert(fill_count_ + records <= fill_limit_ && "RecordSorter::commit beyond reserve()");
    fill_count_ += records;
    stats_.records += records;
  }

  Status finish() override {
    assert(state_ == State::input && "RecordSorter::finish called twice");
    Stopwatch watch(stats_.seconds);
    OCTOLOD_RETURN_IF_ERROR(wait_for_spill());
    out_ = PageArray<std::byte>(out_bytes_);
    out_keys_ = PageArray<std::uint64_t>(out_bytes_ / record_bytes_);
    if (runs_.empty()) {
      // In-core fast path: one in-memory sort, no temporary file.
      stats_.in_core = true;
      if (run_.records) sorted_ = run_.sort(0, fill_count_, key_, options_.threads >= 2);
      state_ = State::in_core;
      return {};
    }
    if (fill_count_ > 0) OCTOLOD_RETURN_IF_ERROR(spill_now(fill_begin_, fill_count_));
    run_.release();
    OCTOLOD_RETURN_IF_ERROR(merge_down());
    stats_.fan_in = std::max(stats_.fan_in, static_cast<std::uint32_t>(runs_.size()));
    ++stats_.merge_passes;
    const std::size_t block = block_bytes(runs_.size());
    OCTOLOD_RETURN_IF_ERROR(final_.open(std::move(runs_), record_bytes_, block, &key_, &stats_));
    runs_.clear();
    state_ = State::merging;
    if (options_.threads >= 2 && out_bytes_ / record_bytes_ >= 2) start_merger();
    return {};
  }

  Result<std::span<const std::byte>> next() override {
    assert(state_ != State::input && "RecordSorter::next before finish()");
    Stopwatch watch(stats_.seconds);
    const std::size_t max = out_bytes_ / record_bytes_;
    std::size_t n = 0;
    if (state_ == State::in_core) {
      n = sorted_.emit(out_.get(), out_keys_.get(), max);
      if (sorted_.exhausted()) run_.release();
    } else if (merger_.joinable()) {
      return next_merged();
    } else {
      auto emitted = final_.emit(out_.get(), out_keys_.get(), max);
      if (!emitted.ok()) return emitted.status();
      n = emitted.value();
    }
    out_key_count_ = n;
    out_key_first_ = 0;
    return std::span<const std::byte>(out_.get(), n * record_bytes_);
  }

  std::span<const std::uint64_t> keys() const override {
    return std::span<const std::uint64_t>(out_keys_.get() + out_key_first_, out_key_count_);
  }

  const SortStats& stats() const override { return stats_; }
  std::size_t record_bytes() const override { return record_bytes_; }

 private:
  enum class State { input, in_core, merging };

  // The final merge on a helper thread (threads >= 2): the output buffer works as two halves,
  // the helper filling one while the caller consumes the other, so merging overlaps with the
  // caller's work on the records. The blocks come in the same order as without it.
  void start_merger() {
    merge_block_records_ = out_bytes_ / record_bytes_ / 2;
    merger_ = std::thread([this] {
      for (std::size_t b = 0;; b ^= 1) {
        {
          std::unique_lock lock(merge_mutex_);
          merge_cv_.wait(lock, [&] { return merge_stop_ || !block_busy_[b]; });
          if (merge_stop_) return;
          block_busy_[b] = true;
        }
        auto emitted = final_.emit(out_.get() + b * merge_block_records_ * record_bytes_,
                                   out_keys_.get() + b * merge_block_records_,
                                   merge_block_records_);
        {
          std::lock_guard lock(merge_mutex_);
          block_ready_[b] = true;
          block_records_[b] = emitted.ok() ? emitted.value() : 0;
          if (!emitted.ok()) merge_status_ = emitted.status();
        }
        merge_cv_.notify_all();
        if (!emitted.ok() || emitted.value() == 0) return;
      }
    });
  }

  // next() with the merger running: hands back the block handed out last, takes the next.
  Result<std::span<const std::byte>> next_merged() {
    std::size_t n = 0;
    Status status;
    {
      std::unique_lock lock(merge_mutex_);
      if (handed_out_ >= 0) block_busy_[handed_out_] = false;
      merge_cv_.notify_all();
      const int b = next_block_;
      merge_cv_.wait(lock, [&] { return block_ready_[b]; });
      block_ready_[b] = false;
      n = block_records_[b];
      status = merge_status_;
      handed_out_ = b;
      next_block_ = b ^ 1;
    }
    if (!status.ok() || n == 0) merger_.join();  // the helper has stopped
    if (!status.ok()) return status;
    out_key_count_ = n;
    out_key_first_ = static_cast<std::size_t>(handed_out_) * merge_block_records_;
    return std::span<const std::byte>(out_.get() + out_key_first_ * record_bytes_,
                                      n * record_bytes_);
  }

  void stop_merger() {
    if (!merger_.joinable()) return;
    {
      std::lock_guard lock(merge_mutex_);
      merge_stop_ = true;
    }
    merge_cv_.notify_all();
    merger_.join();
  }

  // The filled part of the run buffer must go to disk before more records fit. With one thread,
  // or for the first run (so that everything up to the full buffer stays in core), the whole
  // buffer is sorted and written now. After that, with two threads, the buffer is used as two
  // halves: one is sorted and written by a helper thread while the caller fills the other.
  Status make_room() {
    if (options_.threads < 2 || runs_.empty()) {
      OCTOLOD_RETURN_IF_ERROR(wait_for_spill());
      OCTOLOD_RETURN_IF_ERROR(spill_now(fill_begin_, fill_count_));
      if (options_.threads >= 2) fill_limit_ = run_capacity_ / 2;
      fill_begin_ = 0;
      fill_count_ = 0;
      return {};
    }
    OCTOLOD_RETURN_IF_ERROR(wait_for_spill());
    const std::size_t begin = fill_begin_;
    const std::size_t count = fill_count_;
    spill_file_ = make_temp_file(options_.work_dir, "run");
    spiller_ = std::thread([this, begin, count] {
      spill_status_ = write_run(run_.sort(begin, count, key_, false), spill_file_.path());
    });
    spill_records_ = count;
    fill_begin_ = begin == 0 ? fill_limit_ : 0;
    fill_count_ = 0;
    return {};
  }

  // Waits for the helper thread's run, if any, and adopts it.
  Status wait_for_spill() {
    if (!spiller_.joinable()) return {};
    spiller_.join();
    if (!spill_status_.ok()) {
      spill_file_.remove();
      return spill_status_;
    }
    adopt_run(std::move(spill_file_), spill_records_);
    return {};
  }

  // Sorts records [begin, begin + count) of the run buffer and writes them as a run, now.
  Status spill_now(std::size_t begin, std::size_t count) {
    TempFile file = make_temp_file(options_.work_dir, "run");
    OCTOLOD_RETURN_IF_ERROR(
        write_run(run_.sort(begin, count, key_, options_.threads >= 2), file.path()));
    adopt_run(std::move(file), count);
    return {};
  }

  void adopt_run(TempFile file, std::size_t records) {
    stats_.bytes_written += records * record_bytes_;
    ++stats_.runs;
    runs_.push_back(std::move(file));
  }

  Status write_run(SortedRun run, const std::filesystem::path& path) const {
    auto writer = RecordWriter::create(path, record_bytes_, out_bytes_);
    if (!writer.ok()) return writer.status();
    while (!run.exhausted()) {
      auto space = writer->reserve(SIZE_MAX);
      if (!space.ok()) return space.status();
      writer->commit(run.emit(space->data(), nullptr, space->size() / record_bytes_));
    }
    return writer->finish();
  }

  // Memory left for merge inputs once the output buffer and its keys are taken.
  std::size_t merge_bytes() const {
    return static_cast<std::size_t>(options_.memory_budget_bytes) - out_bytes_ -
           out_bytes_ / record_bytes_ * sizeof(std::uint64_t);
  }
  // Bytes one merge input costs with a block of `block` bytes: the block plus its keys.
  std::size_t input_cost(std::size_t block) const {
    return block + block / record_bytes_ * sizeof(std::uint64_t);
  }
  std::size_t min_block() const {
    return std::max<std::size_t>(1, kMinBlockBytes / record_bytes_) * record_bytes_;
  }
  std::size_t max_fan_in() const { return merge_bytes() / input_cost(min_block()); }
  // The largest block (whole records, at most max_io_buffer_bytes) for merging `k` runs.
  std::size_t block_bytes(std::size_t k) const {
    const std::size_t per_input = merge_bytes() / std::max<std::size_t>(k, 1);
    std::size_t records = per_input / (record_bytes_ + sizeof(std::uint64_t));
    records = std::min(records, std::max<std::size_t>(1, options_.max_io_buffer_bytes / record_bytes_));
    return std::max<std::size_t>(records, 1) * record_bytes_;
  }

  // Intermediate passes: merges groups of consecutive runs (so ties keep their input order)
  // until the final merge can take all remaining runs at once. Each group is as large as the
  // fan-in allows but no larger than needed to reach that count.
  Status merge_down() {
    const std::size_t k = max_fan_in();
    assert(k >= 2 && "the budget check in create() guarantees a fan-in of two");
    std::size_t pos = 0;
    while (runs_.size() > k) {
      if (pos == 0) ++stats_.merge_passes;
      const std::size_t group = std::min({k, runs_.size() - k + 1, runs_.size() - pos});
      if (group < 2) {  // one run left at the end of this pass: start the next pass
        pos = 0;
        continue;
      }
      std::vector<TempFile> inputs;
      for (std::size_t i = 0; i < group; ++i) inputs.push_back(std::move(runs_[pos + i]));
      runs_.erase(runs_.begin() + static_cast<std::ptrdiff_t>(pos),
                  runs_.begin() + static_cast<std::ptrdiff_t>(pos + group));
      stats_.fan_in = std::max(stats_.fan_in, static_cast<std::uint32_t>(group));
      TempFile merged = make_temp_file(options_.work_dir, "run");
      OCTOLOD_RETURN_IF_ERROR(merge_to_file(std::move(inputs), merged.path()));
      runs_.insert(runs_.begin() + static_cast<std::ptrdiff_t>(pos), std::move(merged));
      if (++pos >= runs_.size()) pos = 0;
    }
    return {};
  }

  Status merge_to_file(std::vector<TempFile> inputs, const std::filesystem::path& path) {
    KWayMerge merge;
    const std::size_t k = inputs.size();
    OCTOLOD_RETURN_IF_ERROR(merge.open(std::move(inputs), record_bytes_, block_bytes(k), &key_,
                                       &stats_));
    auto writer = RecordWriter::create(path, record_bytes_, out_bytes_);
    if (!writer.ok()) return writer.status();
    while (!merge.empty()) {
      auto space = writer->reserve(SIZE_MAX);
      if (!space.ok()) return space.status();
      auto n = merge.emit(space->data(), nullptr, space->size() / record_bytes_);
      if (!n.ok()) return n.status();
      writer->commit(n.value());
      stats_.bytes_written += n.value() * record_bytes_;
    }
    return writer->finish();
  }

  std::size_t record_bytes_;
  SortKeyFn key_;
  SortOptions options_;
  std::size_t out_bytes_;     // output / run writer buffer
  std::size_t run_capacity_;  // records in the run buffer
  State state_ = State::input;
  RunBuffer run_;
  // The part of the run buffer being filled: records [fill_begin_, fill_begin_ + fill_limit_).
  std::size_t fill_begin_ = 0;
  std::size_t fill_limit_ = 0;
  std::size_t fill_count_ = 0;
  // The run the helper thread is sorting and writing (threads >= 2).
  std::thread spiller_;
  TempFile spill_file_;
  std::size_t spill_records_ = 0;
  Status spill_status_;
  SortedRun sorted_;  // the in-core fast path's output
  std::vector<TempFile> runs_;
  KWayMerge final_;
  PageArray<std::byte> out_;
  PageArray<std::uint64_t> out_keys_;  // keys of the records in out_
  std::size_t out_key_first_ = 0;      // the block next() returned last: its first record
  std::size_t out_key_count_ = 0;      // and its record count
  // The merger thread (start_merger) and its two blocks of out_, guarded by merge_mutex_:
  // busy while the merger fills it or the caller holds it, ready once filled and not yet taken.
  std::thread merger_;
  std::mutex merge_mutex_;
  std::condition_variable merge_cv_;
  std::size_t merge_block_records_ = 0;
  bool block_busy_[2] = {false, false};
  bool block_ready_[2] = {false, false};
  std::size_t block_records_[2] = {0, 0};
  Status merge_status_;
  bool merge_stop_ = false;
  int handed_out_ = -1;  // block the caller holds (caller's thread only)
  int next_block_ = 0;   // block the caller takes next (caller's thread only)
  SortStats stats_;
};

}  // namespace

Status RecordSorter::push(std::span<const std::byte> records) {
  assert(records.size() % record_bytes() == 0 && "RecordSorter::push of a partial record");
  const std::size_t record_bytes = this->record_bytes();
  std::size_t n = records.size() / record_bytes;
  const std::byte* src = records.data();
  while (n > 0) {
    auto space = reserve(n);
    if (!space.ok()) return space.status();
    std::memcpy(space->data(), src, space->size());
    const std::size_t take = space->size() / record_bytes;
    commit(take);
    src += space->size();
    n -= take;
  }
  return {};
}

SortKeyFn sort_key_u32_at(std::size_t offset, std::size_t record_bytes) {
  assert(offset + 4 <= record_bytes && "sort key beyond the record");
  return [offset, record_bytes](std::span<const std::byte> records,
                                std::span<std::uint64_t> keys) {
    const std::byte* p = records.data() + offset;
    for (std::size_t i = 0; i < keys.size(); ++i, p += record_bytes) {
      std::uint32_t v;
      std::memcpy(&v, p, sizeof v);
      keys[i] = v;
    }
  };
}

SortKeyFn sort_key_u64_at(std::size_t offset, std::size_t record_bytes) {
  assert(offset + 8 <= record_bytes && "sort key beyond the record");
  return [offset, record_bytes](std::span<const std::byte> records,
                                std::span<std::uint64_t> keys) {
    const std::byte* p = records.data() + offset;
    for (std::size_t i = 0; i < keys.size(); ++i, p += record_bytes) {
      std::memcpy(&keys[i], p, sizeof(std::uint64_t));
    }
  };
}

Result<std::unique_ptr<RecordSorter>> RecordSorter::create(std::size_t record_bytes,
                                                           SortKeyFn key,
                                                           const SortOptions& options) {
  assert(record_bytes > 0 && key && "RecordSorter needs a record size and a key function");
  const std::uint64_t budget = options.memory_budget_bytes;
  const auto too_small = [&] {
    return usage_error("sort memory budget of " + std::to_string(budget) +
                       " bytes is too small for " + std::to_string(record_bytes) +
                       "-byte records");
  };
  if (budget < kMinBudget || budget > std::numeric_limits<std::size_t>::max() / 2) {
    return too_small();
  }
  // Output / run writer buffer: an eighth of the budget, within [4 KiB, max_io_buffer_bytes].
  std::size_t out_bytes = std::clamp<std::size_t>(static_cast<std::size_t>(budget / 8),
                                                  kMinBlockBytes,
                                                  std::max(options.max_io_buffer_bytes, kMinBlockBytes));
  out_bytes = std::max<std::size_t>(1, out_bytes / record_bytes) * record_bytes;
  // The output buffer's keys (RecordSorter::keys()) come with it.
  const std::size_t out_total = out_bytes + out_bytes / record_bytes * sizeof(std::uint64_t);
  if (out_total >= budget) return too_small();
  const std::size_t rest = static_cast<std::size_t>(budget) - out_total;
  const std::size_t run_capacity =
      std::min<std::size_t>(rest / (record_bytes + kRunOverhead),
                            std::numeric_limits<std::uint32_t>::max());
  const std::size_t min_block = std::max<std::size_t>(1, kMinBlockBytes / record_bytes) * record_bytes;
  const std::size_t fan_in = rest / (min_block + min_block / record_bytes * sizeof(std::uint64_t));
  if (run_capacity < 2 || fan_in < 2) return too_small();
  return std::unique_ptr<RecordSorter>(
      new ExternalSorter(record_bytes, std::move(key), options, out_bytes, run_capacity));
}

Result<SortStats> sort_records(const std::filesystem::path& in, const std::filesystem::path& out,
                               std::size_t record_bytes, SortKeyFn key,
                               const SortOptions& options) {
  // The input reader and output writer take a sixteenth of the budget each.
  const std::size_t io = std::clamp<std::size_t>(
      static_cast<std::size_t>(options.memory_budget_bytes / 16), kMinBlockBytes,
      std::max(options.max_io_buffer_bytes, kMinBlockBytes));
  SortOptions sorter_options = options;
  if (options.memory_budget_bytes <= 2 * io) {
    return usage_error("sort memory budget of " + std::to_string(options.memory_budget_bytes) +
                       " bytes is too small");
  }
  sorter_options.memory_budget_bytes = options.memory_budget_bytes - 2 * io;
  auto sorter = RecordSorter::create(record_bytes, std::move(key), sorter_options);
  if (!sorter.ok()) return sorter.status();
  RecordSorter& s = *sorter.value();
  {
    auto reader = RecordReader::open(in, record_bytes, io);
    if (!reader.ok()) return reader.status();
    for (;;) {
      auto block = reader->read();
      if (!block.ok()) return block.status();
      if (block->empty()) break;
      OCTOLOD_RETURN_IF_ERROR(s.push(block.value()));
    }
  }
  OCTOLOD_RETURN_IF_ERROR(s.finish());
  auto writer = RecordWriter::create(out, record_bytes, io);
  if (!writer.ok()) return writer.status();
  for (;;) {
    auto block = s.next();
    if (!block.ok()) {
      std::error_code ignored;
      std::filesystem::remove(out, ignored);
      return block.status();
    }
    if (block->empty()) break;
    Status st = writer->append(block->data(), block->size() / record_bytes);
    if (!st.ok()) {
      std::error_code ignored;
      std::filesystem::remove(out, ignored);
      return st;
    }
  }
  Status st = writer->finish();
  if (!st.ok()) {
    std::error_code ignored;
    std::filesystem::remove(out, ignored);
    return st;
  }
  return s.stats();
}

}  // namespace octolod::bake
