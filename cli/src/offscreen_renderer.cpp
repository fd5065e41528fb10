// Offscreen OpenGL rendering through OSMesa with the compatibility profile's fixed-function
// pipeline: one light at the eye, per-vertex normals when the mesh has them, else flat normals.
//
// libOSMesa is opened with dlopen on the first render, not linked: it pulls in LLVM, whose
// relocations alone cost ~50 MiB of resident memory at program start — every `octolod` command
// (a bake under a 16 MiB budget, a reader refusing a bad PLY) would pay for it.
#include "offscreen_renderer.h"

#include <dlfcn.h>

#include <GL/osmesa.h>
#include <GL/gl.h>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

namespace octolod::cli {
namespace {

// The entry points render_offscreen uses, resolved from libOSMesa (which exports the GL 1.x
// functions too). The library stays loaded for the life of the process.
struct OsMesa {
  decltype(&::OSMesaCreateContextExt) CreateContextExt = nullptr;
  decltype(&::OSMesaMakeCurrent) MakeCurrent = nullptr;
  decltype(&::OSMesaDestroyContext) DestroyContext = nullptr;
  decltype(&::glViewport) Viewport = nullptr;
  decltype(&::glClearColor) ClearColor = nullptr;
  decltype(&::glClear) Clear = nullptr;
  decltype(&::glEnable) Enable = nullptr;
  decltype(&::glCullFace) CullFace = nullptr;
  decltype(&::glMatrixMode) MatrixMode = nullptr;
  decltype(&::glLoadMatrixf) LoadMatrixf = nullptr;
  decltype(&::glLoadIdentity) LoadIdentity = nullptr;
  decltype(&::glLightfv) Lightfv = nullptr;
  decltype(&::glLightModelfv) LightModelfv = nullptr;
  decltype(&::glLightModeli) LightModeli = nullptr;
  decltype(&::glColorMaterial) ColorMaterial = nullptr;
  decltype(&::glEnableClientState) EnableClientState = nullptr;
  decltype(&::glVertexPointer) VertexPointer = nullptr;
  decltype(&::glNormalPointer) NormalPointer = nullptr;
  decltype(&::glColorPointer) ColorPointer = nullptr;
  decltype(&::glDrawArrays) DrawArrays = nullptr;
  decltype(&::glFinish) Finish = nullptr;
  decltype(&::glDisable) Disable = nullptr;
  decltype(&::glDisableClientState) DisableClientState = nullptr;
  decltype(&::glGenTextures) GenTextures = nullptr;
  decltype(&::glBindTexture) BindTexture = nullptr;
  decltype(&::glTexParameteri) TexParameteri = nullptr;
  decltype(&::glTexImage2D) TexImage2D = nullptr;
  decltype(&::glTexEnvi) TexEnvi = nullptr;
  decltype(&::glTexCoordPointer) TexCoordPointer = nullptr;
  std::string error;  // non-empty when the library or a symbol is missing
};

template <typename Fn>
void resolve(void* library, const char* name, Fn& fn, std::string& error) {
  fn = reinterpret_cast<Fn>(dlsym(library, name));
  if (!fn && error.empty()) error = std::string("libOSMesa has no ") + name;
}

OsMesa load_osmesa() {
  OsMesa api;
  void* library = dlopen("libOSMesa.so.8", RTLD_NOW | RTLD_LOCAL);
  if (!library) library = dlopen("libOSMesa.so", RTLD_NOW | RTLD_LOCAL);
  if (!library) {
    api.error = std::string("cannot load libOSMesa (install libosmesa6): ") + dlerror();
    return api;
  }
  std::string& e = api.error;
  resolve(library, "OSMesaCreateContextExt", api.CreateContextExt, e);
  resolve(library, "OSMesaMakeCurrent", api.MakeCurrent, e);
  resolve(library, "OSMesaDestroyContext", api.DestroyContext, e);
  resolve(library, "glViewport", api.Viewport, e);
  resolve(library, "glClearColor", api.ClearColor, e);
  resolve(library, "glClear", api.Clear, e);
  resolve(library, "glEnable", api.Enable, e);
  resolve(library, "glCullFace", api.CullFace, e);
  resolve(library, "glMatrixMode", api.MatrixMode, e);
  resolve(library, "glLoadMatrixf", api.LoadMatrixf, e);
  resolve(library, "glLoadIdentity", api.LoadIdentity, e);
  resolve(library, "glLightfv", api.Lightfv, e);
  resolve(library, "glLightModelfv", api.LightModelfv, e);
  resolve(library, "glLightModeli", api.LightModeli, e);
  resolve(library, "glColorMaterial", api.ColorMaterial, e);
  resolve(library, "glEnableClientState", api.EnableClientState, e);
  resolve(library, "glVertexPointer", api.VertexPointer, e);
  resolve(library, "glNormalPointer", api.NormalPointer, e);
  resolve(library, "glColorPointer", api.ColorPointer, e);
  resolve(library, "glDrawArrays", api.DrawArrays, e);
  resolve(library, "glFinish", api.Finish, e);
  resolve(library, "glDisable", api.Disable, e);
  resolve(library, "glDisableClientState", api.DisableClientState, e);
  resolve(library, "glGenTextures", api.GenTextures, e);
  resolve(library, "glBindTexture", api.BindTexture, e);
  resolve(library, "glTexParameteri", api.TexParameteri, e);
  resolve(library, "glTexImage2D", api.TexImage2D, e);
  resolve(library, "glTexEnvi", api.TexEnvi, e);
  resolve(library, "glTexCoordPointer", api.TexCoordPointer, e);
  return api;
}

const OsMesa& osmesa() {
  static const OsMesa api = load_osmesa();
  return api;
}

// Expands an indexed NodeMesh into flat arrays of position, normal and colour (and with a texture
// UV) per corner, so meshes without normals still shade (face normals) and colours can be tinted
// per node.
struct DrawArrays {
  std::vector<float> positions, normals, colors, uvs;
};

DrawArrays expand(const NodeMesh& mesh, glm::vec3 tint, float tint_share, bool textured) {
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
      glm::vec3 base = textured           ? glm::vec3(1.0f)
                       : mesh.layout.color ? glm::make_vec3(v[k] + mesh.layout.color_offset())
                                           : glm::vec3(0.8f);
      if (textured) out.uvs.insert(out.uvs.end(), v[k] + mesh.layout.uv_offset(), v[k] + mesh.layout.uv_offset() + 2);
      glm::vec3 c = (1.0f - tint_share) * base + tint_share * tint;
      out.colors.insert(out.colors.end(), {c.x, c.y, c.z});
    }
  }
  return out;
}

