#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <fstream>
#include <string>
#include <sstream>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "octolod/formats/manifest.h"

namespace octolod {
namespace {

// Root with two children (octants 0 and 5); child 5 has one LOD.
Manifest small_manifest() {
  Manifest m;
  m.layout = {true, false, true};
  m.bounds = {{0, 0, 0}, {2, 2, 2}};
  m.input_vertices = 10;
  m.input_triangles = 12;
  m.parameters = {"in.ply", 2000, 10, 64u << 20, 2, "grid"};
  m.stage_seconds["sort"] = 0.5;
  m.stats["peak_rss_bytes"] = 1e6;
  NodeInfo root;
  root.cell = {{0, 0, 0}, {2, 2, 2}};
  root.bounds = root.cell;
  root.children[0] = 1;
  root.children[5] = 2;
  root.source_triangles = 12;
  root.lods.push_back({4, 4, 0.25, 100, "lod0.olod"});
  NodeInfo a;
  a.path = "0";
  a.depth = 1;
  a.parent = 0;
  a.lods.push_back({6, 5, 0.0, 200, "0/lod0.olod"});
  NodeInfo b = a;
  b.path = "5";
  b.lods[0].file = "5/lod0.olod";
  m.nodes = {root, a, b};
  return m;
}

// The text a manifest is written as: the whole document's dump(1) (keys sorted, one space per
// level) but for the nodes, each one line of its own (dump()).
std::string expected_text(const std::string& text) {
  nlohmann::json document = nlohmann::json::parse(text);
  const nlohmann::json nodes = document["nodes"];
  for (std::size_t i = 0; i < nodes.size(); ++i) document["nodes"][i] = "@" + std::to_string(i) + "@";
  std::string expected = document.dump(1) + "\n";
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const std::string placeholder = "\"@" + std::to_string(i) + "@\"";
    expected.replace(expected.find(placeholder), placeholder.size(), nodes[i].dump());
  }
  return expected;
}

TEST(Manifest, JsonRoundTripKeepsEveryField) {
  Manifest m = small_manifest();
  Result<Manifest> back = manifest_from_json(manifest_to_json(m), "m.json");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(manifest_to_json(back.value()), manifest_to_json(m));
  EXPECT_EQ(back->nodes[0].child_mask(), 0b100001);
  EXPECT_EQ(back->layout, m.layout);
  EXPECT_DOUBLE_EQ(back->nodes[0].lods[0].error, 0.25);
}

// Bounds are floats: written as the shortest decimals that read back as them (9 significant
// digits at most, not a double's 17), and read back bit for bit, whatever the float.
TEST(Manifest, BoundsAreWrittenShortAndReadBackExactly) {
  const float values[] = {0.1f, -0.0f, 1e-30f, 1e-45f, 3.4028235e38f, -2.5f, 16777216.0f, 16777218.0f,
                          1.0f / 3.0f, 0.057427104f, -0.69063336f, 4905.123f, 7e-12f, 1.17549435e-38f};
  Manifest m = small_manifest();
  for (std::size_t i = 0; i + 2 < std::size(values); ++i) {
    m.nodes[1].cell.min = {values[i], values[i + 1], values[i + 2]};
    m.nodes[1].bounds.max = {values[i + 2], values[i], values[i + 1]};
    const std::string text = manifest_to_json(m);
    Result<Manifest> back = manifest_from_json(text, "m.json");
    ASSERT_TRUE(back.ok()) << back.status().message();
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_EQ(std::bit_cast<std::uint32_t>(back->nodes[1].cell.min[a]),
                std::bit_cast<std::uint32_t>(m.nodes[1].cell.min[a])) << i << " " << a;
      EXPECT_EQ(std::bit_cast<std::uint32_t>(back->nodes[1].bounds.max[a]),
                std::bit_cast<std::uint32_t>(m.nodes[1].bounds.max[a])) << i << " " << a;
    }
    const nlohmann::json node = nlohmann::json::parse(text)["nodes"][1];
    for (const double written : node["cell"]["min"].get<std::vector<double>>()) {
      // FLT_MAX's shortest decimal, 3.4028235e38, is above FLT_MAX as a double: written whole
      if (std::abs(written) == static_cast<double>(std::numeric_limits<float>::max())) continue;
      char shortest[32];
      std::snprintf(shortest, sizeof shortest, "%.9g", written);
      EXPECT_EQ(std::strtod(shortest, nullptr), written) << "more than 9 digits: " << written;
    }
  }
  m.nodes[1].cell.min = {0.1f, -0.69063336f, 4905.123f};
  EXPECT_NE(manifest_to_json(m).find("\"min\":[0.1,-0.69063336,4905.123]"), std::string::npos)
      << manifest_to_json(m);
}

