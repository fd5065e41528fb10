// PlyReader on broken input: every failure is a Status (never a crash or a throw) with the
// right code, and a message naming the file, the line (ascii and headers) or byte offset
// (binary bodies), and the problem. Truncation is tried at every byte length.
#include <gtest/gtest.h>
#include <unistd.h>

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
using test::status_of;
using test::write_bytes;

constexpr const char* kXyz = "property float x\nproperty float y\nproperty float z\n";
constexpr const char* kFaces = "element face 1\nproperty list uchar int vertex_indices\n";

// ply(1) format(2) element vertex(3) x y z(4-6) element face(7) list(8) end_header(9);
// body lines start at 10.
std::string ascii_mesh(const std::string& vertices, const std::string& faces) {
  return std::string("ply\nformat ascii 1.0\nelement vertex 3\n") + kXyz + kFaces +
         "end_header\n" + vertices + faces;
}
// The same with `texcoord` after the indices: header lines 1-10, body lines start at 11 (the
// face's line is 14).
std::string ascii_uv_mesh(const std::string& faces, const std::string& texcoord_type = "float") {
  return std::string("ply\nformat ascii 1.0\nelement vertex 3\n") + kXyz + kFaces +
         "property list uchar " + texcoord_type + " texcoord\nend_header\n" +
         "0.000 0.000 0.000\n1.000 0.000 0.000\n0.000 1.000 0.000\n" + faces;
}
// The same with a colour per face (`type` red, green, blue) after the indices: header lines
// 1-12, the face's line is 16.
std::string ascii_face_color_mesh(const std::string& faces, const std::string& type = "float") {
  return std::string("ply\nformat ascii 1.0\nelement vertex 3\n") + kXyz + kFaces + "property " + type +
         " red\nproperty " + type + " green\nproperty " + type + " blue\nend_header\n" +
         "0.000 0.000 0.000\n1.000 0.000 0.000\n0.000 1.000 0.000\n" + faces;
}
constexpr std::size_t kOneMiB = std::size_t{1} << 20;
const std::string kGoodVertices = "0.000 0.000 0.000\n1.000 0.000 0.000\n0.000 1.000 0.000\n";

struct MalformedCase {
  const char* name;
  std::string content;
  ErrorCode code;
  std::string location;  // "line N"
  std::string problem;
};

std::string huge_header() {
  std::string text = "ply\nformat ascii 1.0\n";
  const std::string comment = "comment " + std::string(91, 'c') + "\n";  // 100 bytes
  while (text.size() <= kOneMiB) text += comment;
  return text;
}

