// glTF/GLB export and import: exact round trips, Draco within its quantization, GLB container
// validity, clean errors on malformed files, and `octolod export` on a hand-built tree.
#include "octolod/formats/gltf.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <tiny_gltf.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"

namespace octolod {
namespace {

using nlohmann::json;

// Two triangles sharing an edge, with the attributes of `layout`:
//   2---3
//   | \ |
//   0---1
NodeMesh quad_mesh(VertexLayout layout, float z = 0.5f) {
  NodeMesh mesh;
  mesh.layout = layout;
  const float corners[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (const auto& c : corners) {
    mesh.vertices.insert(mesh.vertices.end(), {c[0], c[1], z});
    if (layout.normal) mesh.vertices.insert(mesh.vertices.end(), {0, 0, 1});
    if (layout.color) mesh.vertices.insert(mesh.vertices.end(), {c[0], c[1], 0.25f});
    if (layout.uv) mesh.vertices.insert(mesh.vertices.end(), {c[0] * 2, c[1] * 2});
  }
  mesh.indices = {0, 1, 2, 2, 1, 3};
  return mesh;
}

// An n x n vertex height field over [x0, x0+1] x [0, 1] with every attribute; values vary per
// vertex so a misassigned attribute shows.
NodeMesh grid_mesh(int n, float x0 = 0) {
  NodeMesh mesh;
  mesh.layout = {true, true, true};
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float u = static_cast<float>(i) / static_cast<float>(n - 1);
      const float v = static_cast<float>(j) / static_cast<float>(n - 1);
      const float h = 0.1f * std::sin(6 * u) * std::cos(5 * v);
      const float nx = -0.3f * std::cos(6 * u), ny = 0.2f * std::sin(5 * v);
      const float len = std::sqrt(nx * nx + ny * ny + 1);
      mesh.vertices.insert(mesh.vertices.end(), {x0 + u, v, h, nx / len, ny / len, 1 / len, u, v,
                                                 0.5f * (u + v), u * 3, v * 2});
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * n + i), b = a + 1,
                 c = a + static_cast<std::uint32_t>(n), d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, c, b, d});
    }
  return mesh;
}

GltfWriteOptions text_options() {
  GltfWriteOptions options;
  options.binary = false;
  return options;
}

GltfWriteOptions draco_options(bool draco, int position_bits = DracoOptions{}.position_bits) {
  GltfWriteOptions options;
  options.draco = draco;
  options.draco_options.position_bits = position_bits;
  return options;
}

GltfWriteOptions named(std::vector<std::string> names) {
  GltfWriteOptions options;
  options.names = std::move(names);
  return options;
}

std::vector<std::byte> encode(std::span<const NodeMesh> meshes, GltfWriteOptions options = {}) {
  Result<std::vector<std::byte>> bytes = encode_gltf(meshes, options);
  EXPECT_TRUE(bytes.ok()) << bytes.status().message();
  return bytes.ok() ? bytes.value() : std::vector<std::byte>{};
}

std::uint32_t u32_at(std::span<const std::byte> bytes, std::size_t offset) {
  std::uint32_t v;
  std::memcpy(&v, bytes.data() + offset, 4);
  return v;
}

// The JSON chunk of a GLB.
json glb_json(std::span<const std::byte> glb) {
  const std::uint32_t length = u32_at(glb, 12);
  const auto* text = reinterpret_cast<const char*>(glb.data() + 20);
  return json::parse(text, text + length);
}

// A GLB from `document` and `bin` (both padded to 4 bytes as the format requires).
std::vector<std::byte> make_glb(const json& document, std::span<const std::byte> bin) {
  std::string text = document.dump();
  text.resize((text.size() + 3) & ~std::size_t{3}, ' ');
  std::vector<std::byte> padded_bin(bin.begin(), bin.end());
  padded_bin.resize((padded_bin.size() + 3) & ~std::size_t{3}, std::byte{0});
  std::vector<std::byte> out;
  auto put = [&](std::uint32_t v) {
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    out.insert(out.end(), p, p + 4);
  };
  put(0x46546C67);
  put(2);
  put(static_cast<std::uint32_t>(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + padded_bin.size())));
  put(static_cast<std::uint32_t>(text.size()));
  put(0x4E4F534A);
  for (char c : text) out.push_back(static_cast<std::byte>(c));
  if (!bin.empty()) {
    put(static_cast<std::uint32_t>(padded_bin.size()));
    put(0x004E4942);
    out.insert(out.end(), padded_bin.begin(), padded_bin.end());
  }
  return out;
}

// The BIN chunk of a GLB written by octolod (JSON chunk first, BIN second).
std::vector<std::byte> glb_bin(std::span<const std::byte> glb) {
  const std::size_t bin_header = 20 + u32_at(glb, 12);
  if (bin_header + 8 > glb.size()) return {};
  const std::uint32_t length = u32_at(glb, bin_header);
  return {glb.begin() + static_cast<std::ptrdiff_t>(bin_header + 8),
          glb.begin() + static_cast<std::ptrdiff_t>(bin_header + 8 + length)};
}

// Decodes a GLB whose JSON was edited by `edit`; returns the decode status.
template <class Edit>
Status decode_edited(const std::vector<std::byte>& glb, Edit edit) {
  json document = glb_json(glb);
  edit(document);
  Result<std::vector<NodeMesh>> r = decode_gltf(make_glb(document, glb_bin(glb)), "edited.glb");
  return r.ok() ? Status{} : r.status();
}

class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("octolod_gltf_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// --- exact round trips -------------------------------------------------------------------------

TEST(Gltf, GlbRoundTripsEveryLayoutExactly) {
  for (std::uint32_t mask = 0; mask <= VertexLayout::kValidMask; ++mask) {
    const NodeMesh mesh = quad_mesh(VertexLayout::from_mask(mask));
    const std::vector<std::byte> glb = encode(std::span(&mesh, 1));
    Result<std::vector<NodeMesh>> back = decode_gltf(glb, "quad.glb");
    ASSERT_TRUE(back.ok()) << back.status().message();
    ASSERT_EQ(back->size(), 1u);
    EXPECT_EQ(back->front(), mesh) << VertexLayout::from_mask(mask).describe();
  }
}

TEST(Gltf, EmbeddedGltfRoundTripsEveryLayoutExactly) {
  for (std::uint32_t mask = 0; mask <= VertexLayout::kValidMask; ++mask) {
    const std::vector<NodeMesh> meshes = {quad_mesh(VertexLayout::from_mask(mask)), grid_mesh(5)};
    const std::vector<std::byte> text = encode(meshes, text_options());
    ASSERT_EQ(static_cast<char>(text.front()), '{');
    Result<std::vector<NodeMesh>> back = decode_gltf(text, "quad.gltf");
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back.value(), meshes);
  }
}

