// External k-way merge sort (seed 3.3, 4.2.2) and the bucket (MSD radix) sort for bounded keys:
// sorted and stable output on the in-core fast path and the external paths (multi-pass merges,
// buckets distributed again, with tiny budgets), identical for any budget and thread count,
// temporary files gone when the sort is done or fails (simulated ENOSPC, EIO).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "bucket_sort.h"
#include "octolod/bake/external_sort.h"
#include "record_file.h"

namespace octolod::bake {
namespace {

// A fresh, empty work directory per test, removed afterwards.
class WorkDir {
 public:
  explicit WorkDir(const std::string& suffix = "") {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("octolod-sort-" + std::to_string(::getpid()) + "-" + info->name() + suffix);
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~WorkDir() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }
  std::size_t file_count() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(path_),
                                                  std::filesystem::directory_iterator()));
  }

 private:
  std::filesystem::path path_;
};

// 24-byte test record: a key, its input position (to check stability) and a payload derived
// from both (to check records travel whole).
struct Rec {
  std::uint32_t key;
  std::uint32_t seq;
  std::uint64_t payload;
  std::uint64_t check;
};
static_assert(sizeof(Rec) == 24);

std::vector<Rec> make_records(std::size_t n, std::uint32_t distinct_keys, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Rec> v(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t key = static_cast<std::uint32_t>(rng() % distinct_keys);
    const auto seq = static_cast<std::uint32_t>(i);
    v[i] = Rec{key, seq, std::uint64_t{key} * 1000003u + seq, ~(std::uint64_t{seq} << 7)};
  }
  return v;
}

std::vector<Rec> stable_sorted(std::vector<Rec> v) {
  std::stable_sort(v.begin(), v.end(), [](const Rec& a, const Rec& b) { return a.key < b.key; });
  return v;
}

struct SortRun {
  std::vector<Rec> out;
  SortStats stats;
};

using SorterFactory =
    std::function<Result<std::unique_ptr<RecordSorter>>(const SortOptions& options)>;

Result<std::unique_ptr<RecordSorter>> merge_sorter(const SortOptions& options) {
  return RecordSorter::create(sizeof(Rec), sort_key_u32_at(0, sizeof(Rec)), options);
}

// A bucket sorter for keys below 2^key_bits.
SorterFactory bucket_sorter(unsigned key_bits) {
  return [key_bits](const SortOptions& options) {
    return create_bucket_sorter(sizeof(Rec), sort_key_u32_at(0, sizeof(Rec)), key_bits, options);
  };
}

// Pushes `in` in uneven chunks, then drains the sorter, checking RecordSorter::keys().
SortRun run_sorter(const std::vector<Rec>& in, const SortOptions& options,
                   const SorterFactory& make = merge_sorter) {
  SortRun run;
  auto sorter = make(options);
  EXPECT_TRUE(sorter.ok()) << sorter.status().message();
  if (!sorter.ok()) return run;
  std::size_t pos = 0;
  std::size_t chunk = 1;
  while (pos < in.size()) {
    const std::size_t n = std::min(chunk, in.size() - pos);
    const Status st = sorter.value()->push(std::as_bytes(std::span<const Rec>(in.data() + pos, n)));
    EXPECT_TRUE(st.ok()) << st.message();
    pos += n;
    chunk = chunk * 3 + 1;
  }
  const Status st = sorter.value()->finish();
  EXPECT_TRUE(st.ok()) << st.message();
  for (;;) {
    auto block = sorter.value()->next();
    EXPECT_TRUE(block.ok()) << block.status().message();
    if (!block.ok() || block->empty()) break;
    const std::size_t n = block->size() / sizeof(Rec);
    const std::size_t old = run.out.size();
    run.out.resize(old + n);
    std::memcpy(run.out.data() + old, block->data(), block->size());
    // keys() hands back each returned record's key, in core or merged.
    const std::span<const std::uint64_t> keys = sorter.value()->keys();
    EXPECT_EQ(keys.size(), n);
    for (std::size_t i = 0; i < std::min(n, keys.size()); ++i)
      EXPECT_EQ(keys[i], run.out[old + i].key) << "record " << old + i;
  }
  run.stats = sorter.value()->stats();
  return run;
}

bool same(const std::vector<Rec>& a, const std::vector<Rec>& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), a.size() * sizeof(Rec)) == 0;
}

