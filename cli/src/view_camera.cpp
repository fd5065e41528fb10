#include "view_camera.h"

#include <algorithm>
#include <cmath>

namespace octolod::cli {

ModelSphere model_sphere(const Bounds& bounds) {
  const glm::vec3 lo(bounds.min[0], bounds.min[1], bounds.min[2]);
  const glm::vec3 hi(bounds.max[0], bounds.max[1], bounds.max[2]);
  return {0.5f * (lo + hi), std::max(0.5f * glm::length(hi - lo), 1e-6f)};
}

runtime::Camera look_at_camera(glm::vec3 eye, glm::vec3 target, const Lens& lens, float near_distance,
                               float far_distance) {
  const glm::vec3 forward = glm::normalize(target - eye);
  const glm::vec3 up = std::abs(forward.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
  if (lens.ortho_height > 0.0f)
    return runtime::make_orthographic_camera(eye, target, up, lens.ortho_height, lens.aspect(), near_distance,
                                             far_distance, static_cast<float>(lens.height));
  return runtime::make_perspective_camera(eye, target, up, lens.fovy_radians, lens.aspect(), near_distance,
                                          far_distance, static_cast<float>(lens.height));
}

runtime::Camera fitted_camera(glm::vec3 eye, glm::vec3 target, const Bounds& bounds, const Lens& lens) {
  float box_distance2 = 0, far_distance2 = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    const float e = eye[static_cast<glm::length_t>(a)];
    const float outside = std::max({bounds.min[a] - e, 0.0f, e - bounds.max[a]});
    const float farthest = std::max(std::abs(e - bounds.min[a]), std::abs(e - bounds.max[a]));
    box_distance2 += outside * outside;
    far_distance2 += farthest * farthest;
  }
  const float far_distance = std::max(1.01f * std::sqrt(far_distance2), 1e-5f);
  const float near_distance = std::max(0.5f * std::sqrt(box_distance2), 1e-4f * far_distance);
  return look_at_camera(eye, target, lens, near_distance, far_distance);
}

runtime::Camera framing_camera(const Bounds& bounds, const Lens& lens) {
  const ModelSphere sphere = model_sphere(bounds);
  const glm::vec3 direction = glm::normalize(glm::vec3(0.6f, 0.35f, 1.0f));
  if (lens.ortho_height > 0.0f)
    return fitted_camera(sphere.center + direction * (2.0f * sphere.radius), sphere.center, bounds, lens);
  const float half_fovy = 0.5f * lens.fovy_radians;
  const float half_fovx = std::atan(std::tan(half_fovy) * lens.aspect());
  // The sphere touches the narrower of the two view cones.
  const float distance = sphere.radius / std::sin(std::min(half_fovy, half_fovx));
  return fitted_camera(sphere.center + direction * distance, sphere.center, bounds, lens);
}

float framing_ortho_height(const Bounds& bounds, float aspect) {
  return 2.0f * model_sphere(bounds).radius * std::max(1.0f, 1.0f / aspect);
}

}  // namespace octolod::cli