TEST(Gltf, ThirtyTwoBitIndicesPastSixtyFiveThousandVertices) {
  NodeMesh mesh;
  mesh.vertices.assign(70000 * 3, 0.0f);
  for (std::uint32_t i = 0; i < 70000; ++i) mesh.vertices[i * 3] = static_cast<float>(i);
  mesh.indices = {0, 1, 69999, 65535, 65536, 2};
  const std::vector<std::byte> glb = encode(std::span(&mesh, 1));
  const json document = glb_json(glb);
  const std::size_t indices = document["meshes"][0]["primitives"][0]["indices"];
  EXPECT_EQ(document["accessors"][indices]["componentType"], 5125);
  Result<std::vector<NodeMesh>> back = decode_gltf(glb, "big.glb");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->front(), mesh);
}

TEST(Gltf, WritesOneNamedNodeAndMeshPerNodeMeshWithPositionBounds) {
  const std::vector<NodeMesh> meshes = {quad_mesh({}, 0.5f),
                                        quad_mesh({true, false, false}, -2.0f)};
  const std::vector<std::byte> glb = encode(meshes, named({"root/lod1", "3/5/lod0"}));
  const json document = glb_json(glb);
  ASSERT_EQ(document["nodes"].size(), 2u);
  ASSERT_EQ(document["meshes"].size(), 2u);
  EXPECT_EQ(document["scenes"][0]["nodes"], json::array({0, 1}));
  EXPECT_EQ(document["nodes"][1]["name"], "3/5/lod0");
  EXPECT_EQ(document["nodes"][1]["mesh"], 1);
  EXPECT_EQ(document["meshes"][0]["name"], "root/lod1");
  const json& primitive = document["meshes"][1]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 4);
  EXPECT_TRUE(primitive["attributes"].contains("NORMAL"));
  EXPECT_FALSE(primitive["attributes"].contains("COLOR_0"));
  EXPECT_EQ(document["accessors"][primitive["indices"].get<std::size_t>()]["componentType"], 5123);
  const json& position = document["accessors"][primitive["attributes"]["POSITION"].get<std::size_t>()];
  EXPECT_EQ(position["min"], json::array({0.0, 0.0, -2.0}));
  EXPECT_EQ(position["max"], json::array({1.0, 1.0, -2.0}));
  EXPECT_EQ(document["asset"]["version"], "2.0");
}

TEST(Gltf, MeshWithoutTrianglesBecomesANodeWithoutMesh) {
  NodeMesh empty;
  empty.layout = {true, true, true};
  const std::vector<NodeMesh> meshes = {empty, quad_mesh({})};
  const std::vector<std::byte> glb = encode(meshes);
  const json document = glb_json(glb);
  EXPECT_EQ(document["nodes"].size(), 2u);
  EXPECT_FALSE(document["nodes"][0].contains("mesh"));
  Result<std::vector<NodeMesh>> back = decode_gltf(glb, "e.glb");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->size(), 1u);
  EXPECT_EQ(back->front(), meshes[1]);

  Result<std::vector<NodeMesh>> none = decode_gltf(encode(std::span(&empty, 1)), "none.glb");
  ASSERT_TRUE(none.ok()) << none.status().message();
  EXPECT_TRUE(none->empty());
}

// --- GLB container -----------------------------------------------------------------------------

TEST(Gltf, GlbHasMagicVersionTwoAndConsistentChunkLengths) {
  for (bool draco : {false, true}) {
    const std::vector<NodeMesh> meshes = {grid_mesh(7), quad_mesh({true, true, true})};
    const std::vector<std::byte> glb = encode(meshes, draco_options(draco));
    ASSERT_GE(glb.size(), 28u);
    EXPECT_EQ(std::memcmp(glb.data(), "glTF", 4), 0);
    EXPECT_EQ(u32_at(glb, 4), 2u);
    EXPECT_EQ(u32_at(glb, 8), glb.size());
    const std::uint32_t json_length = u32_at(glb, 12);
    EXPECT_EQ(u32_at(glb, 16), 0x4E4F534Au);  // "JSON"
    EXPECT_EQ(json_length % 4, 0u);
    const std::size_t bin = 20 + json_length;
    ASSERT_LE(bin + 8, glb.size());
    const std::uint32_t bin_length = u32_at(glb, bin);
    EXPECT_EQ(u32_at(glb, bin + 4), 0x004E4942u);  // "BIN\0"
    EXPECT_EQ(bin_length % 4, 0u);
    EXPECT_EQ(bin + 8 + bin_length, glb.size());
    const json document = glb_json(glb);
    EXPECT_LE(document["buffers"][0]["byteLength"].get<std::size_t>(), bin_length);
    EXPECT_FALSE(document["buffers"][0].contains("uri"));
    for (const json& view : document["bufferViews"])
      EXPECT_LE(view.value("byteOffset", std::size_t{0}) + view["byteLength"].get<std::size_t>(),
                bin_length);
  }
}

// An independent loader (the system tinygltf, which octolod only uses for writing) reads what
// octolod writes, GLB and .gltf alike, with the structure the header promises.
// Loads an encoded GLB (`binary`) or .gltf with tinygltf, images kept as their bytes (not decoded).
bool load_with_tinygltf(const std::vector<std::byte>& bytes, bool binary, tinygltf::Model& model,
                        std::string& error, std::string& warning) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int,
                           const unsigned char*, int, void*) { return true; }, nullptr);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  return binary ? loader.LoadBinaryFromMemory(&model, &error, &warning, data, static_cast<unsigned>(bytes.size()))
                : loader.LoadASCIIFromString(&model, &error, &warning, reinterpret_cast<const char*>(data),
                                             static_cast<unsigned>(bytes.size()), "");
}

