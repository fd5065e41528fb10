// Edge flips after a vertex clustering (bake/src/diagonal_flips.h): a quad whose diagonal cuts
// under a ridge is flipped onto the ridge, one whose diagonal follows it is left alone, and no
// flip crosses an attribute seam or doubles an edge. The grid method runs the flips on every
// step; its boundary and crack tests are cluster_test.cpp's and lod_tree_test.cpp's.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "diagonal_flips.h"

namespace octolod::bake {
namespace {

constexpr float kRidgeHeight = 0.5f;

// The roof z = h (1 - |y|) over [-1, 1]^2 with its ridge on y = 0, as a (2n)^2 grid of quads
// (positions only), and each vertex's cluster: the nearest of four quad corners (by default
// those below).
struct Roof {
  NodeMesh mesh;
  std::vector<std::uint32_t> vertex_cluster;
};

// The four quad corners, all on the roof: a and b at the eaves' middle (y = -1 and 1), c and d at
// the ridge's ends (x = -1 and 1).
const std::array<std::array<float, 3>, 4> kCorners{{
    {0.0f, -1.0f, 0.0f},
    {0.0f, 1.0f, 0.0f},
    {-1.0f, 0.0f, kRidgeHeight},
    {1.0f, 0.0f, kRidgeHeight},
}};

Roof make_roof(int n, const std::array<std::array<float, 3>, 4>& corners = kCorners) {
  Roof roof;
  roof.mesh.layout = {false, false, false};
  const int side = 2 * n + 1;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const float x = static_cast<float>(i - n) / static_cast<float>(n);
      const float y = static_cast<float>(j - n) / static_cast<float>(n);
      const float z = kRidgeHeight * (1.0f - std::abs(y));
      roof.mesh.vertices.insert(roof.mesh.vertices.end(), {x, y, z});
      std::uint32_t nearest = 0;
      float best = INFINITY;
      for (std::uint32_t c = 0; c < 4; ++c) {
        const float dx = x - corners[c][0], dy = y - corners[c][1], dz = z - corners[c][2];
        const float d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best) best = d2, nearest = c;
      }
      roof.vertex_cluster.push_back(nearest);
    }
  const auto id = [side](int i, int j) { return static_cast<std::uint32_t>(j * side + i); };
  for (int j = 0; j + 1 < side; ++j)
    for (int i = 0; i + 1 < side; ++i)
      roof.mesh.indices.insert(roof.mesh.indices.end(),
                               {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
  return roof;
}

// Wedge records (positions only) of the given corners, in that order.
std::vector<float> records(const std::vector<std::array<float, 3>>& positions) {
  std::vector<float> out;
  for (const auto& p : positions) out.insert(out.end(), p.begin(), p.end());
  return out;
}

// The triangles' z components of their normals are all positive (none turned over).
bool all_face_up(const std::vector<float>& record, const std::vector<std::uint32_t>& corners) {
  for (std::size_t t = 0; t < corners.size(); t += 3) {
    const float* p0 = &record[3 * corners[t]];
    const float* p1 = &record[3 * corners[t + 1]];
    const float* p2 = &record[3 * corners[t + 2]];
    const float ux = p1[0] - p0[0], uy = p1[1] - p0[1], vx = p2[0] - p0[0], vy = p2[1] - p0[1];
    if (!(ux * vy - uy * vx > 0.0f)) return false;
  }
  return true;
}

// flip_diagonals on a clustered output.
std::size_t flip(const ClusteredOutput& out, std::vector<std::uint32_t>& corners) {
  InputDistances input(out);
  return flip_diagonals(input, corners);
}

// flip_diagonals on the roof with these wedges (clusters, positions) and triangles: no flip,
// the triangles unchanged.
void expect_no_flip(std::uint32_t cluster_count, const std::vector<std::uint32_t>& wedge_cluster,
                    const std::vector<float>& record, std::vector<std::uint32_t> corners) {
  const Roof roof = make_roof(8);
  const std::vector<std::uint32_t> before = corners;
  EXPECT_EQ(flip({roof.mesh, roof.vertex_cluster, cluster_count, wedge_cluster, record, {}}, corners), 0u);
  EXPECT_EQ(corners, before);
}

TEST(DiagonalFlipTest, ADiagonalUnderTheRidgeIsFlippedOntoIt) {
  const Roof roof = make_roof(8);
  const std::vector<std::uint32_t> wedge_cluster{0, 1, 2, 3};
  const std::vector<float> record = records({kCorners[0], kCorners[1], kCorners[2], kCorners[3]});
  // (a, b, c) and (b, a, d): the diagonal a-b crosses the ridge, its midpoint h below it
  std::vector<std::uint32_t> corners{0, 1, 2, 1, 0, 3};
  ASSERT_TRUE(all_face_up(record, corners));
  EXPECT_EQ(flip({roof.mesh, roof.vertex_cluster, 4, wedge_cluster, record, {}}, corners), 1u);
  // now (a, d, c) and (b, c, d): the diagonal c-d runs along the ridge
  EXPECT_EQ(corners, (std::vector<std::uint32_t>{0, 3, 2, 1, 2, 3}));
  EXPECT_TRUE(all_face_up(record, corners));
}

TEST(DiagonalFlipTest, ADiagonalAlongTheRidgeStays) {
  // the same quad named the other way round: its diagonal c-d is the shared edge
  const std::vector<float> record = records({kCorners[2], kCorners[3], kCorners[1], kCorners[0]});
  const std::vector<std::uint32_t> corners{0, 1, 2, 1, 0, 3};
  ASSERT_TRUE(all_face_up(record, corners));
  expect_no_flip(4, {2, 3, 1, 0}, record, corners);
}

TEST(DiagonalFlipTest, NoFlipThatTurnsATriangleAway) {
  // a bent quad on the roof whose other diagonal's midpoint is nearer the roof (0.019 against
  // 0.082), but the flipped (a, d, c) would face more than 60 degrees away from the pair
  const std::array<std::array<float, 3>, 4> quad{{
      {-0.030f, 0.627f, 0.145f},
      {0.722f, -0.112f, 0.414f},
      {0.285f, 0.541f, 0.226f},
      {-0.074f, 0.637f, 0.222f},
  }};
  const Roof roof = make_roof(8, quad);
  const std::vector<std::uint32_t> wedge_cluster{0, 1, 2, 3};
  const std::vector<float> record = records({quad[0], quad[1], quad[2], quad[3]});
  std::vector<std::uint32_t> corners{0, 1, 2, 1, 0, 3};
  ASSERT_TRUE(all_face_up(record, corners));
  EXPECT_EQ(flip({roof.mesh, roof.vertex_cluster, 4, wedge_cluster, record, {}}, corners), 0u);
  EXPECT_EQ(corners, (std::vector<std::uint32_t>{0, 1, 2, 1, 0, 3}));
}

TEST(DiagonalFlipTest, NoFlipAcrossAnAttributeSeam) {
  // wedge 4 is a second wedge of cluster 0 (a) at the same position: the two triangles meet at a
  // with different attribute values, so a-b is a seam
  expect_no_flip(4, {0, 1, 2, 3, 0}, records({kCorners[0], kCorners[1], kCorners[2], kCorners[3], kCorners[0]}),
                 {0, 1, 2, 1, 4, 3});
}

TEST(DiagonalFlipTest, NoFlipOntoAnEdgeThatExists) {
  // a fifth wedge e (its own cluster, above the ridge's middle) with a triangle (c, d, e)
  // already joining c and d: the flip would use c-d twice on one side
  expect_no_flip(5, {0, 1, 2, 3, 4},
                 records({kCorners[0], kCorners[1], kCorners[2], kCorners[3], {0.0f, 0.0f, 2.0f}}),
                 {0, 1, 2, 1, 0, 3, 2, 3, 4});
}

}  // namespace
}  // namespace octolod::bake
