// Exact point-to-triangle distance in double, and the few vector helpers around it (a NodeMesh
// vertex's position in double among them), for the bake's geometric tests (error bounds,
// diagonal flips, folded fans). Positions in any one frame (model units or a node's local
// coordinates).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "octolod/formats/node_file.h"

namespace octolod::bake {

using Vec3d = std::array<double, 3>;

// Vertex v's position in double (model units).
inline Vec3d vertex_position(const NodeMesh& mesh, std::uint32_t v) {
  const float* f = &mesh.vertices[std::size_t{v} * mesh.layout.floats()];
  return {f[0], f[1], f[2]};
}

// Triangle t's corner positions in double (model units).
inline std::array<Vec3d, 3> triangle_positions(const NodeMesh& mesh, std::size_t t) {
  const std::uint32_t* v = &mesh.indices[3 * t];
  return {vertex_position(mesh, v[0]), vertex_position(mesh, v[1]), vertex_position(mesh, v[2])};
}

inline Vec3d sub(const Vec3d& a, const Vec3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double dot(const Vec3d& a, const Vec3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline Vec3d midpoint(const Vec3d& a, const Vec3d& b) {
  return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
}
inline Vec3d centroid(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return {(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0, (a[2] + b[2] + c[2]) / 3.0};
}

// The sphere around the centroid of (a, b, c) through its farthest corner.
struct Sphere {
  Vec3d center;
  double radius;
};
inline Sphere bounding_sphere(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d center = centroid(a, b, c);
  double radius2 = 0.0;
  for (const Vec3d* corner : {&a, &b, &c}) radius2 = std::max(radius2, dot(sub(*corner, center), sub(*corner, center)));
  return {center, std::sqrt(radius2)};
}

// Squared distance from p to triangle (a,b,c), Ericson 2005, 5.1.5 ClosestPtPointTriangle; a
// degenerate triangle is measured by its edges. Squared: callers mostly compare distances.
// Inline: the error bound calls it millions of times per bake.
inline double point_triangle_distance2(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  auto dist2_to = [&p](const Vec3d& q) { const Vec3d d = sub(p, q); return dot(d, d); };
  auto lerp = [](const Vec3d& x, const Vec3d& y, double t) {
    return Vec3d{x[0] + t * (y[0] - x[0]), x[1] + t * (y[1] - x[1]), x[2] + t * (y[2] - x[2])};
  };
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return dot(ap, ap);
  const Vec3d bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return dot(bp, bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return dist2_to(lerp(a, b, d1 / (d1 - d3)));
  const Vec3d cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return dot(cp, cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return dist2_to(lerp(a, c, d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return dist2_to(lerp(b, c, (d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const double denom = va + vb + vc;
  if (!(denom > 0.0)) {  // degenerate triangle: its edges
    double best = std::min({dot(ap, ap), dot(bp, bp), dot(cp, cp)});
    const Vec3d* ends[3][2] = {{&a, &b}, {&b, &c}, {&c, &a}};
    for (const auto& e : ends) {
      const Vec3d d = sub(*e[1], *e[0]);
      const double len2 = dot(d, d);
      if (len2 > 0.0) best = std::min(best, dist2_to(lerp(*e[0], *e[1], std::clamp(dot(sub(p, *e[0]), d) / len2, 0.0, 1.0))));
    }
    return best;
  }
  const double v = vb / denom, w = vc / denom;
  return dist2_to({a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w});
}


}  // namespace octolod::bake
