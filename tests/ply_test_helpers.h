// Fixtures for the PLY tests: a scratch directory, byte-exact file writing, procedural meshes
// for every vertex layout, and assertions on error statuses.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::test {

// A fresh directory per test, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "octolod-ply-" + std::to_string(::getpid()) + "-";
    if (info != nullptr) name += std::string(info->test_suite_name()) + "-" + info->name();
    for (char& c : name)
      if (c == '/') c = '_';
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  std::filesystem::path file(const std::string& name) const { return path_ / name; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline void write_bytes(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << path;
}

inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Little/big-endian byte builders for hand-made binary bodies.
template <class T>
void append_scalar(std::string& out, T value, bool big_endian) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  const bool swap = big_endian == (std::endian::native == std::endian::little);
  if (swap)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  out.append(bytes, sizeof(T));
}

// The float the reader produces for an 8-bit colour channel value k.
// Reader options with the smallest batches (4 KiB): the batch-boundary paths run on small files.
inline PlyReadOptions small_batches() {
  PlyReadOptions options;
  options.buffer_bytes = 4096;
  return options;
}

inline float byte_color(int k) { return static_cast<float>(k / 255.0); }

struct TestMesh {
  VertexLayout layout;
  std::vector<float> vertices;
  std::vector<std::uint32_t> triangles;
  std::uint32_t vertex_count() const {
    return static_cast<std::uint32_t>(vertices.size() / layout.floats());
  }
};

// A strip of `n` vertices (n >= 3) and n-2 triangles whose values stress exact float text
// round trips: tiny, huge (the largest the reader accepts), subnormal, negative zero,
// non-terminating decimals. Colours are byte values k/255 when `byte_colors` (what a uchar file
// can hold), arbitrary otherwise.
inline TestMesh strip_mesh(VertexLayout layout, bool byte_colors, std::uint32_t n = 7) {
  static constexpr float kSpecial[] = {0.1f, -0.0f, 1e-30f, 1e-40f, kMaxVertexValue, -2.5f,
                                       3.14159265f, 1.0f / 3.0f, 16777216.0f, -7e-12f};
  TestMesh mesh;
  mesh.layout = layout;
  for (std::uint32_t i = 0; i < n; ++i) {
    auto special = [&](std::uint32_t k) { return kSpecial[(i * 3 + k) % std::size(kSpecial)]; };
    for (std::uint32_t k = 0; k < 3; ++k)
      mesh.vertices.push_back(special(k) + static_cast<float>(i));
    if (layout.normal) {
      const float a = 0.37f * static_cast<float>(i);
      mesh.vertices.insert(mesh.vertices.end(), {std::cos(a), std::sin(a), 0.0f});
    }
    if (layout.color)
      for (std::uint32_t k = 0; k < 3; ++k)
        mesh.vertices.push_back(byte_colors ? byte_color(static_cast<int>((i * 53 + k * 101) % 256))
                                            : special(k + 1) / 3e38f + 0.3f);
    if (layout.uv) mesh.vertices.insert(mesh.vertices.end(), {special(2) * 0.5f, -special(1)});
  }
  for (std::uint32_t i = 0; i + 2 < n; ++i) {
    if (i % 2 == 0)
      mesh.triangles.insert(mesh.triangles.end(), {i, i + 1, i + 2});
    else
      mesh.triangles.insert(mesh.triangles.end(), {i + 1, i, i + 2});
  }
  return mesh;
}

