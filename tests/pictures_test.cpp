#include <gtest/gtest.h>
#include <turbojpeg.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "heat_scale.h"
#include "image.h"
#include "line_chart.h"
#include "offscreen_renderer.h"
#include "texture_image.h"

namespace octolod::cli {
namespace {

// One quad facing +z, spanning [-1,1]^2 at z = 0.
NodeMesh unit_quad() {
  NodeMesh mesh;
  mesh.vertices = {-1, -1, 0, 1, -1, 0, -1, 1, 0, 1, 1, 0};
  mesh.indices = {0, 1, 2, 2, 1, 3};
  return mesh;
}

RenderView looking_down_z(int w, int h) {
  RenderView view;
  view.width = w;
  view.height = h;
  view.view = glm::lookAt(glm::vec3(0, 0, 4), glm::vec3(0), glm::vec3(0, 1, 0));
  view.projection = glm::perspective(glm::radians(45.0f), float(w) / float(h), 0.1f, 100.0f);
  return view;
}

// A PNG chunk: length, type and data, CRC.
std::string png_chunk(const std::string& type_and_data) {
  std::string out;
  const auto be32 = [&](std::uint32_t value) {
    for (int shift = 24; shift >= 0; shift -= 8) out += static_cast<char>(value >> shift & 0xFF);
  };
  be32(static_cast<std::uint32_t>(type_and_data.size() - 4));
  out += type_and_data;
  be32(static_cast<std::uint32_t>(::crc32(0, reinterpret_cast<const unsigned char*>(type_and_data.data()),
                                          static_cast<unsigned>(type_and_data.size()))));
  return out;
}

// The signature and IHDR of a width x height 8-bit RGB PNG, then an empty IDAT: no pixels.
std::string test_png_header(std::uint32_t width, std::uint32_t height) {
  std::string ihdr = "IHDR";
  for (std::uint32_t value : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8) ihdr += static_cast<char>(value >> shift & 0xFF);
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);
  return "\x89PNG\r\n\x1a\n" + png_chunk(ihdr) + png_chunk("IDAT");
}

TEST(OffscreenRenderer, DrawsTheMeshTintedInTheMiddleAndBackgroundAtTheCorners) {
  NodeMesh quad = unit_quad();
  RenderItem item{&quad, lod_tint(3)};  // red-ish tint
  RenderView view = looking_down_z(64, 48);
  Result<Image> image = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(image.ok()) << image.status().message();
  EXPECT_EQ(image->get(0, 0), view.background);
  std::uint32_t centre = image->get(32, 24);
  EXPECT_NE(centre, view.background);
  EXPECT_GT((centre >> 16) & 0xFF, centre & 0xFF) << "tint should make red dominate blue";
}

TEST(OffscreenRenderer, KeepsTheTopRowOnTop) {
  // A quad covering only the upper half of the view must colour the image's top rows.
  NodeMesh quad = unit_quad();
  for (std::size_t i = 1; i < quad.vertices.size(); i += 3) quad.vertices[i] = quad.vertices[i] * 0.5f + 1.0f;
  RenderItem item{&quad, glm::vec3(1)};
  RenderView view = looking_down_z(64, 64);
  Result<Image> image = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(image.ok());
  EXPECT_NE(image->get(32, 20), view.background);
  EXPECT_EQ(image->get(32, 50), view.background);
}

TEST(OffscreenRenderer, CullsTrianglesFacingAwayOnlyWhenAsked) {
  // the quad wound clockwise as seen from +z: drawn (lit from both sides) unless culled
  NodeMesh quad = unit_quad();
  quad.indices = {0, 2, 1, 2, 3, 1};
  RenderItem item{&quad, glm::vec3(1)};
  RenderView view = looking_down_z(64, 48);
  Result<Image> both_sides = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(both_sides.ok()) << both_sides.status().message();
  EXPECT_NE(both_sides->get(32, 24), view.background);
  view.cull_back_faces = true;
  Result<Image> culled = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(culled.ok());
  EXPECT_EQ(culled->get(32, 24), view.background);
  quad = unit_quad();  // facing the camera: drawn when culling too
  Result<Image> front = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(front.ok());
  EXPECT_NE(front->get(32, 24), view.background);
}

// A 2 x 2 texture on a quad whose UVs run (0, 0) at its lower-left to (1, 1) at its upper-right:
// each quarter of the picture shows its texel, the image's top row at the top (v up), lit and
// filling the quad in white instead of its tint.
TEST(OffscreenRenderer, DrawsATextureOnTheUvsWithTheImagesTopRowAtVOne) {
  NodeMesh quad;
  quad.layout = VertexLayout{.uv = true};
  quad.vertices = {-1, -1, 0, 0, 0, 1, -1, 0, 1, 0, -1, 1, 0, 0, 1, 1, 1, 0, 1, 1};
  quad.indices = {0, 1, 2, 2, 1, 3};
  Image texture(2, 2, 0);
  texture.set(0, 0, 0xff0000);  // top row: red, green
  texture.set(1, 0, 0x00ff00);
  texture.set(0, 1, 0x0000ff);  // bottom row: blue, white
  texture.set(1, 1, 0xffffff);
  RenderItem item{.mesh = &quad, .tint = lod_tint(3), .tint_share = 0.0f, .texture = &texture};
  const RenderView view = looking_down_z(128, 128);
  Result<Image> image = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(image.ok()) << image.status().message();
  const auto channels = [](std::uint32_t rgb) {
    return std::array<int, 3>{int(rgb >> 16 & 0xFF), int(rgb >> 8 & 0xFF), int(rgb & 0xFF)};
  };
  const auto top_left = channels(image->get(48, 48)), top_right = channels(image->get(80, 48));
  const auto bottom_left = channels(image->get(48, 80)), bottom_right = channels(image->get(80, 80));
  EXPECT_GT(top_left[0], 4 * std::max(top_left[1], top_left[2]) + 40);
  EXPECT_GT(top_right[1], 4 * std::max(top_right[0], top_right[2]) + 40);
  EXPECT_GT(bottom_left[2], 4 * std::max(bottom_left[0], bottom_left[1]) + 40);
  EXPECT_GT(std::min({bottom_right[0], bottom_right[1], bottom_right[2]}), 150);
  // without the texture the same item is drawn in its tint
  item.texture = nullptr;
  item.tint_share = 1.0f;
  Result<Image> tinted = render_offscreen(std::span(&item, 1), view);
  ASSERT_TRUE(tinted.ok());
  EXPECT_EQ(tinted->get(48, 48), tinted->get(80, 80));
}

// Textures decode from PNG and JPEG; other files, images too large to sample and corrupt ones
// are refused naming the file, the size known before any pixel is allocated.
TEST(TextureImage, DecodesPngAndJpegAndRefusesOtherOrHugeImages) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "texture_image_test";
  std::filesystem::create_directories(dir);
  Image picture(16, 8, 0x204060);
  for (int x = 0; x < 16; ++x) picture.set(x, 0, 0xffffff);
  ASSERT_TRUE(write_png(dir / "t.png", picture).ok());
  Result<Image> png = read_texture_image(dir / "t.png");
  ASSERT_TRUE(png.ok()) << png.status().message();
  EXPECT_EQ(png->width, 16);
  EXPECT_EQ(png->height, 8);
  EXPECT_EQ(png->rgba, picture.rgba);