TEST(Manifest, OriginKeepsEveryDigitAndDefaultsToZeroWhenAbsent) {
  Manifest m = small_manifest();
  m.origin = {4000000.0, -500001.0, 0.1};
  Result<Manifest> back = manifest_from_json(manifest_to_json(m), "m.json");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->origin, m.origin);
  // a manifest from before the origin existed
  nlohmann::json old = nlohmann::json::parse(manifest_to_json(small_manifest()));
  old.erase("origin");
  Result<Manifest> older = manifest_from_json(old.dump(), "old.json");
  ASSERT_TRUE(older.ok()) << older.status().message();
  EXPECT_EQ(older->origin, (std::array<double, 3>{0.0, 0.0, 0.0}));
  old["origin"] = {1.0, 2.0};
  EXPECT_FALSE(manifest_from_json(old.dump(), "short.json").ok());
}

TEST(Manifest, LodRatioRoundTripsAndIsAHalfWhenAbsent) {
  Manifest m = small_manifest();
  m.parameters.lod_ratio = 0.3;
  Result<Manifest> back = manifest_from_json(manifest_to_json(m), "m.json");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->parameters.lod_ratio, 0.3);
  // a manifest from before bake --lod-ratio existed: every chain halved
  nlohmann::json old = nlohmann::json::parse(manifest_to_json(m));
  old["parameters"].erase("lod_ratio");
  Result<Manifest> older = manifest_from_json(old.dump(), "old.json");
  ASSERT_TRUE(older.ok()) << older.status().message();
  EXPECT_EQ(older->parameters.lod_ratio, 0.5);
  for (const nlohmann::json& bad : {nlohmann::json(0.0), nlohmann::json(1.0), nlohmann::json(-0.5), nlohmann::json("half")}) {
    old["parameters"]["lod_ratio"] = bad;
    Result<Manifest> refused = manifest_from_json(old.dump(), "bad.json");
    EXPECT_EQ(refused.status().code(), ErrorCode::bad_input) << bad.dump();
    EXPECT_NE(refused.status().message().find("bad.json"), std::string::npos) << refused.status().message();
  }
}

// The texture: written only when there is one, in its sorted place; relative and inside the tree.
TEST(Manifest, TextureRoundTripsIsAbsentWhenEmptyAndStaysInsideTheTree) {
  Manifest m = small_manifest();
  EXPECT_EQ(manifest_to_json(m).find("texture"), std::string::npos);
  m.texture = "texture/stone scan.jpg";
  const std::string text = manifest_to_json(m);
  EXPECT_EQ(text, expected_text(text));
  Result<Manifest> back = manifest_from_json(text, "m.json");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->texture, m.texture);
  for (const char* escaping : {"../stone.jpg", "/etc/passwd", "texture//stone.jpg"}) {
    m.texture = escaping;
    Result<Manifest> refused = manifest_from_json(manifest_to_json(m), "m.json");
    EXPECT_EQ(refused.status().code(), ErrorCode::bad_input) << escaping;
    EXPECT_NE(refused.status().message().find("\"texture\" must be a relative path"), std::string::npos)
        << refused.status().message();
  }
}

