// Bounds of an input triangle, or of a part of one, against candidate output triangles: the
// pieces of the conservative step error (error_bound.h). Every bound is an upper bound of the
// largest distance from a point of the part to the output triangles, squared (model units²,
// the frame of the triangles given), by the convexity of x -> dist(x, T) for one triangle T.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "error_bound.h"
#include "octolod/measure/triangle_bvh.h"
#include "point_triangle.h"

namespace octolod::bake {

using Triangle3d = std::array<Vec3d, 3>;

// The index of the triangle of `bvh` nearest to p.
std::uint32_t closest_triangle(const measure::TriangleBvh& bvh, const Vec3d& p);

class PartBounder {
 public:
  // `output`: the output mesh's triangles (double corners), indexed as the candidates below;
  // borrowed, must outlive the bounder. Keeps 68 bytes per triangle (normal, bounding sphere,
  // the triangles across its edges), and a copy of the output re-wound where its winding is
  // inconsistent (across an edge of two triangles, both run it the same way): the prism pieces
  // need neighbours that face alike. Distances do not depend on the winding.
  explicit PartBounder(std::span<const Triangle3d> output);

  double distance2(const Vec3d& p, std::uint32_t triangle) const;
  // min over `candidates` of distance2(p, .); +infinity when there is none.
  double nearest2(const Vec3d& p, std::span<const std::uint32_t> candidates) const;

  // A corner's distance2 to one output triangle, measured before.
  struct Measured {
    std::uint32_t triangle;
    double distance2;
  };

  // One piece: min over the candidates of the max over the part's corners of the distance to it.
  // Tight where the part lies over one output triangle; where it reaches across an output edge
  // it is about how far it reaches. A candidate within `settled2` ends the search (the result is
  // then only known to be at most `settled2`), and a corner within that, or within the
  // candidate's worst so far, of one of the candidate's corners is not measured (it cannot
  // raise either); nor is corner k against measured[k].triangle (when given). +infinity without
  // candidates.
  double single_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double settled2 = 0.0,
                       const std::array<Measured, 3>* measured = nullptr) const;

  // The prism pieces: the prism over each candidate facing like the part, along the part's
  // normal, cuts from it the convex piece that lies straight above or below that candidate, and
  // each piece is bounded at its corners against its candidate. Only valid when the pieces cover
  // the part: their areas add up to its area (a gap in the candidates' shadow or an overlap, as
  // where the output folds, changes the sum) and every piece that ends at an output edge inside
  // the part has the triangle across it among the pieces (an overlap cannot cancel a gap then).
  // The candidates are taken in order until their areas add up (best first: the ones after could
  // only overlap); +infinity when they never do, or do without that proof. Corners whose
  // distance along the normal to their candidate's plane is within `enough2` are not measured
  // exactly (that distance bounds theirs; below `enough2` it cannot raise a total). Where the
  // candidates facing like the part do not cover it, those facing away are tried for the part
  // wound the other way (an input wound inconsistently has parts facing away from the surface).
  double prism_bound2(const Triangle3d& part, std::span<const std::uint32_t> candidates, double enough2) const;

  // prism_bound2 one candidate at a time, for callers that find more candidates only when the
  // first ones do not cover the part. Borrows the bounder and the part.
  class Prism {
   public:
    Prism(const PartBounder& bounder, const Triangle3d& part, double enough2);
    // Cuts the candidate's piece from the part. True once the outcome is known: the pieces
    // cover the part (further candidates could only overlap), or never will (their areas add up
    // without the proof of cover, a degenerate part, too many pieces). A candidate offered
    // before is passed over.
    bool offer(std::uint32_t candidate);
    // Offers the output triangles across the prism sides where the pieces end inside the part,
    // and across theirs, until the outcome is known (true) or there are none left: the
    // candidates a part straddling output edges needs, without the fans around its corners.
    bool offer_neighbours();
    // The bound of the pieces once they cover the part; else, when the candidates offered that
    // face away from it cover it wound the other way, theirs; +infinity when neither does.
    double bound2() const;

   private:
    static constexpr std::size_t kMaxPieces = 64;
    bool closed() const;

    const PartBounder& bounder_;
    const Triangle3d& part_;
    double enough2_;
    double twice_area_ = 0.0, radius_ = 0.0;  // the part's, and its bounding sphere's around middle_
    Vec3d unit_{}, x_axis_{}, y_axis_{}, middle_{};  // its unit normal, its plane's axes, its centroid
    std::array<std::array<double, 2>, 3> part2d_{};  // its corners in its plane (x_axis_, y_axis_)
    double covered_ = 0.0, worst2_ = 0.0;  // twice the pieces' area, their bound
    bool settled_ = false, covers_ = false;
    std::size_t piece_count_ = 0;
    std::uint32_t piece_triangle_[kMaxPieces];  // the candidates with a piece
    unsigned piece_open_[kMaxPieces];           // the prism sides their pieces end at inside the part
    std::size_t facing_away_count_ = 0;
    std::uint32_t facing_away_[kMaxPieces];  // the candidates within reach that face away from the part
  };

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
  std::vector<Triangle3d> oriented_;  // the output re-wound consistently, where it was not (then output_)
  std::span<const Triangle3d> output_;
  std::vector<Vec3d> normal_;    // per output triangle: twice its area times its unit normal
  std::vector<Sphere> sphere_;   // per output triangle: bounding_sphere, widened by a hair for rounding
  // per output triangle and edge k (corner k to k + 1): the first other triangle that runs the
  // edge backwards (corner positions equal), or kNoTriangle (the prism's cover proof looks for
  // it among the pieces)
  std::vector<std::array<std::uint32_t, 3>> across_;
};

}  // namespace octolod::bake