TEST(Gltf, TinygltfLoadsTheWrittenFiles) {
  const std::vector<NodeMesh> meshes = {grid_mesh(6), quad_mesh({false, false, true})};
  for (bool binary : {true, false}) {
    GltfWriteOptions options = named({"a", "b"});
    options.binary = binary;
    const std::vector<std::byte> bytes = encode(meshes, options);
    tinygltf::Model model;
    std::string error, warning;
    ASSERT_TRUE(load_with_tinygltf(bytes, binary, model, error, warning)) << error;
    EXPECT_TRUE(warning.empty()) << warning;
    ASSERT_EQ(model.meshes.size(), 2u);
    EXPECT_EQ(model.nodes[1].name, "b");
    const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
    EXPECT_EQ(primitive.attributes.size(), 4u);
    const tinygltf::Accessor& indices =
        model.accessors[static_cast<std::size_t>(primitive.indices)];
    EXPECT_EQ(indices.count, meshes[0].indices.size());
    const tinygltf::BufferView& view =
        model.bufferViews[static_cast<std::size_t>(indices.bufferView)];
    const unsigned char* first =
        model.buffers[0].data.data() + view.byteOffset + indices.byteOffset;
    std::uint16_t index;
    std::memcpy(&index, first + 2 * 5, 2);  // the sixth index
    EXPECT_EQ(index, meshes[0].indices[5]);
    const tinygltf::Accessor& uv = model.accessors[static_cast<std::size_t>(
        model.meshes[1].primitives[0].attributes.at("TEXCOORD_0"))];
    EXPECT_EQ(uv.type, TINYGLTF_TYPE_VEC2);
    const tinygltf::BufferView& uv_view = model.bufferViews[static_cast<std::size_t>(uv.bufferView)];
    EXPECT_EQ(uv_view.byteStride, 20u);
    // glTF's v runs down the image, octolod's up: every vertex's (u, 1 - v)
    for (std::size_t v = 0; v < 4; ++v) {
      float written[2];
      std::memcpy(written, model.buffers[0].data.data() + uv_view.byteOffset + uv.byteOffset + 20 * v, 8);
      EXPECT_EQ(written[0], meshes[1].vertices[5 * v + 3]) << v;
      EXPECT_EQ(written[1], 1.0f - meshes[1].vertices[5 * v + 4]) << v;
    }
    EXPECT_TRUE(model.materials.empty());
    EXPECT_TRUE(model.images.empty());
  }
}

// With a texture: one material with the image, embedded byte for byte, as its base colour, on
// the primitives that have UVs (not on one without); tinygltf loads it in both containers.
TEST(Gltf, TextureIsEmbeddedAsTheMaterialOfThePrimitivesWithUvs) {
  TempDir dir;
  std::string png = "\x89PNG\r\n\x1a\n";
  png += std::string("an image's bytes after its signature");
  const std::filesystem::path image = dir.path() / "stone.png";
  std::ofstream(image, std::ios::binary) << png;
  Result<GltfTexture> texture = read_gltf_texture(image);
  ASSERT_TRUE(texture.ok()) << texture.status().message();
  EXPECT_EQ(texture->mime_type, "image/png");
  EXPECT_EQ(texture->name, "stone.png");
  const std::vector<NodeMesh> meshes = {grid_mesh(6), quad_mesh({true, false, false})};
  for (bool binary : {true, false}) {
    GltfWriteOptions options;
    options.binary = binary;
    options.texture = texture.value();
    const std::vector<std::byte> bytes = encode(meshes, options);
    tinygltf::Model model;
    std::string error, warning;
    ASSERT_TRUE(load_with_tinygltf(bytes, binary, model, error, warning)) << error;
    ASSERT_EQ(model.images.size(), 1u);
    EXPECT_EQ(model.images[0].mimeType, "image/png");
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(model.images[0].bufferView)];
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(model.buffers[0].data.data()) + view.byteOffset,
                          view.byteLength),
              png);
    ASSERT_EQ(model.materials.size(), 1u);
    EXPECT_EQ(model.materials[0].pbrMetallicRoughness.baseColorTexture.index, 0);
    EXPECT_EQ(model.materials[0].pbrMetallicRoughness.metallicFactor, 0.0);
    ASSERT_EQ(model.textures.size(), 1u);
    EXPECT_EQ(model.textures[0].source, 0);
    EXPECT_EQ(model.meshes[0].primitives[0].material, 0);
    EXPECT_EQ(model.meshes[1].primitives[0].material, -1);  // no UVs to index the image
    // and the meshes come back as they went in, but for v's rounding in 1 - v (v < 0.5: half a
    // float step of 1 - v, 2^-25)
    Result<std::vector<NodeMesh>> back = decode_gltf(bytes, "textured");
    ASSERT_TRUE(back.ok()) << back.status().message();
    const std::vector<float>& expected = meshes[0].vertices;
    const std::vector<float>& decoded = back.value()[0].vertices;
    ASSERT_EQ(decoded.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i)
      if (i % 11 == 10) {
        EXPECT_NEAR(decoded[i], expected[i], 0x1p-25) << i;
      } else {
        EXPECT_EQ(decoded[i], expected[i]) << i;
      }
  }
  // only the image types glTF's core embeds
  const std::filesystem::path tga = dir.path() / "stone.tga";
  std::ofstream(tga, std::ios::binary) << std::string("\0\0\2\0 a targa header", 19);
  Result<GltfTexture> refused = read_gltf_texture(tga);
  EXPECT_EQ(refused.status().code(), ErrorCode::unsupported);
  EXPECT_EQ(refused.status().message(), tga.string() + ": not a PNG or JPEG image, the types glTF 2.0 embeds");
  EXPECT_EQ(read_gltf_texture(dir.path() / "missing.png").status().code(), ErrorCode::io);
}

// --- Draco -------------------------------------------------------------------------------------

// Nearest original vertex (by position) of each decoded vertex; brute force for small meshes.
std::vector<std::size_t> match_vertices(const NodeMesh& original, const NodeMesh& decoded) {
  std::vector<std::size_t> match(decoded.vertex_count());
  const std::uint32_t fo = original.layout.floats(), fd = decoded.layout.floats();
  for (std::size_t d = 0; d < decoded.vertex_count(); ++d) {
    double best = 1e30;
    for (std::size_t o = 0; o < original.vertex_count(); ++o) {
      double dist = 0;
      for (int k = 0; k < 3; ++k) {
        const double diff = decoded.vertices[d * fd + static_cast<std::size_t>(k)] -
                            original.vertices[o * fo + static_cast<std::size_t>(k)];
        dist += diff * diff;
      }
      if (dist < best) best = dist, match[d] = o;
    }
  }
  return match;
}