// The manifest is written node by node, never as one document: its text must still be the
// document's (expected_text), with and without nodes, and one line per node.
TEST(Manifest, StreamedTextIsTheWholeDocumentsDump) {
  Manifest m = small_manifest();
  for (int with_nodes = 1; with_nodes >= 0; --with_nodes) {
    if (!with_nodes) m.nodes.clear();
    const std::string text = manifest_to_json(m);
    EXPECT_EQ(text, expected_text(text)) << text;
  }
  auto path = std::filesystem::path(::testing::TempDir()) / "manifest_stream_test.json";
  ASSERT_TRUE(write_manifest(path, small_manifest()).ok());
  std::ifstream in(path, std::ios::binary);
  std::ostringstream written;
  written << in.rdbuf();
  EXPECT_EQ(written.str(), manifest_to_json(small_manifest()));
  std::filesystem::remove(path);
}

TEST(Manifest, RejectsChildNamingAnotherParent) {
  Manifest m = small_manifest();
  m.nodes[2].parent = 1;
  m.nodes[2].depth = 2;
  Result<Manifest> r = manifest_from_json(manifest_to_json(m), "m.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("m.json: invalid manifest"), std::string::npos);
}

TEST(Manifest, RejectsFilesEscapingTheTree) {
  for (const char* file : {"../x.olod", "/etc/passwd", "a//b", ""}) {
    Manifest m = small_manifest();
    m.nodes[1].lods[0].file = file;
    EXPECT_FALSE(manifest_from_json(manifest_to_json(m), "m.json").ok()) << file;
  }
}

// A LOD's byte count is what its file must hold (the runtime reads exactly that many): one
// below a node file's header cannot be any node file.
TEST(Manifest, RejectsALodSmallerThanANodeFileHeader) {
  Manifest m = small_manifest();
  m.nodes[2].lods[0].bytes = kNodeFileHeaderBytes - 1;
  Result<Manifest> r = manifest_from_json(manifest_to_json(m), "m.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("lod 0: 55 bytes, less than a node file's header (56)"), std::string::npos)
      << r.status().message();
  m.nodes[2].lods[0].bytes = kNodeFileHeaderBytes;
  EXPECT_TRUE(manifest_from_json(manifest_to_json(m), "m.json").ok());
}

TEST(Manifest, RejectsMissingKeysWrongTypesAndGarbage) {
  EXPECT_FALSE(manifest_from_json("{", "a").ok());
  EXPECT_FALSE(manifest_from_json("{\"format\":\"octolod-manifest\"}", "b").ok());
  std::string text = manifest_to_json(small_manifest());
  std::string wrong_type = text;
  wrong_type.replace(wrong_type.find("\"max_tris\": 2000"), 16, "\"max_tris\": \"x\"");
  Result<Manifest> r = manifest_from_json(wrong_type, "c");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
  // the JSON library's messages, without its tags
  r = manifest_from_json("[]", "d");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("d: invalid manifest: not a JSON object"), std::string::npos)
      << r.status().message();
  EXPECT_EQ(r.status().message().find("json.exception"), std::string::npos) << r.status().message();
}

// Nodes are converted while the text is parsed (manifest.cpp): a bad one still fails the whole
// manifest, named by its index.
TEST(Manifest, RejectsABadNodeByIndexAndNonObjectNodes) {
  const std::string text = manifest_to_json(small_manifest());
  std::string missing = text;
  missing.replace(missing.find("\"source_triangles\":0"), 20, "\"source_triangle\": 0");
  Result<Manifest> r = manifest_from_json(missing, "d");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
  EXPECT_NE(r.status().message().find("node 1"), std::string::npos) << r.status().message();
  std::string number = text;
  number.replace(number.find("\"nodes\": ["), 11, "\"nodes\": [7, ");
  r = manifest_from_json(number, "e");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
}

// The reader takes the nodes from the parser's events (manifest_sax.h): members the format does
// not define are skipped at every level, whatever their value.
TEST(Manifest, SkipsMembersTheFormatDoesNotDefine) {
  const Manifest m = small_manifest();
  std::string text = manifest_to_json(m);
  auto insert_after = [&](const std::string& what, const std::string& extra) {
    const std::size_t at = text.find(what);
    ASSERT_NE(at, std::string::npos) << what;
    text.insert(at + what.size(), extra);
  };
  insert_after("\"source_triangles\":0", ", \"extra\": {\"a\": [1, {\"b\": [2]}], \"lods\": 3}");
  insert_after("\"file\":\"0/lod0.olod\"", ", \"more\": [[1], {\"file\": 2}], \"note\": null");
  insert_after("\"cell\":{", "\"center\": [0, [1], {\"min\": 2}], ");
  Result<Manifest> back = manifest_from_json(text, "extra.json");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(manifest_to_json(back.value()), manifest_to_json(m));
}

// A member of the wrong kind or range, or missing, fails the manifest naming the node and the
// member; a bad node does not hide that the manifest is of a newer version.
TEST(Manifest, NamesTheNodeAndMemberThatCannotBeRead) {
  const std::string text = manifest_to_json(small_manifest());
  const std::size_t nodes = text.find("\"nodes\"");
  const std::size_t node1_bounds = text.find("\"bounds\"", text.find("\"bounds\"", nodes) + 1);
  const std::size_t node1_children = text.find("\"children\":[", text.find("\"child_mask\":0"));
  struct Case {
    std::size_t at;
    std::string from, to, message;
  };
  const std::vector<Case> cases{
      {0, "\"path\":\"0\"", "\"path\": 0", "node 1: \"path\" is not a string"},
      {0, "\"depth\":1", "\"depth\": -1", "node 1: \"depth\" is not an integer in range"},
      {0, "\"file\":\"0/lod0.olod\"", "\"file\": 5", "node 1: \"file\" is not a string"},
      {0, "\"file\":\"0/lod0.olod\"", "\"fil\": \"0/lod0.olod\"", "node 1: lod 0: no \"file\""},
      {0, "\"error\":0.0", "\"error\": \"x\"", "node 1: \"error\" is not a number"},
      {0, "\"error\":0.0", "\"error\": [0.0]", "node 1: \"error\" is not a scalar"},
      {0, "\"source_triangles\":0", "\"source_triangles\": 0.5", "node 1: \"source_triangles\" is not an integer"},
      {node1_children, "[", "[-1, ", "node 1: \"children\" has more than 8 elements"},
      {node1_bounds, "\"min\":[", "\"min\": [\"x\", ", "node 1: \"bounds.min\" holds a value that is not a number"},
      {node1_bounds, "\"bounds\":{", "\"bounds\": [{", "node 1: \"bounds\" is not an object"},
      {node1_bounds, "\"min\":[", "\"min\": [1e39, ", "node 1: \"bounds.min\" holds a number beyond the float range"},
      {node1_bounds, "\"max\":[", "\"maximum\": [", "node 1: no \"bounds.max\""},
      {0, "\"source_triangles\":0", "\"source\": 0", "node 1: no \"source_triangles\""},
  };
  for (const Case& c : cases) {
    std::string bad = text;
    const std::size_t at = bad.find(c.from, c.at);
    ASSERT_NE(at, std::string::npos) << c.from;
    bad.replace(at, c.from.size(), c.to);
    if (c.to.find("[{") != std::string::npos) {  // close the array it opens: keep the JSON well formed
      const std::size_t close = bad.find('}', at + c.to.size());
      bad.insert(close + 1, "]");
    }
    Result<Manifest> r = manifest_from_json(bad, "bad.json");
    ASSERT_FALSE(r.ok()) << c.to;
    EXPECT_EQ(r.status().code(), ErrorCode::bad_input) << c.to;
    EXPECT_NE(r.status().message().find("bad.json: invalid manifest: " + c.message), std::string::npos)
        << r.status().message();
    bad.replace(bad.find("\"version\": 1"), 12, "\"version\": 2");
    EXPECT_EQ(manifest_from_json(bad, "v2.json").status().code(), ErrorCode::unsupported) << c.to;
  }
  // the header's integers: a float or a number out of range is refused, never cast (undefined
  // behaviour beyond the type's range; found by manifest_reader_fuzz)
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"\"threads\": 2", "\"threads\": 2e68"},
                                 {"\"max_tris\": 2000", "\"max_tris\": 99999999999"},
                                 {"\"version\": 1", "\"version\": 1.5"}}) {
    std::string bad = text;
    bad.replace(bad.find(from), from.size(), to);
    Result<Manifest> r = manifest_from_json(bad, "header.json");
    ASSERT_FALSE(r.ok()) << to;
    EXPECT_EQ(r.status().code(), ErrorCode::bad_input) << to;
    EXPECT_NE(r.status().message().find("is not an integer in range"), std::string::npos) << r.status().message();
  }
  std::string huge = text;  // the model's bounds, read from the document rather than the events
  huge.replace(huge.find("\"min\": [", huge.find("\"bounds\"")), 8, "\"min\": [-1e39, ");
  Result<Manifest> r = manifest_from_json(huge, "huge.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("beyond the float range"), std::string::npos) << r.status().message();
  Result<Manifest> cut = manifest_from_json(text.substr(0, 200), "cut.json");
  ASSERT_FALSE(cut.ok());
  EXPECT_NE(cut.status().message().find("cut.json: not valid JSON"), std::string::npos) << cut.status().message();
  EXPECT_NE(cut.status().message().find("column"), std::string::npos) << cut.status().message();
}

