// PlyReader on valid input: every attribute layout through every format and back bit-exactly,
// streaming in small batches, element orders, skipped elements and properties, property-name
// aliases, scalar types, polygon fans, and the trailing-bytes rule.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"
#include "ply_test_helpers.h"

namespace octolod {
namespace {

using test::append_scalar;
using test::byte_color;
using test::same_bits;
using test::ScratchDir;
using test::write_bytes;

constexpr PlyFormat kFormats[] = {PlyFormat::ascii, PlyFormat::binary_little_endian,
                                  PlyFormat::binary_big_endian};

PlyMesh read_ok(const std::filesystem::path& path) {
  Result<PlyMesh> mesh = read_ply(path);
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  return mesh.ok() ? std::move(mesh).value() : PlyMesh{};
}

// ---- round trips ----

struct RoundTripCase {
  VertexLayout layout;
  PlyColorType color_type;
};

void PrintTo(const RoundTripCase& c, std::ostream* os) {
  *os << c.layout.describe() << (c.color_type == PlyColorType::uchar ? " uchar" : " float");
}

class PlyRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(PlyRoundTrip, EveryFormatPairIsBitExact) {
  const auto [layout, color_type] = GetParam();
  const test::TestMesh mesh = test::strip_mesh(layout, color_type == PlyColorType::uchar);
  ScratchDir dir;
  for (PlyFormat first : kFormats) {
    for (PlyFormat second : kFormats) {
      SCOPED_TRACE(std::string(to_string(first)) + " -> " + std::string(to_string(second)));
      const auto a = dir.file("a.ply");
      const auto b = dir.file("b.ply");
      ASSERT_TRUE(write_ply(a, {first, layout, color_type, {"first"}, {}}, mesh.vertices,
                            mesh.triangles).ok());
      const PlyMesh once = read_ok(a);
      ASSERT_TRUE(write_ply(b, {second, layout, color_type, {}, {}}, once.vertices, once.triangles).ok());
      const PlyMesh twice = read_ok(b);

      EXPECT_EQ(twice.info.format, second);
      EXPECT_EQ(twice.info.layout, layout);
      if (layout.color) {
        EXPECT_EQ(twice.info.color_type, color_type);
      }
      EXPECT_EQ(twice.info.vertex_count, mesh.vertex_count());
      EXPECT_EQ(twice.info.face_count, mesh.triangles.size() / 3);
      EXPECT_TRUE(same_bits(mesh.vertices, once.vertices));
      EXPECT_TRUE(same_bits(mesh.vertices, twice.vertices));
      EXPECT_EQ(twice.triangles, mesh.triangles);
    }
  }
}

std::vector<RoundTripCase> all_layouts() {
  std::vector<RoundTripCase> cases;
  for (std::uint32_t mask = 0; mask <= VertexLayout::kValidMask; ++mask)
    for (PlyColorType color : {PlyColorType::uchar, PlyColorType::float32})
      if ((mask & 2u) != 0 || color == PlyColorType::uchar)
        cases.push_back({VertexLayout::from_mask(mask), color});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(AllLayouts, PlyRoundTrip, ::testing::ValuesIn(all_layouts()),
                         [](const auto& test_case) {
                           return std::to_string(test_case.param.layout.mask()) +
                                  (test_case.param.color_type == PlyColorType::uchar ? "_uchar"
                                                                                : "_float");
                         });

// ---- streaming ----

// Only a regular file is read: a FIFO would block until a writer comes, /dev/zero would never
// end; each is refused before it is opened, naming the path and why (an I/O error).
TEST(PlyReader, OnlyARegularFileIsRead) {
  ScratchDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo.ply").c_str(), 0600), 0);
  for (const auto& [path, why] : {std::pair{dir.file("fifo.ply"), "it is not a regular file"},
                                  std::pair{dir.path(), "it is a directory"},
                                  std::pair{dir.file("missing.ply"), "it does not exist"},
                                  std::pair{std::filesystem::path("/dev/zero"), "it is not a regular file"}}) {
    auto reader = PlyReader::open(path);
    ASSERT_FALSE(reader.ok()) << path;
    EXPECT_EQ(reader.status().code(), ErrorCode::io);
    EXPECT_NE(reader.status().message().find(path.string() + ": cannot read the PLY: " + why), std::string::npos)
        << reader.status().message();
  }
}

TEST(PlyReader, StreamsInBatchesNoLargerThanTheBuffer) {
  ScratchDir dir;
  const VertexLayout layout{true, true, true};  // 11 floats = 44 bytes per vertex
  const test::TestMesh mesh = test::strip_mesh(layout, true, 1000);
  for (PlyFormat format : kFormats) {
    SCOPED_TRACE(std::string(to_string(format)));
    const auto path = dir.file("stream.ply");
    ASSERT_TRUE(write_ply(path, {format, layout, PlyColorType::uchar, {}, {}}, mesh.vertices,
                          mesh.triangles).ok());
    auto reader = PlyReader::open(path, test::small_batches());
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    std::vector<float> vertices;
    std::vector<std::uint32_t> triangles;
    int vertex_batches = 0;
    int triangle_batches = 0;
    for (;;) {
      auto batch = reader.value()->next();
      ASSERT_TRUE(batch.ok()) << batch.status().message();
      if (batch->kind == PlyBatch::Kind::end) break;
      if (batch->kind == PlyBatch::Kind::vertices) {
        EXPECT_EQ(batch->first, vertices.size() / layout.floats());
        EXPECT_LE(batch->vertices.size_bytes(), 4096u);
        vertices.insert(vertices.end(), batch->vertices.begin(), batch->vertices.end());
        ++vertex_batches;
      } else {
        EXPECT_EQ(batch->first, triangles.size() / 3);
        EXPECT_LE(batch->triangles.size_bytes(), 4096u);
        triangles.insert(triangles.end(), batch->triangles.begin(), batch->triangles.end());
        ++triangle_batches;
      }
    }
    EXPECT_EQ(vertex_batches, (1000 + 92) / 93);    // 4096 / 44 = 93 vertices per batch
    EXPECT_EQ(triangle_batches, (998 + 340) / 341);  // 4096 / 12 = 341 triangles per batch
    EXPECT_TRUE(same_bits(mesh.vertices, vertices));
    EXPECT_EQ(triangles, mesh.triangles);
    // end is sticky
    auto again = reader.value()->next();
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(again->kind, PlyBatch::Kind::end);
  }
}

// Every triangle batch (and its corner values, when the faces give their corners attributes),
// read in the smallest batches.
struct TriangleStream {
  std::vector<std::uint32_t> triangles;
  std::vector<float> corner_values;
  int batches = 0;
};
TriangleStream stream_triangles(const std::filesystem::path& path) {
  TriangleStream out;
  auto reader = PlyReader::open(path, test::small_batches());
  EXPECT_TRUE(reader.ok()) << reader.status().message();
  if (!reader.ok()) return out;
  for (;;) {
    auto batch = reader.value()->next();
    EXPECT_TRUE(batch.ok()) << batch.status().message();
    if (!batch.ok() || batch->kind == PlyBatch::Kind::end) break;
    if (batch->kind != PlyBatch::Kind::triangles) continue;
    EXPECT_EQ(batch->first, out.triangles.size() / 3);
    EXPECT_EQ(batch->corner_values.size(), reader.value()->info().corners.floats() * batch->triangles.size());
    out.triangles.insert(out.triangles.end(), batch->triangles.begin(), batch->triangles.end());
    out.corner_values.insert(out.corner_values.end(), batch->corner_values.begin(), batch->corner_values.end());
    ++out.batches;
  }
  return out;
}

// One polygon of `sides` vertices (vertex i at (i, i + 1, i + 2)), corner k on vertex 7k mod
// sides; with corners.uv corner k's texture coordinates (k, -k / 2), with corners.color the face's
// colour (uchar 51, 102, 255: 0.2, 0.4, 1 as floats) after its indices.
std::string polygon_ply(PlyFormat format, std::uint32_t sides, CornerAttributes corners) {
  const bool binary = format != PlyFormat::ascii;
  const bool big = format == PlyFormat::binary_big_endian;
  std::string text = "ply\nformat " + std::string(to_string(format)) + " 1.0\nelement vertex " +
                     std::to_string(sides) + "\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 1\nproperty list ushort uint vertex_indices\n" +
                     (corners.color ? "property uchar red\nproperty uchar green\nproperty uchar blue\n" : "") +
                     (corners.uv ? "property list ushort double texcoord\n" : "") + "end_header\n";
  for (std::uint32_t i = 0; i < sides; ++i) {
    if (binary) {
      for (std::uint32_t k = 0; k < 3; ++k) append_scalar(text, static_cast<float>(i + k), big);
    } else {
      text += std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
    }
  }
  if (binary) {
    append_scalar(text, static_cast<std::uint16_t>(sides), big);
    for (std::uint32_t i = 0; i < sides; ++i) append_scalar(text, (i * 7) % sides, big);
    if (corners.color)
      for (int channel : {51, 102, 255}) append_scalar(text, static_cast<std::uint8_t>(channel), big);
    if (corners.uv) {
      append_scalar(text, static_cast<std::uint16_t>(2 * sides), big);
      for (std::uint32_t i = 0; i < sides; ++i) {
        append_scalar(text, static_cast<double>(i), big);
        append_scalar(text, -0.5 * i, big);
      }
    }
  } else {
    text += std::to_string(sides);
    for (std::uint32_t i = 0; i < sides; ++i) text += " " + std::to_string((i * 7) % sides);
    if (corners.color) text += " 51 102 255";
    if (corners.uv) {
      text += " " + std::to_string(2 * sides);
      for (std::uint32_t i = 0; i < sides; ++i) text += " " + std::to_string(i) + " " + std::to_string(-0.5 * i);
    }
    text += "\n";
  }
  return text;
}

// A 2000-gon fans into 1998 triangles, more than one 4 KiB batch holds (341): the fan must
// continue across batches with the same centre, with its corners' UVs and colour when the faces
// have them (texcoord, red/green/blue), in every format.
TEST(PlyReader, HugePolygonFanSpansBatches) {
  ScratchDir dir;
  constexpr std::uint32_t kSides = 2000;
  for (const CornerAttributes corners : {CornerAttributes{}, CornerAttributes{.uv = true},
                                         CornerAttributes{.color = true}, CornerAttributes{.color = true, .uv = true}}) {
    for (PlyFormat format : kFormats) {
      SCOPED_TRACE(std::string(to_string(format)) + (corners.color ? " face colours" : "") +
                   (corners.uv ? " corner uvs" : ""));
      const auto path = dir.file("polygon.ply");
      write_bytes(path, polygon_ply(format, kSides, corners));
      const TriangleStream stream = stream_triangles(path);
      EXPECT_EQ(stream.batches, (1998 + 340) / 341);
      ASSERT_EQ(stream.triangles.size(), 3u * 1998);
      const std::size_t floats = corners.floats();
      ASSERT_EQ(stream.corner_values.size(), 3u * floats * 1998);
      for (std::uint32_t t = 0; t < 1998; ++t) {
        const std::uint32_t polygon_corners[3] = {0, t + 1, t + 2};
        for (std::uint32_t c = 0; c < 3; ++c) {
          const std::uint32_t k = polygon_corners[c];
          ASSERT_EQ(stream.triangles[3 * t + c], (k * 7) % kSides) << t;
          const float* values = stream.corner_values.data() + (3 * t + c) * floats;
          if (corners.color) {
            ASSERT_EQ(values[0], static_cast<float>(51 / 255.0)) << t;
            ASSERT_EQ(values[1], static_cast<float>(102 / 255.0)) << t;
            ASSERT_EQ(values[2], 1.0f) << t;
            values += 3;
          }
          if (!corners.uv) continue;
          ASSERT_EQ(values[0], static_cast<float>(k)) << t;
          ASSERT_EQ(values[1], static_cast<float>(-0.5 * k)) << t;
        }
      }
    }
  }
}

// ---- element order, skipping, aliases ----

//   3---2      quad 0 1 2 3     -> (0 1 2) (0 2 3)
//   |   |      pentagon 0 1 4 2 3 -> (0 1 4) (0 4 2) (0 2 3)
//   0---1  4
TEST(PlyReader, FacesBeforeVerticesAndPolygonsFanTriangulated) {
  ScratchDir dir;
  const auto path = dir.file("faces_first.ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\ncomment faces come first\n"
              "element face 3\nproperty list uchar int vertex_indices\n"
              "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n"
              "4 0 1 2 3\n5 0 1 4 2 3\n3 4 3 2\n"
              "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n");
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.info.face_count, 3u);
  EXPECT_EQ(mesh.triangles,
            (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 0, 1, 4, 0, 4, 2, 0, 2, 3, 4, 3, 2}));
  EXPECT_EQ(mesh.vertices, (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0}));
}

