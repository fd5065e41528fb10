// External MSD radix sort (bucket_sort.h): records distributed into bucket files by the top
// bits of their key, each bucket read back whole and radix sorted in memory.
#include "bucket_sort.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstring>
#include <optional>
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

constexpr unsigned kMaxFanBits = 9;              // 512 buckets per level
constexpr std::size_t kMinWriterBytes = 4096;    // a bucket file's buffer, at least
constexpr std::size_t kMaxWriterBytes = 1 << 20;  // ... and at most
constexpr std::size_t kMaxBlockBytes = 1 << 20;   // next()'s blocks, at most
// Bytes per record held in memory for sorting: its key and order, each with radix scratch.
constexpr std::size_t kSortBytes = 2 * (sizeof(std::uint64_t) + sizeof(std::uint32_t));

// A bucket file: records of the bucket's prefix, in input order.
struct Bucket {
  TempFile file;
  std::uint64_t records = 0;
  unsigned low_bits = 0;  // key bits below the bucket's prefix (0: its keys are all equal)
};

// The buckets of one distribution, in key order; `next` is the first not yet taken.
struct Level {
  std::vector<Bucket> buckets;
  std::size_t next = 0;
};

// A bucket in memory, sorted: records[order[k]] with key keys[k], k in [pos, count).
struct Sorted {
  const std::byte* records = nullptr;
  const std::uint64_t* keys = nullptr;
  const std::uint32_t* order = nullptr;
  std::size_t count = 0;
  std::size_t pos = 0;
};

class BucketSorter final : public RecordSorter {
 public:
  struct Sizes {
    std::size_t stage_records = 0;  // the stage, and the largest bucket sorted in memory
    std::size_t output_stage_records = 0;  // the same after finish() (>= stage_records)
    std::size_t block_records = 0;  // next()'s blocks, and reads of a bucket distributed again
    unsigned fan_bits = 0;          // log2 of the buckets per level
    std::size_t writer_bytes = 0;   // each bucket file's buffer
  };

  BucketSorter(std::size_t record_bytes, SortKeyFn key, unsigned key_bits,
               const SortOptions& options, const Sizes& sizes)
      : record_bytes_(record_bytes),
        key_(std::move(key)),
        key_bits_(key_bits),
        options_(options),
        sizes_(sizes) {}
  ~BucketSorter() override {
    if (distributor_.joinable()) distributor_.join();
    if (loader_.joinable()) loader_.join();
  }
  BucketSorter(const BucketSorter&) = delete;
  BucketSorter& operator=(const BucketSorter&) = delete;

  Result<std::span<std::byte>> reserve(std::size_t max_records) override {
    assert(!finished_ && "RecordSorter::reserve after finish()");
    const Stopwatch watch(stats_.seconds);
    if (!stage_.get()) {
      allocate_arrays();
      fill_limit_ = sizes_.stage_records;
    }
    if (staged_ == fill_limit_) OCTOLOD_RETURN_IF_ERROR(make_room());
    const std::size_t n = std::min(max_records, fill_limit_ - staged_);
    return std::span<std::byte>(stage_.get() + (fill_begin_ + staged_) * record_bytes_,
                                n * record_bytes_);
  }

  void commit(std::size_t records) override {
    assert(staged_ + records <= fill_limit_ && "RecordSorter::commit beyond reserve()");
    // The keys now, while the records are in the cache (and off the distributing thread).
    const std::size_t first = fill_begin_ + staged_;
    key_(std::span<const std::byte>(stage_.get() + first * record_bytes_, records * record_bytes_),
         std::span<std::uint64_t>(keys_.get() + first, records));
    staged_ += records;
    stats_.records += records;
  }

  Status finish() override {
    assert(!finished_ && "RecordSorter::finish called twice");
    const Stopwatch watch(stats_.seconds);
    finished_ = true;
    OCTOLOD_RETURN_IF_ERROR(wait_for_distributor());
    if (writers_.empty()) {  // everything is in the stage: sort it there
      stats_.in_core = true;
      if (staged_ > 0) current_ = sort_in_place(stage_.get(), staged_, 0, /*keys_known=*/true);
      return {};
    }
    OCTOLOD_RETURN_IF_ERROR(distribute(stage_.get() + fill_begin_ * record_bytes_, staged_,
                                       keys_.get() + fill_begin_));
    staged_ = 0;
    OCTOLOD_RETURN_IF_ERROR(close_level(key_bits_));
    if (sizes_.output_stage_records > sizes_.stage_records) {  // the caller freed memory
      sizes_.stage_records = sizes_.output_stage_records;
      allocate_arrays();
    }
    return {};
  }