// Triangles as sorted rotations of original vertex ids (orientation kept).
std::multiset<std::array<std::size_t, 3>> triangle_set(const NodeMesh& mesh,
                                                       const std::vector<std::size_t>* map) {
  std::multiset<std::array<std::size_t, 3>> set;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::array<std::size_t, 3> tri;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t i = mesh.indices[3 * t + k];
      tri[k] = map ? (*map)[i] : i;
    }
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    set.insert(tri);
  }
  return set;
}

TEST(Gltf, DracoRoundTripStaysWithinQuantizationAndKeepsTriangles) {
  const NodeMesh mesh = grid_mesh(21);
  for (int bits : {8, 11, 14}) {
    GltfWriteOptions options = draco_options(true);
    options.draco_options.position_bits = bits;
    const std::vector<std::byte> glb = encode(std::span(&mesh, 1), options);
    Result<std::vector<NodeMesh>> back = decode_gltf(glb, "draco.glb");
    ASSERT_TRUE(back.ok()) << back.status().message();
    const NodeMesh& decoded = back->front();
    ASSERT_EQ(decoded.layout, mesh.layout);
    EXPECT_EQ(decoded.triangle_count(), mesh.triangle_count());

    // Positions within the bounding box's largest extent / 2^bits of their original vertex.
    const Bounds b = mesh.bounds();
    const double extent = std::max({b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]});
    const double tolerance = extent / std::pow(2.0, bits);
    const std::vector<std::size_t> match = match_vertices(mesh, decoded);
    const std::uint32_t f = mesh.layout.floats();
    for (std::size_t d = 0; d < decoded.vertex_count(); ++d) {
      for (std::size_t k = 0; k < 3; ++k)
        ASSERT_NEAR(decoded.vertices[d * f + k], mesh.vertices[match[d] * f + k], tolerance)
            << bits;
      // Normals within ~0.5 degree (10 bits octahedral), colours within 1/255, UVs within 1/2^12.
      for (std::size_t k = 3; k < 6; ++k)
        EXPECT_NEAR(decoded.vertices[d * f + k], mesh.vertices[match[d] * f + k], 0.01);
      for (std::size_t k = 6; k < 9; ++k)
        EXPECT_NEAR(decoded.vertices[d * f + k], mesh.vertices[match[d] * f + k], 1.0 / 255);
      for (std::size_t k = 9; k < 11; ++k)
        EXPECT_NEAR(decoded.vertices[d * f + k], mesh.vertices[match[d] * f + k], 3.0 / 4096);
    }
    // Same triangles, same orientation, whatever order Edgebreaker chose.
    EXPECT_EQ(triangle_set(decoded, &match), triangle_set(mesh, nullptr)) << bits;

    // POSITION min/max describe the decoded data exactly.
    const json document = glb_json(glb);
    const json& position =
        document["accessors"]
                [document["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<std::size_t>()];
    const Bounds decoded_bounds = decoded.bounds();
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(position["min"][k].get<float>(), decoded_bounds.min[k]);
      EXPECT_EQ(position["max"][k].get<float>(), decoded_bounds.max[k]);
    }
  }
}

// Edgebreaker keeps non-manifold and duplicate triangles but cannot encode one that repeats a
// vertex index:
//   2---3      triangles 012, 213, a duplicate 012, 415 (4 sits on 0: zero area but three
//   | \ |      distinct indices), and 001 (repeats vertex 0: dropped)
//  0,4--1--5
TEST(Gltf, DracoDropsOnlyTrianglesThatRepeatAVertex) {
  NodeMesh mesh;
  mesh.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 0, 2, 0, 0};
  mesh.indices = {0, 1, 2, 2, 1, 3, 0, 1, 2, 4, 1, 5, 0, 0, 1};
  Result<std::vector<NodeMesh>> back =
      decode_gltf(encode(std::span(&mesh, 1), draco_options(true)), "d.glb");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->front().triangle_count(), 4u);
}

TEST(Gltf, DracoFileDeclaresTheExtensionAndHasNoUncompressedData) {
  const NodeMesh mesh = grid_mesh(30);
  const std::vector<std::byte> plain = encode(std::span(&mesh, 1));
  const std::vector<std::byte> draco = encode(std::span(&mesh, 1), draco_options(true));
  EXPECT_LT(draco.size() * 3, plain.size());
  const json document = glb_json(draco);
  EXPECT_EQ(document["extensionsUsed"], json::array({"KHR_draco_mesh_compression"}));
  EXPECT_EQ(document["extensionsRequired"], json::array({"KHR_draco_mesh_compression"}));
  for (const json& accessor : document["accessors"]) EXPECT_FALSE(accessor.contains("bufferView"));
  const json& extension =
      document["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"];
  EXPECT_TRUE(extension["attributes"].contains("TEXCOORD_0"));
  EXPECT_EQ(document["bufferViews"].size(), 1u);
}

// The triangles of `mesh` whose centroid x is below (or not below) `x`, with their vertices.
NodeMesh split_by_x(const NodeMesh& mesh, float x, bool below) {
  NodeMesh out;
  out.layout = mesh.layout;
  std::map<std::uint32_t, std::uint32_t> remap;
  const std::uint32_t f = mesh.layout.floats();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    float cx = 0;
    for (std::size_t k = 0; k < 3; ++k) cx += mesh.vertices[mesh.indices[3 * t + k] * f] / 3;
    if ((cx < x) != below) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t i = mesh.indices[3 * t + k];
      auto [it, added] = remap.try_emplace(i, static_cast<std::uint32_t>(out.vertex_count()));
      if (added)
        out.vertices.insert(out.vertices.end(), mesh.vertices.begin() + i * f,
                            mesh.vertices.begin() + (i + 1) * f);
      out.indices.push_back(it->second);
    }
  }
  return out;
}

// One grid cut into two meshes along x = 0.5 (as octree nodes are): with one quantization grid
// per file, the seam's vertices decode to identical positions in both meshes, so a cut exported
// with Draco has no cracks.
TEST(Gltf, DracoKeepsVerticesSharedBetweenMeshesIdentical) {
  const NodeMesh whole = grid_mesh(17);
  const std::vector<NodeMesh> meshes = {split_by_x(whole, 0.5f, true),
                                        split_by_x(whole, 0.5f, false)};
  Result<std::vector<NodeMesh>> back =
      decode_gltf(encode(meshes, draco_options(true, 9)), "pair.glb");
  ASSERT_TRUE(back.ok()) << back.status().message();
  auto seam = [](const NodeMesh& m) {
    std::set<std::array<float, 3>> points;  // decoded vertices within one 9-bit step of x = 0.5
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      const float* p = m.vertices.data() + v * m.layout.floats();
      if (std::fabs(p[0] - 0.5f) < 1.0f / 511) points.insert({p[0], p[1], p[2]});
    }
    return points;
  };
  const auto left = seam(back.value()[0]), right = seam(back.value()[1]);
  EXPECT_EQ(left.size(), 17u);
  EXPECT_EQ(left, right);
}

