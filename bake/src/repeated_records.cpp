// Repeated faces of a soup record file, found by external sorts (repeated_records.h).
#include "repeated_records.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <span>
#include <vector>

#include "flat_hash.h"
#include "octolod/bake/external_sort.h"
#include "octolod/bake/soup.h"
#include "record_file.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

// Each file's buffer: a sixteenth of the budget, within [4 KiB, 256 KiB]; the sort of the faces
// gets the rest but for the two files it runs with (as sort_records leaves its own two).
std::size_t io_buffer_bytes(std::uint64_t budget) {
  return std::clamp<std::size_t>(static_cast<std::size_t>(budget / 16), std::size_t{4} << 10, std::size_t{256} << 10);
}

// A face's corner positions (the bits of x, y, z of each), rotated so that the smallest of its
// three cyclic orders comes first: equal for the same face whatever corner it starts at.
using FacePositions = std::array<std::uint32_t, 9>;

FacePositions face_positions(const std::byte* record, VertexLayout layout) {
  std::array<std::array<std::uint32_t, 3>, 3> corner;
  for (int c = 0; c < 3; ++c)
    std::memcpy(corner[static_cast<std::size_t>(c)].data(), record + soup_corner_offset(layout, c), 12);
  std::size_t first = 0;
  auto rotation = [&](std::size_t start) {
    return std::array{corner[start], corner[(start + 1) % 3], corner[(start + 2) % 3]};
  };
  for (std::size_t start = 1; start < 3; ++start)
    if (rotation(start) < rotation(first)) first = start;
  FacePositions face;
  for (std::size_t k = 0; k < 3; ++k) std::copy_n(corner[(first + k) % 3].data(), 3, face.data() + 3 * k);
  return face;
}

// One face to sort: its record number in the file (u64), then its FacePositions.
constexpr std::size_t kFaceBytes = 8 + sizeof(FacePositions);

FacePositions positions_of_face(const std::byte* face) {
  FacePositions positions;
  std::memcpy(positions.data(), face + 8, sizeof positions);
  return positions;
}

SortOptions sort_options(const fs::path& work_dir, std::uint64_t budget) {
  SortOptions options;
  options.memory_budget_bytes = budget;
  options.work_dir = work_dir;
  options.threads = 1;
  return options;
}

// The record numbers of the repeats (u64 records) into `repeats`, in the order the sort by hash
// gives them; how many.
Result<std::uint64_t> find_repeats(const fs::path& records, VertexLayout layout, const fs::path& work_dir,
                                   std::uint64_t budget, RecordWriter& repeats) {
  const std::size_t record_bytes = soup_record_bytes(layout);
  auto created = RecordSorter::create(kFaceBytes,
                                     [](std::span<const std::byte> faces, std::span<std::uint64_t> keys) {
                                       for (std::size_t i = 0; i < keys.size(); ++i) {
                                         const FacePositions p = positions_of_face(faces.data() + i * kFaceBytes);
                                         keys[i] = hash_words(p.data(), p.size());
                                       }
                                     },
                                     sort_options(work_dir, budget - 2 * io_buffer_bytes(budget)));
  if (!created.ok()) return created.status();
  RecordSorter& sorter = *created.value();
  auto reader = RecordReader::open(records, record_bytes, io_buffer_bytes(budget));
  if (!reader.ok()) return reader.status();
  std::uint64_t number = 0;
  for (;;) {
    auto block = reader->read();
    if (!block.ok()) return block.status();
    if (block->empty()) break;
    for (std::size_t i = 0; i < block->size(); i += record_bytes, ++number) {
      std::array<std::byte, kFaceBytes> face;
      const FacePositions positions = face_positions(block->data() + i, layout);
      std::memcpy(face.data(), &number, 8);
      std::memcpy(face.data() + 8, positions.data(), sizeof positions);
      OCTOLOD_RETURN_IF_ERROR(sorter.push(face));
    }
  }
  OCTOLOD_RETURN_IF_ERROR(sorter.finish());
  // Equal faces have equal hashes, and the sort is stable: within a run of one hash the first
  // record of each face comes first. Distinct faces of one hash are told apart within the run.
  std::uint64_t count = 0, run_hash = 0;
  std::vector<FacePositions> run;
  for (;;) {
    auto block = sorter.next();
    if (!block.ok()) return block.status();
    if (block->empty()) break;
    const std::span<const std::uint64_t> keys = sorter.keys();
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (!run.empty() && keys[i] != run_hash) run.clear();
      run_hash = keys[i];
      const std::byte* face = block->data() + i * kFaceBytes;
      const FacePositions positions = positions_of_face(face);
      if (std::find(run.begin(), run.end(), positions) == run.end()) {
        run.push_back(positions);
        continue;
      }
      OCTOLOD_RETURN_IF_ERROR(repeats.append(face, 1));  // its first 8 bytes: the number
      ++count;
    }
  }
  return count;
}