std::vector<MalformedCase> malformed_cases() {
  return {
      {"Empty", "", ErrorCode::bad_input, "line 1", "empty file"},
      {"BadMagic", "plx\nformat ascii 1.0\n", ErrorCode::bad_input, "line 1",
       "missing 'ply' magic"},
      {"BinaryGarbage", std::string("\x89PNG\r\n\x1a\n", 8), ErrorCode::bad_input, "line 1",
       "missing 'ply' magic, the file starts with '\\x89PNG'"},
      {"BareCrLineEnds", "ply\rformat ascii 1.0\relement vertex 0\rend_header\r", ErrorCode::bad_input, "line 1",
       "the header's lines end in a bare CR"},
      {"MissingFormat", "ply\nelement vertex 0\n", ErrorCode::bad_input, "line 2",
       "expected the format line"},
      {"GarbledFormat", "ply\nformat ascii\nend_header\n", ErrorCode::bad_input, "line 2",
       "bad format line 'format ascii'"},
      {"UnknownFormat", "ply\nformat binary 1.0\nend_header\n", ErrorCode::bad_input, "line 2",
       "bad format line"},
      {"Version2", "ply\nformat ascii 2.0\nend_header\n", ErrorCode::unsupported, "line 2",
       "PLY version '2.0' is not supported"},
      {"UnknownType",
       "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty half y\nend_header\n",
       ErrorCode::bad_input, "line 5", "unknown property type 'half'"},
      {"FloatListCount",
       "ply\nformat ascii 1.0\nelement face 0\nproperty list float int vertex_indices\n",
       ErrorCode::bad_input, "line 4", "list count type 'float' is not an integer type"},
      {"PropertyBeforeElement", "ply\nformat ascii 1.0\nproperty float x\n", ErrorCode::bad_input,
       "line 3", "property before any element"},
      {"UnknownKeyword", "ply\nformat ascii 1.0\nelemnt vertex 3\n", ErrorCode::bad_input,
       "line 3", "unknown header keyword 'elemnt'"},
      {"BadElementCount", "ply\nformat ascii 1.0\nelement vertex -5\n", ErrorCode::bad_input,
       "line 3", "bad element count '-5'"},
      {"DuplicateProperty",
       "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty uchar x\n",
       ErrorCode::bad_input, "line 5", "property 'x' declared twice"},
      {"DuplicateElement", "ply\nformat ascii 1.0\nelement vertex 0\nelement vertex 0\n",
       ErrorCode::bad_input, "line 4", "element 'vertex' declared twice"},
      {"MissingEndHeader", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n",
       ErrorCode::bad_input, "line 4", "missing end_header"},
      {"HeaderOver1MiB", huge_header(), ErrorCode::bad_input, "line 10488",
       "header exceeds 1 MiB"},
      {"NoVertexElement", "ply\nformat ascii 1.0\nelement face 0\n"
                          "property list uchar int vertex_indices\nend_header\n",
       ErrorCode::bad_input, "line 5", "no 'vertex' element"},
      {"VertexWithoutZ",
       "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
       ErrorCode::bad_input, "line 3", "element 'vertex' has no property 'z'"},
      {"FaceWithoutIndices",
       std::string("ply\nformat ascii 1.0\nelement vertex 0\n") + kXyz +
           "element face 0\nproperty list uchar int corners\nend_header\n",
       ErrorCode::bad_input, "line 7", "no list property vertex_indices or vertex_index"},
      {"FloatIndices",
       std::string("ply\nformat ascii 1.0\nelement vertex 0\n") + kXyz +
           "element face 0\nproperty list uchar float vertex_indices\nend_header\n",
       ErrorCode::bad_input, "line 7", "non-integer items (float)"},
      {"CountLargerThanFile", ascii_mesh("0 0 0\n1 0 0\n", ""), ErrorCode::bad_input, "line 3",
       "element 'vertex' declares 3 entries of at least 6 bytes each, more than the file can hold"},
      {"ElementMissing", ascii_mesh(kGoodVertices, ""), ErrorCode::bad_input, "line 13",
       "file ends early: element 'face' declares 1 entries, found 0"},
      {"LineMissing", ascii_mesh("0.000000 0.000000 0.000000\n1.000000 1.000000 1.000000\n"
                                 "3 0 1 2\n", ""),
       ErrorCode::bad_input, "line 12", "extra value '2' after vertex 2 of 3"},
      {"TooFewValues", ascii_mesh("0.000 0.000\n1.000 0.000 0.000\n0.000 1.000 0.000\n", "3 0 1 2\n"),
       ErrorCode::bad_input, "line 10", "vertex 0 of 3 has too few values"},
      {"ExtraValues", ascii_mesh(kGoodVertices, "3 0 1 2 0\n"), ErrorCode::bad_input, "line 13",
       "extra value '0' after face 0 of 1"},
      {"BadNumber", ascii_mesh("0.000 0.000 0.000\n1.000 abc 0.000\n0.000 1.000 0.000\n", "3 0 1 2\n"),
       ErrorCode::bad_input, "line 11", "bad float value 'abc' in vertex 1 of 3"},
      {"NanCoordinate", ascii_mesh("0.000 0.000 0.000\n1.000 0.000 0.000\n0.000 nan 0.000\n", "3 0 1 2\n"),
       ErrorCode::bad_input, "line 12", "vertex 2 has a non-finite y (NaN)"},
      {"InfCoordinate", ascii_mesh("-inf 0.000 0.000\n1.000 0.000 0.000\n0.000 0.000 0.000\n", "3 0 1 2\n"),
       ErrorCode::bad_input, "line 10", "vertex 0 has a non-finite x (Inf)"},
      {"FloatOverflowCoordinate",
       ascii_mesh("0.000 0.000 0.000\n1.000 0.000 1e39\n0.000 0.000 0.000\n", "3 0 1 2\n"),
       ErrorCode::bad_input, "line 11", "vertex 1 has a non-finite z (Inf)"},
      {"CoordinateBeyond1e18",
       ascii_mesh("0.000 0.000 0.000\n1.000 -2e19 0.000\n0.000 0.000 0.000\n", "3 0 1 2\n"),
       ErrorCode::bad_input, "line 11", "vertex 1 has a y of -2e+19, beyond ±1e18"},
      {"ListCountTwo", ascii_mesh(kGoodVertices, "2 0 1     \n"), ErrorCode::bad_input, "line 13",
       "face 0 has 2 vertices (a polygon needs 3 to 1048576)"},
      {"ListCountZero", ascii_mesh(kGoodVertices, "0         \n"), ErrorCode::bad_input, "line 13",
       "face 0 has 0 vertices"},
      {"ListCountZeroInATightFile", ascii_mesh("0 0 0\n1 0 0\n0 1 0\n", "0\n"), ErrorCode::bad_input, "line 7",
       "truncated file or corrupt count (or faces of fewer than 3 vertices, which are not polygons)"},
      {"ListCountOver2To20",
       std::string("ply\nformat ascii 1.0\nelement vertex 3\n") + kXyz +
           "element face 1\nproperty list uint int vertex_indices\nend_header\n" + kGoodVertices +
           "1048577 0 1 2\n",
       ErrorCode::bad_input, "line 13", "face 0 has 1048577 vertices"},
      {"ListCountOverUchar", ascii_mesh(kGoodVertices, "256 0 1 2\n"), ErrorCode::bad_input,
       "line 13", "bad uchar value '256'"},
      {"IndexOutOfRange", ascii_mesh(kGoodVertices, "3 0 1 3\n"), ErrorCode::bad_input, "line 13",
       "face 0 has vertex index 3, out of range (the file has 3 vertices)"},
      {"NegativeIndex", ascii_mesh(kGoodVertices, "3 0 -1 2\n"), ErrorCode::bad_input, "line 13",
       "face 0 has a negative vertex index -1"},
      {"NegativeListCountInSkippedElement",
       std::string("ply\nformat ascii 1.0\nelement vertex 0\n") + kXyz +
           "element extra 1\nproperty list int float data\nend_header\n-1 0 0 0\n",
       ErrorCode::bad_input, "line 10", "negative count -1 for list 'data'"},
      {"TexcoordCountNotTwoPerCorner", ascii_uv_mesh("3 0 1 2 4 0 0 1 0\n"), ErrorCode::bad_input, "line 14",
       "face 0 has 4 texture coordinates for 3 vertices (texcoord holds u and v for every corner)"},
      {"TexcoordNaN", ascii_uv_mesh("3 0 1 2 6 0 0 1 nan 0 1\n"), ErrorCode::bad_input, "line 14",
       "face 0 has a texture coordinate of NaN"},
      {"TexcoordBeyond1e18", ascii_uv_mesh("3 0 1 2 6 0 0 1 3e18 0 1\n"), ErrorCode::bad_input, "line 14",
       "face 0 has a texture coordinate of 3e+18, beyond ±1e18"},
      {"TexcoordIntegers", ascii_uv_mesh("3 0 1 2 6 0 0 1 0 0 1\n", "int"), ErrorCode::bad_input, "line 7",
       "face property 'texcoord' is not a list of floats"},
      {"TexcoordIndexOutOfRange", ascii_uv_mesh("3 0 1 3 6 0 0 1 0 0 1\n"), ErrorCode::bad_input, "line 14",
       "face 0 has vertex index 3, out of range (the file has 3 vertices)"},
      {"FaceColourNaN", ascii_face_color_mesh("3 0 1 2 0.5 nan 1\n"), ErrorCode::bad_input, "line 16",
       "face 0 has a non-finite green (NaN)"},
      {"FaceColourBeyond1e18", ascii_face_color_mesh("3 0 1 2 0.5 1 -2e19\n"), ErrorCode::bad_input,
       "line 16", "face 0 has a blue of -2e+19, beyond ±1e18"},
      {"FaceColourOverUchar", ascii_face_color_mesh("3 0 1 2 255 256 0\n", "uchar"), ErrorCode::bad_input,
       "line 16", "bad uchar value '256'"},
      {"FaceColourIndexOutOfRange", ascii_face_color_mesh("3 0 5 2 1 1 1\n"), ErrorCode::bad_input,
       "line 16", "face 0 has vertex index 5, out of range (the file has 3 vertices)"},
      {"AsciiOverlongValue", ascii_mesh(std::string(2000, '1') + " 0 0\n" + kGoodVertices, ""),
       ErrorCode::bad_input, "line 10", "value longer than 1024 characters in vertex 0 of 3"},
  };
}

