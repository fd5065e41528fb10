// The vertex attribute layout shared by every stage: PLY reading, the triangle soup, node files,
// the runtime's GPU buffers. A vertex is a run of 32-bit floats, always in this order:
//   position x,y,z (model units)
//   [normal nx,ny,nz]   unit length when valid
//   [color  r,g,b]      linear 0..1 (PLY uchar colours are divided by 255)
//   [uv     u,v]        texture coordinates, unbounded
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace octolod {

// The largest magnitude of a vertex float that octolod reads (PLY) or measures; for positions,
// model units after the PLY reader's origin is subtracted. Differences of two such values
// squared stay finite in float (4e36 < 3.4e38), which the simplifier's and the measures' float
// distances rely on: a vertex at 3e38 made both produce points far outside the model.
inline constexpr float kMaxVertexValue = 1e18f;
// "-2e+19, beyond ±1e18 (squared distances that far out overflow float)": a value past
// kMaxVertexValue as the errors that refuse it name it.
inline std::string beyond_max_vertex_value(float value) {
  static_assert(kMaxVertexValue == 1e18f, "the message names the limit");
  char text[96];
  std::snprintf(text, sizeof(text), "%g, beyond ±1e18 (squared distances that far out overflow float)",
                static_cast<double>(value));
  return text;
}

struct VertexLayout {
  bool normal = false;
  bool color = false;
  bool uv = false;

  // Floats per vertex.
  constexpr std::uint32_t floats() const {
    return 3u + (normal ? 3u : 0u) + (color ? 3u : 0u) + (uv ? 2u : 0u);
  }
  constexpr std::uint32_t bytes() const { return floats() * 4u; }
  // Offsets in floats from the start of a vertex; only meaningful when the attribute is present.
  static constexpr std::uint32_t position_offset() { return 0; }
  static constexpr std::uint32_t normal_offset() { return 3; }
  constexpr std::uint32_t color_offset() const { return 3u + (normal ? 3u : 0u); }
  constexpr std::uint32_t uv_offset() const { return color_offset() + (color ? 3u : 0u); }

  // Bit 0 normal, bit 1 color, bit 2 uv: the encoding used by node files and the manifest.
  constexpr std::uint32_t mask() const {
    return (normal ? 1u : 0u) | (color ? 2u : 0u) | (uv ? 4u : 0u);
  }
  static constexpr VertexLayout from_mask(std::uint32_t m) {
    return VertexLayout{(m & 1u) != 0, (m & 2u) != 0, (m & 4u) != 0};
  }
  static constexpr std::uint32_t kValidMask = 7u;

  // "position", "position,normal,color,uv", ...
  std::string describe() const {
    std::string s = "position";
    if (normal) s += ",normal";
    if (color) s += ",color";
    if (uv) s += ",uv";
    return s;
  }

  friend constexpr bool operator==(const VertexLayout&, const VertexLayout&) = default;
};

}  // namespace octolod