// The records of `records` whose numbers are not in `sorted_repeats` (u64, increasing) into
// `once`.
Status copy_without(const fs::path& records, std::size_t record_bytes, const fs::path& sorted_repeats,
                    std::size_t io_bytes, RecordWriter& once) {
  auto reader = RecordReader::open(records, record_bytes, io_bytes);
  if (!reader.ok()) return reader.status();
  auto repeats = RecordReader::open(sorted_repeats, 8, io_bytes);
  if (!repeats.ok()) return repeats.status();
  constexpr std::uint64_t kNoMore = ~std::uint64_t{0};
  std::span<const std::byte> pending;  // repeat numbers read, not yet taken
  std::uint64_t next = kNoMore;        // the next repeat's number
  auto advance = [&]() -> Status {
    if (pending.empty()) {
      auto block = repeats->read();
      if (!block.ok()) return block.status();
      pending = block.value();
    }
    if (pending.empty()) {
      next = kNoMore;
      return {};
    }
    std::memcpy(&next, pending.data(), 8);
    pending = pending.subspan(8);
    return {};
  };
  OCTOLOD_RETURN_IF_ERROR(advance());
  std::uint64_t number = 0;
  for (;;) {
    auto block = reader->read();
    if (!block.ok()) return block.status();
    if (block->empty()) return {};
    for (std::size_t i = 0; i < block->size(); i += record_bytes, ++number) {
      if (number == next) {
        OCTOLOD_RETURN_IF_ERROR(advance());
        continue;
      }
      OCTOLOD_RETURN_IF_ERROR(once.append(block->data() + i, 1));
    }
  }
}

}  // namespace

Result<std::optional<TempFile>> without_repeated_records(const fs::path& records, VertexLayout layout,
                                                         const fs::path& work_dir, std::uint64_t sort_budget_bytes) {
  const std::size_t io_bytes = io_buffer_bytes(sort_budget_bytes);
  TempFile repeats = make_temp_file(work_dir, "repeats");
  std::uint64_t count = 0;
  {
    auto writer = RecordWriter::create(repeats.path(), 8, io_bytes);
    if (!writer.ok()) return writer.status();
    auto found = find_repeats(records, layout, work_dir, sort_budget_bytes, writer.value());
    if (!found.ok()) return found.status();
    OCTOLOD_RETURN_IF_ERROR(writer->finish());
    count = found.value();
  }
  if (count == 0) return std::optional<TempFile>{};
  TempFile sorted = make_temp_file(work_dir, "repeats-sorted");
  auto sorted_stats = sort_records(repeats.path(), sorted.path(), 8, sort_key_u64_at(0, 8),
                                   sort_options(work_dir, sort_budget_bytes));
  if (!sorted_stats.ok()) return sorted_stats.status();
  repeats.remove();
  TempFile once = make_temp_file(work_dir, "once");
  auto writer = RecordWriter::create(once.path(), soup_record_bytes(layout), io_bytes);
  if (!writer.ok()) return writer.status();
  OCTOLOD_RETURN_IF_ERROR(copy_without(records, soup_record_bytes(layout), sorted.path(), io_bytes, writer.value()));
  OCTOLOD_RETURN_IF_ERROR(writer->finish());
  return std::optional<TempFile>{std::move(once)};
}

}  // namespace octolod::bake
