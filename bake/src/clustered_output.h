// What the passes after a vertex clustering's output rule (diagonal_flips.h, folded_fans.h) see:
// the clustered input, its clusters, and the output's wedges; and the distances from points to
// the input triangles around a few clusters, with which they judge a change.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "octolod/formats/node_file.h"
#include "point_triangle.h"

namespace octolod::bake {

struct ClusteredOutput {
  const NodeMesh& input;                          // the clustered mesh (model units)
  std::span<const std::uint32_t> vertex_cluster;  // per input vertex
  std::uint32_t cluster_count;
  std::span<const std::uint32_t> wedge_cluster;   // per output wedge
  std::span<const float> wedge_record;            // per output wedge: input.layout's floats
  std::span<const std::uint32_t> vertex_wedge;    // per input vertex: its wedge

  Vec3d wedge_position(std::uint32_t wedge) const {
    const float* f = &wedge_record[wedge * input.layout.floats()];
    return {f[0], f[1], f[2]};
  }
};

// Squared distances from points to the input triangles with a corner in given clusters. The
// triangles of every cluster are gathered (CSR) at the first query, so a step whose passes ask
// nothing pays nothing, and the passes of one step share them. `out` must outlive it.
class InputDistances {
 public:
  explicit InputDistances(const ClusteredOutput& out) : out_(out) {}

  const ClusteredOutput& output() const { return out_; }

  // distance2[i] = min over the input triangles with a corner in one of `clusters` (each
  // counted once) of the squared distance from points[i] to it; +infinity when there are none.
  void nearest2(std::span<const std::uint32_t> clusters, std::span<const Vec3d> points, std::span<double> distance2);

  // Whether nearest2 of `candidate` is below `share` (>= 0) times nearest2 of `current`, over
  // the same triangles: the answer of comparing the two, but `candidate` is measured only
  // against the triangles that may still bring it below share times the best of `current` so far.
  bool nearer(std::span<const std::uint32_t> clusters, const Vec3d& candidate, const Vec3d& current, double share);

 private:
  void gather();
  // f(t) for every input triangle t with a corner in one of `clusters`, once each, in the list's
  // order; gathers first.
  template <class F>
  void for_each_triangle(std::span<const std::uint32_t> clusters, const F& f);
  // False when triangle t's sphere is no nearer to p than squared distance `distance2`: then
  // neither is the triangle.
  bool may_be_nearer(std::uint32_t t, const Vec3d& p, double distance2) const;

  const ClusteredOutput& out_;
  bool gathered_ = false;
  std::vector<std::uint32_t> offset_;    // per cluster, into triangle_
  std::vector<std::uint32_t> triangle_;  // a triangle once per distinct cluster of its corners
  struct FloatSphere {
    std::array<float, 3> center;
    float radius;
  };
  std::vector<FloatSphere> sphere_;  // per input triangle: holds its corners (skips far triangles)
  // per input triangle: the number of the last query that met it (queries count from 1), so
  // that a triangle at several of a query's clusters is measured once without comparing its
  // corners' clusters with the earlier ones of the list
  std::vector<std::uint32_t> met_in_;
  std::uint32_t query_ = 0;
};

}  // namespace octolod::bake
