// Cameras the CLI places around a baked model, sized from the manifest's bounds: the overview
// that frames the whole model (`render`'s default) and eye/target cameras (`render --camera`, the
// `walk` paths). All positions are in model space (the manifest's units and axes).
#pragma once

#include <glm/glm.hpp>

#include "octolod/formats/bounds.h"
#include "octolod/runtime/camera.h"

namespace octolod::cli {

// The sphere around a model's bounding box: its centre and half its diagonal (model units; at
// least 1e-6 so an empty or flat model still gets a usable camera).
struct ModelSphere {
  glm::vec3 center{0.0f};
  float radius = 1.0f;
};
ModelSphere model_sphere(const Bounds& bounds);

// What a camera projects onto: vertical field of view (or an orthographic view's height) and the
// render target's size in pixels.
struct Lens {
  float fovy_radians = 1.0471976f;  // 60 degrees
  // > 0: an orthographic projection this many model units high instead of a perspective one
  float ortho_height = 0.0f;
  int width = 1920;
  int height = 1080;
  float aspect() const { return static_cast<float>(width) / static_cast<float>(height); }
};

// A perspective (or, with lens.ortho_height, orthographic) camera at `eye` looking at `target`
// with near/far clip distances in model units. Up is +y, or +z when the view direction is
// (nearly) vertical. eye must differ from target.
runtime::Camera look_at_camera(glm::vec3 eye, glm::vec3 target, const Lens& lens, float near_distance,
                               float far_distance);

// Like look_at_camera, with near/far fitted to `bounds` as seen from `eye`: far reaches the
// farthest corner, near is half the distance to the box (a small fraction of far when the eye is
// inside it), so nothing of the model is clipped and depth precision goes where the model is.
runtime::Camera fitted_camera(glm::vec3 eye, glm::vec3 target, const Bounds& bounds, const Lens& lens);

// The overview: looks at the model's centre from above and in front (direction (0.6, 0.35, 1)),
// just far enough that the whole model sphere fits the vertical and horizontal field of view
// (orthographic: from twice its radius).
runtime::Camera framing_camera(const Bounds& bounds, const Lens& lens);

// The height (model units) of an orthographic view in which the model sphere of `bounds` fits
// both ways at `aspect` (width / height).
float framing_ortho_height(const Bounds& bounds, float aspect);

}  // namespace octolod::cli
