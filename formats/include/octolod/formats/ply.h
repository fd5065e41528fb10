// Shared PLY vocabulary for ply_reader.h and ply_writer.h.
#pragma once

#include <cstdint>
#include <string_view>

namespace octolod {

enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };

// How a PLY file stores colours. Readers normalize to 0..1 floats either way; writers use this
// to choose the on-disk type (uchar: round(c*255) after clamping to 0..1).
enum class PlyColorType { uchar, float32 };

std::string_view to_string(PlyFormat format);

}  // namespace octolod