// ---- texture coordinates per face corner (texcoord) ----

//   3---2      quad 0 1 2 3 (its texcoord before its indices) -> (0 1 2) (0 2 3)
//   |   |      triangle 1 4 2, whose corner at 2 has another (u, v): a seam
//   0---1  4
TEST(PlyReader, CornerUvsComeWithTheirTrianglesAndReadPlyMakesWedges) {
  ScratchDir dir;
  const auto path = dir.file("corner_uvs.ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\ncomment TextureFile stone.png\n"
              "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
              "element face 2\nproperty list uchar float texcoord\nproperty uchar flags\n"
              "property list uchar int vertex_indices\nend_header\n"
              "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n"
              "8 0 0 1 0 1 1 0 1 7 4 0 1 2 3\n6 1 0 0.5 0 0.9 1 7 3 1 4 2\n");
  const TriangleStream stream = stream_triangles(path);
  EXPECT_EQ(stream.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 4, 2}));
  EXPECT_EQ(stream.corner_values, (std::vector<float>{0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1, 1, 0, 0.5f, 0, 0.9f, 1}));

  // one vertex per (vertex, u, v) in first use order: vertex 2 twice, once per side of the seam
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.info.corners, (CornerAttributes{.uv = true}));
  EXPECT_EQ(mesh.info.texture_files, std::vector<std::string>{"stone.png"});
  EXPECT_EQ(mesh.info.layout, (VertexLayout{.uv = true}));
  EXPECT_EQ(mesh.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 4, 5}));
  EXPECT_EQ(mesh.vertices, (std::vector<float>{0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1, 1, 0, 1, 0, 0, 1,
                                               2, 0, 0, 0.5f, 0, 1, 1, 0, 0.9f, 1}));
}

