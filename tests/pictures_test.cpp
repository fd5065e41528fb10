#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "heat_scale.h"
#include "image.h"
#include "line_chart.h"
#include "offscreen_renderer.h"

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
