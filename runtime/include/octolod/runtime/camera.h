// The view the runtime selects for: a camera in the tree's model space (the units and axes of the
// baked manifest). A game that places the model with a model matrix M passes view * M as `view`
// and the eye position transformed into model space by inverse(M) as `position`.
#pragma once

#include <array>

#include <glm/glm.hpp>

namespace octolod::runtime {

struct Camera {
  glm::mat4 view{1.0f};  // model space -> eye space
  // Eye space -> clip space in OpenGL convention: a perspective projection (glm::perspective; a
  // [0, 1] depth range, an infinite far plane or a y flip for a y-down clip space work too) or an
  // orthographic one (glm::ortho: is_orthographic). Besides culling, its vertical scale
  // |projection[1][1]| sets how many pixels a model unit covers: at unit distance for a
  // perspective (1/tan(fovy/2), off-centre projections included: the field of view of the
  // screen-space error is the projection's), at every distance for an orthographic projection
  // (2 / the view's height in model units).
  glm::mat4 projection{1.0f};
  glm::vec3 position{0.0f};    // eye position in model space (model units)
  float viewport_height_px = 1080.0f;  // height of the render target in pixels
};

// Whether update() can select for `camera`: every number finite, a projection with a vertical
// scale (projection[1][1] != 0) and a positive viewport height. A NaN eye (lookAt with eye ==
// target gives a NaN view) would refine every node to its leaves and cull nothing.
bool is_usable(const Camera& camera);

// Whether `projection` is orthographic (clip w does not depend on depth: projection[2][3] == 0,
// as glm::ortho makes), so a node's size on screen does not shrink with its distance.
bool is_orthographic(const glm::mat4& projection);

// A symmetric perspective camera at `eye` looking at `target` (model space), with near/far
// clip distances in model units and aspect = width / height.
Camera make_perspective_camera(glm::vec3 eye, glm::vec3 target, glm::vec3 up, float fovy_radians,
                               float aspect, float near_distance, float far_distance,
                               float viewport_height_px);
// An orthographic camera at `eye` looking at `target` (model space) that sees a view
// `view_height` model units high (and aspect x that wide) around the line of sight, between the
// near and far clip distances (model units).
Camera make_orthographic_camera(glm::vec3 eye, glm::vec3 target, glm::vec3 up, float view_height,
                                float aspect, float near_distance, float far_distance,
                                float viewport_height_px);

// A plane n·x + d = 0 with unit normal n pointing into the half-space it keeps.
struct Plane {
  glm::vec3 normal{0.0f, 0.0f, 1.0f};
  float d = 0.0f;
  float distance(glm::vec3 p) const { return glm::dot(normal, p) + d; }
};

// The six clip planes of a view-projection matrix in model space, inward facing: left, right,
// bottom, top, near, far (Gribb & Hartmann 2001). A degenerate plane (the far plane of an
// infinite projection) is replaced by one that keeps everything.
struct Frustum {
  std::array<Plane, 6> planes;
};
Frustum extract_frustum(const glm::mat4& view_projection);

// Axis-aligned box against the frustum by the p-vertex / n-vertex test: `outside` only when the
// whole box lies behind one plane, so a large box straddling the frustum is never culled (the
// seed's "one corner inside" test would cull it). `inside` when the box is in front of all six.
enum class Containment { outside, intersects, inside };
Containment classify_box(const Frustum& frustum, glm::vec3 center, glm::vec3 half_extent);

}  // namespace octolod::runtime
