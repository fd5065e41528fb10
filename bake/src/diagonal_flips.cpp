// diagonal_flips.h: one pass over the output's edges with a cluster-pair edge table.
#include "diagonal_flips.h"

#include <array>
#include <cmath>

#include "flat_hash.h"
#include "point_triangle.h"

namespace octolod::bake {
namespace {

// Bent pairs only: the two triangles' normals at least this far apart (cosine). Between nearly
// coplanar triangles the diagonal hardly moves the surface.
constexpr double kMinBendCosine = 0.98;
// Each flipped triangle faces within 60 degrees of the pair it replaces (their summed normals):
// a flip to a long diagonal across a concave quad would otherwise stand slivers off the surface.
constexpr double kMinFacingCosine = 0.5;
// A flip must lower the squared distance by this share, so that rounding never decides it.
constexpr double kMinGain = 0.05;

struct EdgeUse {
  std::uint32_t uses = 0;
  std::uint32_t corner[2] = {0, 0};  // the first two uses: 3 * triangle + k, the edge k -> k+1
};

}  // namespace

std::size_t flip_diagonals(InputDistances& input, std::vector<std::uint32_t>& corners) {
  const ClusteredOutput& out = input.output();
  const std::size_t triangle_count = corners.size() / 3;
  auto cluster_of = [&](std::size_t corner) { return out.wedge_cluster[corners[corner]]; };
  auto edge_key = [](std::uint32_t a, std::uint32_t b) {
    return a < b ? std::array<std::uint32_t, 2>{a, b} : std::array<std::uint32_t, 2>{b, a};
  };

  // cluster-pair edges: uses and the first two corners using them; new diagonals join the table
  FlatHashMap<2> edge_of(corners.size() + triangle_count);
  std::vector<EdgeUse> edges;
  edges.reserve(corners.size() / 2 + 1);
  auto use_edge = [&](std::size_t corner, std::size_t next) {
    bool inserted = false;
    const std::uint32_t e = edge_of.find_or_insert(edge_key(cluster_of(corner), cluster_of(next)),
                                                   static_cast<std::uint32_t>(edges.size()), inserted);
    if (inserted) edges.emplace_back();
    EdgeUse& use = edges[e];
    if (use.uses < 2) use.corner[use.uses] = static_cast<std::uint32_t>(corner);
    ++use.uses;
  };
  for (std::size_t corner = 0; corner < corners.size(); corner += 3)
    use_edge(corner, corner + 1), use_edge(corner + 1, corner + 2), use_edge(corner + 2, corner);

  // the wedges of a corner's triangle from that corner on (k, k + 1, k + 2 mod 3, from a table)
  auto from_corner = [&](std::uint32_t corner) {
    static constexpr std::size_t kNext[3] = {1, 2, 0};
    const std::size_t base = corner / 3 * 3, k = corner - base;
    return std::array<std::uint32_t, 3>{corners[base + k], corners[base + kNext[k]], corners[base + kNext[kNext[k]]]};
  };
  std::vector<std::uint8_t> flipped(triangle_count, 0);
  std::size_t flips = 0;
  const std::size_t original_edges = edges.size();
  for (std::size_t e = 0; e < original_edges; ++e) {
    if (edges[e].uses != 2) continue;
    const std::uint32_t c0 = edges[e].corner[0], c1 = edges[e].corner[1];
    const std::size_t t0 = c0 / 3, t1 = c1 / 3;
    if (flipped[t0] || flipped[t1]) continue;
    // t0 = (a, b, c), t1 = (b, a, d) with the same wedges a and b
    const auto [a, b, c] = from_corner(c0);
    const auto [b1, a1, d] = from_corner(c1);
    if (b1 != b || a1 != a) continue;
    const std::uint32_t cc = out.wedge_cluster[c], cd = out.wedge_cluster[d];
    if (cc == cd || edge_of.find(edge_key(cc, cd)) != FlatHashMap<2>::kMissing) continue;

    const Vec3d pa = out.wedge_position(a), pb = out.wedge_position(b), pc = out.wedge_position(c), pd = out.wedge_position(d);
    const Vec3d n0 = cross(sub(pb, pa), sub(pc, pa)), n1 = cross(sub(pa, pb), sub(pd, pb));
    const double l0 = std::sqrt(dot(n0, n0)), l1 = std::sqrt(dot(n1, n1));
    if (!(l0 > 0.0 && l1 > 0.0) || dot(n0, n1) > kMinBendCosine * l0 * l1) continue;
    // the flipped pair (a, d, c), (b, c, d) must face like the pair it replaces
    const Vec3d m0 = cross(sub(pd, pa), sub(pc, pa)), m1 = cross(sub(pc, pb), sub(pd, pb));
    const Vec3d facing{n0[0] + n1[0], n0[1] + n1[1], n0[2] + n1[2]};
    const double facing_length = std::sqrt(dot(facing, facing));
    auto faces_like_the_pair = [&](const Vec3d& m) {
      return dot(m, facing) > kMinFacingCosine * std::sqrt(dot(m, m)) * facing_length;
    };
    if (!(faces_like_the_pair(m0) && faces_like_the_pair(m1))) continue;

    // the diagonals' midpoints by their squared distances to the input triangles at the quad's
    // four clusters
    const std::array<std::uint32_t, 4> quad{out.wedge_cluster[a], out.wedge_cluster[b], cc, cd};
    if (!input.nearer(quad, midpoint(pc, pd), midpoint(pa, pb), 1.0 - kMinGain)) continue;

    corners[3 * t0] = a, corners[3 * t0 + 1] = d, corners[3 * t0 + 2] = c;
    corners[3 * t1] = b, corners[3 * t1 + 1] = c, corners[3 * t1 + 2] = d;
    flipped[t0] = flipped[t1] = 1;
    bool inserted = false;
    edge_of.find_or_insert(edge_key(cc, cd), static_cast<std::uint32_t>(edges.size()), inserted);
    edges.push_back({2, {0, 0}});
    ++flips;
  }
  return flips;
}

}  // namespace octolod::bake
