// Stacked line charts rendered into an Image (one panel per series, shared x axis = frame):
// the picture `walk --plot` writes. Text uses a built-in 5x7 pixel font (upper case, digits).
#pragma once

#include <string>
#include <vector>

#include "image.h"

namespace octolod::cli {

struct ChartSeries {
  std::string title;           // drawn above the panel, with the series' maximum
  std::vector<double> values;  // one per frame
  std::uint32_t color = 0x3070e0;
  double reference = -1;       // drawn as a dashed horizontal line when >= 0 (e.g. a budget)
};

Image draw_line_charts(const std::vector<ChartSeries>& series, int width, int panel_height);

// Draws `text` with its top-left corner at (x, y), `scale` pixels per font pixel.
void draw_text(Image& image, int x, int y, const std::string& text, std::uint32_t rgb, int scale = 1);

}  // namespace octolod::cli