  Result<std::span<const std::byte>> next() override {
    assert(finished_ && "RecordSorter::next before finish()");
    const Stopwatch watch(stats_.seconds);
    for (;;) {
      if (current_.pos < current_.count) {
        OCTOLOD_RETURN_IF_ERROR(prefetch());
        return emit_current();
      }
      if (stream_) {
        auto block = stream_->read(sizes_.block_records);
        if (!block.ok()) return block.status();
        if (!block->empty()) {
          stats_.bytes_read += block->size();
          out_count_ = block->size() / record_bytes_;
          key_(block.value(), std::span<std::uint64_t>(out_keys_.get(), out_count_));
          return block.value();
        }
        stream_.reset();
        stream_file_.remove();
      }
      if (loader_.joinable()) {  // the next bucket, loaded meanwhile
        loader_.join();
        if (!loader_status_.ok()) return loader_status_;
        current_ = loaded_;
        current_half_ = 1 - current_half_;
        ++current_serial_;
        continue;
      }
      Bucket* bucket = next_bucket();
      if (!bucket) {
        out_count_ = 0;
        return std::span<const std::byte>();
      }
      Bucket taken = std::move(*bucket);
      if (taken.records <= sizes_.stage_records) {
        // The first half, or the whole stage for a bucket larger than half of it.
        current_half_ = 0;
        auto loaded = load(std::move(taken), 0, sizes_.stage_records);
        if (!loaded.ok()) return loaded.status();
        current_ = loaded.value();
        ++current_serial_;
      } else if (taken.low_bits == 0) {
        auto reader = RecordReader::open(taken.file.path(), record_bytes_,
                                         sizes_.block_records * record_bytes_);
        if (!reader.ok()) return reader.status();
        stream_.emplace(std::move(reader).value());
        stream_file_ = std::move(taken.file);
      } else {
        OCTOLOD_RETURN_IF_ERROR(distribute_again(std::move(taken)));
      }
    }
  }

  std::span<const std::uint64_t> keys() const override {
    return std::span<const std::uint64_t>(out_keys_.get(), out_count_);
  }
  const SortStats& stats() const override { return stats_; }
  std::size_t record_bytes() const override { return record_bytes_; }

 private:
  void allocate_arrays() {  // (re)allocates the stage and the sort arrays for stage_records
    const std::size_t n = sizes_.stage_records;
    stage_.reset();  // before the new arrays: the old and new never coexist
    keys_.reset();
    order_.reset();
    keys_tmp_.reset();
    order_tmp_.reset();
    stage_ = PageArray<std::byte>(n * record_bytes_);
    keys_ = PageArray<std::uint64_t>(n);
    order_ = PageArray<std::uint32_t>(n);
    keys_tmp_ = PageArray<std::uint64_t>(n);
    order_tmp_ = PageArray<std::uint32_t>(n);
    out_ = PageArray<std::byte>(sizes_.block_records * record_bytes_);
    out_keys_ = PageArray<std::uint64_t>(sizes_.block_records);
  }

  // The bucket of `key` in a distribution whose prefix ends above bit `shift`.
  std::size_t bucket_of(std::uint64_t key, unsigned shift, unsigned bits) const {
    return bits == 0 ? 0 : static_cast<std::size_t>((key >> shift) & ((std::uint64_t{1} << bits) - 1));
  }

  // Appends `count` records with their `keys` to the open level's bucket files. The runs of
  // consecutive records of one bucket are gathered per bucket first: a bucket with at least a
  // buffer's worth is written straight from `records` (writev), a smaller share is buffered.
  Status distribute(const std::byte* records, std::size_t count, const std::uint64_t* keys) {
    runs_.resize(writers_.size());
    for (std::size_t i = 0; i < count;) {
      const std::size_t b = bucket_of(keys[i], shift_, bits_);
      std::size_t j = i + 1;
      while (j < count && bucket_of(keys[j], shift_, bits_) == b) ++j;
      runs_[b].emplace_back(records + i * record_bytes_, (j - i) * record_bytes_);
      i = j;
    }
    for (std::size_t b = 0; b < runs_.size(); ++b) {
      std::vector<std::span<const std::byte>>& runs = runs_[b];
      if (runs.empty()) continue;
      if (!writers_[b]) {
        files_[b] = make_temp_file(options_.work_dir, "bucket");
        auto writer = RecordWriter::create(files_[b].path(), record_bytes_, sizes_.writer_bytes);
        if (!writer.ok()) return writer.status();
        writers_[b].emplace(std::move(writer).value());
        ++stats_.runs;
      }
      std::size_t bytes = 0;
      for (const auto& run : runs) bytes += run.size();
      if (bytes >= sizes_.writer_bytes) {
        OCTOLOD_RETURN_IF_ERROR(writers_[b]->append_runs(runs));
      } else {
        for (const auto& run : runs)
          OCTOLOD_RETURN_IF_ERROR(writers_[b]->append(run.data(), run.size() / record_bytes_));
      }
      stats_.bytes_written += bytes;
      runs.clear();
    }
    return {};
  }

