// Offscreen OpenGL rendering through OSMesa with the compatibility profile's fixed-function
// pipeline: one light at the eye, per-vertex normals when the mesh has them, else flat normals.
#include "offscreen_renderer.h"

#include <GL/osmesa.h>
#include <GL/gl.h>

#include <array>
#include <memory>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

namespace octolod::cli {
namespace {

struct ContextDeleter {
  void operator()(osmesa_context* context) const { OSMesaDestroyContext(context); }
};

// Expands an indexed NodeMesh into flat arrays of position, normal and colour per corner, so
// meshes without normals still shade (face normals) and colours can be tinted per node.
struct DrawArrays {
  std::vector<float> positions, normals, colors;
};

DrawArrays expand(const NodeMesh& mesh, glm::vec3 tint) {
  DrawArrays out;
  const std::size_t stride = mesh.layout.floats();
  const std::size_t corners = mesh.indices.size();
  out.positions.reserve(corners * 3);
  out.normals.reserve(corners * 3);
  out.colors.reserve(corners * 3);
  for (std::size_t t = 0; t + 2 < corners; t += 3) {
    const float* v[3];
    for (std::size_t k = 0; k < 3; ++k) v[k] = &mesh.vertices[mesh.indices[t + k] * stride];
    glm::vec3 p0 = glm::make_vec3(v[0]), p1 = glm::make_vec3(v[1]), p2 = glm::make_vec3(v[2]);
    glm::vec3 face = glm::cross(p1 - p0, p2 - p0);
    float len = glm::length(face);
    face = len > 0 ? face / len : glm::vec3(0, 0, 1);
    for (std::size_t k = 0; k < 3; ++k) {
      out.positions.insert(out.positions.end(), v[k], v[k] + 3);
      glm::vec3 n = mesh.layout.normal ? glm::make_vec3(v[k] + VertexLayout::normal_offset()) : face;
      out.normals.insert(out.normals.end(), {n.x, n.y, n.z});
      glm::vec3 base = mesh.layout.color ? glm::make_vec3(v[k] + mesh.layout.color_offset())
                                         : glm::vec3(0.8f);
      glm::vec3 c = 0.5f * base + 0.5f * tint;
      out.colors.insert(out.colors.end(), {c.x, c.y, c.z});
    }
  }
  return out;
}

}  // namespace

glm::vec3 lod_tint(std::size_t level) {
  static constexpr std::array<glm::vec3, 8> kTints{
      glm::vec3(0.20f, 0.80f, 0.30f), glm::vec3(0.95f, 0.85f, 0.20f), glm::vec3(1.00f, 0.55f, 0.15f),
      glm::vec3(0.90f, 0.20f, 0.20f), glm::vec3(0.65f, 0.30f, 0.85f), glm::vec3(0.25f, 0.45f, 0.95f),
      glm::vec3(0.20f, 0.80f, 0.85f), glm::vec3(0.90f, 0.40f, 0.70f)};
  return kTints[level % kTints.size()];
}

Result<Image> render_offscreen(std::span<const RenderItem> items, const RenderView& view) {
  std::unique_ptr<osmesa_context, ContextDeleter> context(
      OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr));
  if (!context) return unsupported_error("render: cannot create an OSMesa OpenGL context");
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(view.width) *
                                   static_cast<std::size_t>(view.height) * 4);
  if (!OSMesaMakeCurrent(context.get(), pixels.data(), GL_UNSIGNED_BYTE, view.width, view.height))
    return unsupported_error("render: cannot make the OSMesa context current");

  auto channel = [](std::uint32_t rgb, int shift) {
    return static_cast<float>((rgb >> shift) & 0xFFu) / 255.0f;
  };
  glViewport(0, 0, view.width, view.height);
  glClearColor(channel(view.background, 16), channel(view.background, 8), channel(view.background, 0), 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixf(glm::value_ptr(view.projection));
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  // Headlight: set while the modelview is identity, so it stays at the eye.
  const float light_dir[4] = {0.3f, 0.5f, 1.0f, 0.0f};
  const float ambient[4] = {0.25f, 0.25f, 0.25f, 1.0f};
  glLightfv(GL_LIGHT0, GL_POSITION, light_dir);
  glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT0);
  glEnable(GL_NORMALIZE);
  glEnable(GL_COLOR_MATERIAL);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glLoadMatrixf(glm::value_ptr(view.view));
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glEnableClientState(GL_COLOR_ARRAY);
  for (const RenderItem& item : items) {
    DrawArrays arrays = expand(*item.mesh, item.tint);
    glVertexPointer(3, GL_FLOAT, 0, arrays.positions.data());
    glNormalPointer(GL_FLOAT, 0, arrays.normals.data());
    glColorPointer(3, GL_FLOAT, 0, arrays.colors.data());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(arrays.positions.size() / 3));
  }
  glFinish();

  // OpenGL's first row is the bottom one; Image's is the top one.
  Image image;
  image.width = view.width;
  image.height = view.height;
  image.rgba.resize(pixels.size());
  const std::size_t row = static_cast<std::size_t>(view.width) * 4;
  for (int y = 0; y < view.height; ++y)
    std::copy_n(pixels.data() + static_cast<std::size_t>(view.height - 1 - y) * row, row,
                image.rgba.data() + static_cast<std::size_t>(y) * row);
  return image;
}

}  // namespace octolod::cli