// --- errors ------------------------------------------------------------------------------------

TEST(Gltf, GarbageIsBadInputNamingTheFile) {
  std::mt19937 random(7);
  std::vector<std::vector<std::byte>> inputs = {{}, {std::byte{'g'}}};
  for (std::size_t size : {4u, 12u, 40u, 1000u}) {
    std::vector<std::byte> junk(size);
    for (std::byte& b : junk) b = static_cast<std::byte>(random());
    inputs.push_back(junk);
    std::memcpy(junk.data(), "glTF", 4);  // right magic, garbage after it
    inputs.push_back(junk);
  }
  for (const char* text : {"{", "[]", "{}", "{\"asset\":{\"version\":2}}", "null", "\"glTF\""})
    inputs.emplace_back(reinterpret_cast<const std::byte*>(text),
                        reinterpret_cast<const std::byte*>(text) + std::strlen(text));
  for (const auto& input : inputs) {
    Result<std::vector<NodeMesh>> r = decode_gltf(input, "junk.glb");
    ASSERT_FALSE(r.ok()) << input.size();
    EXPECT_EQ(r.status().code(), ErrorCode::bad_input) << r.status().message();
    EXPECT_EQ(r.status().message().rfind("junk.glb: ", 0), 0u) << r.status().message();
  }
}

TEST(Gltf, EveryTruncationIsBadInput) {
  for (bool draco : {false, true}) {
    const NodeMesh mesh = quad_mesh({true, true, true});
    const std::vector<std::byte> glb = encode(std::span(&mesh, 1), draco_options(draco));
    for (std::size_t n = 0; n < glb.size(); ++n) {
      Result<std::vector<NodeMesh>> r = decode_gltf(std::span(glb).first(n), "cut.glb");
      ASSERT_FALSE(r.ok()) << n;
      EXPECT_EQ(r.status().code(), ErrorCode::bad_input) << n << ": " << r.status().message();
    }
  }
}

TEST(Gltf, EveryTruncationOfEmbeddedGltfFails) {
  const NodeMesh mesh = quad_mesh({true, false, true});
  std::vector<std::byte> text = encode(std::span(&mesh, 1), text_options());
  while (std::isspace(static_cast<int>(text.back()))) text.pop_back();  // a cut there still parses
  for (std::size_t n = 0; n < text.size(); ++n)
    ASSERT_FALSE(decode_gltf(std::span(text).first(n), "cut.gltf").ok()) << n;
}

// Flipping any single byte must never crash or read out of bounds (run under ASan); the result
// is a mesh or a bad_input/unsupported status. Binary bytes get three flips, JSON text one
// (most JSON flips only break the syntax). The Draco variant has no UVs: Draco's texture
// coordinate decoder trusts a 32-bit orientation count, so one flipped bit there costs seconds
// (see docs/formats.md, "glTF export").
TEST(Gltf, SingleByteCorruptionsDecodeOrFailCleanly) {
  for (bool draco : {false, true}) {
    const NodeMesh mesh = quad_mesh({true, true, !draco});
    std::vector<std::byte> glb = encode(std::span(&mesh, 1), draco_options(draco));
    const std::size_t json_end = 20 + u32_at(glb, 12);
    for (std::size_t i = 0; i < glb.size(); ++i) {
      const std::byte saved = glb[i];
      const bool text = i >= 20 && i < json_end;
      for (std::byte flip : {std::byte{0x01}, std::byte{0x80}, std::byte{0xFF}}) {
        if (text && flip != std::byte{0x01}) continue;
        glb[i] = saved ^ flip;
        Result<std::vector<NodeMesh>> r = decode_gltf(glb, "flip.glb");
        if (!r.ok()) {
          EXPECT_NE(r.status().code(), ErrorCode::io);
          continue;
        }
        for (const NodeMesh& m : r.value())
          for (std::uint32_t index : m.indices) ASSERT_LT(index, m.vertex_count());
      }
      glb[i] = saved;
    }
  }
}

TEST(Gltf, InconsistentStructureIsBadInputWithWhatWasWrong) {
  const NodeMesh mesh = quad_mesh({true, true, true});
  const std::vector<std::byte> glb = encode(std::span(&mesh, 1));
  struct Case {
    const char* expect;
    std::function<void(json&)> edit;
  };
  const std::vector<Case> cases = {
      {"accessors index 99 out of range",
       [](json& d) { d["meshes"][0]["primitives"][0]["indices"] = 99; }},
      {"overrun its bufferView", [](json& d) { d["accessors"][0]["count"] = 1000; }},
      {"exceed the buffer", [](json& d) { d["bufferViews"][0]["byteLength"] = 100000; }},
      {"no POSITION",
       [](json& d) { d["meshes"][0]["primitives"][0]["attributes"].erase("POSITION"); }},
      {"not a non-negative integer", [](json& d) { d["accessors"][0]["count"] = -4; }},
      {"'buffers' is not an array", [](json& d) { d["buffers"] = 3; }},
      {"no uri and there is no GLB BIN chunk",
       [](json& d) {
         d["buffers"].push_back({{"byteLength", 4}});
       }},
      {"values for 4 vertices", [](json& d) { d["accessors"][1]["count"] = 3; }},
  };
  for (const Case& c : cases) {
    const Status s = decode_edited(glb, c.edit);
    ASSERT_FALSE(s.ok()) << c.expect;
    EXPECT_EQ(s.code(), ErrorCode::bad_input) << s.message();
    EXPECT_NE(s.message().find(c.expect), std::string::npos) << s.message();
    EXPECT_EQ(s.message().rfind("edited.glb: ", 0), 0u) << s.message();
  }

  // An index past the vertex count (indices are the last bufferView: quad index 3 -> 4).
  std::vector<std::byte> bin = glb_bin(glb);
  const json document = glb_json(glb);
  const std::size_t indices = document["meshes"][0]["primitives"][0]["indices"];
  const std::size_t at =
      document["bufferViews"][document["accessors"][indices]["bufferView"].get<std::size_t>()]
              ["byteOffset"];
  bin[at] = std::byte{4};
  Result<std::vector<NodeMesh>> r = decode_gltf(make_glb(document, bin), "index.glb");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("index 0 is 4, but there are 4 vertices"), std::string::npos)
      << r.status().message();
}

