#include <gtest/gtest.h>

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

}  // namespace
}  // namespace octolod