  // Opens a distribution of keys whose bits below `prefix_bits` are still to be used.
  void open_level(unsigned prefix_bits) {
    bits_ = std::min(sizes_.fan_bits, prefix_bits);
    shift_ = prefix_bits - bits_;
    writers_.clear();
    writers_.resize(std::size_t{1} << bits_);
    files_.clear();
    files_.resize(std::size_t{1} << bits_);
    const auto depth = static_cast<std::uint32_t>(levels_.size() + 1);
    stats_.fan_in = std::max(stats_.fan_in, static_cast<std::uint32_t>(writers_.size()));
    stats_.merge_passes = std::max(stats_.merge_passes, depth);
  }

  // The filled part of the stage must go to the bucket files before more records fit. With
  // one thread, or the first time (so that input up to the whole stage stays in core), the
  // whole stage is distributed now. After that, with two threads, the stage works as two
  // halves: a helper thread distributes one while the caller fills the other.
  Status make_room() {
    OCTOLOD_RETURN_IF_ERROR(wait_for_distributor());
    const std::size_t begin = fill_begin_;
    const std::size_t count = staged_;
    staged_ = 0;
    if (writers_.empty() || options_.threads < 2) {
      if (writers_.empty()) open_level(key_bits_);
      OCTOLOD_RETURN_IF_ERROR(distribute(stage_.get() + begin * record_bytes_, count,
                                         keys_.get() + begin));
      if (options_.threads >= 2) fill_limit_ = sizes_.stage_records / 2;
      fill_begin_ = 0;
      return {};
    }
    distributor_ = std::thread([this, begin, count] {
      distributor_status_ =
          distribute(stage_.get() + begin * record_bytes_, count, keys_.get() + begin);
    });
    fill_begin_ = begin == 0 ? fill_limit_ : 0;
    return {};
  }

  Status wait_for_distributor() {
    if (!distributor_.joinable()) return {};
    distributor_.join();
    return distributor_status_;
  }

  // Closes the open distribution's files and queues its buckets to be taken next.
  Status close_level(unsigned prefix_bits) {
    Level level;
    level.buckets.resize(writers_.size());
    for (std::size_t b = 0; b < writers_.size(); ++b) {
      if (!writers_[b]) continue;
      level.buckets[b].records = writers_[b]->records_written();
      OCTOLOD_RETURN_IF_ERROR(writers_[b]->finish());
      level.buckets[b].file = std::move(files_[b]);
      level.buckets[b].low_bits = prefix_bits - bits_;
    }
    writers_.clear();
    files_.clear();
    levels_.push_back(std::move(level));
    return {};
  }

  // A bucket too large for memory: distributed by its next bits, a stage at a time.
  Status distribute_again(Bucket bucket) {
    auto reader = RecordReader::open(bucket.file.path(), record_bytes_, record_bytes_);
    if (!reader.ok()) return reader.status();
    open_level(bucket.low_bits);
    const std::span<std::byte> stage(stage_.get(), sizes_.stage_records * record_bytes_);
    while (reader->records_left() > 0) {
      auto n = reader->read_into(stage);
      if (!n.ok()) return n.status();
      stats_.bytes_read += n.value() * record_bytes_;
      key_(std::span<const std::byte>(stage.data(), n.value() * record_bytes_),
           std::span<std::uint64_t>(keys_.get(), n.value()));
      OCTOLOD_RETURN_IF_ERROR(distribute(stage.data(), n.value(), keys_.get()));
    }
    bucket.file.remove();
    return close_level(bucket.low_bits);
  }

