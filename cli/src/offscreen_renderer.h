// Renders node meshes into an Image with real OpenGL on Mesa's OSMesa (llvmpipe): works on
// CPU-only machines and in CI, no display needed. Shaded with a headlight; every mesh is tinted
// by its own colour so a picture shows which node LODs a cut is made of (or drawn in its vertex
// colours alone, as the error pictures are).
#pragma once

#include <glm/glm.hpp>

#include <span>

#include "image.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod::cli {

struct RenderItem {
  const NodeMesh* mesh = nullptr;  // positions in model units; must outlive the call
  glm::vec3 tint{1.0f};            // linear RGB 0..1, mixed with the surface colour
  float tint_share = 0.5f;         // of the tint in the mix: 0 draws the mesh's own colours
  // When set and the mesh has UVs: drawn with this image on its UVs (v up: v = 0 is the image's
  // bottom row), on a white surface instead of the vertex colours, still tinted by tint_share and
  // lit. Must outlive the call.
  const Image* texture = nullptr;
};

struct RenderView {
  glm::mat4 view{1.0f};        // model -> eye
  glm::mat4 projection{1.0f};  // eye -> clip (OpenGL conventions)
  int width = 1024;            // pixels
  int height = 768;
  std::uint32_t background = 0x20242c;  // 0xRRGGBB
  // Cull triangles wound clockwise on screen, as a game's renderer does: a triangle facing away
  // from its neighbours shows as a hole. Otherwise both sides are drawn and lit (two-sided
  // lighting), such a triangle as a dark patch.
  bool cull_back_faces = false;
};

// Returns io_error-class `unsupported` if no OpenGL context can be created.
Result<Image> render_offscreen(std::span<const RenderItem> items, const RenderView& view);

// A distinct tint per LOD level (0 = finest): green, yellow, orange, red, purple, blue, ...
glm::vec3 lod_tint(std::size_t level);

}  // namespace octolod::cli
