#include "image.h"

#include <png.h>

#include <cstdio>

#include "atomic_file.h"

namespace octolod::cli {

Image::Image(int w, int h, std::uint32_t fill_rgb)
    : width(w), height(h), rgba(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4) {
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) set(x, y, fill_rgb);
}

void Image::set(int x, int y, std::uint32_t rgb) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  std::uint8_t* p = &rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                           static_cast<std::size_t>(x)) * 4];
  p[0] = static_cast<std::uint8_t>(rgb >> 16);
  p[1] = static_cast<std::uint8_t>(rgb >> 8);
  p[2] = static_cast<std::uint8_t>(rgb);
  p[3] = 255;
}

std::uint32_t Image::get(int x, int y) const {
  const std::uint8_t* p = &rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                                 static_cast<std::size_t>(x)) * 4];
  return (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2];
}

namespace {

// libpng's default handlers print their own line ("libpng error: Write Error") before ours,
// which names the file and errno's reason (write_file_atomically): these only jump back.
[[noreturn]] void jump_on_png_error(png_structp png, png_const_charp) { png_longjmp(png, 1); }
void ignore_png_warning(png_structp, png_const_charp) {}

// libpng reports failures by longjmp: keep the setjmp frame free of objects with destructors and
// of locals modified after setjmp.
bool encode_png(std::FILE* file, const Image& image) {
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, jump_on_png_error, ignore_png_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, image.rgba.data() +
                           static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) * 4);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

Status write_png(const std::filesystem::path& path, const Image& image) {
  return write_file_atomically(path, "the PNG", [&](std::FILE* file) { return encode_png(file, image); });
}

}  // namespace octolod::cli
