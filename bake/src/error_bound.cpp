// Conservative one-sided Hausdorff bound from an input mesh to its simplification (seed 3.5.3).
//
// For a fixed output triangle T', x -> dist(x, T') is convex, so over an input triangle t it is
// largest at one of t's corners: max_{x in t} dist(x, output) <= min over T' of max over t's
// corners of dist(corner, T'). Candidates T' are the output triangles nearest to t's corners (and,
// when refining, to its centroid), found with the closest-point BVH of measure/. Where the bound
// of t is far above the distances of its corners (t spans a ridge of the output, say), t is split
// in four (midpoints) and the bound is the max over the parts, a few levels deep. Only triangles
// whose bound exceeds the best total so far are refined — the total is a max — so the cost is a
// little more than one BVH query per input vertex. With the hints of a vertex clustering
// (error_bound.h, ImageHints) the candidates come from the clustering instead and the queries
// are only the fallback.
#include "error_bound.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include "octolod/measure/triangle_bvh.h"
#include "point_triangle.h"

namespace octolod::bake {
namespace {

using Vec = Vec3d;

constexpr int kMaxRefineDepth = 4;

constexpr std::uint32_t kNoHint = 0xFFFFFFFFu;

class Bounder {
 public:
  Bounder(const NodeMesh& output)
      : output_(output),
        stride_(output.layout.floats()),
        bvh_(output.vertices, output.layout.floats(), output.indices) {}

  Vec position(std::uint32_t output_triangle, int corner) const {
    const float* f = &output_.vertices[output_.indices[3 * std::size_t{output_triangle} + static_cast<std::size_t>(corner)] * stride_];
    return {f[0], f[1], f[2]};
  }
  double distance(const Vec& p, std::uint32_t output_triangle) const {
    return std::sqrt(point_triangle_distance2(p, position(output_triangle, 0), position(output_triangle, 1),
                                              position(output_triangle, 2)));
  }
  // Nearest output triangle to p and the distance to it (double precision).
  std::pair<std::uint32_t, double> nearest(const Vec& p) const {
    const auto hit = bvh_.closest(glm::vec3(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])));
    return {hit.triangle, distance(p, hit.triangle)};
  }

  // min over candidates of the max distance of the corners to it.
  double corner_bound(const std::array<Vec, 3>& corners, const std::vector<std::uint32_t>& candidates) const {
    double best = std::numeric_limits<double>::infinity();
    for (std::uint32_t candidate : candidates) {
      double worst = 0.0;
      for (const Vec& c : corners) {
        worst = std::max(worst, distance(c, candidate));
        if (worst >= best) break;
      }
      best = std::min(best, worst);
    }
    return best;
  }

  // Bound of the triangle `corners` whose corners are at distances `corner_distance`; parts
  // whose bound is at most `enough` are not refined further.
  double refine(const std::array<Vec, 3>& corners, const std::array<double, 3>& corner_distance,
                std::vector<std::uint32_t> candidates, double enough, int depth) const {
    candidates.push_back(nearest(centroid(corners[0], corners[1], corners[2])).first);
    const double bound = corner_bound(corners, candidates);
    const double lower = std::max({corner_distance[0], corner_distance[1], corner_distance[2]});
    if (depth >= kMaxRefineDepth || bound <= enough || bound <= lower * 1.05) return bound;
    std::array<Vec, 3> mid;
    std::array<double, 3> mid_distance;
    for (int k = 0; k < 3; ++k) {
      mid[static_cast<std::size_t>(k)] =
          midpoint(corners[static_cast<std::size_t>(k)], corners[static_cast<std::size_t>((k + 1) % 3)]);
      const auto [triangle, d] = nearest(mid[static_cast<std::size_t>(k)]);
      candidates.push_back(triangle);
      mid_distance[static_cast<std::size_t>(k)] = d;
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    const std::array<std::array<Vec, 3>, 4> parts{{{corners[0], mid[0], mid[2]},
                                                   {mid[0], corners[1], mid[1]},
                                                   {mid[2], mid[1], corners[2]},
                                                   {mid[0], mid[1], mid[2]}}};
    const std::array<std::array<double, 3>, 4> part_distance{{{corner_distance[0], mid_distance[0], mid_distance[2]},
                                                              {mid_distance[0], corner_distance[1], mid_distance[1]},
                                                              {mid_distance[2], mid_distance[1], corner_distance[2]},
                                                              {mid_distance[0], mid_distance[1], mid_distance[2]}}};
    double result = 0.0;
    for (std::size_t i = 0; i < 4; ++i) {
      result = std::max(result, refine(parts[i], part_distance[i], candidates, std::max(enough, result), depth + 1));
    }
    return std::min(result, bound);
  }

 private:
  const NodeMesh& output_;
  std::size_t stride_;
  measure::TriangleBvh bvh_;
};

// Raises `total` to a bound over the input triangles `triangles` by closest-point queries.
double bvh_bound(const NodeMesh& input, const NodeMesh& output, const std::vector<std::uint32_t>& triangles,
                 double total) {
  const Bounder bounder(output);
  const std::size_t stride = input.layout.floats();
  auto input_position = [&](std::uint32_t v) {
    const float* f = &input.vertices[v * stride];
    return Vec{f[0], f[1], f[2]};
  };

  // nearest output triangle of every corner; their max is a lower bound
  constexpr std::uint32_t kUnset = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> nearest_triangle(input.vertex_count(), kUnset);
  std::vector<double> nearest_distance(input.vertex_count(), 0.0);
  for (std::uint32_t t : triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = input.indices[3 * std::size_t{t} + k];
      if (nearest_triangle[v] != kUnset) continue;
      std::tie(nearest_triangle[v], nearest_distance[v]) = bounder.nearest(input_position(v));
      total = std::max(total, nearest_distance[v]);
    }
  }