// ---- colours per face ----

// Face colours (uchar, with alpha) replace the vertices' colours: each corner gets its face's,
// read_ply makes a vertex per (vertex, colour) in first-use order, and the kept colours' type is
// the faces'. With texcoord as well each corner's values are its colour, then its (u, v).
//   3---2      quad 0 1 2 3 (red)        -> (0 1 2) (0 2 3)
//   |   |      triangle 1 4 2 (blue), after the colour
//   0---1  4
TEST(PlyReader, FaceColoursGoToTheirCornersAndReadPlyMakesWedges) {
  ScratchDir dir;
  const auto path = dir.file("face_colours.ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\n"
              "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
              "property float red\nproperty float green\nproperty float blue\n"
              "element face 2\nproperty list uchar int vertex_indices\nproperty uchar red\n"
              "property uchar green\nproperty uchar blue\nproperty uchar alpha\nend_header\n"
              "0 0 0 0.5 0.5 0.5\n1 0 0 0.5 0.5 0.5\n1 1 0 0.5 0.5 0.5\n0 1 0 0.5 0.5 0.5\n2 0 0 0.5 0.5 0.5\n"
              "4 0 1 2 3 255 0 0 9\n3 1 4 2 0 0 255 9\n");
  const TriangleStream stream = stream_triangles(path);
  EXPECT_EQ(stream.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 4, 2}));
  EXPECT_EQ(stream.corner_values, (std::vector<float>{1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0,
                                                      0, 0, 1, 0, 0, 1, 0, 0, 1}));
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.info.corners, (CornerAttributes{.color = true}));
  EXPECT_EQ(mesh.info.layout, (VertexLayout{.color = true}));
  // the vertices' colours the faces' replace are skipped, and so is the faces' alpha
  EXPECT_EQ(mesh.info.skipped, (std::vector<std::string>{"vertex.red", "vertex.green", "vertex.blue", "face.alpha"}));
  EXPECT_EQ(mesh.info.color_type, PlyColorType::uchar);
  EXPECT_EQ(mesh.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 4, 5, 6}));
  EXPECT_EQ(mesh.vertices, (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 1, 0, 0,
                                               0, 1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1, 2, 0, 0, 0, 0, 1,
                                               1, 1, 0, 0, 0, 1}));

  // float face colours and texcoord, vertices with normals and their own u, v (dropped)
  write_bytes(path,
              "ply\nformat ascii 1.0\n"
              "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
              "element face 1\nproperty float blue\nproperty list uchar float texcoord\nproperty float red\n"
              "property list uchar int vertex_indices\nproperty float green\nend_header\n"
              "0 0 0 0 0 1 9 9\n1 0 0 0 0 1 9 9\n0 1 0 0 0 1 9 9\n"
              "0.75 6 0 0 1 0 0 1 0.25 3 0 1 2 0.5\n");
  const TriangleStream both = stream_triangles(path);
  EXPECT_EQ(both.corner_values,
            (std::vector<float>{0.25f, 0.5f, 0.75f, 0, 0, 0.25f, 0.5f, 0.75f, 1, 0, 0.25f, 0.5f, 0.75f, 0, 1}));
  const PlyMesh textured = read_ok(path);
  EXPECT_EQ(textured.info.corners, (CornerAttributes{.color = true, .uv = true}));
  EXPECT_EQ(textured.info.color_type, PlyColorType::float32);
  EXPECT_EQ(textured.vertices, (std::vector<float>{0, 0, 0, 0, 0, 1, 0.25f, 0.5f, 0.75f, 0, 0,
                                                   1, 0, 0, 0, 0, 1, 0.25f, 0.5f, 0.75f, 1, 0,
                                                   0, 1, 0, 0, 0, 1, 0.25f, 0.5f, 0.75f, 0, 1}));
}