TEST(Gltf, ValidButUnhandledGltfIsUnsupported) {
  const NodeMesh mesh = quad_mesh({});
  const std::vector<std::byte> glb = encode(std::span(&mesh, 1));
  for (auto edit : std::vector<std::function<void(json&)>>{
           [](json& d) { d["meshes"][0]["primitives"][0]["mode"] = 1; },
           [](json& d) { d["extensionsRequired"] = {"EXT_meshopt_compression"}; },
           [](json& d) { d["accessors"][0]["sparse"] = json::object(); },
           [](json& d) { d["asset"]["version"] = "1.0"; },
       }) {
    const Status s = decode_edited(glb, edit);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.code(), ErrorCode::unsupported) << s.message();
  }
}

TEST(Gltf, RejectsInconsistentMeshesAndOptions) {
  NodeMesh bad_index = quad_mesh({});
  bad_index.indices[4] = 4;
  Result<std::vector<std::byte>> r = encode_gltf(std::span(&bad_index, 1), {});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
  NodeMesh ragged = quad_mesh({});
  ragged.vertices.pop_back();
  EXPECT_EQ(encode_gltf(std::span(&ragged, 1), {}).status().code(), ErrorCode::bad_input);

  const NodeMesh mesh = quad_mesh({});
  EXPECT_EQ(encode_gltf(std::span(&mesh, 1), named({"a", "b"})).status().code(), ErrorCode::usage);
  // past kMaxDracoBits (Draco's tables grow as 2^bits): refused, not gigabytes
  EXPECT_EQ(encode_gltf(std::span(&mesh, 1), draco_options(true, kMaxDracoBits + 1)).status().code(),
            ErrorCode::usage);
  EXPECT_TRUE(encode_gltf(std::span(&mesh, 1), draco_options(true, kMaxDracoBits)).ok());
}

// --- other writers' files ----------------------------------------------------------------------

// A .gltf as other tools write it: non-indexed triangles, interleaved with a byte stride,
// normalized unsigned-byte RGBA colours, and a second primitive without colours.
TEST(Gltf, ReadsStridedNormalizedNonIndexedMultiPrimitiveFiles) {
  // Vertex: position 3 f32 + RGBA u8 = 16 bytes; three vertices.
  std::vector<std::byte> bin;
  auto put_f = [&](float v) {
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    bin.insert(bin.end(), p, p + 4);
  };
  const float positions[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int v = 0; v < 3; ++v) {
    for (float c : positions[v]) put_f(c);
    for (int c = 0; c < 4; ++c) bin.push_back(static_cast<std::byte>(v == c ? 255 : 51));
  }
  // Second primitive: indexed (u8 indices), positions only.
  const std::size_t second = bin.size();
  for (float c : {5.f, 5.f, 5.f, 6.f, 5.f, 5.f, 5.f, 6.f, 5.f}) put_f(c);
  const std::size_t second_indices = bin.size();
  for (int i : {2, 1, 0}) bin.push_back(static_cast<std::byte>(i));

  json document = {
      {"asset", {{"version", "2.0"}, {"generator", "hand"}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}, {"byteStride", 16}},
        {{"buffer", 0}, {"byteOffset", second}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", second_indices}, {"byteLength", 3}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 0},
         {"byteOffset", 12},
         {"componentType", 5121},
         {"normalized", true},
         {"count", 3},
         {"type", "VEC4"}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5121}, {"count", 3}, {"type", "SCALAR"}}}},
      {"meshes",
       {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"COLOR_0", 1}}}}}}},
        {{"primitives",
          {{{"attributes", {{"POSITION", 0}, {"COLOR_0", 1}}}},
           {{"attributes", {{"POSITION", 2}}}, {"indices", 3}}}}}}},
  };
  Result<std::vector<NodeMesh>> r = decode_gltf(make_glb(document, bin), "other.glb");
  ASSERT_TRUE(r.ok()) << r.status().message();
  ASSERT_EQ(r->size(), 2u);
  const NodeMesh& colored = r.value()[0];
  EXPECT_EQ(colored.layout, (VertexLayout{false, true, false}));
  EXPECT_EQ(colored.indices, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(colored.vertices, (std::vector<float>{0, 0, 0, 1, 0.2f, 0.2f, 1, 0, 0, 0.2f, 1, 0.2f, 0,
                                                  1, 0, 0.2f, 0.2f, 1}));
  const NodeMesh& merged = r.value()[1];
  EXPECT_EQ(merged.layout, VertexLayout{});
  EXPECT_EQ(merged.indices, (std::vector<std::uint32_t>{0, 1, 2, 5, 4, 3}));
  EXPECT_EQ(merged.vertex_count(), 6u);
  EXPECT_EQ(merged.vertices[3 * 4], 6.0f);
}

// --- files -------------------------------------------------------------------------------------

TEST(Gltf, WriteGltfIsAtomicAndReadGltfReadsItBack) {
  TempDir dir;
  const std::vector<NodeMesh> meshes = {grid_mesh(4), quad_mesh({false, true, false})};
  for (const char* name : {"cut.glb", "cut.gltf"}) {
    const std::filesystem::path path = dir.path() / name;
    GltfWriteOptions options;
    options.binary = path.extension() == ".glb";
    ASSERT_TRUE(write_gltf(path, meshes, options).ok());
    ASSERT_TRUE(write_gltf(path, meshes, options).ok());  // replaces the existing file
    Result<std::vector<NodeMesh>> back = read_gltf(path);
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back.value(), meshes);
  }
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 2u) << "no temporary files left behind";
}

