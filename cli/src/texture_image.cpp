#include "texture_image.h"

#include <png.h>
#include <turbojpeg.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "octolod/formats/gltf.h"

namespace octolod::cli {
namespace {

Status too_large(const std::filesystem::path& path, std::uint64_t width, std::uint64_t height) {
  return unsupported_error(path.string() + ": a " + std::to_string(width) + " x " + std::to_string(height) +
                           " texture, larger than " + std::to_string(kMaxTextureSide) + " on a side");
}

Result<Image> decode_png(const std::filesystem::path& path, const std::vector<std::byte>& bytes) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  const auto release = [](png_image* p) { png_image_free(p); };
  std::unique_ptr<png_image, decltype(release)> owner(&png, release);
  if (!png_image_begin_read_from_memory(&png, bytes.data(), bytes.size()))
    return bad_input_error(path.string() + ": not a readable PNG: " + png.message);
  if (png.width > kMaxTextureSide || png.height > kMaxTextureSide) return too_large(path, png.width, png.height);
  png.format = PNG_FORMAT_RGBA;
  Image image;
  image.width = static_cast<int>(png.width);
  image.height = static_cast<int>(png.height);
  image.rgba.resize(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, image.rgba.data(), 0, nullptr))
    return bad_input_error(path.string() + ": not a readable PNG: " + png.message);
  return image;
}

Result<Image> decode_jpeg(const std::filesystem::path& path, const std::vector<std::byte>& bytes) {
  const auto release = [](void* handle) { tjDestroy(handle); };
  std::unique_ptr<void, decltype(release)> handle(tjInitDecompress(), release);
  if (!handle) return unsupported_error(path.string() + ": cannot start the JPEG decoder");
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const auto size = static_cast<unsigned long>(bytes.size());
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  const auto refused = [&] {
    return bad_input_error(path.string() + ": not a readable JPEG: " + tjGetErrorStr2(handle.get()));
  };
  if (tjDecompressHeader3(handle.get(), data, size, &width, &height, &subsampling, &colorspace) != 0) return refused();
  if (width <= 0 || height <= 0 || width > kMaxTextureSide || height > kMaxTextureSide)
    return too_large(path, static_cast<std::uint64_t>(width), static_cast<std::uint64_t>(height));
  Image image;
  image.width = width;
  image.height = height;
  image.rgba.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
  if (tjDecompress2(handle.get(), data, size, image.rgba.data(), width, 0, height, TJPF_RGBA, 0) != 0 &&
      tjGetErrorCode(handle.get()) == TJERR_FATAL)
    return refused();
  return image;
}

}  // namespace

Result<Image> read_texture_image(const std::filesystem::path& path) {
  // the images glTF embeds are the ones render draws: read and told apart by the same code
  Result<GltfTexture> image = read_gltf_texture(path);
  if (!image.ok()) return image.status();
  return image->mime_type == "image/png" ? decode_png(path, image->bytes) : decode_jpeg(path, image->bytes);
}

}  // namespace octolod::cli