  // per triangle: bound from its corners' nearest triangles
  struct Pending {
    double bound;
    std::uint32_t triangle;
  };
  std::vector<Pending> pending;
  for (std::uint32_t t : triangles) {
    const std::uint32_t* corner = &input.indices[3 * std::size_t{t}];
    const std::array<Vec, 3> corners{input_position(corner[0]), input_position(corner[1]), input_position(corner[2])};
    const std::vector<std::uint32_t> candidates{nearest_triangle[corner[0]], nearest_triangle[corner[1]],
                                                nearest_triangle[corner[2]]};
    const double bound = bounder.corner_bound(corners, candidates);
    if (bound > total) pending.push_back({bound, t});
  }

  // refine the worst first while they can raise the total
  std::sort(pending.begin(), pending.end(), [](const Pending& a, const Pending& b) {
    return a.bound != b.bound ? a.bound > b.bound : a.triangle < b.triangle;
  });
  for (const Pending& p : pending) {
    if (p.bound <= total) break;
    const std::uint32_t* corner = &input.indices[3 * std::size_t{p.triangle}];
    const std::array<Vec, 3> corners{input_position(corner[0]), input_position(corner[1]), input_position(corner[2])};
    std::vector<std::uint32_t> candidates{nearest_triangle[corner[0]], nearest_triangle[corner[1]],
                                          nearest_triangle[corner[2]]};
    const std::array<double, 3> distances{nearest_distance[corner[0]], nearest_distance[corner[1]],
                                          nearest_distance[corner[2]]};
    total = std::max(total, bounder.refine(corners, distances, std::move(candidates), total, 0));
  }
  return total;
}

}  // namespace