TEST(Gltf, FileErrorsNameTheFile) {
  TempDir dir;
  const NodeMesh mesh = quad_mesh({});
  const std::filesystem::path missing_dir = dir.path() / "no" / "such" / "dir.glb";
  const Status s = write_gltf(missing_dir, std::span(&mesh, 1), {});
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), ErrorCode::io);
  EXPECT_NE(s.message().find(missing_dir.string()), std::string::npos) << s.message();

  const std::filesystem::path fifo = dir.path() / "fifo.glb";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Status special = write_gltf(fifo, std::span(&mesh, 1), {});
  EXPECT_EQ(special.code(), ErrorCode::io);
  EXPECT_NE(special.message().find(fifo.string() + ": cannot write the glTF: it is not a regular file"),
            std::string::npos) << special.message();
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  std::filesystem::remove(fifo);

  NodeMesh bad = quad_mesh({});
  bad.indices[0] = 9;
  const Status invalid = write_gltf(dir.path() / "bad.glb", std::span(&bad, 1), {});
  EXPECT_EQ(invalid.code(), ErrorCode::bad_input);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "neither the file nor a temporary";

  Result<std::vector<NodeMesh>> r = read_gltf(dir.path() / "absent.glb");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::io);

  const std::filesystem::path junk = dir.path() / "junk.glb";
  std::ofstream(junk) << "glTF not really";
  r = read_gltf(junk);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::bad_input);
  EXPECT_NE(r.status().message().find(junk.string()), std::string::npos);
}

TEST(Gltf, ReadGltfResolvesExternalBuffersNextToTheFile) {
  TempDir dir;
  const NodeMesh mesh = quad_mesh({true, false, false});
  const std::vector<std::byte> glb = encode(std::span(&mesh, 1));
  const std::vector<std::byte> bin = glb_bin(glb);
  json document = glb_json(glb);
  document["buffers"][0]["uri"] = "data.bin";
  std::ofstream(dir.path() / "data.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(bin.data()), static_cast<std::streamsize>(bin.size()));
  std::ofstream(dir.path() / "split.gltf") << document.dump();
  Result<std::vector<NodeMesh>> back = read_gltf(dir.path() / "split.gltf");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->front(), mesh);
  // In memory there is no directory to resolve against.
  const std::string text = document.dump();
  Result<std::vector<NodeMesh>> in_memory = decode_gltf(
      std::span(reinterpret_cast<const std::byte*>(text.data()), text.size()), "split.gltf");
  ASSERT_FALSE(in_memory.ok());
  EXPECT_EQ(in_memory.status().code(), ErrorCode::unsupported);
}

// --- octolod export ----------------------------------------------------------------------------

// A baked tree by hand: root (2 LODs: 8 and 2 triangles, errors 0.01 and 0.5) over two leaf
// children (octants 0 and 1, one LOD each with error 0, 4 triangles each).
void write_tree(const std::filesystem::path& root) {
  const VertexLayout layout{true, true, true};
  auto node_mesh = [&](int quads, float x0) {
    NodeMesh m;
    m.layout = layout;
    for (int q = 0; q < quads; ++q) {
      NodeMesh quad = quad_mesh(layout, 0.5f);
      const auto base = static_cast<std::uint32_t>(m.vertex_count());
      for (std::size_t v = 0; v < quad.vertex_count(); ++v)
        quad.vertices[v * layout.floats()] += x0 + static_cast<float>(q);
      m.vertices.insert(m.vertices.end(), quad.vertices.begin(), quad.vertices.end());
      for (std::uint32_t i : quad.indices) m.indices.push_back(base + i);
    }
    return m;
  };
  Manifest manifest;
  manifest.layout = layout;
  auto add_lod = [&](NodeInfo& node, const NodeMesh& mesh, double error, const std::string& file) {
    std::filesystem::create_directories((root / file).parent_path());
    EXPECT_TRUE(write_node_file(root / file, mesh).ok());
    node.lods.push_back({static_cast<std::uint32_t>(mesh.triangle_count()),
                         static_cast<std::uint32_t>(mesh.vertex_count()), error,
                         std::filesystem::file_size(root / file), file});
    node.bounds.extend(mesh.bounds());
  };
  NodeInfo top;
  top.cell = {{0, 0, 0}, {4, 4, 4}};
  top.children[0] = 1;
  top.children[1] = 2;
  top.source_triangles = 8;
  add_lod(top, node_mesh(4, 0), 0.01, "lod0.olod");
  add_lod(top, node_mesh(1, 0), 0.5, "lod1.olod");
  NodeInfo left;
  left.path = "0";
  left.depth = 1;
  left.parent = 0;
  left.cell = {{0, 0, 0}, {2, 2, 2}};
  left.source_triangles = 4;
  add_lod(left, node_mesh(2, 0), 0.0, "0/lod0.olod");
  NodeInfo right = left;
  right.path = "1";
  right.cell = {{2, 0, 0}, {4, 2, 2}};
  right.lods.clear();
  right.bounds = {};
  add_lod(right, node_mesh(2, 2), 0.0, "1/lod0.olod");
  manifest.nodes = {top, left, right};
  for (const NodeInfo& n : manifest.nodes) manifest.bounds.extend(n.bounds);
  manifest.input_triangles = 8;
  ASSERT_TRUE(write_manifest(root / std::string(kManifestFileName), manifest).ok());
}

// Runs the CLI, returns its exit code and stdout.
std::pair<int, std::string> run_cli(const std::string& arguments) {
  const char* cli = std::getenv("OCTOLOD_CLI");
  std::string out;
  FILE* pipe = ::popen((std::string(cli) + " " + arguments + " 2>/dev/null").c_str(), "r");
  if (pipe == nullptr) return {-1, out};
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(GltfExport, WritesTheUniformCutAsOneNamedMeshPerNodeLod) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  TempDir dir;
  const std::filesystem::path tree = dir.path() / "tree";
  write_tree(tree);
  struct Case {
    std::string args;
    std::vector<std::string> names;
    std::size_t triangles;
  };
  const std::vector<Case> cases = {
      {"--error 1", {"root/lod1"}, 2},
      {"--error 0.1", {"root/lod0"}, 8},
      {"--error 0.001", {"0/lod0", "1/lod0"}, 8},
      {"--level 1", {"0/lod0", "1/lod0"}, 8},
      {"--level 0", {"root/lod0"}, 8},
  };
  for (bool draco : {false, true}) {
    for (const Case& c : cases) {
      const std::filesystem::path out = dir.path() / (draco ? "cut_draco.glb" : "cut.glb");
      const auto [code, stdout_text] = run_cli("--json export " + tree.string() + " " + c.args +
                                               " -o " + out.string() + (draco ? " --draco" : ""));
      ASSERT_EQ(code, 0) << c.args;
      const json report = json::parse(stdout_text);
      EXPECT_EQ(report["meshes"], c.names.size());
      EXPECT_EQ(report["triangles"], c.triangles);
      EXPECT_EQ(report["bytes"], std::filesystem::file_size(out));
      EXPECT_EQ(report["draco"], draco);

      std::ifstream in(out, std::ios::binary);
      std::vector<char> raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(raw.data()),
                                             raw.size());
      const json document = glb_json(bytes);
      std::vector<std::string> names;
      for (const json& node : document["nodes"]) names.push_back(node["name"]);
      EXPECT_EQ(names, c.names) << c.args;
      Result<std::vector<NodeMesh>> meshes = read_gltf(out);
      ASSERT_TRUE(meshes.ok()) << meshes.status().message();
      std::size_t triangles = 0;
      for (const NodeMesh& m : meshes.value()) triangles += m.triangle_count();
      EXPECT_EQ(triangles, c.triangles) << c.args;
    }
  }
}