  // The next non-empty bucket to take, in key order (nullptr at the end): levels distributed
  // last come first.
  Bucket* next_bucket() {
    while (!levels_.empty()) {
      Level& level = levels_.back();
      while (level.next < level.buckets.size() && level.buckets[level.next].records == 0)
        ++level.next;
      if (level.next < level.buckets.size()) return &level.buckets[level.next++];
      levels_.pop_back();
    }
    return nullptr;
  }

  // With two threads, while the current bucket is handed out from one half of the stage, the
  // next one is read and sorted into the other half, if it fits there and needs no further
  // distribution.
  Status prefetch() {
    const std::size_t half = sizes_.stage_records / 2;
    if (options_.threads < 2 || loader_.joinable() || current_.count > half) return {};
    if (prefetched_for_ == current_serial_) return {};  // once per bucket
    prefetched_for_ = current_serial_;
    if (levels_.empty()) return {};
    Level& level = levels_.back();
    while (level.next < level.buckets.size() && level.buckets[level.next].records == 0)
      ++level.next;
    if (level.next == level.buckets.size() || level.buckets[level.next].records > half) return {};
    Bucket bucket = std::move(level.buckets[level.next++]);
    const std::size_t target = 1 - current_half_;
    loader_ = std::thread([this, target, b = std::move(bucket)]() mutable {
      auto loaded = load(std::move(b), target, sizes_.stage_records / 2);
      if (loaded.ok()) {
        loaded_ = loaded.value();
      } else {
        loader_status_ = loaded.status();
      }
    });
    return {};
  }

  // Reads a bucket whole into half `half` of the stage (capacity `capacity` records; half 0
  // with the whole stage's capacity for a large bucket) and sorts it there.
  Result<Sorted> load(Bucket bucket, std::size_t half, std::size_t capacity) {
    const std::size_t first = half * (sizes_.stage_records / 2);
    std::byte* records = stage_.get() + first * record_bytes_;
    auto reader = RecordReader::open(bucket.file.path(), record_bytes_, record_bytes_);
    if (!reader.ok()) return reader.status();
    if (reader->record_count() != bucket.records || bucket.records > capacity) {
      return io_error("bucket file '" + bucket.file.path().string() + "' holds " +
                      std::to_string(reader->record_count()) + " records, " +
                      std::to_string(bucket.records) + " were written");
    }
    // Read a block at a time, each block's keys computed while it is in the cache.
    const std::size_t count = static_cast<std::size_t>(bucket.records);
    for (std::size_t done = 0; done < count;) {
      const std::size_t want = std::min(sizes_.block_records, count - done);
      auto n = reader->read_into(
          std::span<std::byte>(records + done * record_bytes_, want * record_bytes_));
      if (!n.ok()) return n.status();
      key_(std::span<const std::byte>(records + done * record_bytes_, n.value() * record_bytes_),
           std::span<std::uint64_t>(keys_.get() + first + done, n.value()));
      done += n.value();
    }
    stats_.bytes_read += count * record_bytes_;
    bucket.file.remove();
    return sort_in_place(records, count, first, /*keys_known=*/true);
  }

  // Sorts `count` records using the sort arrays from entry `first` on (the keys there already
  // when `keys_known`).
  Sorted sort_in_place(const std::byte* records, std::size_t count, std::size_t first,
                       bool keys_known) {
    if (!keys_known) {
      key_(std::span<const std::byte>(records, count * record_bytes_),
           std::span<std::uint64_t>(keys_.get() + first, count));
    }
    std::uint64_t* keys = keys_.get() + first;
    std::uint32_t* order = order_.get() + first;
    std::uint64_t* keys_tmp = keys_tmp_.get() + first;
    std::uint32_t* order_tmp = order_tmp_.get() + first;
    for (std::size_t i = 0; i < count; ++i) order[i] = static_cast<std::uint32_t>(i);
    radix_sort(keys, order, keys_tmp, order_tmp, count);
    return Sorted{records, keys, order, count, 0};
  }

