// Conservative one-sided Hausdorff bound from an input mesh to its simplification (seed 3.5.3).
//
// For a fixed output triangle T, x -> dist(x, T) is convex, so over a convex piece of an input
// triangle it is largest at one of the piece's corners. The bound of an input triangle t is the
// max over pieces that cover t, each measured against one output triangle:
// - one piece, t itself, against the best single candidate (min over T of the max over t's
//   corners): tight when t lies over one output triangle, but where t reaches across an output
//   edge or vertex it is about how far t reaches, a step's cell, rather than how far the output
//   is from the surface (7-10x the true distance on a rock: docs/benchmarks.md);
// - the prism pieces: the prism over each candidate T along t's normal cuts from t the convex
//   piece that lies straight above or below T. When the candidates facing like t tile its
//   shadow (the pieces' areas add up to t's), this is within a few percent of the true distance;
// - else t is split in four (midpoints), a few levels deep, with closest-point queries
//   (measure::TriangleBvh) adding the output triangles nearest to each part.
// Only triangles whose cheap single-candidate bound exceeds the total so far get a closer look,
// worst first: the total is a max. Candidates come from the clustering's hints (error_bound.h,
// ImageHints): the triangle's image, each corner's nearest image, the fans around its corners'
// clusters. The version without hints takes every corner's nearest triangle by query.
#include "error_bound.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "octolod/measure/triangle_bvh.h"
#include "part_bound.h"
#include "point_triangle.h"

namespace octolod::bake {
namespace {

using Vec = Vec3d;
using Triangle = Triangle3d;

// A prism bound within twice its part's corner distances is taken as it is (the corners'
// distances are a lower bound of the true one); above, the output may stand steep under the
// part (the pieces lie straight over their triangles but far from them), and the split bound
// with closest-point queries is tried as well.
constexpr double kPrismTrusted2 = 2.0 * 2.0;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr std::uint32_t kNone = 0xFFFFFFFFu;

std::vector<Triangle> triangle_corners(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  std::vector<Triangle> corners(mesh.triangle_count());
  for (std::size_t t = 0; t < corners.size(); ++t)
    for (std::size_t k = 0; k < 3; ++k) {
      const float* f = &mesh.vertices[mesh.indices[3 * t + k] * stride];
      corners[t][k] = {f[0], f[1], f[2]};
    }
  return corners;
}

// |x - corner| bounds dist(x, T) from above: a corner of T within sqrt(limit2) of x settles x.
bool near_corner(const Vec& x, const Triangle& tri, double limit2) {
  for (const Vec& corner : tri) {
    const Vec d = sub(x, corner);
    if (dot(d, d) <= limit2) return true;
  }
  return false;
}

struct Pending {
  double bound2;
  std::uint32_t triangle;
};

// Sorts `pending` worst first and raises `total2` with the closer bound of each while its cheap
// bound exceeds the total.
template <class Closer>
double settle_pending(std::vector<Pending>& pending, double total2, Closer&& closer) {
  std::sort(pending.begin(), pending.end(), [](const Pending& a, const Pending& b) {
    return a.bound2 != b.bound2 ? a.bound2 > b.bound2 : a.triangle < b.triangle;
  });
  for (const Pending& p : pending) {
    if (p.bound2 <= total2) break;
    total2 = std::max(total2, closer(p.triangle, total2));
  }
  return total2;
}

// Raises `total2` to a bound over the input triangles `triangles` by closest-point queries.
double bvh_bound2(const NodeMesh& input, std::span<const Triangle> output, const NodeMesh& output_mesh,
                  const std::vector<std::uint32_t>& triangles, double total2) {
  const measure::TriangleBvh bvh(output_mesh.vertices, output_mesh.layout.floats(), output_mesh.indices);
  const PartBounder bounder(output);
  const std::size_t stride = input.layout.floats();
  auto input_position = [&](std::uint32_t v) {
    const float* f = &input.vertices[v * stride];
    return Vec{f[0], f[1], f[2]};
  };
  auto corners_of = [&](std::uint32_t t) {
    const std::uint32_t* v = &input.indices[3 * std::size_t{t}];
    return Triangle{input_position(v[0]), input_position(v[1]), input_position(v[2])};
  };

  // nearest output triangle of every corner; their max is a lower bound
  std::vector<std::uint32_t> nearest_triangle(input.vertex_count(), kNone);
  for (std::uint32_t t : triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = input.indices[3 * std::size_t{t} + k];
      if (nearest_triangle[v] != kNone) continue;
      const Vec p = input_position(v);
      nearest_triangle[v] = closest_triangle(bvh, p);
      total2 = std::max(total2, bounder.distance2(p, nearest_triangle[v]));
    }
  }
  auto candidates_of = [&](std::uint32_t t) {
    const std::uint32_t* v = &input.indices[3 * std::size_t{t}];
    return std::array<std::uint32_t, 3>{nearest_triangle[v[0]], nearest_triangle[v[1]], nearest_triangle[v[2]]};
  };
  std::vector<Pending> pending;
  for (std::uint32_t t : triangles) {
    const double bound2 = bounder.single_bound2(corners_of(t), candidates_of(t));
    if (bound2 > total2) pending.push_back({bound2, t});
  }
  return settle_pending(pending, total2, [&](std::uint32_t t, double enough2) {
    return bounder.bound2(corners_of(t), candidates_of(t), enough2, &bvh);
  });
}

// The bound from the squared total, with margins for rounding: relative 1e-6 for this file's
// double arithmetic, and eight float epsilons of the largest coordinate of either mesh for those
// who measure the same distances in float (measure::TriangleBvh, the runtime): the positions are
// floats, and a bound this tight is otherwise a few float ulps below their measurements. An
// output that holds every input point (total 0) stays at 0.
double finish(double total2, const NodeMesh& input, const NodeMesh& output) {
  if (total2 == 0.0) return 0.0;
  double scale = 0.0;
  for (const NodeMesh* mesh : {&input, &output}) {
    const std::size_t stride = mesh->layout.floats();
    for (std::size_t i = 0; i < mesh->vertices.size(); i += stride)
      for (std::size_t k = 0; k < 3; ++k) scale = std::max(scale, static_cast<double>(std::abs(mesh->vertices[i + k])));
  }
  return std::sqrt(total2) * (1.0 + 1e-6) + 8.0 * std::numeric_limits<float>::epsilon() * scale;
}

}  // namespace