// Input that fits the budget: sorted in memory, no temporary file.
void expect_sorted_in_core(const SorterFactory& make, std::uint32_t seed) {
  WorkDir dir;
  const auto in = make_records(5000, 300, seed);
  SortOptions options;
  options.memory_budget_bytes = 4 << 20;
  options.work_dir = dir.path();
  const SortRun run = run_sorter(in, options, make);
  EXPECT_TRUE(same(run.out, stable_sorted(in)));
  EXPECT_TRUE(run.stats.in_core);
  EXPECT_EQ(run.stats.runs, 0u);
  EXPECT_EQ(run.stats.merge_passes, 0u);
  EXPECT_EQ(run.stats.bytes_written, 0u);
  EXPECT_EQ(run.stats.records, in.size());
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(ExternalSort, FitsBudgetSortsInCoreWithoutTempFiles) { expect_sorted_in_core(merge_sorter, 1); }

TEST(ExternalSort, TinyBudgetMergesInSeveralPassesAndStaysStable) {
  WorkDir dir;
  const auto in = make_records(60000, 97, 2);  // many equal keys: stability matters
  SortOptions options;
  options.memory_budget_bytes = 16 << 10;
  options.work_dir = dir.path();
  const SortRun run = run_sorter(in, options);
  EXPECT_TRUE(same(run.out, stable_sorted(in)));
  EXPECT_FALSE(run.stats.in_core);
  EXPECT_GT(run.stats.runs, 100u);
  EXPECT_GE(run.stats.merge_passes, 2u);
  EXPECT_GT(run.stats.fan_in, 1u);
  // Run formation writes everything once, intermediate merge passes rewrite part of it.
  EXPECT_GT(run.stats.bytes_written, in.size() * sizeof(Rec));
  EXPECT_EQ(run.stats.bytes_read, run.stats.bytes_written);
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(ExternalSort, OneMergePassWhenFanInSuffices) {
  WorkDir dir;
  const auto in = make_records(100000, 1u << 30, 3);
  SortOptions options;
  options.memory_budget_bytes = 1 << 20;
  options.work_dir = dir.path();
  const SortRun run = run_sorter(in, options);
  EXPECT_TRUE(same(run.out, stable_sorted(in)));
  EXPECT_GT(run.stats.runs, 2u);
  EXPECT_EQ(run.stats.merge_passes, 1u);
  EXPECT_EQ(run.stats.fan_in, run.stats.runs);
  EXPECT_EQ(run.stats.bytes_written, in.size() * sizeof(Rec));
}

TEST(ExternalSort, OutputIsTheSameForAnyBudgetAndThreadCount) {
  WorkDir dir;
  // Enough records that a run is sorted as two halves on two threads.
  const auto in = make_records(300000, 5000, 4);
  const auto expected = stable_sorted(in);
  for (const std::uint64_t budget : {std::uint64_t{64} << 10, std::uint64_t{1} << 20,
                                     std::uint64_t{64} << 20}) {
    for (const unsigned threads : {1u, 2u}) {
      SortOptions options;
      options.memory_budget_bytes = budget;
      options.threads = threads;
      options.work_dir = dir.path();
      const SortRun run = run_sorter(in, options);
      EXPECT_TRUE(same(run.out, expected)) << "budget " << budget << " threads " << threads;
      EXPECT_EQ(run.stats.in_core, budget == (std::uint64_t{64} << 20));
    }
  }
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(ExternalSort, SixtyFourBitKeysSortByAllBytes) {
  WorkDir dir;
  std::mt19937_64 rng(5);
  std::vector<std::uint64_t> in(20000);
  for (auto& v : in) v = rng() >> (rng() % 64);  // magnitudes across every byte
  SortOptions options;
  options.memory_budget_bytes = 32 << 10;
  options.work_dir = dir.path();
  auto sorter = RecordSorter::create(8, sort_key_u64_at(0, 8), options);
  ASSERT_TRUE(sorter.ok());
  ASSERT_TRUE(sorter.value()->push(std::as_bytes(std::span<const std::uint64_t>(in))).ok());
  ASSERT_TRUE(sorter.value()->finish().ok());
  std::vector<std::uint64_t> out;
  for (;;) {
    auto block = sorter.value()->next();
    ASSERT_TRUE(block.ok());
    if (block->empty()) break;
    const std::size_t old = out.size();
    out.resize(old + block->size() / 8);
    std::memcpy(out.data() + old, block->data(), block->size());
  }
  std::sort(in.begin(), in.end());
  EXPECT_EQ(out, in);
}

TEST(ExternalSort, EmptyInputGivesEmptyOutput) {
  WorkDir dir;
  SortOptions options;
  options.work_dir = dir.path();
  const SortRun run = run_sorter({}, options);
  EXPECT_TRUE(run.out.empty());
  EXPECT_TRUE(run.stats.in_core);
}

TEST(ExternalSort, BudgetTooSmallIsAUsageError) {
  SortOptions options;
  options.memory_budget_bytes = 1000;
  auto sorter = RecordSorter::create(16, sort_key_u32_at(0, 16), options);
  ASSERT_FALSE(sorter.ok());
  EXPECT_EQ(sorter.status().code(), ErrorCode::usage);
  options.memory_budget_bytes = 16 << 10;
  auto huge = RecordSorter::create(12000, sort_key_u32_at(0, 12000), options);
  ASSERT_FALSE(huge.ok());
  EXPECT_EQ(huge.status().code(), ErrorCode::usage);
}

void write_file(const std::filesystem::path& path, const std::vector<Rec>& records) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(records.data()),
            static_cast<std::streamsize>(records.size() * sizeof(Rec)));
}

std::vector<Rec> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<Rec> out(bytes.size() / sizeof(Rec));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(Rec));
  return out;
}

