// Error pictures of meshes against a surface, see error_picture.h.
#include "error_picture.h"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "heat_scale.h"
#include "line_chart.h"
#include "offscreen_renderer.h"
#include "view_camera.h"

namespace octolod::cli {
namespace {

constexpr std::uint32_t kText = 0xe0e0e0;
constexpr int kScaleStrip = 48;  // pixels under the panels: the bar and its labels
// Distances are sampled at most this fraction of the frame's diagonal apart (the framing camera
// shows the diagonal across about 500 pixels: a sample every 2-3 pixels at most).
constexpr double kSampleSpacing = 1.0 / 200.0;

// `mesh` (positions and normals, when it has them) with each triangle cut into n x n triangles
// of a grid of its barycentric coordinates, n the smallest that makes their edges at most
// `edge` (at most kMaxSplit): the points its distances are sampled at. A triangle's error lies
// between its corners (an edge collapse keeps its vertices on the input), so corners alone
// would miss it. The mesh's own vertices come first, shared by the triangles that need no cut.
NodeMesh sampled_surface(const NodeMesh& mesh, double edge) {
  constexpr int kMaxSplit = 32;
  const std::size_t stride = mesh.layout.floats();
  const std::size_t kept = mesh.layout.normal ? 6 : 3;  // position, normal
  NodeMesh out;
  out.layout = VertexLayout{mesh.layout.normal, false, false};
  out.vertices.reserve(mesh.vertex_count() * kept);
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    out.vertices.insert(out.vertices.end(), &mesh.vertices[v * stride], &mesh.vertices[v * stride] + kept);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint32_t* index = &mesh.indices[3 * t];
    const float* corner[3];
    for (std::size_t k = 0; k < 3; ++k) corner[k] = &mesh.vertices[index[k] * stride];
    double longest = 0;
    for (std::size_t k = 0; k < 3; ++k)
      longest = std::max(longest, static_cast<double>(glm::distance(glm::make_vec3(corner[k]),
                                                                     glm::make_vec3(corner[(k + 1) % 3]))));
    const int n = std::clamp(static_cast<int>(std::ceil(longest / edge)), 1, kMaxSplit);
    if (n == 1) {
      out.indices.insert(out.indices.end(), index, index + 3);
      continue;
    }
    const auto first = static_cast<std::uint32_t>(out.vertex_count());
    // grid point (i, j), i + j <= n: corner 0 + i/n (corner 1 - corner 0) + j/n (corner 2 - corner 0)
    auto id = [&](int i, int j) { return first + static_cast<std::uint32_t>(i * (2 * n + 3 - i) / 2 + j); };
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const float b1 = static_cast<float>(i) / static_cast<float>(n), b2 = static_cast<float>(j) / static_cast<float>(n);
        for (std::size_t f = 0; f < kept; ++f)
          out.vertices.push_back((1.0f - b1 - b2) * corner[0][f] + b1 * corner[1][f] + b2 * corner[2][f]);
      }
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        out.indices.insert(out.indices.end(), {id(i, j), id(i + 1, j), id(i, j + 1)});
        if (i + j + 1 < n) out.indices.insert(out.indices.end(), {id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
  }
  return out;
}

// Per vertex of `mesh`: the distance of its position to the nearest point of `surface`.
std::vector<float> vertex_distances(const NodeMesh& mesh, const measure::TriangleBvh& surface) {
  const std::size_t stride = mesh.layout.floats();
  std::vector<float> distance(mesh.vertex_count(), 0.0f);
  for (std::size_t v = 0; v < distance.size(); ++v) {
    const measure::TriangleBvh::Hit hit = surface.closest(glm::make_vec3(&mesh.vertices[v * stride]));
    if (hit.found()) distance[v] = hit.distance;
  }
  return distance;
}

// `mesh` (positions and normals only) with every vertex's colour heat_colour(distance / scale);
// its indices are taken over, not copied.
NodeMesh coloured_by_distance(NodeMesh&& mesh, const std::vector<float>& distance, double scale) {
  NodeMesh out;
  out.layout = VertexLayout{mesh.layout.normal, true, false};
  out.indices = std::move(mesh.indices);
  const std::size_t stride = mesh.layout.floats();
  out.vertices.reserve(distance.size() * out.layout.floats());
  for (std::size_t v = 0; v < distance.size(); ++v) {
    const float* in = &mesh.vertices[v * stride];
    out.vertices.insert(out.vertices.end(), in, in + stride);
    const glm::vec3 c = heat_colour(static_cast<float>(distance[v] / scale));
    out.vertices.insert(out.vertices.end(), {c.r, c.g, c.b});
  }
  return out;
}

std::string distance_text(double d) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", d);
  std::string s = text;
  if (const std::size_t plus = s.find("e+"); plus != std::string::npos) s.erase(plus + 1, 1);  // the font has no '+'
  return s;
}

}  // namespace

Result<ErrorPicture> render_error_picture(std::span<const ErrorPanel> panels, int columns, const Bounds& frame,
                                          double scale) {
  constexpr int panel_width = kErrorPanelWidth, panel_height = kErrorPanelHeight;
  // the scale needs every panel's distances before the first is coloured; the samples are
  // made again for the colouring, one panel at a time
  const double spacing = kSampleSpacing * frame.diagonal();
  std::vector<std::vector<float>> distances;
  const bool given = scale > 0.0;
  if (!given) scale = 1e-6 * frame.diagonal();
  for (const ErrorPanel& panel : panels) {
    distances.push_back(vertex_distances(sampled_surface(*panel.mesh, spacing), *panel.surface));
    if (!given)
      for (float d : distances.back()) scale = std::max(scale, static_cast<double>(d));
  }
  if (!(scale > 0.0)) scale = 1.0;  // every panel a point at no distance: all blue
  Lens lens;
  lens.width = panel_width;
  lens.height = panel_height;
  const runtime::Camera camera = framing_camera(frame, lens);
  RenderView view;
  view.view = camera.view;
  view.projection = camera.projection;
  view.width = panel_width;
  view.height = panel_height;

  ErrorPicture picture;
  picture.scale = scale;
  const int rows = (static_cast<int>(panels.size()) + columns - 1) / columns;
  const int width = panel_width * columns, panels_height = panel_height * rows;
  picture.image = Image(width, panels_height + kScaleStrip, view.background);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const NodeMesh coloured = coloured_by_distance(sampled_surface(*panels[i].mesh, spacing), distances[i], scale);
    distances[i] = {};
    const RenderItem item{&coloured, glm::vec3(0.0f), 0.0f};
    Result<Image> rendered = render_offscreen({&item, 1}, view);
    if (!rendered.ok()) return rendered.status();
    const int left = panel_width * (static_cast<int>(i) % columns), top = panel_height * (static_cast<int>(i) / columns);
    for (int y = 0; y < panel_height; ++y)
      for (int x = 0; x < panel_width; ++x) picture.image.set(left + x, top + y, rendered->get(x, y));
    draw_text(picture.image, left + 12, top + 12, panels[i].caption, kText, 2);
  }
  constexpr int kMargin = 16;
  draw_heat_scale(picture.image, kMargin, panels_height + 8, width - 2 * kMargin, 12, "0",
                  distance_text(scale) + " MODEL UNITS", kText);
  return picture;
}

}  // namespace octolod::cli
