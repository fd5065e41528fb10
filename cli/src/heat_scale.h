// The colour scale of error pictures (`octolod compare --pictures`): a distance mapped to a hue
// from blue (none) through cyan, green and yellow to red (the top of the scale), and the scale
// drawn as a labelled bar, so that a picture reads without its caption.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <string>

#include "image.h"

namespace octolod::cli {

// Linear RGB 0..1 of `t` clamped to [0, 1]: fully saturated and bright, hue 240 (1 - t)
// degrees (0 blue, 0.25 cyan, 0.5 green, 0.75 yellow, 1 red). Shading scales the channels
// alike, so a lit pixel keeps the hue of its distance.
glm::vec3 heat_colour(float t);

// A bar `width` x `height` pixels with its top-left corner at (x, y), heat_colour(0) at its left
// end to heat_colour(1) at its right, with `low` under the left end and `high` under the right
// end (draw_text's 5x7 font at scale 2: upper case, digits and . - : / ( ) % =).
void draw_heat_scale(Image& image, int x, int y, int width, int height, const std::string& low,
                     const std::string& high, std::uint32_t text_rgb);

}  // namespace octolod::cli