// The mesh (VertexLayout floats, `triangles` 3 per triangle) as a binary little-endian PLY whose
// faces carry the attributes `corners` names and whose vertices do not: a colour per face (float
// red, green, blue after the indices; every corner of a face must have its face's colour) and
// texture coordinates per corner (a texcoord list after that, as MeshLab writes textured meshes).
// Vertices equal but for those are written once, so a seam's two sides share one vertex. Colours
// as floats (exact). The header names `texture` in a TextureFile comment, unless it is empty.
inline void write_face_attribute_ply(const std::filesystem::path& path, VertexLayout layout,
                                     const std::vector<float>& vertices,
                                     const std::vector<std::uint32_t>& triangles, CornerAttributes corners,
                                     const std::string& texture = "") {
  ASSERT_TRUE(corners.any());
  ASSERT_TRUE(layout.color || !corners.color);
  ASSERT_TRUE(layout.uv || !corners.uv);
  const std::size_t floats = layout.floats();
  const VertexLayout kept{layout.normal, layout.color && !corners.color, layout.uv && !corners.uv};
  auto kept_floats = [&](std::size_t v) {
    const float* vertex = vertices.data() + v * floats;
    std::vector<float> key(vertex, vertex + 3 + (layout.normal ? 3 : 0));
    if (kept.color) key.insert(key.end(), vertex + layout.color_offset(), vertex + layout.color_offset() + 3);
    if (kept.uv) key.insert(key.end(), vertex + layout.uv_offset(), vertex + layout.uv_offset() + 2);
    return key;
  };
  std::map<std::vector<float>, std::uint32_t> welded;
  std::vector<std::uint32_t> id(vertices.size() / floats);
  std::string vertex_bytes;
  for (std::size_t v = 0; v < id.size(); ++v) {
    const std::vector<float> key = kept_floats(v);
    const auto [it, added] = welded.try_emplace(key, static_cast<std::uint32_t>(welded.size()));
    if (added)
      for (float f : key) append_scalar(vertex_bytes, f, false);
    id[v] = it->second;
  }
  std::string text = "ply\nformat binary_little_endian 1.0\n";
  if (!texture.empty()) text += "comment TextureFile " + texture + "\n";
  text += "element vertex " + std::to_string(welded.size()) + "\nproperty float x\nproperty float y\nproperty float z\n";
  if (kept.normal) text += "property float nx\nproperty float ny\nproperty float nz\n";
  if (kept.color) text += "property float red\nproperty float green\nproperty float blue\n";
  if (kept.uv) text += "property float u\nproperty float v\n";
  text += "element face " + std::to_string(triangles.size() / 3) + "\nproperty list uchar int vertex_indices\n";
  if (corners.color) text += "property float red\nproperty float green\nproperty float blue\n";
  if (corners.uv) text += "property list uchar float texcoord\n";
  text += "end_header\n" + vertex_bytes;
  for (std::size_t t = 0; t < triangles.size(); t += 3) {
    append_scalar(text, std::uint8_t{3}, false);
    for (std::size_t c = 0; c < 3; ++c) append_scalar(text, static_cast<std::int32_t>(id[triangles[t + c]]), false);
    if (corners.color) {
      const float* color = vertices.data() + triangles[t] * floats + layout.color_offset();
      for (std::size_t c = 1; c < 3; ++c)
        ASSERT_TRUE(std::equal(color, color + 3, vertices.data() + triangles[t + c] * floats + layout.color_offset()))
            << "triangle " << t / 3 << "'s corners have different colours";
      for (std::size_t k = 0; k < 3; ++k) append_scalar(text, color[k], false);
    }
    if (corners.uv) {
      append_scalar(text, std::uint8_t{6}, false);
      for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t k = 0; k < 2; ++k)
          append_scalar(text, vertices[triangles[t + c] * floats + layout.uv_offset() + k], false);
    }
  }
  write_bytes(path, text);
}

// The mesh with a colour per face, as a segmented scan has it: triangle t's corners get the
// colour of band t / 97 (four colours in turn, exact in float), in vertices of their own where
// their colour differs from the vertex's other triangles' (welded: equal wedges are one vertex).
// The layout gains colour when it has none.
inline TestMesh with_face_colours(VertexLayout layout, const std::vector<float>& vertices,
                                  const std::vector<std::uint32_t>& triangles) {
  static constexpr float kPalette[4][3] = {{1, 0.25f, 0}, {0, 0.5f, 1}, {0.75f, 0.75f, 0.25f}, {0.5f, 0, 0.5f}};
  TestMesh out;
  out.layout = VertexLayout{layout.normal, true, layout.uv};
  const std::size_t floats = layout.floats(), out_floats = out.layout.floats();
  std::map<std::vector<float>, std::uint32_t> welded;
  for (std::size_t corner = 0; corner < triangles.size(); ++corner) {
    const float* source = vertices.data() + std::size_t{triangles[corner]} * floats;
    std::vector<float> wedge(out_floats);
    std::copy(source, source + 3 + (layout.normal ? 3 : 0), wedge.begin());
    const float* colour = kPalette[(corner / 3 / 97) % 4];
    std::copy(colour, colour + 3, wedge.begin() + out.layout.color_offset());
    if (layout.uv) std::copy(source + layout.uv_offset(), source + layout.uv_offset() + 2, wedge.begin() + out.layout.uv_offset());
    const auto [it, added] = welded.try_emplace(wedge, static_cast<std::uint32_t>(welded.size()));
    if (added) out.vertices.insert(out.vertices.end(), wedge.begin(), wedge.end());
    out.triangles.push_back(it->second);
  }
  return out;
}

// Bit-exact float comparison (so -0.0 != 0.0 and NaN patterns matter).
inline ::testing::AssertionResult same_bits(const std::vector<float>& expected,
                                            const std::vector<float>& actual) {
  if (expected.size() != actual.size())
    return ::testing::AssertionFailure()
           << "sizes differ: " << expected.size() << " vs " << actual.size();
  for (std::size_t i = 0; i < expected.size(); ++i)
    if (std::bit_cast<std::uint32_t>(expected[i]) != std::bit_cast<std::uint32_t>(actual[i]))
      return ::testing::AssertionFailure() << "float " << i << " differs: " << expected[i]
                                           << " vs " << actual[i];
  return ::testing::AssertionSuccess();
}

// The status is `code` and its message contains every one of `parts`.
inline ::testing::AssertionResult is_error(const Status& status, ErrorCode code,
                                           std::initializer_list<std::string_view> parts) {
  if (status.ok()) return ::testing::AssertionFailure() << "expected an error, got ok";
  if (status.code() != code)
    return ::testing::AssertionFailure() << "code " << static_cast<int>(status.code())
                                         << " instead of " << static_cast<int>(code) << ": "
                                         << status.message();
  for (std::string_view part : parts)
    if (status.message().find(part) == std::string::npos)
      return ::testing::AssertionFailure()
             << "message lacks '" << part << "': " << status.message();
  return ::testing::AssertionSuccess();
}

template <class T>
Status status_of(const Result<T>& result) {
  return result.ok() ? Status{} : result.status();
}

}  // namespace octolod::test