// Names the case in test listings instead of dumping its bytes.
void PrintTo(const MalformedCase& c, std::ostream* os) { *os << c.name; }

class PlyMalformed : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(PlyMalformed, FailsNamingFileLocationAndProblem) {
  const MalformedCase& c = GetParam();
  ScratchDir dir;
  const auto path = dir.file(std::string(c.name) + ".ply");
  write_bytes(path, c.content);
  EXPECT_TRUE(is_error(status_of(read_ply(path)), c.code,
                       {path.string() + ": " + c.location + ": ", c.problem}));
}

INSTANTIATE_TEST_SUITE_P(Ascii, PlyMalformed, ::testing::ValuesIn(malformed_cases()),
                         [](const auto& test_case) { return std::string(test_case.param.name); });

// ---- binary bodies: byte offsets ----

struct BinaryMesh {
  std::string bytes;
  std::size_t header = 0;  // header size: vertex 0 starts here
};

// Three float-xyz vertices (12 bytes each) and the given face list bytes.
BinaryMesh binary_mesh(bool big, const std::string& face_element, const std::string& faces,
                       float y0 = 0.0f) {
  BinaryMesh mesh;
  mesh.bytes = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
               " 1.0\nelement vertex 3\n" + kXyz + face_element + "end_header\n";
  mesh.header = mesh.bytes.size();
  for (float v : {0.0f, y0, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}) append_scalar(mesh.bytes, v, big);
  mesh.bytes += faces;
  return mesh;
}