TEST(ExternalSort, SortRecordsSortsAFile) {
  WorkDir dir;
  WorkDir io("-io");
  const auto in = make_records(40000, 1000, 6);
  write_file(io.path() / "in.bin", in);
  SortOptions options;
  options.memory_budget_bytes = 256 << 10;
  options.work_dir = dir.path();
  auto stats = sort_records(io.path() / "in.bin", io.path() / "out.bin", sizeof(Rec),
                            sort_key_u32_at(0, sizeof(Rec)), options);
  ASSERT_TRUE(stats.ok()) << stats.status().message();
  EXPECT_TRUE(same(read_file(io.path() / "out.bin"), stable_sorted(in)));
  EXPECT_GT(stats->runs, 1u);
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(ExternalSort, PartialRecordInInputIsAnIoError) {
  WorkDir dir;
  const auto in = make_records(10, 5, 7);
  write_file(dir.path() / "in.bin", in);
  std::filesystem::resize_file(dir.path() / "in.bin", 10 * sizeof(Rec) - 3);
  SortOptions options;
  options.work_dir = dir.path();
  auto stats = sort_records(dir.path() / "in.bin", dir.path() / "out.bin", sizeof(Rec),
                            sort_key_u32_at(0, sizeof(Rec)), options);
  ASSERT_FALSE(stats.ok());
  EXPECT_EQ(stats.status().code(), ErrorCode::io);
  EXPECT_NE(stats.status().message().find("in.bin"), std::string::npos);
}

// The sort fails cleanly wherever the disk fills up: io error naming a file and the reason,
// and no run file left behind.
// Pushes `in` at once, finishes and drains the sorter; the first error.
Status sort_all(const std::vector<Rec>& in, const SortOptions& options, const SorterFactory& make) {
  auto sorter = make(options);
  if (!sorter.ok()) return sorter.status();
  Status status = sorter.value()->push(std::as_bytes(std::span<const Rec>(in)));
  if (status.ok()) status = sorter.value()->finish();
  while (status.ok()) {
    auto block = sorter.value()->next();
    if (!block.ok()) status = block.status();
    else if (block->empty()) break;
  }
  return status;
}

void expect_out_of_space_handled(std::uint64_t budget, const SorterFactory& make) {
  WorkDir dir("-" + std::to_string(budget));
  const auto in = make_records(30000, 500, 8);
  SortOptions options;
  options.memory_budget_bytes = budget;
  options.work_dir = dir.path();
  std::uint64_t total = 0;  // bytes the sort writes to its files
  {
    ScopedIoFault never(ScopedIoFault::Op::write, std::uint64_t{1} << 40, ENOSPC);
    ASSERT_TRUE(sort_all(in, options, make).ok());
    total = never.bytes_seen();
  }
  ASSERT_GE(total, in.size() * sizeof(Rec));  // everything goes to disk at least once
  for (const std::uint64_t after : {std::uint64_t{0}, std::uint64_t{5000}, total / 3, total / 2,
                                    total - 1, total}) {
    Status failure;
    {
      ScopedIoFault fault(ScopedIoFault::Op::write, after, ENOSPC);
      failure = sort_all(in, options, make);
    }
    EXPECT_EQ(dir.file_count(), 0u) << "fault after " << after;
    if (after < total) {
      ASSERT_FALSE(failure.ok()) << "fault after " << after;
      EXPECT_EQ(failure.code(), ErrorCode::io);
      EXPECT_NE(failure.message().find("No space left on device"), std::string::npos)
          << failure.message();
      EXPECT_NE(failure.message().find(dir.path().string()), std::string::npos)
          << failure.message();
    } else {
      EXPECT_TRUE(failure.ok()) << failure.message();
    }
  }
}

TEST(ExternalSort, OutOfSpaceAnywhereIsAnIoErrorAndLeavesNoFiles) {
  expect_out_of_space_handled(16 << 10, merge_sorter);
}

void expect_read_error_handled(const SorterFactory& make) {
  WorkDir dir;
  const auto in = make_records(30000, 500, 9);
  SortOptions options;
  options.memory_budget_bytes = 64 << 10;
  options.work_dir = dir.path();
  Status failure;
  {
    ScopedIoFault fault(ScopedIoFault::Op::read, in.size() * sizeof(Rec) / 3, EIO);
    failure = sort_all(in, options, make);
  }
  ASSERT_FALSE(failure.ok());
  EXPECT_EQ(failure.code(), ErrorCode::io);
  EXPECT_NE(failure.message().find("Input/output error"), std::string::npos) << failure.message();
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(ExternalSort, ReadErrorDuringMergeIsAnIoErrorAndLeavesNoFiles) {
  expect_read_error_handled(merge_sorter);
}

// The bucket sort.

TEST(BucketSort, FitsBudgetSortsInCoreWithoutTempFiles) {
  expect_sorted_in_core(bucket_sorter(9), 11);
}

// 20-bit keys, 64 KiB: buckets of the first level (9 bits) are too large for memory and are
// distributed again by the next 9 bits, then the last 2.
TEST(BucketSort, TinyBudgetDistributesAgainAndStaysStable) {
  WorkDir dir;
  const auto in = make_records(60000, 1u << 20, 12);
  for (const unsigned threads : {1u, 2u}) {
    SortOptions options;
    options.memory_budget_bytes = 64 << 10;
    options.work_dir = dir.path();
    options.threads = threads;
    const SortRun run = run_sorter(in, options, bucket_sorter(20));
    EXPECT_TRUE(same(run.out, stable_sorted(in))) << "threads " << threads;
    EXPECT_FALSE(run.stats.in_core);
    EXPECT_GE(run.stats.merge_passes, 2u);
    EXPECT_GT(run.stats.runs, 8u);
    EXPECT_EQ(run.stats.bytes_read, run.stats.bytes_written);
    EXPECT_EQ(dir.file_count(), 0u);
  }
}

// One key for every record: no bits to distribute by, the bucket larger than memory comes out
// as it went in.
TEST(BucketSort, OneKeyLargerThanMemoryKeepsInputOrder) {
  WorkDir dir;
  auto in = make_records(30000, 1, 13);
  for (Rec& r : in) r.key = 5;
  SortOptions options;
  options.memory_budget_bytes = 64 << 10;
  options.work_dir = dir.path();
  const SortRun run = run_sorter(in, options, bucket_sorter(4));
  EXPECT_TRUE(same(run.out, in));
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(BucketSort, OutputIsTheSameForAnyBudgetAndThreadCount) {
  WorkDir dir;
  const auto in = make_records(40000, 1u << 16, 14);
  const auto expected = stable_sorted(in);
  for (const std::uint64_t budget : {std::uint64_t{32} << 10, std::uint64_t{256} << 10,
                                     std::uint64_t{4} << 20}) {
    for (const unsigned threads : {1u, 2u}) {
      SortOptions options;
      options.memory_budget_bytes = budget;
      options.work_dir = dir.path();
      options.threads = threads;
      EXPECT_TRUE(same(run_sorter(in, options, bucket_sorter(16)).out, expected))
          << "budget " << budget << " threads " << threads;
    }
  }
  EXPECT_EQ(dir.file_count(), 0u);
}

TEST(BucketSort, EmptyInputAndTooSmallBudget) {
  WorkDir dir;
  SortOptions options;
  options.work_dir = dir.path();
  EXPECT_TRUE(run_sorter({}, options, bucket_sorter(9)).out.empty());
  options.memory_budget_bytes = 1000;
  auto sorter = bucket_sorter(9)(options);
  ASSERT_FALSE(sorter.ok());
  EXPECT_EQ(sorter.status().code(), ErrorCode::usage);
}

TEST(BucketSort, OutOfSpaceAnywhereIsAnIoErrorAndLeavesNoFiles) {
  expect_out_of_space_handled(64 << 10, bucket_sorter(9));
}

TEST(BucketSort, ReadErrorIsAnIoErrorAndLeavesNoFiles) {
  expect_read_error_handled(bucket_sorter(9));
}

}  // namespace
}  // namespace octolod::bake
