// Bounds of an input triangle, or of a part of one, against candidate output triangles: the
// pieces of the conservative step error (error_bound.h). Every bound is an upper bound of the
// largest distance from a point of the part to the output triangles, squared (model units²,
// the frame of the triangles given), by the convexity of x -> dist(x, T) for one triangle T.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "octolod/measure/triangle_bvh.h"
#include "point_triangle.h"

namespace octolod::bake {

using Triangle3d = std::array<Vec3d, 3>;

// The index of the triangle of `bvh` nearest to p.
std::uint32_t closest_triangle(const measure::TriangleBvh& bvh, const Vec3d& p);

class PartBounder {
 public:
  // `output`: the output mesh's triangles (double corners), indexed as the candidates below;
  // borrowed, must outlive the bounder. Keeps 80 bytes per triangle (normal, bounding sphere,
  // a key per corner).
  explicit PartBounder(std::span<const Triangle3d> output);

  double distance2(const Vec3d& p, std::uint32_t triangle) const;
  // min over `candidates` of distance2(p, .); +infinity when there is none.
  double nearest2(const Vec3d& p, std::span<const std::uint32_t> candidates) const;

  // One piece: min over the candidates of the max over the part's corners of the distance to it.
  // Tight where the part lies over one output triangle; where it reaches across an output edge
  // it is about how far it reaches. A candidate within `settled2` ends the search (the result is
  // then only known to be at most `settled2`), and a corner within that, or within the
  // candidate's worst so far, of one of the candidate's corners is not measured (it cannot
  // raise either). +infinity without candidates.
  double single_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double settled2 = 0.0) const;

  // The prism pieces: the prism over each candidate facing like the part, along the part's
  // normal, cuts from it the convex piece that lies straight above or below that candidate, and
  // each piece is bounded at its corners against its candidate. Only valid when the pieces cover
  // the part: their areas add up to its area (a gap in the candidates' shadow or an overlap, as
  // where the output folds, changes the sum) and every piece that ends at an output edge inside
  // the part has the triangle across it among the pieces (an overlap cannot cancel a gap then).
  // The candidates are taken in order until their areas add up (best first: the ones after could
  // only overlap); +infinity when they never do, or do without that proof. Corners whose
  // distance along the normal to their candidate's plane is within `enough2` are not measured
  // exactly (that distance bounds theirs; below `enough2` it cannot raise a total).
  double prism_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double enough2) const;

  // The prism pieces when they cover the part within `enough2`; else the smaller of them and the
  // single candidate, the part split in four (midpoints) while that can lower it below the
  // corners' own distances and it exceeds `enough2`, down to depth kMaxRefineDepth. With
  // `queries` (a hierarchy over the same output triangles), the triangles nearest to the part's
  // corners and centroid, and to the split parts' midpoints, join the candidates.
  double bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double enough2,
                const measure::TriangleBvh* queries, int depth = 0) const;
  // bound2 after its first step: `prism2` is prism_bound2(part, candidates, enough2), already
  // known to the caller (with `queries`, candidates should hold the triangles nearest to the
  // part's corners and centroid, as bound2 adds them).
  double split_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double prism2,
                      double enough2, const measure::TriangleBvh* queries, int depth = 0) const;

  static constexpr int kMaxRefineDepth = 4;

 private:
  std::span<const Triangle3d> output_;
  std::vector<Vec3d> normal_;    // per output triangle: twice its area times its unit normal
  std::vector<Sphere> sphere_;   // per output triangle: bounding_sphere, widened by a hair for rounding
  std::vector<std::array<std::uint64_t, 3>> corner_key_;  // per output triangle: its corners' position keys
};

}  // namespace octolod::bake