double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output, const ImageHints& hints) {
  if (input.triangle_count() == 0) return 0.0;
  if (output.triangle_count() == 0) return std::numeric_limits<double>::infinity();
  const std::size_t in_stride = input.layout.floats();
  const std::size_t out_stride = output.layout.floats();
  const bool have_fans = !hints.vertex_cluster.empty() && !hints.fan_offset.empty();
  auto input_position = [&](std::uint32_t v) {
    const float* f = &input.vertices[v * in_stride];
    return Vec{f[0], f[1], f[2]};
  };
  // the output's triangles as double corners, converted once: every one is a candidate of many
  // input vertices and triangles
  std::vector<std::array<Vec, 3>> output_corners(output.triangle_count());
  for (std::size_t triangle = 0; triangle < output_corners.size(); ++triangle) {
    for (std::size_t k = 0; k < 3; ++k) {
      const float* f = &output.vertices[output.indices[3 * triangle + k] * out_stride];
      output_corners[triangle][k] = {f[0], f[1], f[2]};
    }
  }
  auto output_triangle = [&](std::uint32_t triangle) -> const std::array<Vec, 3>& { return output_corners[triangle]; };
  auto fan = [&](std::uint32_t v) {
    const std::uint32_t c = hints.vertex_cluster[v];
    return hints.fan_triangle.subspan(hints.fan_offset[c], hints.fan_offset[c + 1] - hints.fan_offset[c]);
  };

  // Squared distances below: a first total, every input vertex's distance to the nearest
  // triangle of its cluster's fan (each is the bound of a degenerate triangle, so the final total
  // is at least their max, and a high total early lets most triangles below skip their exact
  // distances). A vertex stops at the first fan triangle within the total: it cannot raise it.
  // |x - corner| bounds dist(x, T) from above, so a corner within the total settles it too.
  auto near_corner = [](const Vec& x, const std::array<Vec, 3>& tri, double limit2) {
    for (const Vec& corner : tri) {
      const Vec d = sub(x, corner);
      if (dot(d, d) <= limit2) return true;
    }
    return false;
  };
  double total2 = 0.0;
  if (have_fans) {
    for (std::uint32_t v = 0; v < input.vertex_count(); ++v) {
      double best2 = std::numeric_limits<double>::infinity();
      const Vec p = input_position(v);
      for (std::uint32_t triangle : fan(v)) {
        const std::array<Vec, 3>& t = output_triangle(triangle);
        if (near_corner(p, t, total2)) {
          best2 = total2;
          break;
        }
        best2 = std::min(best2, point_triangle_distance2(p, t[0], t[1], t[2]));
        if (best2 <= total2) break;
      }
      if (best2 < std::numeric_limits<double>::infinity()) total2 = std::max(total2, best2);
    }
  }

  std::vector<std::uint32_t> unresolved;
  // the input triangle that last evaluated each output triangle: the image and the fans of a
  // triangle's corners overlap (corners in one cluster share its fan, a surviving image is in
  // every corner's fan), and a candidate evaluated twice cannot lower the minimum
  std::vector<std::uint32_t> evaluated_for(output.triangle_count(), kNoHint);
  for (std::size_t t = 0; t < input.triangle_count(); ++t) {
    const std::uint32_t* corner = &input.indices[3 * t];
    const std::array<Vec, 3> p{input_position(corner[0]), input_position(corner[1]), input_position(corner[2])};
    // max over the corners of the squared distance to output triangle `candidate` where it
    // exceeds total2 (at most total2 otherwise: a corner within total2 of one of the candidate's
    // corners is not measured, it cannot raise the total); stops early once it reaches `enough2`
    // (then returns a value >= enough2, only good for taking a minimum)
    auto corner_bound2 = [&](std::uint32_t candidate, double enough2) {
      const std::array<Vec, 3>& tri = output_triangle(candidate);
      double worst2 = 0.0;
      for (const Vec& x : p) {
        if (near_corner(x, tri, std::max(worst2, total2))) continue;
        worst2 = std::max(worst2, point_triangle_distance2(x, tri[0], tri[1], tri[2]));
        if (worst2 >= enough2) break;
      }
      return worst2;
    };
    const std::uint32_t hint = hints.nearby_output_triangle.empty() ? kNoHint : hints.nearby_output_triangle[t];
    double best2 = std::numeric_limits<double>::infinity();
    if (hint != kNoHint && hint < output.triangle_count()) {
      best2 = corner_bound2(hint, std::numeric_limits<double>::infinity());
      if (best2 <= total2) continue;
      evaluated_for[hint] = static_cast<std::uint32_t>(t);
    }
    if (have_fans) {
      for (std::uint32_t v : {corner[0], corner[1], corner[2]}) {
        for (std::uint32_t candidate : fan(v)) {
          if (evaluated_for[candidate] == t) continue;
          evaluated_for[candidate] = static_cast<std::uint32_t>(t);
          best2 = std::min(best2, corner_bound2(candidate, best2));
          if (best2 <= total2) break;
        }
        if (best2 <= total2) break;
      }
    }
    if (best2 == std::numeric_limits<double>::infinity()) unresolved.push_back(static_cast<std::uint32_t>(t));
    else total2 = std::max(total2, best2);
  }
  double total = std::sqrt(total2);
  if (!unresolved.empty()) total = bvh_bound(input, output, unresolved, total);
  return total * (1.0 + 1e-6);
}

double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output) {
  return hausdorff_upper_bound(input, output, ImageHints{});
}

}  // namespace octolod::bake
