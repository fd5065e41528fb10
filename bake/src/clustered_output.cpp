// clustered_output.h: the input triangles per cluster, and brute-force nearest distances over
// the few clusters a pass asks about (a quad's four, a fan's four: some 30 triangles).
#include "clustered_output.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace octolod::bake {

void InputDistances::gather() {
  gathered_ = true;
  const NodeMesh& input = out_.input;
  offset_.assign(std::size_t{out_.cluster_count} + 1, 0);
  auto for_clusters_of = [&](std::size_t t, auto&& f) {
    const std::uint32_t* v = &input.indices[3 * t];
    const std::uint32_t x = out_.vertex_cluster[v[0]], y = out_.vertex_cluster[v[1]], z = out_.vertex_cluster[v[2]];
    f(x);
    if (y != x) f(y);
    if (z != x && z != y) f(z);
  };
  const std::size_t triangles = input.triangle_count();
  for (std::size_t t = 0; t < triangles; ++t) for_clusters_of(t, [&](std::uint32_t c) { ++offset_[c + 1]; });
  for (std::size_t c = 0; c < out_.cluster_count; ++c) offset_[c + 1] += offset_[c];
  triangle_.resize(offset_.back());
  std::vector<std::uint32_t> fill(offset_.begin(), offset_.end() - 1);
  for (std::size_t t = 0; t < triangles; ++t)
    for_clusters_of(t, [&](std::uint32_t c) { triangle_[fill[c]++] = static_cast<std::uint32_t>(t); });

  // bounding spheres in float: the centre rounded, the radius widened by the rounding's shift
  // and rounded up (to the next float: the radius is finite and not negative), so that they
  // still hold the corners
  sphere_.resize(triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t* v = &input.indices[3 * t];
    const Sphere exact = bounding_sphere(vertex_position(input, v[0]), vertex_position(input, v[1]), vertex_position(input, v[2]));
    FloatSphere& sphere = sphere_[t];
    for (std::size_t i = 0; i < 3; ++i) sphere.center[i] = static_cast<float>(exact.center[i]);
    const Vec3d shift = sub(exact.center, {sphere.center[0], sphere.center[1], sphere.center[2]});
    const auto radius = static_cast<float>(exact.radius + std::sqrt(dot(shift, shift)));
    sphere.radius = std::bit_cast<float>(std::bit_cast<std::uint32_t>(radius) + 1);
  }
  met_in_.assign(triangles, 0);
}

void InputDistances::nearest2(std::span<const std::uint32_t> clusters, std::span<const Vec3d> points,
                              std::span<double> distance2) {
  if (!gathered_) gather();
  const NodeMesh& input = out_.input;
  std::fill(distance2.begin(), distance2.end(), INFINITY);
  ++query_;
  for (std::size_t q = 0; q < clusters.size(); ++q)
    for (std::uint32_t i = offset_[clusters[q]]; i < offset_[clusters[q] + 1]; ++i) {
      const std::uint32_t t = triangle_[i];
      if (met_in_[t] == query_) continue;  // at an earlier cluster of the list
      met_in_[t] = query_;
      // a triangle whose sphere is farther from every point than its best so far cannot lower it
      const FloatSphere& sphere = sphere_[t];
      bool reaches = false;
      for (std::size_t p = 0; p < points.size() && !reaches; ++p) {
        const Vec3d d = sub(points[p], {sphere.center[0], sphere.center[1], sphere.center[2]});
        const double gap = std::sqrt(dot(d, d)) - sphere.radius;
        reaches = gap <= 0.0 || gap * gap < distance2[p];
      }
      if (!reaches) continue;
      const std::uint32_t* v = &input.indices[3 * std::size_t{t}];
      const Vec3d q0 = vertex_position(input, v[0]), q1 = vertex_position(input, v[1]), q2 = vertex_position(input, v[2]);
      for (std::size_t p = 0; p < points.size(); ++p)
        distance2[p] = std::min(distance2[p], point_triangle_distance2(points[p], q0, q1, q2));
    }
}

}  // namespace octolod::bake
