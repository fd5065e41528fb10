// A tree's texture decoded for `render --texture`: the PNG (libpng) or JPEG (libjpeg-turbo) the
// manifest names, as an Image.
#pragma once

#include <filesystem>

#include "image.h"
#include "octolod/formats/status.h"

namespace octolod::cli {

// Wider or taller images are not decoded: 8192 x 8192 RGBA is 256 MiB, and the software renderer
// samples no larger texture.
inline constexpr int kMaxTextureSide = 8192;

// Decodes the PNG or JPEG at `path` (read and told apart by read_gltf_texture: the images an
// export embeds) into RGBA, the image's top row first. Errors name the file: io when it cannot be
// read, unsupported for another image type or one over kMaxTextureSide on a side (known from its
// header, before the pixels are allocated), bad_input for an image the decoder refuses.
Result<Image> read_texture_image(const std::filesystem::path& path);

}  // namespace octolod::cli
