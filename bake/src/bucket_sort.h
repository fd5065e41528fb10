// External MSD radix sort for keys of a known width: the octree's Morton codes (seed 4.3).
//
// The merge sort of external_sort.h moves every record through run formation, a k-way merge
// and two key computations. When the keys are bounded (below 2^key_bits), distributing is
// cheaper: records pushed are staged in memory; whenever the stage is full they are
// distributed by the top bits of their key into bucket files (up to 512 per level, input
// order kept), one write of the data. next() then takes the buckets in key order: each one
// that fits in memory is read back whole, sorted by an LSD radix sort and handed out, one read
// of the data and no merge. A bucket too large for memory is distributed again by the next
// bits; a bucket without key bits left holds one key only and is handed out in input order.
// When everything fits in the stage, nothing touches the disk.
//
// Same contract as any RecordSorter (external_sort.h): stable, so the output is a pure
// function of the input whatever the budget; memory within SortOptions::memory_budget_bytes;
// bucket files deleted as soon as they are read and on every error. SortStats: runs = bucket
// files written, merge_passes = deepest level of distribution (0: in core), fan_in = buckets
// per level. Single-threaded: SortOptions::threads is not used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "octolod/bake/external_sort.h"
#include "octolod/formats/status.h"

namespace octolod::bake {

// `key` must give keys below 2^key_bits (key_bits <= 64). `output_budget_bytes`: the memory
// the sorter may use once finish() is called, when the caller has freed some of its own (less
// than options.memory_budget_bytes means the same); a larger one means larger buckets sorted
// in memory. usage error when the budget cannot hold a few records, their keys and one bucket
// buffer per bucket of a level.
Result<std::unique_ptr<RecordSorter>> create_bucket_sorter(std::size_t record_bytes, SortKeyFn key,
                                                           unsigned key_bits,
                                                           const SortOptions& options,
                                                           std::uint64_t output_budget_bytes = 0);

}  // namespace octolod::bake
