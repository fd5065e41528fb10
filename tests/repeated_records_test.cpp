// Soup record files without their repeated faces (repeated_records.h), the streamed leaves'
// counterpart of without_repeated_triangles: checked against a set of the faces seen, with a
// sort budget small enough for both sorts to write runs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "octolod/bake/soup.h"
#include "record_file.h"
#include "repeated_records.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

constexpr VertexLayout kLayout{false, false, true};  // position, uv
constexpr std::size_t kRecordBytes = soup_record_bytes(kLayout);
constexpr std::uint64_t kSortBudget = 64 << 10;  // 44-byte faces: about a thousand a run, and the repeats' numbers over a run too

std::vector<std::byte> file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> chars{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::vector<std::byte> bytes(chars.size());
  std::memcpy(bytes.data(), chars.data(), chars.size());
  return bytes;
}

void write_file(const fs::path& path, const std::vector<std::byte>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

class RepeatedRecords : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("octolod-repeated-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// 20,000 faces over the 8 corners of a cube (each vertex a position and a uv; several vertices share a
// position with different uvs), chosen at random, many of them the same face again: from any
// corner, with other uvs, wound the other way (a back, no repeat), or degenerate (two equal
// corners, whose rotations are one face too).
TEST_F(RepeatedRecords, DropsEveryLaterCopyOfAFaceFromAnyCornerButNotItsBack) {
  std::mt19937 random(11);
  std::vector<float> vertices;  // 5 floats each: 3 vertices per position, uvs 0, 0.5, 1
  for (int p = 0; p < 8; ++p)
    for (int w = 0; w < 3; ++w)
      vertices.insert(vertices.end(), {float(p % 2), float(p / 2 % 2), float(p / 4), 0.5f * float(w), 0.0f});
  auto position = [](std::uint32_t vertex) { return vertex / 3; };
  std::vector<std::byte> input, expected;
  std::set<std::array<std::uint32_t, 3>> seen;  // faces as positions from the least cyclic order
  for (std::uint32_t t = 0; t < 20000; ++t) {
    std::array<std::uint32_t, 3> v{};
    for (std::uint32_t& c : v) c = static_cast<std::uint32_t>(random() % 24);
    if (t % 7 == 0) v[1] = 3 * position(v[0]) + 1;  // degenerate: corners 0 and 1 at one position
    std::array<std::uint32_t, 3> face{position(v[0]), position(v[1]), position(v[2])};
    const std::array<std::array<std::uint32_t, 3>, 3> rotations{
        face, std::array{face[1], face[2], face[0]}, std::array{face[2], face[0], face[1]}};
    std::array<std::byte, kRecordBytes> record{};
    store_soup_record(record.data(), kLayout, vertices.data(), v.data(), t);
    input.insert(input.end(), record.begin(), record.end());
    if (seen.insert(*std::min_element(rotations.begin(), rotations.end())).second)
      expected.insert(expected.end(), record.begin(), record.end());
  }
  ASSERT_LT(expected.size(), input.size() / 2);  // 512 faces at most: most repeat
  write_file(dir_ / "records", input);
  auto once = without_repeated_records(dir_ / "records", kLayout, dir_, kSortBudget);
  ASSERT_TRUE(once.ok()) << once.status().message();
  ASSERT_TRUE(once->has_value());
  EXPECT_TRUE(file_bytes(once.value()->path()) == expected);
  // the kept faces repeat none: nothing to drop, no copy
  write_file(dir_ / "kept", expected);
  auto again = without_repeated_records(dir_ / "kept", kLayout, dir_, kSortBudget);
  ASSERT_TRUE(again.ok()) << again.status().message();
  EXPECT_FALSE(again->has_value());
  // nothing but the input files is left in the work directory
  once.value().reset();
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 2);
}

// Out of space or a failed read at any point of the sorts and the copy: an io error naming a
// file, and no temporary file left behind.
TEST_F(RepeatedRecords, AFailedWriteOrReadAnywhereLeavesNoTemporaryFile) {
  std::vector<std::byte> input;
  const std::vector<float> vertices{0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 0, 0};
  for (std::uint32_t t = 0; t < 6000; ++t) {  // four faces, each about 1,500 times
    const std::array<std::uint32_t, 3> v{t % 4, (t + 1) % 4, (t + 2) % 4};
    std::array<std::byte, kRecordBytes> record{};
    store_soup_record(record.data(), kLayout, vertices.data(), v.data(), t);
    input.insert(input.end(), record.begin(), record.end());
  }
  write_file(dir_ / "records", input);
  for (const ScopedIoFault::Op op : {ScopedIoFault::Op::write, ScopedIoFault::Op::read}) {
    std::uint64_t total = 0;
    {
      ScopedIoFault never(op, std::uint64_t{1} << 40, EIO);
      auto once = without_repeated_records(dir_ / "records", kLayout, dir_, kSortBudget);
      ASSERT_TRUE(once.ok() && once->has_value()) << once.status().message();
      total = never.bytes_seen();
    }
    ASSERT_GT(total, input.size());
    for (std::uint64_t after = 0; after < total; after += total / 16) {
      {
        ScopedIoFault fault(op, after, EIO);
        auto once = without_repeated_records(dir_ / "records", kLayout, dir_, kSortBudget);
        ASSERT_FALSE(once.ok()) << "fault after " << after;
        EXPECT_EQ(once.status().code(), ErrorCode::io);
        EXPECT_NE(once.status().message().find(dir_.string()), std::string::npos) << once.status().message();
      }
      EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1) << "fault after " << after;
    }
  }
}

TEST_F(RepeatedRecords, AMissingFileIsAnErrorNamingIt) {
  auto once = without_repeated_records(dir_ / "absent", kLayout, dir_, kSortBudget);
  ASSERT_FALSE(once.ok());
  EXPECT_NE(once.status().message().find("absent"), std::string::npos) << once.status().message();
}

}  // namespace
}  // namespace octolod::bake