// The images a textured mesh's UVs index: every "comment TextureFile <name>", the keyword in any
// case, the name as written (spaces inside kept, around it dropped), in order.
TEST(PlyReader, InfoNamesTheTexturesOfTheTextureFileComments) {
  ScratchDir dir;
  const std::pair<std::string, std::vector<std::string>> cases[] = {
      {"comment TextureFile stone.png\n", {"stone.png"}},
      {"comment   texturefile \t old stone.jpg  \ncomment TextureFile second.png\n", {"old stone.jpg", "second.png"}},
      {"comment TextureFiles x.png\ncomment a TextureFile y.png\ncomment TextureFile\n", {}},
      {"", {}}};
  for (const auto& [comments, expected] : cases) {
    SCOPED_TRACE(comments);
    const auto path = dir.file("textured.ply");
    write_bytes(path, "ply\nformat ascii 1.0\n" + comments +
                          "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    auto reader = PlyReader::open(path);
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    EXPECT_EQ(reader.value()->info().texture_files, expected);
  }
}

TEST(PlyReader, SkipsUnknownElementsAndPropertiesIncludingLists) {
  ScratchDir dir;
  for (PlyFormat format : kFormats) {
    SCOPED_TRACE(std::string(to_string(format)));
    const bool big = format == PlyFormat::binary_big_endian;
    std::string text = "ply\nformat " + std::string(to_string(format)) +
                       " 1.0\nobj_info scanner 7\n"
                       "element camera 2\nproperty double focal\nproperty list int short samples\n"
                       "element vertex 3\nproperty uchar flags\nproperty float x\n"
                       "property list uchar float extra\nproperty float y\nproperty double quality\n"
                       "property float z\nproperty float nx\n"  // lone nx: no normal
                       "element face 1\nproperty int material\nproperty list uchar int vertex_indices\n"
                       "property list uint uchar tags\n"
                       "element edge 2\nproperty int vertex1\nproperty int vertex2\n"
                       "end_header\n";
    if (format == PlyFormat::ascii) {
      text += "1.5 2 7 8\n2.5 0\n";
      text += "9 1 2 10 20 2 9 3 1\n9 4 0 5 9 6 1\n\n9 7 1 0 8 9 9 1\n";
      text += "42 3 2 1 0 3 1 2 3\n";
      text += "0 1\n1 2\n";
    } else {
      append_scalar(text, 1.5, big);
      append_scalar(text, std::int32_t{2}, big);
      append_scalar(text, std::int16_t{7}, big);
      append_scalar(text, std::int16_t{8}, big);
      append_scalar(text, 2.5, big);
      append_scalar(text, std::int32_t{0}, big);
      const float xyz[3][3] = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
      for (const auto& v : xyz) {
        text += '\x09';
        append_scalar(text, v[0], big);
        text += '\x01';
        append_scalar(text, 10.0f, big);
        append_scalar(text, v[1], big);
        append_scalar(text, 9.0, big);
        append_scalar(text, v[2], big);
        append_scalar(text, 1.0f, big);
      }
      append_scalar(text, std::int32_t{42}, big);
      text += '\x03';
      for (std::int32_t i : {2, 1, 0}) append_scalar(text, i, big);
      append_scalar(text, std::uint32_t{3}, big);
      text += "\x01\x02\x03";
      for (std::int32_t i : {0, 1, 1, 2}) append_scalar(text, i, big);
    }
    const auto path = dir.file("extra.ply");
    write_bytes(path, text);
    const PlyMesh mesh = read_ok(path);
    EXPECT_EQ(mesh.info.layout, VertexLayout{});
    EXPECT_EQ(mesh.vertices, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
    EXPECT_EQ(mesh.triangles, (std::vector<std::uint32_t>{2, 1, 0}));
    // what was skipped, named for `octolod info`
    EXPECT_EQ(mesh.info.skipped, (std::vector<std::string>{"element camera", "vertex.flags", "vertex.extra",
                                                           "vertex.quality", "vertex.nx", "face.material",
                                                           "face.tags", "element edge"}));
  }
}

TEST(PlyReader, ElementsWithoutPropertiesTakeNoSpace) {
  ScratchDir dir;
  for (PlyFormat format : kFormats) {
    SCOPED_TRACE(std::string(to_string(format)));
    std::string text = "ply\nformat " + std::string(to_string(format)) +
                       " 1.0\nelement marker 1000000\nelement vertex 1\nproperty uchar x\n"
                       "property uchar y\nproperty uchar z\nelement empty 5\nend_header\n";
    text += format == PlyFormat::ascii ? "1 2 3\n" : "\x01\x02\x03";
    const auto path = dir.file("empty_elements.ply");
    write_bytes(path, text);
    EXPECT_EQ(read_ok(path).vertices, (std::vector<float>{1, 2, 3}));
  }
}

TEST(PlyReader, VertexIndexAndTextureAliases) {
  ScratchDir dir;
  struct Alias {
    const char* u;
    const char* v;
  };
  for (Alias alias : {Alias{"u", "v"}, Alias{"s", "t"}, Alias{"texture_u", "texture_v"},
                      Alias{"texture_s", "texture_t"}}) {
    SCOPED_TRACE(alias.u);
    const auto path = dir.file("alias.ply");
    write_bytes(path, std::string("ply\nformat ascii 1.0\nelement vertex 3\n") +
                          "property float " + alias.v + "\nproperty float x\nproperty float y\n"
                          "property float z\nproperty float " + alias.u + "\n"
                          "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
                          "0.5 0 0 0 0.25\n0.75 1 0 0 1\n1 0 1 0 0\n3 0 1 2\n");
    const PlyMesh mesh = read_ok(path);
    EXPECT_EQ(mesh.info.layout, (VertexLayout{false, false, true}));
    EXPECT_EQ(mesh.vertices, (std::vector<float>{0, 0, 0, 0.25f, 0.5f, 1, 0, 0, 1, 0.75f,
                                                 0, 1, 0, 0, 1}));
    EXPECT_EQ(mesh.triangles, (std::vector<std::uint32_t>{0, 1, 2}));
  }
}

// Some exporters name the colour diffuse_red / _green / _blue: the same colour.
TEST(PlyReader, DiffuseColourAlias) {
  ScratchDir dir;
  const auto path = dir.file("diffuse.ply");
  write_bytes(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nproperty uchar diffuse_red\nproperty uchar diffuse_green\n"
                    "property uchar diffuse_blue\nelement face 1\nproperty list uchar int vertex_indices\n"
                    "end_header\n0 0 0 255 0 51\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n");
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.info.layout, (VertexLayout{false, true, false}));
  EXPECT_EQ(mesh.info.color_type, PlyColorType::uchar);
  EXPECT_EQ(std::vector<float>(mesh.vertices.begin(), mesh.vertices.begin() + 6),
            (std::vector<float>{0, 0, 0, 1, 0, 0.2f}));
}

// Big-endian doubles for positions, ushort colours (divided by 65535) with an alpha that is
// dropped, float normals, short-counted int indices.
TEST(PlyReader, BigEndianDoublesAndWideColours) {
  ScratchDir dir;
  std::string text =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\n"
      "property float64 x\nproperty float64 y\nproperty float64 z\n"
      "property uint16 red\nproperty uint16 green\nproperty uint16 blue\nproperty uint16 alpha\n"
      "property float32 nx\nproperty float32 ny\nproperty float32 nz\n"
      "element face 1\nproperty list int16 int32 vertex_indices\nend_header\n";
  const double positions[3][3] = {{0.1, -2e10, 1e-300}, {1, 2, 3}, {-4, 5.5, 6.25}};
  for (int i = 0; i < 3; ++i) {
    for (double p : positions[i]) append_scalar(text, p, true);
    for (std::uint16_t c : {std::uint16_t{0}, std::uint16_t{65535}, std::uint16_t{32768},
                            std::uint16_t{7}})
      append_scalar(text, c, true);
    for (float n : {0.0f, 0.0f, 1.0f}) append_scalar(text, n, true);
  }
  append_scalar(text, std::int16_t{3}, true);
  for (std::int32_t i : {2, 0, 1}) append_scalar(text, i, true);
  const auto path = dir.file("big.ply");
  write_bytes(path, text);
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.info.format, PlyFormat::binary_big_endian);
  EXPECT_EQ(mesh.info.layout, (VertexLayout{true, true, false}));
  EXPECT_EQ(mesh.info.color_type, PlyColorType::uchar);
  ASSERT_EQ(mesh.vertices.size(), 27u);
  for (int i = 0; i < 3; ++i) {
    const float* v = mesh.vertices.data() + 9 * i;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(v[k], static_cast<float>(positions[i][k]));
    EXPECT_EQ(v[3], 0.0f);
    EXPECT_EQ(v[5], 1.0f);
    EXPECT_EQ(v[6], 0.0f);
    EXPECT_EQ(v[7], 1.0f);
    EXPECT_EQ(v[8], static_cast<float>(32768 / 65535.0));
  }
  EXPECT_EQ(mesh.triangles, (std::vector<std::uint32_t>{2, 0, 1}));
}

