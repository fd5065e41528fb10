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
// - else t is split in four (midpoints), a few levels deep, over the candidates, and where
//   that stays well above the corners' distances, again with closest-point queries
//   (measure::TriangleBvh) adding the output triangles nearest to each part.
// Only triangles whose cheap single-candidate bound exceeds the total so far get the prism
// pieces, and only those the pieces do not cover get the split, worst first: the total is a max.
// Candidates come from the clustering's hints (error_bound.h, ImageHints): the triangle's image
// and each corner's nearest image first, then the output triangles across the sides where the
// pieces end inside the triangle, then the fans around its corners' clusters. The version
// without hints takes every corner's nearest triangle by query.
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
// part (the pieces lie straight over their triangles but far from them), and the split bounds
// (closer_look below) are tried as well.
constexpr double kPrismTrusted2 = 2.0 * 2.0;
// The split bound over the candidates alone (no queries) is taken within 10% of the corners'
// distances: on a 1M rock bake, queries after it lowered the sum of all stored errors by 0.003%
// and cost 6% of the bake's CPU (docs/benchmarks.md).
constexpr double kLocalTrusted2 = 1.1 * 1.1;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::vector<Triangle> triangle_corners(const NodeMesh& mesh) {
  std::vector<Triangle> all(mesh.triangle_count());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = triangle_positions(mesh, t);
  return all;
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

// Raises `total2` to a bound over the input triangles `triangles` by closest-point queries
// (`bvh` over the output triangles `bounder` bounds against).
double bvh_bound2(const NodeMesh& input, const PartBounder& bounder, const measure::TriangleBvh& bvh,
                  const std::vector<std::uint32_t>& triangles, double total2) {
  // nearest output triangle of every corner; their max is a lower bound
  std::vector<std::uint32_t> nearest_triangle(input.vertex_count(), kNoTriangle);
  for (std::uint32_t t : triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = input.indices[3 * std::size_t{t} + k];
      if (nearest_triangle[v] != kNoTriangle) continue;
      const Vec p = vertex_position(input, v);
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
    const double bound2 = bounder.single_bound2(triangle_positions(input, t), candidates_of(t));
    if (bound2 > total2) pending.push_back({bound2, t});
  }
  return settle_pending(pending, total2, [&](std::uint32_t t, double enough2) {
    return bounder.bound2(triangle_positions(input, t), candidates_of(t), enough2, &bvh);
  });
}

// The bound from the squared total, with a relative margin of 1e-6 for this file's double
// arithmetic. An output that holds every input point (total 0) stays at 0.
double finish(double total2) { return total2 == 0.0 ? 0.0 : std::sqrt(total2) * (1.0 + 1e-6); }

}  // namespace