TEST(GltfExport, ReportsUsageAndMissingTreeErrors) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  TempDir dir;
  const std::string out = (dir.path() / "x.glb").string();
  EXPECT_EQ(run_cli("export " + dir.path().string() + " --error 1 -o " + out).first,
            4);  // no manifest
  write_tree(dir.path());
  EXPECT_EQ(run_cli("export " + dir.path().string() + " -o " + out).first, 1);  // no cut given
  EXPECT_EQ(run_cli("export " + dir.path().string() + " --error 1 --level 2 -o " + out).first, 1);
  EXPECT_EQ(run_cli("export " + dir.path().string() + " --error -1 -o " + out).first, 1);
  const std::string obj = (dir.path() / "x.obj").string();  // neither .glb nor .gltf
  EXPECT_EQ(run_cli("export " + dir.path().string() + " --error 1 -o " + obj).first, 1);
  EXPECT_FALSE(std::filesystem::exists(obj));
  EXPECT_EQ(
      run_cli("export " + dir.path().string() + " --error 1 --position-bits 9 -o " + out).first,
      1);  // quantization without --draco
  EXPECT_EQ(
      run_cli("export " + dir.path().string() + " --error 1 --draco --position-bits 40 -o " + out)
          .first,
      1);
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove(dir.path() / "1" / "lod0.olod");
  EXPECT_EQ(run_cli("export " + dir.path().string() + " --level 1 -o " + out).first, 4);
}

// A tree baked from an empty mesh (a root without LODs): export refuses it as extract does
// (bad input, exit 2) and writes nothing.
// A tree's texture: export embeds it as the meshes' material, extract names it in a TextureFile
// comment relative to the cut; an image glTF cannot embed leaves the export untextured, not failed.
TEST(GltfExport, TheTreesTextureGoesIntoTheGltfAndIsNamedByTheExtractedPly) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  TempDir dir;
  const std::filesystem::path tree = dir.path() / "tree";
  write_tree(tree);
  Result<Manifest> manifest = read_tree_manifest(tree);
  ASSERT_TRUE(manifest.ok()) << manifest.status().message();
  manifest->texture = "texture/stone.jpg";
  ASSERT_TRUE(write_manifest(tree / std::string(kManifestFileName), manifest.value()).ok());
  std::filesystem::create_directories(tree / "texture");
  const std::string jpeg = "\xFF\xD8\xFF\xE0 a JPEG's bytes";
  std::ofstream(tree / "texture/stone.jpg", std::ios::binary) << jpeg;

  const std::filesystem::path glb = dir.path() / "cut.glb";
  const auto [code, text] = run_cli("--json export " + tree.string() + " --level 1 -o " + glb.string());
  ASSERT_EQ(code, 0);
  EXPECT_EQ(json::parse(text)["texture"], "stone.jpg");
  std::ifstream in(glb, std::ios::binary);
  std::vector<char> raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(raw.data()), raw.size());
  const json document = glb_json(bytes);
  ASSERT_EQ(document["images"].size(), 1u);
  EXPECT_EQ(document["images"][0]["mimeType"], "image/jpeg");
  const json& view = document["bufferViews"][document["images"][0]["bufferView"].get<std::size_t>()];
  const std::vector<std::byte> bin = glb_bin(bytes);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(bin.data()) + view.value("byteOffset", 0),
                        view["byteLength"].get<std::size_t>()),
            jpeg);
  for (const json& mesh : document["meshes"]) EXPECT_EQ(mesh["primitives"][0]["material"], 0);

  std::filesystem::create_directories(dir.path() / "cuts");
  const std::filesystem::path ply = dir.path() / "cuts" / "cut.ply";
  ASSERT_EQ(run_cli("extract " + tree.string() + " --level 1 -o " + ply.string()).first, 0);
  std::ifstream header(ply, std::ios::binary);
  std::string line;
  std::vector<std::string> comments;
  while (std::getline(header, line) && line != "end_header")
    if (line.rfind("comment ", 0) == 0) comments.push_back(line);
  EXPECT_EQ(comments, std::vector<std::string>{"comment TextureFile ../tree/texture/stone.jpg"});

  // not an image glTF embeds: exported without it
  std::ofstream(tree / "texture/stone.jpg", std::ios::binary | std::ios::trunc) << "BM a bitmap";
  const auto [plain_code, plain_text] = run_cli("--json export " + tree.string() + " --level 1 -o " + glb.string());
  ASSERT_EQ(plain_code, 0);
  EXPECT_EQ(json::parse(plain_text)["texture"], "");
}

TEST(GltfExport, RefusesATreeWithoutNodeLodsLikeExtract) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  TempDir dir;
  const std::filesystem::path tree = dir.path() / "tree";
  std::filesystem::create_directories(tree);
  Manifest manifest;
  manifest.nodes.emplace_back();
  manifest.nodes.back().cell = {{0, 0, 0}, {1, 1, 1}};
  ASSERT_TRUE(write_manifest(tree / std::string(kManifestFileName), manifest).ok());
  const std::filesystem::path glb = dir.path() / "cut.glb", ply = dir.path() / "cut.ply";
  EXPECT_EQ(run_cli("export " + tree.string() + " --error 1 -o " + glb.string()).first, 2);
  EXPECT_EQ(run_cli("extract " + tree.string() + " --error 1 -o " + ply.string()).first, 2);
  EXPECT_EQ(run_cli("export " + tree.string() + " --level 0 -o " + glb.string()).first, 2);
  EXPECT_FALSE(std::filesystem::exists(glb));
  EXPECT_FALSE(std::filesystem::exists(ply));
}

}  // namespace
}  // namespace octolod