// A geo-referenced mesh: `n` vertices 1 mm apart along x, 4,000 km from the origin (where floats
// are 0.25 apart), as double positions, ascii or little-endian binary.
std::string far_double_mesh(PlyFormat format, int n, std::vector<std::array<double, 3>>& positions) {
  std::string text = std::string("ply\nformat ") + (format == PlyFormat::ascii ? "ascii" : "binary_little_endian") +
                     " 1.0\nelement vertex " + std::to_string(n) +
                     "\nproperty double x\nproperty double y\nproperty double z\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n";
  positions.clear();
  for (int i = 0; i < n; ++i) {
    positions.push_back({4000000.375 + 0.001 * i, -500000.5, 12.25 + 0.001 * i});
    for (double p : positions.back()) {
      if (format == PlyFormat::ascii) {
        char number[64];
        std::snprintf(number, sizeof number, "%.17g ", p);
        text += number;
      } else {
        append_scalar(text, p, false);
      }
    }
    if (format == PlyFormat::ascii) text += "\n";
  }
  if (format == PlyFormat::ascii) return text + "3 0 1 2\n";
  text += '\x03';
  for (std::int32_t i : {0, 1, 2}) append_scalar(text, i, false);
  return text;
}

TEST(PlyReader, DoublePositionsAreRecentredOnTheFirstVertexBeforeRoundingToFloat) {
  ScratchDir dir;
  for (PlyFormat format : {PlyFormat::ascii, PlyFormat::binary_little_endian}) {
    SCOPED_TRACE(std::string(to_string(format)));
    std::vector<std::array<double, 3>> positions;
    const auto path = dir.file("far.ply");
    write_bytes(path, far_double_mesh(format, 500, positions));  // binary: several batches, the fast path
    PlyReadOptions options = test::small_batches();
    options.recentre_double_positions = true;
    Result<PlyMesh> mesh = read_ply(path, options);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    EXPECT_TRUE(mesh->info.double_positions);
    // the first vertex rounded to whole units (half away from zero)
    EXPECT_EQ(mesh->info.position_origin, (std::array<double, 3>{4000000.0, -500001.0, 12.0}));
    ASSERT_EQ(mesh->vertices.size(), 3 * positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i)
      for (std::size_t k = 0; k < 3; ++k)
        ASSERT_EQ(mesh->vertices[3 * i + k], static_cast<float>(positions[i][k] - mesh->info.position_origin[k]))
            << "vertex " << i;
    // 1 mm steps survive; without the origin, every x of the first 125 vertices is one float
    EXPECT_NE(mesh->vertices[0], mesh->vertices[3]);
    Result<PlyMesh> absolute = read_ply(path);
    ASSERT_TRUE(absolute.ok());
    EXPECT_EQ(absolute->info.position_origin, (std::array<double, 3>{0.0, 0.0, 0.0}));
    EXPECT_EQ(absolute->vertices[0], absolute->vertices[3]);
    // a given origin instead: the frame of another mesh
    options.position_origin = std::array<double, 3>{4000000.0, -500000.0, 0.0};
    Result<PlyMesh> framed = read_ply(path, options);
    ASSERT_TRUE(framed.ok());
    EXPECT_EQ(framed->info.position_origin, *options.position_origin);
    EXPECT_EQ(framed->vertices[1], -0.5f);
    EXPECT_EQ(framed->vertices[2], 12.25f);
  }
}