// The textures of one render, each image uploaded once: its rows bottom first, since OpenGL's
// t = 0 is the first row it is given and a mesh's v = 0 is the image's bottom row. Modulated by the
// lit surface colour, repeating, mipmapped. The textures go with the context.
class TextureUploads {
 public:
  explicit TextureUploads(const OsMesa& gl) : gl_(gl) {}

  void bind(const Image& image) {
    auto [it, added] = names_.try_emplace(&image, 0u);
    if (added) {
      gl_.GenTextures(1, &it->second);
      gl_.BindTexture(GL_TEXTURE_2D, it->second);
      // mipmaps built by the GL (1.4's GENERATE_MIPMAP): a far view of a large texture does not alias
      gl_.TexParameteri(GL_TEXTURE_2D, GL_GENERATE_MIPMAP, GL_TRUE);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
      const std::size_t row = static_cast<std::size_t>(image.width) * 4;
      std::vector<std::uint8_t> bottom_first(image.rgba.size());
      for (int y = 0; y < image.height; ++y)
        std::copy_n(image.rgba.data() + static_cast<std::size_t>(image.height - 1 - y) * row, row,
                    bottom_first.data() + static_cast<std::size_t>(y) * row);
      gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                     bottom_first.data());
    }
    gl_.BindTexture(GL_TEXTURE_2D, it->second);
    gl_.TexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE);
    gl_.Enable(GL_TEXTURE_2D);
  }

 private:
  const OsMesa& gl_;
  std::map<const Image*, GLuint> names_;
};

}  // namespace