std::string int_list(bool big, std::initializer_list<std::int32_t> items, std::uint8_t count) {
  std::string out(1, static_cast<char>(count));
  for (std::int32_t i : items) append_scalar(out, i, big);
  return out;
}

Status read_status(const ScratchDir& dir, const std::string& bytes) {
  const auto path = dir.file("binary.ply");
  write_bytes(path, bytes);
  return status_of(read_ply(path));
}

std::string at(const ScratchDir& dir, std::size_t offset) {
  return dir.file("binary.ply").string() + ": byte offset " + std::to_string(offset) + ": ";
}

TEST(PlyMalformedBinary, TruncatedPolygonNamesTheOffset) {
  ScratchDir dir;
  for (bool big : {false, true}) {
    // A quad whose last index is missing: the size check (3 indices minimum) cannot see it.
    const BinaryMesh m = binary_mesh(big, kFaces, int_list(big, {0, 1, 2}, 4));
    EXPECT_TRUE(is_error(read_status(dir, m.bytes), ErrorCode::bad_input,
                         {at(dir, m.header + 36 + 1 + 12),
                          "file truncated in face 0 of 1: needs 4 more bytes, 0 left"}));
  }
}

TEST(PlyMalformedBinary, IndexErrorsNameTheOffsetOfTheIndex) {
  ScratchDir dir;
  for (bool big : {false, true}) {
    const BinaryMesh range = binary_mesh(big, kFaces, int_list(big, {0, 1, 2, 3}, 4));
    EXPECT_TRUE(is_error(read_status(dir, range.bytes), ErrorCode::bad_input,
                         {at(dir, range.header + 36 + 1 + 12),
                          "face 0 has vertex index 3, out of range (the file has 3 vertices)"}));
    const BinaryMesh negative = binary_mesh(big, kFaces, int_list(big, {0, -7, 2}, 3));
    EXPECT_TRUE(is_error(read_status(dir, negative.bytes), ErrorCode::bad_input,
                         {at(dir, negative.header + 36 + 1 + 4),
                          "face 0 has a negative vertex index -7"}));
    const BinaryMesh two = binary_mesh(big, kFaces, int_list(big, {0, 1, 2}, 2));
    EXPECT_TRUE(is_error(read_status(dir, two.bytes), ErrorCode::bad_input,
                         {at(dir, two.header + 36), "face 0 has 2 vertices"}));
  }
}