TEST(PlyReader, FloatPositionsAreNotRecentredButTakeAGivenOrigin) {
  ScratchDir dir;
  const VertexLayout layout{false, false, false};
  const test::TestMesh mesh = test::strip_mesh(layout, true, 5);
  const auto path = dir.file("float.ply");
  ASSERT_TRUE(write_ply(path, {PlyFormat::binary_little_endian, layout, PlyColorType::uchar, {}, {}}, mesh.vertices,
                        mesh.triangles).ok());
  PlyReadOptions options;
  options.recentre_double_positions = true;
  Result<PlyMesh> read = read_ply(path, options);
  ASSERT_TRUE(read.ok());
  EXPECT_FALSE(read->info.double_positions);
  EXPECT_EQ(read->info.position_origin, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_TRUE(same_bits(mesh.vertices, read->vertices));
  options.position_origin = std::array<double, 3>{1.0, 2.0, 3.0};
  Result<PlyMesh> shifted = read_ply(path, options);
  ASSERT_TRUE(shifted.ok());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    EXPECT_EQ(shifted->vertices[i], static_cast<float>(mesh.vertices[i] - (*options.position_origin)[i % 3]));
}

TEST(PlyReader, IntegerAndFloatColourTypes) {
  ScratchDir dir;
  const auto path = dir.file("colors.ply");
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
              "property float z\nproperty char red\nproperty float green\nproperty double blue\n"
              "element face 0\nproperty list uchar int vertex_indices\nend_header\n"
              "0 0 0 127 0.25 2.5\n1 1 1 -127 -1 0\n");
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.info.color_type, PlyColorType::uchar);  // the type of red decides
  EXPECT_EQ(mesh.vertices, (std::vector<float>{0, 0, 0, 1, 0.25f, 2.5f, 1, 1, 1, -1, -1, 0}));
  EXPECT_TRUE(mesh.triangles.empty());
  EXPECT_EQ(byte_color(255), 1.0f);
}

