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
    const auto [a, b, c] = triangle_positions(input, t);
    const Sphere exact = bounding_sphere(a, b, c);
    FloatSphere& sphere = sphere_[t];
    for (std::size_t i = 0; i < 3; ++i) sphere.center[i] = static_cast<float>(exact.center[i]);
    const Vec3d shift = sub(exact.center, {sphere.center[0], sphere.center[1], sphere.center[2]});
    const auto radius = static_cast<float>(exact.radius + std::sqrt(dot(shift, shift)));
    sphere.radius = std::bit_cast<float>(std::bit_cast<std::uint32_t>(radius) + 1);
  }
  met_in_.assign(triangles, 0);
}

template <class F>
void InputDistances::for_each_triangle(std::span<const std::uint32_t> clusters, const F& f) {
  if (!gathered_) gather();
  ++query_;
  for (const std::uint32_t c : clusters)
    for (std::uint32_t i = offset_[c]; i < offset_[c + 1]; ++i) {
      const std::uint32_t t = triangle_[i];
      if (met_in_[t] == query_) continue;  // at an earlier cluster of the list
      met_in_[t] = query_;
      f(t);
    }
}

inline bool InputDistances::may_be_nearer(std::uint32_t t, const Vec3d& p, double distance2) const {
  const FloatSphere& sphere = sphere_[t];
  const Vec3d d = sub(p, {sphere.center[0], sphere.center[1], sphere.center[2]});
  const double gap = std::sqrt(dot(d, d)) - sphere.radius;
  return gap <= 0.0 || gap * gap < distance2;
}

void InputDistances::nearest2(std::span<const std::uint32_t> clusters, std::span<const Vec3d> points,
                              std::span<double> distance2) {
  std::fill(distance2.begin(), distance2.end(), INFINITY);
  for_each_triangle(clusters, [&](std::uint32_t t) {
    const auto [a, b, c] = triangle_positions(out_.input, t);
    for (std::size_t p = 0; p < points.size(); ++p)
      if (may_be_nearer(t, points[p], distance2[p]))
        distance2[p] = std::min(distance2[p], point_triangle_distance2(points[p], a, b, c));
  });
}

bool InputDistances::nearer(std::span<const std::uint32_t> clusters, const Vec3d& candidate, const Vec3d& current,
                            double share) {
  // `current` exactly; `candidate` below the bound share x current's best so far, which only
  // falls (a product with a share is monotone): a triangle that brings it below the final bound
  // is never skipped, and the others do not change the answer
  double current2 = INFINITY, candidate2 = INFINITY;
  for_each_triangle(clusters, [&](std::uint32_t t) {
    const bool lowers_current = may_be_nearer(t, current, current2);
    const bool lowers_candidate = may_be_nearer(t, candidate, std::min(candidate2, share * current2));
    if (!lowers_current && !lowers_candidate) return;
    const auto [a, b, c] = triangle_positions(out_.input, t);
    if (lowers_current) current2 = std::min(current2, point_triangle_distance2(current, a, b, c));
    if (lowers_candidate) candidate2 = std::min(candidate2, point_triangle_distance2(candidate, a, b, c));
  });
  return candidate2 < share * current2;
}

}  // namespace octolod::bake
