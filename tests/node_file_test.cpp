#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>

#include "octolod/formats/node_file.h"

namespace octolod {
namespace {

// Two triangles sharing an edge, with every attribute:
//   2---3
//   | \ |
//   0---1
NodeMesh quad_mesh(VertexLayout layout) {
  NodeMesh mesh;
  mesh.layout = layout;
  const float corners[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (const auto& c : corners) {
    mesh.vertices.insert(mesh.vertices.end(), {c[0], c[1], 0.5f});
    if (layout.normal) mesh.vertices.insert(mesh.vertices.end(), {0, 0, 1});
    if (layout.color) mesh.vertices.insert(mesh.vertices.end(), {c[0], c[1], 0.25f});
    if (layout.uv) mesh.vertices.insert(mesh.vertices.end(), {c[0] * 2, c[1] * 2});
  }
  mesh.indices = {0, 1, 2, 2, 1, 3};
  return mesh;
}

TEST(NodeFile, RoundTripsEveryLayoutExactly) {
  for (std::uint32_t mask = 0; mask <= VertexLayout::kValidMask; ++mask) {
    NodeMesh mesh = quad_mesh(VertexLayout::from_mask(mask));
    std::vector<std::byte> bytes = encode_node_file(mesh);
    EXPECT_EQ(bytes.size(), node_file_size(mesh));
    Result<NodeMesh> back = decode_node_file(bytes, "quad");
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back.value(), mesh);
  }
}

// A mesh without vertices is a file of its header and checksum, and reads back (its empty
// vertex buffer was once handed to memcpy as a null pointer: undefined behaviour that
// tests/fuzz/node_file_fuzz found under UBSan).
TEST(NodeFile, RoundTripsAnEmptyMesh) {
  NodeMesh empty;
  empty.layout = VertexLayout::from_mask(VertexLayout::kValidMask);
  const std::vector<std::byte> bytes = encode_node_file(empty);
  EXPECT_EQ(bytes.size(), kNodeFileHeaderBytes + 4);
  Result<NodeMesh> back = decode_node_file(bytes, "empty");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back.value(), empty);
}

TEST(NodeFile, UsesSixteenBitIndicesForSmallMeshes) {
  NodeMesh mesh = quad_mesh({});
  EXPECT_EQ(node_file_size(mesh), kNodeFileHeaderBytes + 4 * 3 * 4 + 6 * 2 + 4);
}

TEST(NodeFile, UsesThirtyTwoBitIndicesPastSixtyFiveThousandVertices) {
  NodeMesh mesh;
  mesh.vertices.assign(70000 * 3, 0.0f);
  for (std::uint32_t i = 0; i < 70000; ++i) mesh.vertices[i * 3] = static_cast<float>(i);
  mesh.indices = {0, 1, 69999};
  std::vector<std::byte> bytes = encode_node_file(mesh);
  EXPECT_EQ(bytes.size(), kNodeFileHeaderBytes + 70000 * 12 + 3 * 4 + 4);
  Result<NodeMesh> back = decode_node_file(bytes, "big");
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value().indices[2], 69999u);
}

TEST(NodeFile, RejectsEveryTruncation) {
  std::vector<std::byte> bytes = encode_node_file(quad_mesh({true, true, true}));
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    Result<NodeMesh> r = decode_node_file(std::span(bytes).first(n), "cut.olod");
    ASSERT_FALSE(r.ok()) << n;
    EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
    EXPECT_NE(r.status().message().find("cut.olod: byte offset"), std::string::npos);
  }
}

TEST(NodeFile, RejectsTrailingBytes) {
  std::vector<std::byte> bytes = encode_node_file(quad_mesh({}));
  bytes.push_back(std::byte{0});
  Result<NodeMesh> r = decode_node_file(bytes, "long");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("size mismatch"), std::string::npos);
}

TEST(NodeFile, DetectsAnyFlippedBitByChecksumOrHeaderCheck) {
  const std::vector<std::byte> good = encode_node_file(quad_mesh({true, false, true}));
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::vector<std::byte> bad = good;
    bad[i] ^= std::byte{0x10};
    EXPECT_FALSE(decode_node_file(bad, "flip").ok()) << "byte " << i;
  }
}

TEST(NodeFile, RejectsUnknownVersionAsUnsupported) {
  std::vector<std::byte> bytes = encode_node_file(quad_mesh({}));
  bytes[8] = std::byte{99};
  Result<NodeMesh> r = decode_node_file(bytes, "v99");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::unsupported);
  EXPECT_NE(r.status().message().find("version 99"), std::string::npos);
}

TEST(NodeFile, RejectsHugeDeclaredCountsWithoutAllocating) {
  std::vector<std::byte> bytes = encode_node_file(quad_mesh({}));
  for (int i = 16; i < 20; ++i) bytes[static_cast<std::size_t>(i)] = std::byte{0xFF};
  Result<NodeMesh> r = decode_node_file(bytes, "huge");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
}

// `bytes` with `value` stored at `offset` and the checksum made right again: what a writer that
// gets the header wrong produces, which only the header checks catch.
std::vector<std::byte> with_field(std::vector<std::byte> bytes, std::size_t offset, auto value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(value));
  const std::uint32_t crc = crc32(std::span(bytes).first(bytes.size() - 4));
  std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
  return bytes;
}