TEST(PlyMalformedBinary, ListCountOver2To20) {
  ScratchDir dir;
  for (bool big : {false, true}) {
    std::string faces;
    append_scalar(faces, std::uint32_t{(1u << 20) + 1}, big);
    for (std::int32_t i : {0, 1, 2}) append_scalar(faces, i, big);
    const BinaryMesh m =
        binary_mesh(big, "element face 1\nproperty list uint int vertex_indices\n", faces);
    EXPECT_TRUE(is_error(read_status(dir, m.bytes), ErrorCode::bad_input,
                         {at(dir, m.header + 36), "face 0 has 1048577 vertices"}));
  }
}

TEST(PlyMalformedBinary, NonFiniteAndHugeCoordinatesNameTheValue) {
  ScratchDir dir;
  for (bool big : {false, true}) {
    const BinaryMesh nan = binary_mesh(big, kFaces, int_list(big, {0, 1, 2}, 3),
                                       std::numeric_limits<float>::quiet_NaN());
    EXPECT_TRUE(is_error(read_status(dir, nan.bytes), ErrorCode::bad_input,
                         {at(dir, nan.header + 4), "vertex 0 has a non-finite y (NaN)"}));
    const BinaryMesh inf = binary_mesh(big, kFaces, int_list(big, {0, 1, 2}, 3),
                                       -std::numeric_limits<float>::infinity());
    EXPECT_TRUE(is_error(read_status(dir, inf.bytes), ErrorCode::bad_input,
                         {at(dir, inf.header + 4), "vertex 0 has a non-finite y (Inf)"}));
  }
  // A finite float whose squared distances would overflow: in vertex 0 (the generic path, which
  // sets the origin) and in vertex 1 (the fast path of fixed-size entries).
  for (bool big : {false, true}) {
    const BinaryMesh first = binary_mesh(big, kFaces, int_list(big, {0, 1, 2}, 3), 3e38f);
    EXPECT_TRUE(is_error(read_status(dir, first.bytes), ErrorCode::bad_input,
                         {at(dir, first.header + 4), "vertex 0 has a y of 3e+38, beyond ±1e18"}));
    BinaryMesh second = binary_mesh(big, kFaces, int_list(big, {0, 1, 2}, 3));
    std::string huge;
    append_scalar(huge, -3e38f, big);
    second.bytes.replace(second.header + 16, 4, huge);
    EXPECT_TRUE(is_error(read_status(dir, second.bytes), ErrorCode::bad_input,
                         {at(dir, second.header + 16), "vertex 1 has a y of -3e+38, beyond ±1e18"}));
  }
  // A finite double too large for a float.
  std::string text = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                     "property double x\nproperty double y\nproperty double z\nend_header\n";
  const std::size_t header = text.size();
  for (double v : {0.0, 0.0, 1e300}) append_scalar(text, v, false);
  EXPECT_TRUE(is_error(read_status(dir, text), ErrorCode::bad_input,
                       {at(dir, header + 16), "vertex 0 has a non-finite z (Inf after conversion to float)"}));
}