  std::span<const std::byte> emit_current() {
    const std::size_t n = std::min(sizes_.block_records, current_.count - current_.pos);
    std::byte* out = out_.get();
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = current_.pos + i;
      std::memcpy(out + i * record_bytes_,
                  current_.records + std::size_t{current_.order[k]} * record_bytes_,
                  record_bytes_);
      out_keys_[i] = current_.keys[k];
    }
    current_.pos += n;
    out_count_ = n;
    return std::span<const std::byte>(out, n * record_bytes_);
  }

  std::size_t record_bytes_;
  SortKeyFn key_;
  unsigned key_bits_;
  SortOptions options_;
  Sizes sizes_;
  SortStats stats_;
  bool finished_ = false;

  // The stage (input) or the bucket being handed out (output), with the sort arrays.
  PageArray<std::byte> stage_;
  PageArray<std::uint64_t> keys_;
  PageArray<std::uint32_t> order_;
  PageArray<std::uint64_t> keys_tmp_;
  PageArray<std::uint32_t> order_tmp_;
  // The part of the stage being filled: records [fill_begin_, fill_begin_ + fill_limit_),
  // staged_ of them filled.
  std::size_t fill_begin_ = 0;
  std::size_t fill_limit_ = 0;
  std::size_t staged_ = 0;
  // The helper thread distributing the other half of the stage (threads >= 2).
  std::thread distributor_;
  Status distributor_status_;

  // The distribution being written: a writer per bucket, opened with its first record.
  std::vector<std::optional<RecordWriter>> writers_;
  std::vector<TempFile> files_;
  unsigned bits_ = 0;   // its bucket index bits
  unsigned shift_ = 0;  // bits below them

  std::vector<Level> levels_;  // distributions with buckets still to take, outermost first
  std::vector<std::vector<std::span<const std::byte>>> runs_;  // distribute()'s, per bucket

  // The bucket being handed out, in half current_half_ of the stage (0 when it takes all).
  Sorted current_;
  std::size_t current_half_ = 0;
  // The helper thread loading the next bucket into the other half (threads >= 2).
  std::thread loader_;
  Sorted loaded_;
  Status loader_status_;
  std::uint64_t current_serial_ = 0;  // counts the buckets taken
  std::uint64_t prefetched_for_ = 0;  // the bucket (serial) the last prefetch started under
  // A bucket of one key too large for memory, handed out as read.
  std::optional<RecordReader> stream_;
  TempFile stream_file_;

  PageArray<std::byte> out_;
  PageArray<std::uint64_t> out_keys_;
  std::size_t out_count_ = 0;
};

}  // namespace

Result<std::unique_ptr<RecordSorter>> create_bucket_sorter(std::size_t record_bytes, SortKeyFn key,
                                                           unsigned key_bits,
                                                           const SortOptions& options,
                                                           std::uint64_t output_budget_bytes) {
  assert(record_bytes > 0 && key && key_bits <= 64 && "create_bucket_sorter: bad arguments");
  const std::uint64_t budget = options.memory_budget_bytes;
  const auto too_small = [&] {
    return usage_error("sort memory budget of " + std::to_string(budget) +
                       " bytes is too small for " + std::to_string(record_bytes) +
                       "-byte records");
  };
  // A quarter of the budget for the bucket files' buffers, the rest for the stage (the largest
  // bucket sorted in memory) with its sort arrays and next()'s block.
  const std::uint64_t stage_budget = budget - budget / 4;
  BucketSorter::Sizes sizes;
  sizes.block_records = static_cast<std::size_t>(
      std::clamp<std::uint64_t>(budget / 16 / record_bytes, 1, kMaxBlockBytes / record_bytes + 1));
  const std::uint64_t block_bytes = sizes.block_records * (record_bytes + sizeof(std::uint64_t));
  if (block_bytes >= stage_budget) return too_small();
  // The stage's records for a budget: a quarter left for the bucket files' buffers (of the
  // input phase's size, also when a bucket is distributed again after finish()).
  const auto stage_records = [&](std::uint64_t b) {
    return static_cast<std::size_t>(std::min<std::uint64_t>(
        (b - budget / 4 - block_bytes) / (record_bytes + kSortBytes), std::uint64_t{1} << 31));
  };
  sizes.stage_records = stage_records(budget);
  sizes.output_stage_records =
      std::max(sizes.stage_records, stage_records(std::max(budget, output_budget_bytes)));
  const std::size_t writer_min = std::max(kMinWriterBytes, record_bytes);
  const std::uint64_t fan = std::min<std::uint64_t>(std::uint64_t{1} << kMaxFanBits,
                                                    (budget - stage_budget) / writer_min);
  if (sizes.stage_records < 2 || fan < 2) return too_small();
  sizes.fan_bits = static_cast<unsigned>(std::bit_width(fan) - 1);
  sizes.writer_bytes = static_cast<std::size_t>(std::min<std::uint64_t>(
      (budget - stage_budget) >> sizes.fan_bits, kMaxWriterBytes));
  return std::unique_ptr<RecordSorter>(
      new BucketSorter(record_bytes, std::move(key), key_bits, options, sizes));
}

}  // namespace octolod::bake
