// PlyWriter: exact header and body bytes, colour quantization, atomic publish (nothing at the
// path until finish(), no temporary left behind), misuse reported as usage errors, and write
// failures (a full disk, simulated with RLIMIT_FSIZE) as io errors naming the file.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"
#include "ply_test_helpers.h"

namespace octolod {
namespace {

using test::append_scalar;
using test::is_error;
using test::ScratchDir;

std::vector<std::string> directory_entries(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(PlyWriter, AsciiBytesAreExact) {
  ScratchDir dir;
  const auto path = dir.file("tri.ply");
  const std::vector<float> vertices = {0.1f, -0.0f, 1e-40f, 1, 0.5f, 0,
                                       3e38f, 2, 1, 0, 1, 1.0f / 3.0f};
  ASSERT_TRUE(write_ply(path,
                        {PlyFormat::ascii, VertexLayout{false, true, false}, PlyColorType::uchar,
                         {"made by octolod", ""}, {}},
                        vertices, std::vector<std::uint32_t>{0, 1, 0})
                  .ok());
  EXPECT_EQ(test::read_bytes(path),
            "ply\nformat ascii 1.0\ncomment made by octolod\ncomment \nelement vertex 2\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0.1 -0 1e-40 255 128 0\n"
            "3e+38 2 1 0 255 85\n"
            "3 0 1 0\n");
}

TEST(PlyWriter, BinaryBytesAreExactInBothByteOrders) {
  ScratchDir dir;
  const std::vector<float> vertices = {1.5f, 2, 3, 0.25f, 0.75f, 4, 5, 6, 0, 1, 7, 8, 9, -1, 2};
  for (bool big : {false, true}) {
    const auto path = dir.file("tri.ply");
    ASSERT_TRUE(write_ply(path,
                          {big ? PlyFormat::binary_big_endian : PlyFormat::binary_little_endian,
                           VertexLayout{false, false, true}, PlyColorType::uchar, {}, {}},
                          vertices, std::vector<std::uint32_t>{2, 1, 0})
                    .ok());
    std::string expected = std::string("ply\nformat ") +
                           (big ? "binary_big_endian" : "binary_little_endian") +
                           " 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nproperty float u\nproperty float v\n"
                           "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (float f : vertices) append_scalar(expected, f, big);
    expected += '\x03';
    for (std::int32_t i : {2, 1, 0}) append_scalar(expected, i, big);
    EXPECT_EQ(test::read_bytes(path), expected);
  }
}

TEST(PlyWriter, ColoursAreClampedAndRoundedOrKeptAsFloat) {
  ScratchDir dir;
  const VertexLayout layout{false, true, false};
  const std::vector<float> vertices = {0, 0, 0, -0.5f, 0.5f, 2.0f,
                                       0, 0, 0, std::numeric_limits<float>::quiet_NaN(),
                                       1.0f / 255.0f, 0.998f};
  const auto path = dir.file("colors.ply");
  ASSERT_TRUE(write_ply(path, {PlyFormat::binary_little_endian, layout, PlyColorType::uchar, {}, {}},
                        vertices, {}).ok());
  auto mesh = read_ply(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->vertices, (std::vector<float>{0, 0, 0, 0, test::byte_color(128), 1, 0, 0, 0,
                                                0, test::byte_color(1), test::byte_color(254)}));
  // float colours are written as they are, out-of-range values included
  const std::vector<float> wide = {0, 0, 0, -0.5f, 0.5f, 2.0f};
  ASSERT_TRUE(write_ply(path, {PlyFormat::ascii, layout, PlyColorType::float32, {}, {}}, wide, {}).ok());
  mesh = read_ply(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->info.color_type, PlyColorType::float32);
  EXPECT_EQ(mesh->vertices, wide);
}

TEST(PlyWriter, PositionsWithAnOriginAreWrittenAsDoublesAndReadBackExactly) {
  // A quad of floats within a few units of 0 relative to a point 4,000 km out: written with the
  // origin added in double, read relative to it again, every float comes back bit for bit (none
  // is below 1/64, whose bits the doubles there, 2^-30 apart, hold; read as floats they would be
  // 0.25 apart).
  ScratchDir dir;
  const VertexLayout layout{false, false, true};
  struct {
    std::vector<float> vertices{0.1f, -0.125f, 1.0f / 3.0f, 0.5f, 0.25f,  //
                                1.001f, 0.0f, -2.5f, 1.0f, 0.0f,        //
                                3.14159265f, 0.0625f, -0.03125f, 0.0f, 1.0f,  //
                                -1.0f / 48.0f, 2.0f, 0.375f, 1.0f, 1.0f};
    std::vector<std::uint32_t> triangles{0, 1, 2, 0, 2, 3};
  } mesh;
  const std::array<double, 3> origin{4000000.0, -500001.0, 12.0};
  for (PlyFormat format : {PlyFormat::ascii, PlyFormat::binary_little_endian, PlyFormat::binary_big_endian}) {
    SCOPED_TRACE(std::string(to_string(format)));
    const auto path = dir.file("far.ply");
    PlyWriteOptions options;
    options.format = format;
    options.layout = layout;
    options.position_origin = origin;
    ASSERT_TRUE(write_ply(path, options, mesh.vertices, mesh.triangles).ok());
    EXPECT_NE(test::read_bytes(path).find("property double x"), std::string::npos);
    PlyReadOptions framed;
    framed.position_origin = origin;
    Result<PlyMesh> back = read_ply(path, framed);
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_TRUE(back->info.double_positions);
    EXPECT_TRUE(test::same_bits(mesh.vertices, back->vertices));
    EXPECT_EQ(back->triangles, mesh.triangles);
  }
}

TEST(PlyWriter, PublishesAtomicallyOnFinish) {
  ScratchDir dir;
  const auto path = dir.file("mesh.ply");
  const test::TestMesh mesh = test::strip_mesh(VertexLayout{}, true);
  auto writer = PlyWriter::create(path, {}, mesh.vertex_count(), mesh.triangles.size() / 3);
  ASSERT_TRUE(writer.ok()) << writer.status().message();
  ASSERT_TRUE(writer.value()->write_vertices(mesh.vertices).ok());
  ASSERT_TRUE(writer.value()->write_triangles(mesh.triangles).ok());
  const std::vector<std::string> during = directory_entries(dir.path());
  ASSERT_EQ(during.size(), 1u);
  EXPECT_EQ(during[0].rfind("mesh.ply.tmp-", 0), 0u) << during[0];
  EXPECT_FALSE(std::filesystem::exists(path));
  ASSERT_TRUE(writer.value()->finish().ok());
  EXPECT_EQ(directory_entries(dir.path()), std::vector<std::string>{"mesh.ply"});
  EXPECT_TRUE(is_error(writer.value()->finish(), ErrorCode::usage, {"after finish()"}));
  writer.value().reset();
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_TRUE(read_ply(path).ok());
}

TEST(PlyWriter, UnfinishedWriterLeavesNothingBehind) {
  ScratchDir dir;
  const auto path = dir.file("mesh.ply");
  test::write_bytes(path, "old contents");
  {
    auto writer = PlyWriter::create(path, {}, 3, 1);
    ASSERT_TRUE(writer.ok());
    ASSERT_TRUE(writer.value()->write_vertices(std::vector<float>(9, 1.0f)).ok());
  }
  EXPECT_EQ(directory_entries(dir.path()), std::vector<std::string>{"mesh.ply"});
  EXPECT_EQ(test::read_bytes(path), "old contents");
}

TEST(PlyWriter, MisuseIsAUsageError) {
  ScratchDir dir;
  const auto path = dir.file("mesh.ply");
  auto create = [&] {
    auto writer = PlyWriter::create(path, {}, 3, 1);
    EXPECT_TRUE(writer.ok());
    return std::move(writer).value();
  };
  EXPECT_TRUE(is_error(create()->write_vertices(std::vector<float>(4)), ErrorCode::usage,
                       {path.string(), "not a multiple of 3"}));
  EXPECT_TRUE(is_error(create()->write_vertices(std::vector<float>(12)), ErrorCode::usage,
                       {"more vertices than the declared 3"}));
  EXPECT_TRUE(is_error(create()->write_triangles(std::vector<std::uint32_t>{0, 1, 2}),
                       ErrorCode::usage, {"triangles written before all 3 vertices"}));
  auto writer = create();
  ASSERT_TRUE(writer->write_vertices(std::vector<float>(9)).ok());
  EXPECT_TRUE(is_error(writer->write_triangles(std::vector<std::uint32_t>{0, 1, 3}),
                       ErrorCode::usage, {"vertex index 3 out of range"}));
  writer = create();
  ASSERT_TRUE(writer->write_vertices(std::vector<float>(9)).ok());
  EXPECT_TRUE(is_error(writer->finish(), ErrorCode::usage, {"0 of 1 triangles"}));
  writer.reset();
  EXPECT_FALSE(std::filesystem::exists(path));
  PlyWriteOptions commented;
  commented.comments = {"two\nlines"};
  EXPECT_TRUE(is_error(test::status_of(PlyWriter::create(path, commented, 0, 0)), ErrorCode::usage,
                       {"line break"}));
}

TEST(PlyWriter, UnwritableDirectoryIsAnIoError) {
  ScratchDir dir;
  const auto path = dir.file("missing") / "mesh.ply";
  auto writer = PlyWriter::create(path, {}, 0, 0);
  EXPECT_TRUE(is_error(test::status_of(writer), ErrorCode::io,
                       {path.string(), "cannot write the PLY: directory", "does not exist"}));
}

// Publishing renames over the path: over a FIFO or a device (/dev/null, as root) that would
// replace the node itself. Such outputs, a directory and a symlink to a FIFO are refused and kept.
TEST(PlyWriter, AnOutputThatIsNotARegularFileIsRefusedAndKept) {
  ScratchDir dir;
  const auto fifo = dir.file("fifo.ply"), link = dir.file("link.ply"), sub = dir.file("sub.ply");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::filesystem::create_symlink(fifo, link);
  std::filesystem::create_directory(sub);
  for (const auto& path : {fifo, link})
    EXPECT_TRUE(is_error(test::status_of(PlyWriter::create(path, {}, 0, 0)), ErrorCode::io,
                         {path.string(), "cannot write the PLY: it is not a regular file"}));
  EXPECT_TRUE(is_error(test::status_of(PlyWriter::create(sub, {}, 0, 0)), ErrorCode::io,
                       {sub.string(), "it is a directory"}));
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(directory_entries(dir.path()), (std::vector<std::string>{"fifo.ply", "link.ply", "sub.ply"}));
}

// A full disk, simulated by a file size limit in a child process: the write fails with EFBIG
// (SIGXFSZ ignored), which must come back as an io error naming the file, with no file left.
TEST(PlyWriterDeathTest, WriteFailureIsAnIoError) {
  ScratchDir dir;
  const auto path = dir.file("big.ply");
  const test::TestMesh mesh = test::strip_mesh(VertexLayout{true, true, true}, true, 20000);
  auto write_beyond_the_limit = [&] {
        std::signal(SIGXFSZ, SIG_IGN);
        const rlimit limit{100000, 100000};
        setrlimit(RLIMIT_FSIZE, &limit);
        const Status status =
            write_ply(path, {PlyFormat::binary_little_endian, mesh.layout, PlyColorType::uchar, {}, {}},
                      mesh.vertices, mesh.triangles);
        const bool expected = status.code() == ErrorCode::io &&
                              status.message().find(path.string() + ": write failed") == 0 &&
                              directory_entries(dir.path()).empty();
        std::fprintf(stderr, "%s\n", status.message().c_str());
        std::_Exit(expected ? 0 : 1);
  };
  EXPECT_EXIT(write_beyond_the_limit(), ::testing::ExitedWithCode(0),
              "write failed: File too large");
}

}  // namespace
}  // namespace octolod