TEST(PlyMalformedBinary, CountsAreCheckedAgainstTheFileSizeBeforeReading) {
  ScratchDir dir;
  // 10^12 vertices in a file of about 200 bytes: fails in open(), before any allocation.
  std::string text = std::string("ply\nformat binary_little_endian 1.0\ncomment tiny file\n"
                                 "element vertex 1000000000000\n") + kXyz + kFaces + "end_header\n";
  text += std::string(200 - text.size(), '\0');
  const auto path = dir.file("binary.ply");
  write_bytes(path, text);
  EXPECT_TRUE(is_error(status_of(PlyReader::open(path)), ErrorCode::bad_input,
                       {path.string() + ": line 4: ",
                        "element 'vertex' declares 1000000000000 entries of at least 12 bytes each",
                        "more than the file can hold"}));
  // An overflowing product must not wrap around into a small number.
  write_bytes(path, std::string("ply\nformat binary_little_endian 1.0\n"
                                "element vertex 3\n") + kXyz +
                        "element edge 6148914691236517206\nproperty uchar a\nproperty uchar b\n"
                        "property uchar c\nend_header\n" + std::string(36, '\0'));
  EXPECT_TRUE(is_error(status_of(PlyReader::open(path)), ErrorCode::bad_input,
                       {path.string() + ": line 7: ", "element 'edge' declares 6148914691236517206"}));
  // The same for faces: 1000 quads need at least 1000 * 13 bytes.
  const BinaryMesh m = binary_mesh(false, "element face 1000\nproperty list uchar int vertex_indices\n",
                                   int_list(false, {0, 1, 2}, 3));
  EXPECT_TRUE(is_error(read_status(dir, m.bytes), ErrorCode::bad_input,
                       {"line 7: ", "element 'face' declares 1000 entries of at least 13 bytes"}));
}

// 2^32 vertices cannot be indexed with 32 bits: unsupported, not bad input. A sparse file
// large enough to hold them keeps the size check from firing first.
TEST(PlyMalformedBinary, FourBillionVerticesAreUnsupported) {
  ScratchDir dir;
  const auto path = dir.file("huge.ply");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4294967296\n"
      "property uchar x\nproperty uchar y\nproperty uchar z\nend_header\n";
  write_bytes(path, header);
  if (::truncate(path.c_str(), static_cast<off_t>(header.size() + 3 * (std::uint64_t{1} << 32))) != 0)
    GTEST_SKIP() << "no sparse files here";
  EXPECT_TRUE(is_error(status_of(PlyReader::open(path)), ErrorCode::unsupported,
                       {path.string() + ": line 3: ", "4294967296 vertices", "32 bits"}));
}

TEST(PlyMalformedBinary, ReaderStaysFailedAfterAnError) {
  ScratchDir dir;
  const BinaryMesh m = binary_mesh(false, kFaces, int_list(false, {0, 1, 9}, 3));
  const auto path = dir.file("binary.ply");
  write_bytes(path, m.bytes);
  auto reader = PlyReader::open(path);
  ASSERT_TRUE(reader.ok());
  auto vertices = reader.value()->next();
  ASSERT_TRUE(vertices.ok());
  EXPECT_EQ(vertices->kind, PlyBatch::Kind::vertices);
  for (int i = 0; i < 2; ++i) {
    auto batch = reader.value()->next();
    EXPECT_TRUE(is_error(status_of(batch), ErrorCode::bad_input, {"face 0 has vertex index 9"}));
  }
}

TEST(PlyMalformed, MissingFileIsAnIoError) {
  ScratchDir dir;
  const auto path = dir.file("absent.ply");
  EXPECT_TRUE(is_error(status_of(read_ply(path)), ErrorCode::io, {path.string()}));
  EXPECT_TRUE(is_error(status_of(read_ply(dir.path())), ErrorCode::io, {dir.path().string()}));
}

