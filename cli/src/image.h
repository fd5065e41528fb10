// An 8-bit RGBA picture in memory and its PNG encoding (libpng): the output of `render` and of
// the `walk --plot` chart.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "octolod/formats/status.h"

namespace octolod::cli {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  // row-major, top row first, 4 bytes per pixel

  Image() = default;
  Image(int w, int h, std::uint32_t fill_rgb);
  void set(int x, int y, std::uint32_t rgb);  // ignores pixels outside the picture
  std::uint32_t get(int x, int y) const;      // 0xRRGGBB
};

// Writes atomically (temporary sibling + rename); io_error names the file.
Status write_png(const std::filesystem::path& path, const Image& image);

}  // namespace octolod::cli