TEST(Manifest, NewerVersionIsUnsupported) {
  std::string text = manifest_to_json(small_manifest());
  text.replace(text.find("\"version\": 1"), 12, "\"version\": 7");
  Result<Manifest> r = manifest_from_json(text, "v7");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::unsupported);
}

TEST(Manifest, WriteIsAtomicAndReadable) {
  auto path = std::filesystem::path(::testing::TempDir()) / "manifest_test.json";
  ASSERT_TRUE(write_manifest(path, small_manifest()).ok());
  Result<Manifest> back = read_manifest(path);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->nodes.size(), 3u);
  for (const auto& entry : std::filesystem::directory_iterator(path.parent_path()))
    EXPECT_EQ(entry.path().string().find("manifest_test.json.tmp"), std::string::npos);
  std::filesystem::remove(path);
}

// A directory named manifest.json, a FIFO (reading it would block) or a missing file is refused,
// naming the path and why.
TEST(Manifest, OnlyARegularFileIsRead) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "manifest_test_special";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "manifest.json");
  ASSERT_EQ(::mkfifo((dir / "fifo.json").c_str(), 0600), 0);
  for (const auto& [name, why] : {std::pair{"manifest.json", "it is a directory"},
                                  std::pair{"fifo.json", "it is not a regular file"},
                                  std::pair{"missing.json", "it does not exist"}}) {
    Result<Manifest> read = read_manifest(dir / name);
    ASSERT_FALSE(read.ok()) << name;
    EXPECT_EQ(read.status().code(), ErrorCode::io);
    EXPECT_NE(read.status().message().find((dir / name).string() + ": cannot read the manifest: " + why),
              std::string::npos)
        << read.status().message();
  }
  std::filesystem::remove_all(dir);
}

