// The heat colour scale of error pictures, see heat_scale.h.
#include "heat_scale.h"

#include <algorithm>
#include <cmath>

#include "line_chart.h"

namespace octolod::cli {

glm::vec3 heat_colour(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  // four legs between the five stops, one channel moving linearly on each: the hue moves by 60
  // degrees per leg, linearly in t
  if (t < 0.25f) return {0.0f, 4.0f * t, 1.0f};
  if (t < 0.5f) return {0.0f, 1.0f, 1.0f - 4.0f * (t - 0.25f)};
  if (t < 0.75f) return {4.0f * (t - 0.5f), 1.0f, 0.0f};
  return {1.0f, 1.0f - 4.0f * (t - 0.75f), 0.0f};
}

void draw_heat_scale(Image& image, int x, int y, int width, int height, const std::string& low,
                     const std::string& high, std::uint32_t text_rgb) {
  for (int i = 0; i < width; ++i) {
    const glm::vec3 c = heat_colour(width > 1 ? static_cast<float>(i) / static_cast<float>(width - 1) : 0.0f);
    const auto channel = [](float v) { return static_cast<std::uint32_t>(std::lround(v * 255.0f)); };
    const std::uint32_t rgb = channel(c.r) << 16 | channel(c.g) << 8 | channel(c.b);
    for (int j = 0; j < height; ++j) image.set(x + i, y + j, rgb);
  }
  constexpr int kScale = 2, kGlyphWidth = 6 * kScale;  // 5 pixels and a gap per character
  const int text_y = y + height + 4;
  draw_text(image, x, text_y, low, text_rgb, kScale);
  draw_text(image, x + width - kGlyphWidth * static_cast<int>(high.size()), text_y, high, text_rgb, kScale);
}

}  // namespace octolod::cli
