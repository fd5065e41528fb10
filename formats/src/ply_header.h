// PLY syntax (the half of Draco's ply_reader/ply_decoder split that knows nothing about meshes):
// scalar types, the element/property model of a header, parsing it from a file and writing it.
// What the properties mean (positions, colours, faces) is decided in ply_reader.cpp.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "octolod/formats/ply.h"
#include "octolod/formats/status.h"
#include "ply_file_buffer.h"

namespace octolod::ply {

enum class ScalarType : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

// "char".."double" and "int8".."float64"; nullopt for anything else.
std::optional<ScalarType> parse_scalar_type(std::string_view name);
// The classic name ("uchar", "float", ...), as PlyWriter writes it.
std::string_view to_string(ScalarType type);

constexpr std::size_t size_of(ScalarType type) {
  switch (type) {
    case ScalarType::int8:
    case ScalarType::uint8: return 1;
    case ScalarType::int16:
    case ScalarType::uint16: return 2;
    case ScalarType::int32:
    case ScalarType::uint32:
    case ScalarType::float32: return 4;
    case ScalarType::float64: return 8;
  }
  return 0;
}
constexpr bool is_integer(ScalarType type) {
  return type != ScalarType::float32 && type != ScalarType::float64;
}
// Largest value of an integer type (the divisor that maps integer colours to 0..1).
constexpr double max_value(ScalarType type) {
  switch (type) {
    case ScalarType::int8: return 127.0;
    case ScalarType::uint8: return 255.0;
    case ScalarType::int16: return 32767.0;
    case ScalarType::uint16: return 65535.0;
    case ScalarType::int32: return 2147483647.0;
    case ScalarType::uint32: return 4294967295.0;
    case ScalarType::float32:
    case ScalarType::float64: return 1.0;
  }
  return 1.0;
}

struct Property {
  std::string name;
  ScalarType type = ScalarType::float32;  // the value type; the item type of a list
  bool is_list = false;
  ScalarType count_type = ScalarType::uint8;  // lists only; always an integer type
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  std::uint64_t line = 0;  // header line of the "element" keyword, for messages

  // Index of the property called `name`, or -1.
  int find(std::string_view property_name) const;
};

struct Header {
  PlyFormat format = PlyFormat::ascii;
  std::vector<std::string> comments;  // "comment" lines, without the keyword
  std::vector<Element> elements;      // in file order
  std::uint64_t bytes = 0;  // up to and including the end_header line: where the body starts
  std::uint64_t lines = 0;  // lines in the header, so the ascii body starts at line lines + 1
};

// Headers larger than this are rejected: a real header is a few hundred bytes, and the limit
// keeps a garbage file from making us buffer it.
inline constexpr std::size_t kMaxHeaderBytes = std::size_t{1} << 20;

// Parses the header at the start of `in` and consumes it. Errors are bad_input ("<path>: line N:
// <problem>"), or unsupported for a format version other than 1.0; io errors pass through.
Result<Header> parse_header(FileBuffer& in);

// The header text for `header` (elements, comments, format), ending with "end_header\n".
std::string format_header(const Header& header);

// "<path>: line N: <what>" and "<path>: byte offset N: <what>", the shapes of every reader error.
std::string message_at_line(const std::string& path, std::uint64_t line, std::string_view what);
std::string message_at_offset(const std::string& path, std::uint64_t offset, std::string_view what);

// Byte order of binary PLY bodies.
template <class T>
inline T byte_swap(T value) {
  static_assert(std::is_integral_v<T>);
  if constexpr (sizeof(T) == 1) {
    return value;
  } else if constexpr (sizeof(T) == 2) {
    return static_cast<T>(__builtin_bswap16(static_cast<std::uint16_t>(value)));
  } else if constexpr (sizeof(T) == 4) {
    return static_cast<T>(__builtin_bswap32(static_cast<std::uint32_t>(value)));
  } else {
    return static_cast<T>(__builtin_bswap64(static_cast<std::uint64_t>(value)));
  }
}
constexpr bool native_format_is(PlyFormat format) {
  return (format == PlyFormat::binary_little_endian) == (std::endian::native == std::endian::little);
}

// Loads the unsigned integer of sizeof(T) bytes at `p`, swapping when kSwap.
template <class T, bool kSwap>
inline T load(const char* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  if constexpr (kSwap) value = byte_swap(value);
  return value;
}

// The binary scalar at `p` as a double (exact for every PLY type).
template <bool kSwap>
inline double load_as_double(const char* p, ScalarType type) {
  switch (type) {
    case ScalarType::int8: return static_cast<std::int8_t>(p[0]);
    case ScalarType::uint8: return static_cast<std::uint8_t>(p[0]);
    case ScalarType::int16: return static_cast<std::int16_t>(load<std::uint16_t, kSwap>(p));
    case ScalarType::uint16: return load<std::uint16_t, kSwap>(p);
    case ScalarType::int32: return static_cast<std::int32_t>(load<std::uint32_t, kSwap>(p));
    case ScalarType::uint32: return load<std::uint32_t, kSwap>(p);
    case ScalarType::float32: return std::bit_cast<float>(load<std::uint32_t, kSwap>(p));
    case ScalarType::float64: return std::bit_cast<double>(load<std::uint64_t, kSwap>(p));
  }
  return 0.0;
}

// The binary integer at `p` (an integer type) as int64.
template <bool kSwap>
inline std::int64_t load_as_int(const char* p, ScalarType type) {
  switch (type) {
    case ScalarType::int8: return static_cast<std::int8_t>(p[0]);
    case ScalarType::uint8: return static_cast<std::uint8_t>(p[0]);
    case ScalarType::int16: return static_cast<std::int16_t>(load<std::uint16_t, kSwap>(p));
    case ScalarType::uint16: return load<std::uint16_t, kSwap>(p);
    case ScalarType::int32: return static_cast<std::int32_t>(load<std::uint32_t, kSwap>(p));
    case ScalarType::uint32: return load<std::uint32_t, kSwap>(p);
    case ScalarType::float32:
    case ScalarType::float64: break;
  }
  return 0;
}

}  // namespace octolod::ply