glm::vec3 lod_tint(std::size_t level) {
  static constexpr std::array<glm::vec3, 8> kTints{
      glm::vec3(0.20f, 0.80f, 0.30f), glm::vec3(0.95f, 0.85f, 0.20f), glm::vec3(1.00f, 0.55f, 0.15f),
      glm::vec3(0.90f, 0.20f, 0.20f), glm::vec3(0.65f, 0.30f, 0.85f), glm::vec3(0.25f, 0.45f, 0.95f),
      glm::vec3(0.20f, 0.80f, 0.85f), glm::vec3(0.90f, 0.40f, 0.70f)};
  return kTints[level % kTints.size()];
}

Result<Image> render_offscreen(std::span<const RenderItem> items, const RenderView& view) {
  const OsMesa& gl = osmesa();
  if (!gl.error.empty()) return unsupported_error("render: " + gl.error);
  auto destroy = [&gl](osmesa_context* c) { gl.DestroyContext(c); };
  std::unique_ptr<osmesa_context, decltype(destroy)> context(
      gl.CreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr), destroy);
  if (!context) return unsupported_error("render: cannot create an OSMesa OpenGL context");
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(view.width) *
                                   static_cast<std::size_t>(view.height) * 4);
  if (!gl.MakeCurrent(context.get(), pixels.data(), GL_UNSIGNED_BYTE, view.width, view.height))
    return unsupported_error("render: cannot make the OSMesa context current");

  auto channel = [](std::uint32_t rgb, int shift) {
    return static_cast<float>((rgb >> shift) & 0xFFu) / 255.0f;
  };
  gl.Viewport(0, 0, view.width, view.height);
  gl.ClearColor(channel(view.background, 16), channel(view.background, 8), channel(view.background, 0), 1);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_DEPTH_TEST);
  if (view.cull_back_faces) {
    gl.CullFace(GL_BACK);
    gl.Enable(GL_CULL_FACE);
  }
  gl.MatrixMode(GL_PROJECTION);
  gl.LoadMatrixf(glm::value_ptr(view.projection));
  gl.MatrixMode(GL_MODELVIEW);
  gl.LoadIdentity();
  // Headlight: set while the modelview is identity, so it stays at the eye.
  const float light_dir[4] = {0.3f, 0.5f, 1.0f, 0.0f};
  const float ambient[4] = {0.25f, 0.25f, 0.25f, 1.0f};
  gl.Lightfv(GL_LIGHT0, GL_POSITION, light_dir);
  gl.LightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  gl.LightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  gl.Enable(GL_LIGHTING);
  gl.Enable(GL_LIGHT0);
  gl.Enable(GL_NORMALIZE);
  gl.Enable(GL_COLOR_MATERIAL);
  gl.ColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  gl.LoadMatrixf(glm::value_ptr(view.view));
  gl.EnableClientState(GL_VERTEX_ARRAY);
  gl.EnableClientState(GL_NORMAL_ARRAY);
  gl.EnableClientState(GL_COLOR_ARRAY);
  TextureUploads textures(gl);
  for (const RenderItem& item : items) {
    const bool textured = item.texture != nullptr && item.mesh->layout.uv;
    DrawArrays arrays = expand(*item.mesh, item.tint, item.tint_share, textured);
    gl.VertexPointer(3, GL_FLOAT, 0, arrays.positions.data());
    gl.NormalPointer(GL_FLOAT, 0, arrays.normals.data());
    gl.ColorPointer(3, GL_FLOAT, 0, arrays.colors.data());
    if (textured) {
      textures.bind(*item.texture);
      gl.EnableClientState(GL_TEXTURE_COORD_ARRAY);
      gl.TexCoordPointer(2, GL_FLOAT, 0, arrays.uvs.data());
    }
    gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(arrays.positions.size() / 3));
    if (textured) {
      gl.DisableClientState(GL_TEXTURE_COORD_ARRAY);
      gl.Disable(GL_TEXTURE_2D);
    }
  }
  gl.Finish();

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