  unsigned char* jpeg = nullptr;
  unsigned long jpeg_size = 0;
  tjhandle encoder = tjInitCompress();
  ASSERT_EQ(tjCompress2(encoder, picture.rgba.data(), 16, 0, 8, TJPF_RGBA, &jpeg, &jpeg_size, TJSAMP_444, 95, 0), 0);
  std::ofstream(dir / "t.jpg", std::ios::binary).write(reinterpret_cast<const char*>(jpeg), static_cast<std::streamsize>(jpeg_size));
  tjFree(jpeg);
  tjDestroy(encoder);
  Result<Image> decoded = read_texture_image(dir / "t.jpg");
  ASSERT_TRUE(decoded.ok()) << decoded.status().message();
  ASSERT_EQ(decoded->rgba.size(), picture.rgba.size());
  for (std::size_t i = 0; i < picture.rgba.size(); ++i)
    EXPECT_NEAR(decoded->rgba[i], picture.rgba[i], 8) << i;  // lossy, but close

  std::ofstream(dir / "t.bmp", std::ios::binary) << "BM not a texture glTF knows";
  EXPECT_EQ(read_texture_image(dir / "t.bmp").status().code(), ErrorCode::unsupported);
  // a PNG whose header says 9000 pixels wide: refused from the header
  std::string header = test_png_header(9000, 4);
  std::ofstream(dir / "huge.png", std::ios::binary) << header;
  Result<Image> huge = read_texture_image(dir / "huge.png");
  EXPECT_EQ(huge.status().code(), ErrorCode::unsupported);
  EXPECT_EQ(huge.status().message(), (dir / "huge.png").string() + ": a 9000 x 4 texture, larger than 8192 on a side");
  std::ofstream(dir / "cut.png", std::ios::binary) << header.substr(0, 20);
  Result<Image> cut = read_texture_image(dir / "cut.png");
  EXPECT_EQ(cut.status().code(), ErrorCode::bad_input);
  EXPECT_NE(cut.status().message().find((dir / "cut.png").string() + ": not a readable PNG"), std::string::npos)
      << cut.status().message();
  std::filesystem::remove_all(dir);
}