TEST(NodeFile, RejectsAReservedFieldOrBoundsThatDisagreeWithTheVertices) {
  const std::vector<std::byte> good = encode_node_file(quad_mesh({true, true, true}));
  ASSERT_TRUE(decode_node_file(with_field(good, 28, std::uint32_t{0}), "good").ok());
  Result<NodeMesh> reserved = decode_node_file(with_field(good, 28, std::uint32_t{7}), "r.olod");
  EXPECT_EQ(reserved.status().code(), ErrorCode::bad_input);
  EXPECT_NE(reserved.status().message().find("r.olod: byte offset 28: reserved field is 7, not 0"),
            std::string::npos) << reserved.status().message();
  // max y 0.5 leaves out vertices 2 and 3 (y 1); the stride is 11 floats
  Result<NodeMesh> bounds = decode_node_file(with_field(good, 48, 0.5f), "b.olod");
  EXPECT_EQ(bounds.status().code(), ErrorCode::bad_input);
  EXPECT_NE(bounds.status().message().find("b.olod: byte offset " + std::to_string(kNodeFileHeaderBytes + (2 * 11 + 1) * 4) +
                                               ": vertex 2 lies outside the header's bounds"),
            std::string::npos) << bounds.status().message();
  // a min above the max holds no vertex
  EXPECT_FALSE(decode_node_file(with_field(good, 32, 2.0f), "inverted").ok());
}

TEST(NodeFile, Crc32MatchesTheStandardCheckValue) {
  const char* text = "123456789";
  auto bytes = std::as_bytes(std::span(text, 9));
  EXPECT_EQ(crc32(bytes), 0xCBF43926u);
}

TEST(NodeFile, WriteThenReadFromDisk) {
  auto path = std::filesystem::path(::testing::TempDir()) / "node_file_test.olod";
  NodeMesh mesh = quad_mesh({false, true, false});
  ASSERT_TRUE(write_node_file(path, mesh).ok());
  Result<NodeMesh> back = read_node_file(path);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value(), mesh);
  std::filesystem::remove(path);
  Result<NodeMesh> missing = read_node_file(path);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), ErrorCode::io);
}

// A FIFO (no writer: reading it would block) and a device that never ends (/dev/zero) are not
// node files: refused at once naming the path, before any read.
TEST(NodeFile, OnlyRegularFilesAreRead) {
  const auto fifo = std::filesystem::path(::testing::TempDir()) / "node_file_test_fifo.olod";
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::filesystem::path& path : {fifo, std::filesystem::path("/dev/zero")}) {
    Result<NodeMesh> read = read_node_file(path);
    ASSERT_FALSE(read.ok()) << path;
    EXPECT_EQ(read.status().code(), ErrorCode::io);
    EXPECT_NE(read.status().message().find(path.string() + ": not a regular file"), std::string::npos)
        << read.status().message();
  }
  std::filesystem::remove(fifo);
}

std::vector<char> file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The streaming writer, fed in uneven pieces (some crossing its 1 MiB buffer), writes the same
// bytes as write_node_file: a 16-bit-index quad, a 32-bit-index mesh of 5 MiB with every
// attribute, and an empty mesh (zero bounds).
TEST(NodeFile, StreamedFileEqualsWriteNodeFile) {
  NodeMesh big;
  big.layout = {true, true, true};
  const std::size_t stride = big.layout.floats();
  for (std::uint32_t v = 0; v < 120000; ++v)
    for (std::size_t i = 0; i < stride; ++i) big.vertices.push_back(static_cast<float>(v * stride + i) * 0.25f);
  for (std::uint32_t t = 0; t < 100000; ++t) big.indices.insert(big.indices.end(), {t, t + 1, (t * 7) % 120000});
  NodeMesh empty;
  const auto dir = std::filesystem::path(::testing::TempDir());
  for (const NodeMesh& mesh : {quad_mesh({true, false, true}), big, empty}) {
    ASSERT_TRUE(write_node_file(dir / "whole.olod", mesh).ok());
    auto writer = NodeFileWriter::create(dir / "streamed.olod", mesh.layout,
                                         static_cast<std::uint32_t>(mesh.vertex_count()),
                                         static_cast<std::uint32_t>(mesh.indices.size()), mesh.bounds());
    ASSERT_TRUE(writer.ok()) << writer.status().message();
    const std::size_t floats = mesh.layout.floats();
    for (std::size_t v = 0, step = 1; v < mesh.vertex_count(); v += step, step = step * 3 + 1) {
      const std::size_t n = std::min(step, mesh.vertex_count() - v);
      ASSERT_TRUE(writer->append_vertices(std::span(mesh.vertices).subspan(v * floats, n * floats)).ok());
    }
    for (std::size_t i = 0, step = 3; i < mesh.indices.size(); i += step, step = step * 5 + 2) {
      const std::size_t n = std::min(step, mesh.indices.size() - i);
      ASSERT_TRUE(writer->append_indices(std::span(mesh.indices).subspan(i, n)).ok());
    }
    auto bytes = writer->finish();
    ASSERT_TRUE(bytes.ok()) << bytes.status().message();
    EXPECT_EQ(bytes.value(), node_file_size(mesh));
    EXPECT_TRUE(file_bytes(dir / "streamed.olod") == file_bytes(dir / "whole.olod"))
        << mesh.triangle_count() << " triangles";
  }
  std::filesystem::remove(dir / "whole.olod");
  std::filesystem::remove(dir / "streamed.olod");
}

// A writer dropped before finish() leaves no file behind.
TEST(NodeFile, UnfinishedStreamedFileIsRemoved) {
  const auto path = std::filesystem::path(::testing::TempDir()) / "unfinished.olod";
  {
    auto writer = NodeFileWriter::create(path, {}, 3, 3, Bounds{{0, 0, 0}, {1, 1, 1}});
    ASSERT_TRUE(writer.ok());
    const float vertices[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    ASSERT_TRUE(writer->append_vertices(vertices).ok());
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace octolod
