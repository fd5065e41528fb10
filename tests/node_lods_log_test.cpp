// The bake's log of finished nodes' LOD records (bake/src/node_lods_log.h): what the manifest is
// written from once the tree is done.
#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <string>
#include <vector>

#include "node_lods_log.h"
#include "record_file.h"

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

class NodeLodsLogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // one directory per test: ctest runs the cases as parallel processes
    dir_ = fs::path(::testing::TempDir()) /
           ("node_lods_log_test-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The log's files in the work directory: its records and their offsets by node.
  std::vector<fs::path> files() const {
    std::vector<fs::path> found;
    for (const auto& entry : fs::directory_iterator(dir_)) found.push_back(entry.path());
    return found;
  }
  fs::path log_file() const {
    for (const fs::path& file : files())
      if (file.filename().string().find("index") == std::string::npos) return file;
    return {};
  }

  static NodeLods lods(std::uint32_t count, float at) {
    NodeLods n;
    const float corner[3] = {at, -at, 2 * at};
    n.bounds.extend(corner);
    for (std::uint32_t i = 0; i < count; ++i) {
      LodInfo l;
      l.triangles = 1000 >> i;
      l.vertices = 600 >> i;
      l.error = 0.125 * i + at;
      l.bytes = 10000 + i;
      l.file = "ignored";
      n.lods.push_back(l);
    }
    return n;
  }

  // A node at octant path `prefix` (3 bits per level), `depth` levels down.
  static NodeShape shape(std::uint64_t prefix, std::uint32_t depth, bool leaf) {
    NodeShape s;
    s.prefix = prefix;
    s.depth = depth;
    s.parent = depth == 0 ? -1 : 3;
    s.triangles = 1000 + prefix;
    s.leaf = leaf;
    if (!leaf) s.children = {-1, 6, -1, 7, -1, -1, 9, -1};
    return s;
  }

  fs::path dir_;
};

TEST_F(NodeLodsLogTest, RecordsComeBackByNodeWithTheirFilesNamedAfterTheirDirectory) {
  auto log = NodeLodsLog::create(dir_);
  ASSERT_TRUE(log.ok()) << log.status().message();
  // completion order, not node order; an internal node without LODs (a bake without them)
  const NodeShape at_3_5 = shape(3 << 3 | 5, 2, true), root = shape(0, 0, false), at_7 = shape(7, 1, false);
  ASSERT_TRUE(log->append(5, at_3_5, lods(3, 1.5f)).ok());
  ASSERT_TRUE(log->append(0, root, lods(1, 0.5f)).ok());
  ASSERT_TRUE(log->append(2, at_7, lods(0, 2.5f)).ok());
  ASSERT_TRUE(log->finish().ok());
  EXPECT_TRUE(log->has(0) && log->has(2) && log->has(5));
  EXPECT_FALSE(log->has(1) || log->has(3) || log->has(6));

  for (const auto& [node, node_shape, count, at, dir] :
       {std::tuple{5, at_3_5, 3u, 1.5f, std::string("3/5")}, {0, root, 1u, 0.5f, ""}, {2, at_7, 0u, 2.5f, "7"}}) {
    auto back = log->read(node);
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back->shape, node_shape);
    const NodeLods expected = lods(count, at);
    EXPECT_EQ(back->lods.bounds, expected.bounds);
    ASSERT_EQ(back->lods.lods.size(), count);
    for (std::uint32_t i = 0; i < count; ++i) {
      const LodInfo& l = back->lods.lods[i];
      EXPECT_EQ(l.triangles, expected.lods[i].triangles);
      EXPECT_EQ(l.vertices, expected.lods[i].vertices);
      EXPECT_EQ(l.error, expected.lods[i].error);
      EXPECT_EQ(l.bytes, expected.lods[i].bytes);
      EXPECT_EQ(l.file, (dir.empty() ? "" : dir + "/") + "lod" + std::to_string(i) + ".olod");
    }
  }
  // a node never recorded is an error naming it, not a record read from nowhere
  auto missing = log->read(3);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("node 3"), std::string::npos) << missing.status().message();
  // the files go with the log
  EXPECT_EQ(files().size(), 2u);
  { NodeLodsLog gone = std::move(log).value(); }
  EXPECT_TRUE(files().empty());
}

TEST_F(NodeLodsLogTest, ACutLogIsAnIoErrorNamingTheFileNodeAndOffset) {
  auto log = NodeLodsLog::create(dir_);
  ASSERT_TRUE(log.ok());
  ASSERT_TRUE(log->append(0, shape(0, 0, false), lods(2, 1.0f)).ok());
  ASSERT_TRUE(log->append(1, shape(0, 1, true), lods(4, 1.0f)).ok());
  ASSERT_TRUE(log->finish().ok());
  const fs::path file = log_file();
  fs::resize_file(file, fs::file_size(file) - 1);
  EXPECT_TRUE(log->read(0).ok());
  auto cut = log->read(1);
  ASSERT_FALSE(cut.ok());
  EXPECT_EQ(cut.status().code(), ErrorCode::io);
  for (const std::string& part : {file.string(), std::string("node 1"), std::string("offset")})
    EXPECT_NE(cut.status().message().find(part), std::string::npos) << cut.status().message();
}

TEST_F(NodeLodsLogTest, AFailedWriteIsAnIoErrorNamingTheFile) {
  auto log = NodeLodsLog::create(dir_);
  ASSERT_TRUE(log.ok());
  ScopedIoFault full(ScopedIoFault::Op::write, 0, ENOSPC);
  Status status = log->append(0, shape(0, 0, true), lods(2, 1.0f));
  if (status.ok()) status = log->finish();  // the records are buffered until then
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), ErrorCode::io);
  EXPECT_NE(status.message().find(log_file().string()), std::string::npos) << status.message();
}

}  // namespace
}  // namespace octolod::bake