TEST(Png, WritesAFileThatStartsWithThePngSignature) {
  Image image(8, 4, 0x112233);
  auto path = std::filesystem::path(::testing::TempDir()) / "pictures_test.png";
  ASSERT_TRUE(write_png(path, image).ok());
  std::FILE* f = std::fopen(path.c_str(), "rb");
  ASSERT_NE(f, nullptr);
  unsigned char sig[8] = {};
  ASSERT_EQ(std::fread(sig, 1, 8, f), 8u);
  std::fclose(f);
  EXPECT_EQ(sig[1], 'P');
  EXPECT_EQ(sig[2], 'N');
  EXPECT_EQ(sig[3], 'G');
  std::filesystem::remove(path);
  EXPECT_EQ(write_png("/nonexistent-dir/x.png", image).code(), ErrorCode::io);
}

}  // namespace
}  // namespace octolod::cli

namespace octolod::cli {
namespace {

TEST(LineChart, DrawsOnePanelPerSeriesWithTheLineInItsColour) {
  ChartSeries rising{"RESIDENT BYTES", {0, 1, 2, 3, 4}, 0x0000ff, 5};
  ChartSeries flat{"MISSES", {1, 1, 1}, 0x00ff00, -1};
  Image chart = draw_line_charts({rising, flat}, 200, 60);
  EXPECT_EQ(chart.width, 200);
  EXPECT_EQ(chart.height, 2 * (60 + 22 + 10) + 10);
  int blue = 0, green = 0;
  for (int y = 0; y < chart.height; ++y)
    for (int x = 0; x < chart.width; ++x) {
      blue += chart.get(x, y) == 0x0000ff;
      green += chart.get(x, y) == 0x00ff00;
    }
  EXPECT_GT(blue, 100);
  EXPECT_GT(green, 100);
}

TEST(LineChart, TextUsesTheFontAndSkipsUnknownCharacters) {
  Image image(40, 10, 0xffffff);
  draw_text(image, 0, 0, "1~", 0x000000);
  int ink = 0;
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 40; ++x) ink += image.get(x, y) == 0;
  EXPECT_EQ(ink, 10);  // the glyph '1' has 10 lit pixels; '~' draws nothing
}


// The error pictures' scale: hue 240 (1 - t) degrees, fully saturated, clamped outside [0, 1].
TEST(HeatScale, HueFallsLinearlyFromBlueToRed) {
  auto hue = [](glm::vec3 c) {
    const float hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
    float h = hi == c.r ? std::fmod((c.g - c.b) / (hi - lo), 6.0f) : hi == c.g ? (c.b - c.r) / (hi - lo) + 2.0f
                                                                              : (c.r - c.g) / (hi - lo) + 4.0f;
    h *= 60.0f;
    return h < 0 ? h + 360.0f : h;
  };
  for (int i = 0; i <= 20; ++i) {
    const float t = static_cast<float>(i) / 20.0f;
    const glm::vec3 c = heat_colour(t);
    EXPECT_NEAR(hue(c), 240.0f * (1.0f - t), 1e-3f) << t;
    EXPECT_EQ(std::max({c.r, c.g, c.b}), 1.0f) << t;
    EXPECT_EQ(std::min({c.r, c.g, c.b}), 0.0f) << t;
  }
  EXPECT_EQ(heat_colour(-1.0f), heat_colour(0.0f));
  EXPECT_EQ(heat_colour(7.0f), heat_colour(1.0f));
}

TEST(HeatScale, BarRunsBlueToRedWithItsEndsLabelledBelow) {
  Image image(200, 40, 0x000000);
  draw_heat_scale(image, 10, 4, 180, 10, "0", "1.5", 0xffffff);
  EXPECT_EQ(image.get(10, 8), 0x0000ffu);
  EXPECT_EQ(image.get(189, 8), 0xff0000u);
  EXPECT_EQ(image.get(9, 8), 0x000000u);  // nothing outside the bar
  auto text_pixels = [&](int x0, int x1) {
    int n = 0;
    for (int y = 14; y < 40; ++y)
      for (int x = x0; x < x1; ++x) n += image.get(x, y) == 0xffffffu;
    return n;
  };
  EXPECT_GT(text_pixels(10, 30), 0);    // "0" under the left end
  EXPECT_GT(text_pixels(150, 190), 0);  // "1.5" under the right end
  EXPECT_EQ(text_pixels(40, 140), 0);
}

}  // namespace
}  // namespace octolod::cli