double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output, const ImageHints& hints,
                             double give_up) {
  if (input.triangle_count() == 0) return 0.0;
  if (output.triangle_count() == 0) return kInfinity;
  // the squared totals below are lower bounds of the result's square: above this, give up
  const double give_up2 = give_up * give_up;
  const bool have_fans = !hints.vertex_cluster.empty() && !hints.fan_offset.empty();
  const bool have_images = !hints.nearby_output_triangle.empty();
  auto image_of = [&](std::size_t t) {
    const std::uint32_t image = have_images ? hints.nearby_output_triangle[t] : kNoTriangle;
    return image < output.triangle_count() ? image : kNoTriangle;
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
  // the input triangles around it: a candidate of the triangles at the vertex. On the way, every
  // input triangle's bound against its image alone (the max of its corners' distances to it),
  // the first of its single candidates below.
  std::vector<std::uint32_t> vertex_best(input.vertex_count(), kNoTriangle);
  std::vector<double> vertex_best2(input.vertex_count(), kInfinity);  // distance2 to vertex_best (once it has one)
  auto offer = [&](std::uint32_t v, std::uint32_t triangle) {
    if (vertex_best[v] == triangle) return vertex_best2[v];  // the image of a triangle next to it, measured
    const double d2 = bounder.distance2(vertex_position(input, v), triangle);
    if (d2 < vertex_best2[v]) vertex_best2[v] = d2, vertex_best[v] = triangle;
    return d2;
  };
  std::vector<double> image_bound2(input.triangle_count(), kInfinity);
  for (std::size_t t = 0; t < input.triangle_count(); ++t)
    if (const std::uint32_t image = image_of(t); image != kNoTriangle) {
      double worst2 = 0.0;
      for (std::size_t k = 0; k < 3; ++k) worst2 = std::max(worst2, offer(input.indices[3 * t + k], image));
      image_bound2[t] = worst2;
    }

  // A first total, the exact distance of the vertices whose hinted one is the largest, until
  // the next hinted one is within it: at most the true Hausdorff distance, so the total loses
  // nothing, and high enough that most triangles below skip their closer look. (The hints miss
  // a vertex's nearest triangle now and then, by up to ten times its distance: one such vertex
  // would set the whole total.) The hierarchy is built at the first query.
  std::optional<measure::TriangleBvh> lazy_bvh;
  auto bvh = [&]() -> const measure::TriangleBvh& {
    if (!lazy_bvh) lazy_bvh.emplace(output.vertices, output.layout.floats(), output.indices);
    return *lazy_bvh;
  };
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
    const Vec p = vertex_position(input, v);
    vertex_best[v] = closest_triangle(bvh(), p);
    vertex_best2[v] = bounder.distance2(p, vertex_best[v]);
    total2 = std::max(total2, vertex_best2[v]);
  }
  worst = {};
  if (total2 > give_up2) return kInfinity;

  // The bound of input triangle `part` where it may raise the total, given `prism2`, its prism
  // pieces' bound over `candidates`: that bound, unless the pieces leave a gap or overlap (1% of
  // the triangles, mostly where the output's node border or a fold crosses the part's shadow)
  // or exceed twice its corners' distances (loose where the output stands steep under the part:
  // the pieces lie straight over their triangles but far from them); then the split bound over
  // the candidates, and where that ends more than 10% above the corners' distances, the split
  // bound with closest-point queries as well. All are bounds: the smallest.
  auto closer_look = [&](const Triangle& part, std::span<const std::uint32_t> candidates, double prism2,
                         double enough2) {
    if (prism2 <= enough2) return prism2;
    const double lower2 = std::max({bounder.nearest2(part[0], candidates), bounder.nearest2(part[1], candidates),
                                    bounder.nearest2(part[2], candidates)});
    if (prism2 <= kPrismTrusted2 * lower2) return prism2;
    const double local2 = bounder.split_bound2(part, candidates, prism2, enough2, nullptr);
    if (local2 <= enough2 || local2 <= kLocalTrusted2 * lower2) return local2;
    return std::min(local2, bounder.bound2(part, candidates, enough2, &bvh()));
  };

  // A triangle's few candidates: its image and its corners' nearest triangles (sorted, distinct;
  // held in `own`).
  auto few_of = [&](std::size_t t, std::array<std::uint32_t, 4>& own) {
    const std::uint32_t* corner = &input.indices[3 * t];
    own = {image_of(t), vertex_best[corner[0]], vertex_best[corner[1]], vertex_best[corner[2]]};
    std::sort(own.begin(), own.end());
    const auto distinct = static_cast<std::size_t>(std::unique(own.begin(), own.end()) - own.begin());
    return std::span<const std::uint32_t>(own.data(), own[distinct - 1] == kNoTriangle ? distinct - 1 : distinct);
  };
  // A triangle's candidates for the prism pieces: `few` (its image and its corners' nearest
  // triangles, which cover half the triangles that need a prism), then the fans around its
  // corners' clusters (for the prisms the walk across the pieces' sides, below, leaves open).
  // One prism over them all: a second prism over the fans repeated the first.
  std::vector<std::uint32_t> candidates;
  std::vector<std::uint32_t> added_in(output.triangle_count(), 0);  // the gathering that added it
  std::uint32_t gathering = 0;
  auto gather = [&](std::uint32_t t, std::span<const std::uint32_t> few) {
    candidates.clear();
    ++gathering;
    auto add = [&](std::uint32_t candidate) {
      if (added_in[candidate] == gathering) return;
      added_in[candidate] = gathering;
      candidates.push_back(candidate);
    };
    for (std::uint32_t candidate : few) add(candidate);
    if (have_fans)
      for (std::size_t k = 0; k < 3; ++k)
        for (std::uint32_t candidate : fan(input.indices[3 * std::size_t{t} + k])) add(candidate);
    return std::span<const std::uint32_t>(candidates);
  };

  // Every triangle's cheap bound: the best of its image and its corners' nearest triangles as
  // the single candidate (the image's known; the others only where it does not settle the
  // triangle). A corner within total2 of one of the candidate's corners is not measured (it
  // cannot raise the total); a candidate within the total settles the triangle. Where it does
  // not, the prism pieces; triangles they do not cover wait for the closer look.
  std::vector<Pending> pending;
  std::vector<std::uint32_t> unresolved;
  std::array<std::uint32_t, 4> own, others;
  for (std::size_t t = 0; t < input.triangle_count(); ++t) {
    if (image_bound2[t] <= total2) continue;
    const auto few = few_of(t, own);
    const Triangle p = triangle_positions(input, t);
    const std::uint32_t image = image_of(t);
    const auto others_end = std::remove_copy(few.begin(), few.end(), others.begin(), image);
    // each corner's distance to its nearest triangle so far, one of the others, is known
    const std::uint32_t* corner = &input.indices[3 * t];
    const std::array<PartBounder::Measured, 3> measured{{{vertex_best[corner[0]], vertex_best2[corner[0]]},
                                                         {vertex_best[corner[1]], vertex_best2[corner[1]]},
                                                         {vertex_best[corner[2]], vertex_best2[corner[2]]}}};
    const double best2 =
        std::min(image_bound2[t], bounder.single_bound2(p, {others.data(), others_end}, total2, &measured));
    if (best2 == kInfinity) {
      unresolved.push_back(static_cast<std::uint32_t>(t));
      continue;
    }
    if (best2 <= total2) continue;
    // the fans only where the few do not cover the triangle (gather puts the few first; it is
    // never empty, so an empty `all` means not gathered yet)
    std::span<const std::uint32_t> all;
    auto gathered = [&] {
      if (all.empty()) all = gather(static_cast<std::uint32_t>(t), few);
      return all;
    };
    // The prism over the few, then over the output triangles across its pieces' open sides (on
    // a 1M rock they settle 97% of the prisms the few do not, where the fans took 5 offers
    // each), then the fans.
    PartBounder::Prism prism(bounder, p, total2);
    auto offer_each = [&](std::span<const std::uint32_t> list) {
      return std::any_of(list.begin(), list.end(), [&](std::uint32_t candidate) { return prism.offer(candidate); });
    };
    if (!offer_each(few) && !prism.offer_neighbours()) offer_each(gathered().subspan(few.size()));
    const double prism2 = prism.bound2();
    if (prism2 == kInfinity) pending.push_back({best2, static_cast<std::uint32_t>(t)});
    else if (std::min(prism2, best2) > total2)
      total2 = std::max(total2, std::min(best2, closer_look(p, gathered(), prism2, total2)));
    if (total2 > give_up2) return kInfinity;
  }

  // The closer look for the triangles the prism pieces did not cover, worst first.
  total2 = settle_pending(pending, total2, [&](std::uint32_t t, double enough2) {
    return closer_look(triangle_positions(input, t), gather(t, few_of(t, own)), kInfinity, enough2);
  });
  if (total2 > give_up2) return kInfinity;
  if (!unresolved.empty()) total2 = bvh_bound2(input, bounder, bvh(), unresolved, total2);
  const double bound = finish(total2);
  return bound > give_up ? kInfinity : bound;
}

double hausdorff_upper_bound(const NodeMesh& input, const NodeMesh& output) {
  if (input.triangle_count() == 0) return 0.0;
  if (output.triangle_count() == 0) return kInfinity;
  std::vector<std::uint32_t> all(input.triangle_count());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<std::uint32_t>(t);
  const std::vector<Triangle> output_corners = triangle_corners(output);
  const measure::TriangleBvh bvh(output.vertices, output.layout.floats(), output.indices);
  return finish(bvh_bound2(input, PartBounder(output_corners), bvh, all, 0.0));
}

double float_measurement_margin(const Bounds& region) {
  return 8.0 * std::numeric_limits<float>::epsilon() * region.largest_magnitude();
}

}  // namespace octolod::bake