// A bake writes its nodes one at a time as it reads them back: the same text as the whole
// Manifest's, and a node that cannot be produced fails the write without leaving a file.
TEST(Manifest, NodeByNodeWriteIsTheWholeManifestOrNothing) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "manifest_nodes_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const Manifest m = small_manifest();
  Manifest header = m;
  header.nodes.clear();
  std::vector<std::size_t> asked;
  ASSERT_TRUE(write_manifest(dir / "streamed.json", header, m.nodes.size(), [&](std::size_t i) -> Result<NodeInfo> {
                asked.push_back(i);
                return m.nodes[i];
              }).ok());
  EXPECT_EQ(asked, (std::vector<std::size_t>{0, 1, 2}));
  std::ifstream in(dir / "streamed.json", std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), manifest_to_json(m));

  const Status failed = write_manifest(dir / "failed.json", header, m.nodes.size(), [&](std::size_t i) -> Result<NodeInfo> {
    if (i == 2) return io_error("node-lods.tmp: node 2: cannot read 52 bytes at offset 80");
    return m.nodes[i];
  });
  EXPECT_EQ(failed.code(), ErrorCode::io);
  EXPECT_NE(failed.message().find("offset 80"), std::string::npos) << failed.message();
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "streamed.json");
  }
  EXPECT_EQ(files, 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace octolod
