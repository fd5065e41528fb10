// Frustum planes from a view-projection matrix (Gribb & Hartmann 2001, "Fast extraction of
// viewing frustum planes from the world-view-projection matrix") and the p-vertex / n-vertex box
// test that replaces the seed's "a corner is inside" test (docs/design.md "The runtime").
#include "octolod/runtime/camera.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace octolod::runtime {

Camera make_perspective_camera(glm::vec3 eye, glm::vec3 target, glm::vec3 up, float fovy_radians,
                               float aspect, float near_distance, float far_distance,
                               float viewport_height_px) {
  Camera camera;
  camera.view = glm::lookAt(eye, target, up);
  camera.projection = glm::perspective(fovy_radians, aspect, near_distance, far_distance);
  camera.position = eye;
  camera.viewport_height_px = viewport_height_px;
  return camera;
}

Camera make_orthographic_camera(glm::vec3 eye, glm::vec3 target, glm::vec3 up, float view_height,
                                float aspect, float near_distance, float far_distance,
                                float viewport_height_px) {
  Camera camera;
  camera.view = glm::lookAt(eye, target, up);
  const float half_height = 0.5f * view_height, half_width = half_height * aspect;
  camera.projection = glm::ortho(-half_width, half_width, -half_height, half_height, near_distance, far_distance);
  camera.position = eye;
  camera.viewport_height_px = viewport_height_px;
  return camera;
}

bool is_usable(const Camera& camera) {
  const auto finite = [](const auto& v) { return !glm::any(glm::isnan(v)) && !glm::any(glm::isinf(v)); };
  for (int i = 0; i < 4; ++i)
    if (!finite(camera.view[i]) || !finite(camera.projection[i])) return false;
  return finite(camera.position) && camera.projection[1][1] != 0.0f && camera.viewport_height_px > 0.0f &&
         std::isfinite(camera.viewport_height_px);
}

bool is_orthographic(const glm::mat4& projection) { return projection[2][3] == 0.0f; }

Frustum extract_frustum(const glm::mat4& m) {
  // GLM is column-major: row i of the matrix is (m[0][i], m[1][i], m[2][i], m[3][i]).
  auto row = [&](int i) { return glm::vec4(m[0][i], m[1][i], m[2][i], m[3][i]); };
  const glm::vec4 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  // Near is w + z >= 0 (OpenGL clip depth); for a [0,1] depth projection it keeps a superset.
  const glm::vec4 raw[6] = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2, r3 - r2};
  Frustum f;
  for (int i = 0; i < 6; ++i) {
    const glm::vec3 n(raw[i]);
    const float length = glm::length(n);
    if (!(length > 1e-12f) || !std::isfinite(length)) {
      f.planes[static_cast<std::size_t>(i)] = Plane{glm::vec3(0.0f), 1.0f};
      continue;
    }
    f.planes[static_cast<std::size_t>(i)] = Plane{n / length, raw[i].w / length};
  }
  return f;
}

Containment classify_box(const Frustum& frustum, glm::vec3 center, glm::vec3 half_extent) {
  Containment result = Containment::inside;
  for (const Plane& p : frustum.planes) {
    const float c = p.distance(center);
    const float r = glm::dot(glm::abs(p.normal), half_extent);
    if (c + r < 0.0f) return Containment::outside;  // even the p-vertex is behind the plane
    if (c - r < 0.0f) result = Containment::intersects;  // the n-vertex is behind it
  }
  return result;
}

}  // namespace octolod::runtime