double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output, const ImageHints& hints) {
  if (input.triangle_count() == 0) return 0.0;
  if (output.triangle_count() == 0) return kInfinity;
  const std::size_t in_stride = input.layout.floats();
  const bool have_fans = !hints.vertex_cluster.empty() && !hints.fan_offset.empty();
  const bool have_images = !hints.nearby_output_triangle.empty();
  auto input_position = [&](std::uint32_t v) {
    const float* f = &input.vertices[v * in_stride];
    return Vec{f[0], f[1], f[2]};
  };
  auto corners_of = [&](std::size_t t) {
    const std::uint32_t* v = &input.indices[3 * t];
    return Triangle{input_position(v[0]), input_position(v[1]), input_position(v[2])};
  };
  auto image_of = [&](std::size_t t) {
    const std::uint32_t image = have_images ? hints.nearby_output_triangle[t] : kNone;
    return image < output.triangle_count() ? image : kNone;
  };
  auto fan = [&](std::uint32_t v) {
    const std::uint32_t c = hints.vertex_cluster[v];
    return hints.fan_triangle.subspan(hints.fan_offset[c], hints.fan_offset[c + 1] - hints.fan_offset[c]);
  };
  // the output's triangles as double corners, converted once: every one is a candidate of many
  // input vertices and triangles
  const std::vector<Triangle> output_corners = triangle_corners(output);
  const PartBounder bounder(output_corners);

  // Squared distances below. Every input vertex's nearest output triangle among the images of
  // the input triangles around it: a candidate of the triangles at the vertex.
  std::vector<std::uint32_t> vertex_best(input.vertex_count(), kNone);
  std::vector<double> vertex_best2(input.vertex_count(), kInfinity);
  auto offer = [&](std::uint32_t v, std::uint32_t triangle) {
    const double d2 = bounder.distance2(input_position(v), triangle);
    if (d2 < vertex_best2[v]) vertex_best2[v] = d2, vertex_best[v] = triangle;
  };
  for (std::size_t t = 0; t < input.triangle_count(); ++t)
    if (const std::uint32_t image = image_of(t); image != kNone)
      for (std::size_t k = 0; k < 3; ++k) offer(input.indices[3 * t + k], image);

  // A first total, the exact distance of the vertices whose hinted one is the largest, until
  // the next hinted one is within it: at most the true Hausdorff distance, so the total loses
  // nothing, and high enough that most triangles below skip their closer look. (The hints miss
  // a vertex's nearest triangle now and then, by up to ten times its distance: one such vertex
  // would set the whole total.) The hierarchy is built at the first query.
  std::optional<measure::TriangleBvh> bvh;
  std::vector<std::pair<double, std::uint32_t>> worst;
  worst.reserve(input.vertex_count());
  for (std::uint32_t v = 0; v < input.vertex_count(); ++v)
    if (vertex_best2[v] < kInfinity) worst.emplace_back(vertex_best2[v], v);
  std::make_heap(worst.begin(), worst.end());
  double total2 = 0.0;
  while (!worst.empty() && worst.front().first > total2) {
    const std::uint32_t v = worst.front().second;
    std::pop_heap(worst.begin(), worst.end());
    worst.pop_back();
    if (!bvh) bvh.emplace(output.vertices, output.layout.floats(), output.indices);
    const Vec p = input_position(v);
    vertex_best[v] = closest_triangle(*bvh, p);
    vertex_best2[v] = bounder.distance2(p, vertex_best[v]);
    total2 = std::max(total2, vertex_best2[v]);
  }
  worst = {};

  // The bound of input triangle `part` where it may raise the total: its prism pieces over
  // `candidates`; where these leave a gap (rare), or exceed twice its corners' distances (loose
  // where the output stands steep under the part: the pieces lie straight over their triangles
  // but far from them), the split bound with closest-point queries as well. Both are bounds:
  // the smaller.
  auto closer_look = [&](const Triangle& part, std::span<const std::uint32_t> candidates, double enough2) {
    const double prism2 = bounder.prism_bound2(part, candidates, enough2);
    if (prism2 <= enough2) return prism2;
    const double lower2 = std::max({bounder.nearest2(part[0], candidates), bounder.nearest2(part[1], candidates),
                                    bounder.nearest2(part[2], candidates)});
    if (prism2 <= kPrismTrusted2 * lower2) return prism2;
    if (!bvh) bvh.emplace(output.vertices, output.layout.floats(), output.indices);
    return std::min(prism2, bounder.bound2(part, candidates, enough2, &*bvh));
  };

  // Every triangle's cheap bound: the best of its image and its corners' nearest triangles as
  // the single candidate. A corner within total2 of one of the candidate's corners is not
  // measured (it cannot raise the total); a candidate within the total settles the triangle.
  std::vector<Pending> pending;
  std::vector<std::uint32_t> unresolved;
  for (std::size_t t = 0; t < input.triangle_count(); ++t) {
    const std::uint32_t* corner = &input.indices[3 * t];
    const Triangle p = corners_of(t);
    double best2 = kInfinity;
    std::array<std::uint32_t, 4> own{image_of(t), vertex_best[corner[0]], vertex_best[corner[1]], vertex_best[corner[2]]};
    for (std::uint32_t candidate : own) {
      if (candidate == kNone) continue;
      const Triangle& tri = output_corners[candidate];
      double worst2 = 0.0;
      for (const Vec& x : p) {
        if (near_corner(x, tri, std::max(worst2, total2))) continue;
        worst2 = std::max(worst2, bounder.distance2(x, candidate));
        if (worst2 >= best2) break;
      }
      best2 = std::min(best2, worst2);
      if (best2 <= total2) break;
    }
    if (best2 == kInfinity) {
      unresolved.push_back(static_cast<std::uint32_t>(t));
      continue;
    }
    if (best2 <= total2) continue;
    // the prism pieces of these few candidates: they cover most triangles that straddle an
    // output edge (the two triangles are the corners' nearest)
    std::sort(own.begin(), own.end());
    const auto distinct = static_cast<std::size_t>(std::unique(own.begin(), own.end()) - own.begin());
    const std::span<const std::uint32_t> few(own.data(), own[distinct - 1] == kNone ? distinct - 1 : distinct);
    const double prism2 = bounder.prism_bound2(p, few, total2);
    if (prism2 == kInfinity) pending.push_back({best2, static_cast<std::uint32_t>(t)});
    else if (std::min(prism2, best2) > total2) total2 = std::max(total2, std::min(best2, closer_look(p, few, total2)));
  }

  // The closer look, worst first: the candidates and the fans around the corners' clusters.
  std::vector<std::uint32_t> candidates;
  std::vector<std::uint32_t> added_for(output.triangle_count(), kNone);
  total2 = settle_pending(pending, total2, [&](std::uint32_t t, double enough2) {
    candidates.clear();
    auto add = [&](std::uint32_t candidate) {
      if (candidate == kNone || added_for[candidate] == t) return;
      added_for[candidate] = t;
      candidates.push_back(candidate);
    };
    const std::uint32_t* corner = &input.indices[3 * std::size_t{t}];
    add(image_of(t));
    for (std::size_t k = 0; k < 3; ++k) add(vertex_best[corner[k]]);
    if (have_fans)
      for (std::size_t k = 0; k < 3; ++k)
        for (std::uint32_t candidate : fan(corner[k])) add(candidate);
    return closer_look(corners_of(t), candidates, enough2);
  });
  if (!unresolved.empty()) total2 = bvh_bound2(input, output_corners, output, unresolved, total2);
  return finish(total2, input, output);
}

double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output) {
  if (input.triangle_count() == 0) return 0.0;
  if (output.triangle_count() == 0) return kInfinity;
  std::vector<std::uint32_t> all(input.triangle_count());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<std::uint32_t>(t);
  return finish(bvh_bound2(input, triangle_corners(output), output, all, 0.0), input, output);
}

}  // namespace octolod::bake