// ---- truncation at every length ----

// A small mesh with quads (so the size check, which assumes triangles, lets many truncated
// files through to the streaming decoder), read back after cutting it at every byte length.
// Also with attributes per corner (a colour and a texcoord list after each quad's indices), which
// are read whole per face.
TEST(PlyTruncation, EveryLengthFailsCleanly) {
  ScratchDir dir;
  const VertexLayout layout{true, true, true};
  const test::TestMesh strip = test::strip_mesh(layout, true, 40);
  constexpr PlyFormat kFormats[] = {PlyFormat::binary_little_endian,
                                    PlyFormat::binary_big_endian, PlyFormat::ascii};
  for (const bool corner_values : {false, true}) {
    for (PlyFormat format : kFormats) {
      SCOPED_TRACE(std::string(to_string(format)) + (corner_values ? " face colours and corner uvs" : ""));
      const bool big = format == PlyFormat::binary_big_endian;
      // Write the vertices with PlyWriter, then replace the face element with 100 quads.
      const auto source = dir.file("source.ply");
      ASSERT_TRUE(write_ply(source, {format, layout, PlyColorType::uchar, {}, {}}, strip.vertices, {}).ok());
      std::string bytes = test::read_bytes(source);
      const std::string old_faces = "element face 0\n";
      bytes.replace(bytes.find(old_faces), old_faces.size(), "element face 100\n");
      if (corner_values) {
        const std::string indices = "property list uchar int vertex_indices\n";
        bytes.insert(bytes.find(indices) + indices.size(),
                     "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                     "property list uchar float texcoord\n");
      }
      for (std::int32_t q = 0; q < 100; ++q) {
        const std::int32_t a = q % 37;
        if (format == PlyFormat::ascii) {
          bytes += "4 " + std::to_string(a) + " " + std::to_string(a + 1) + " " +
                   std::to_string(a + 2) + " " + std::to_string(a + 3);
          if (corner_values) bytes += " 7 80 255 8 0.5 0.25 1 0.25 1 1 0.5 " + std::to_string(q);
          bytes += "\n";
        } else {
          bytes += '\x04';
          for (std::int32_t k = 0; k < 4; ++k) append_scalar(bytes, a + k, big);
          if (corner_values) {
            bytes += "\x07\x50\xff\x08";
            for (std::int32_t k = 0; k < 8; ++k) append_scalar(bytes, static_cast<float>(q + k) * 0.125f, big);
          }
        }
      }
      const auto path = dir.file("whole.ply");
      write_bytes(path, bytes);
      auto whole = read_ply(path);
      ASSERT_TRUE(whole.ok()) << whole.status().message();
      ASSERT_EQ(whole->triangles.size(), 600u);
      ASSERT_EQ(whole->info.corners, (CornerAttributes{.color = corner_values, .uv = corner_values}));

      // An ascii file cut inside its last value (or its final newline) is still a valid file.
      const std::size_t last_value = bytes.find_last_of(' ') + 1;
      const auto cut = dir.file("cut.ply");
      for (std::size_t length = 0; length < bytes.size(); ++length) {
        write_bytes(cut, std::string_view(bytes).substr(0, length));
        auto reader = PlyReader::open(cut, test::small_batches());
        Status status = status_of(reader);
        while (status.ok()) {
          auto batch = reader.value()->next();
          status = status_of(batch);
          if (status.ok() && batch->kind == PlyBatch::Kind::end) break;
        }
        if (format == PlyFormat::ascii && length > last_value) {
          EXPECT_TRUE(status.ok()) << length << ": " << status.message();
          continue;
        }
        ASSERT_TRUE(is_error(status, ErrorCode::bad_input, {cut.string() + ": "}))
            << "cut at " << length << " of " << bytes.size();
      }
    }
  }
}

}  // namespace
}  // namespace octolod