TEST(PlyReader, ToleratesCrLfHeaderBlankLinesAndPlusSigns) {
  ScratchDir dir;
  const auto path = dir.file("crlf.ply");
  write_bytes(path,
              "ply\r\nformat ascii 1.0\r\ncomment made on windows\r\nelement vertex 3\r\n"
              "property float x\r\nproperty float y\r\nproperty float z\r\n"
              "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
              "+1 2e0 -3\r\n\r\n4\t5 6\r\n7 8 9\r\n3 0 +1 2\r\n\r\n  \n");
  const PlyMesh mesh = read_ok(path);
  EXPECT_EQ(mesh.vertices, (std::vector<float>{1, 2, -3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(mesh.triangles, (std::vector<std::uint32_t>{0, 1, 2}));
}

TEST(PlyReader, InfoDescribesTheHeader) {
  ScratchDir dir;
  const auto path = dir.file("info.ply");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
      "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nend_header\n";
  write_bytes(path, header);
  auto reader = PlyReader::open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  const PlyInfo& info = reader.value()->info();
  EXPECT_EQ(info.path, path);
  EXPECT_EQ(info.vertex_count, 0u);
  EXPECT_EQ(info.face_count, 0u);
  EXPECT_EQ(info.layout, (VertexLayout{false, true, false}));
  EXPECT_EQ(info.header_bytes, header.size());
  auto batch = reader.value()->next();
  ASSERT_TRUE(batch.ok());
  EXPECT_EQ(batch->kind, PlyBatch::Kind::end);
}

// ---- trailing data ----

TEST(PlyReader, BinaryIgnoresAndCountsTrailingBytes) {
  ScratchDir dir;
  const test::TestMesh mesh = test::strip_mesh(VertexLayout{}, true);
  for (PlyFormat format : {PlyFormat::binary_little_endian, PlyFormat::binary_big_endian}) {
    const auto path = dir.file("trailing.ply");
    ASSERT_TRUE(write_ply(path, {format, {}, PlyColorType::uchar, {}, {}}, mesh.vertices,
                          mesh.triangles).ok());
    EXPECT_EQ(read_ok(path).info.trailing_bytes, 0u);
    write_bytes(path, test::read_bytes(path) + std::string("\0\0garbage\n", 10));
    const PlyMesh read = read_ok(path);
    EXPECT_TRUE(same_bits(mesh.vertices, read.vertices));
    EXPECT_EQ(read.triangles, mesh.triangles);
    EXPECT_EQ(read.info.trailing_bytes, 10u);  // counted, for callers to warn
  }
}

TEST(PlyReader, AsciiAllowsTrailingWhitespaceOnly) {
  ScratchDir dir;
  const auto path = dir.file("trailing.ply");
  const std::string body =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0";  // no final newline either
  write_bytes(path, body + "\n \n\t\n");
  EXPECT_EQ(read_ok(path).vertices.size(), 9u);
  write_bytes(path, body);
  EXPECT_EQ(read_ok(path).vertices.size(), 9u);
  write_bytes(path, body + "\n\n7\n");
  EXPECT_TRUE(test::is_error(test::status_of(read_ply(path)), ErrorCode::bad_input,
                             {path.string(), "line 12", "unexpected data '7' after the last element"}));
}

}  // namespace
}  // namespace octolod
