// Folded fans after a vertex clustering (bake/src/folded_fans.h): a wedge whose three triangles
// fold over themselves is replaced by its neighbours' triangle when that lies nearer the input;
// an unfolded fan, or one whose neighbours already have a triangle, stays. The grid method runs
// the pass on every step; its crack tests are lod_tree_test.cpp's.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "folded_fans.h"

namespace octolod::bake {
namespace {

// The input: the unit square in z = 0 as a 10 x 10 grid of quads (positions only). Its
// vertices near the square's corners (0,0), (1,0), (0,1) and (1,1) belong to the clusters 0, 1,
// 2 of the three neighbours u1, u2, u3 at those corners, those within 0.2 of (1/3, 1/3) to the
// cluster 3 of the fan's wedge v; each cluster is one wedge (wedge = cluster).
struct Square {
  NodeMesh mesh;
  std::vector<std::uint32_t> vertex_cluster;
};

const std::array<std::array<float, 3>, 3> kNeighbours{{{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}}};

Square make_square() {
  Square square;
  square.mesh.layout = {false, false, false};
  constexpr int n = 10;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = static_cast<float>(i) / n, y = static_cast<float>(j) / n;
      square.mesh.vertices.insert(square.mesh.vertices.end(), {x, y, 0.0f});
      const float dx = x - 1.0f / 3, dy = y - 1.0f / 3;
      std::uint32_t cluster = x + y > 1.0f ? (x > y ? 1 : 2) : (x > y ? (x > 0.5f ? 1 : 0) : (y > 0.5f ? 2 : 0));
      if (dx * dx + dy * dy < 0.04f) cluster = 3;
      square.vertex_cluster.push_back(cluster);
    }
  const auto id = [](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      square.mesh.indices.insert(square.mesh.indices.end(),
                                 {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
  return square;
}

// Wedge records: the three neighbours, then v at `v`.
std::vector<float> records(const std::array<float, 3>& v) {
  std::vector<float> out;
  for (const auto& p : kNeighbours) out.insert(out.end(), p.begin(), p.end());
  out.insert(out.end(), v.begin(), v.end());
  return out;
}

// remove_folded_fans on a clustered output.
FoldRepair remove_folds(const ClusteredOutput& out, std::vector<std::uint32_t>& corners) {
  InputDistances input(out);
  return remove_folded_fans(input, corners);
}

FoldRepair repair(const Square& square, const std::vector<float>& record, std::vector<std::uint32_t>& corners) {
  static const std::vector<std::uint32_t> wedge_cluster{0, 1, 2, 3};
  return remove_folds({square.mesh, square.vertex_cluster, 4, wedge_cluster, record, square.vertex_cluster}, corners);
}

TEST(FoldedFanTest, AFoldedFanIsReplacedByItsNeighboursTriangle) {
  const Square square = make_square();
  // v's representative beyond the neighbours' triangle, above the plane (another sheet's): of
  // the fan (v, u1, u2), (v, u2, u3), (v, u3, u1) the last is wound the other way, (v, u1, u3)
  const std::vector<float> record = records({1.2f, 1.2f, 0.3f});
  std::vector<std::uint32_t> corners{3, 0, 1, 3, 1, 2, 3, 0, 2};
  const FoldRepair done = repair(square, record, corners);
  EXPECT_EQ(corners, (std::vector<std::uint32_t>{0, 1, 2}));  // wound like two of the three
  EXPECT_EQ(done.index, (std::vector<std::uint32_t>{0, 0, 0}));
  ASSERT_EQ(done.fan_extra.size(), 1u);
  EXPECT_EQ(done.fan_extra[0], (std::array<std::uint32_t, 2>{3, 0}));
}

TEST(FoldedFanTest, AnUnfoldedFanStays) {
  const Square square = make_square();
  // a tent over the neighbours' triangle, wound consistently: a fan like any other
  const std::vector<float> record = records({0.33f, 0.33f, 0.3f});
  std::vector<std::uint32_t> corners{3, 0, 1, 3, 1, 2, 3, 2, 0};
  const std::vector<std::uint32_t> before = corners;
  const FoldRepair done = repair(square, record, corners);
  EXPECT_EQ(corners, before);
  EXPECT_EQ(done.index, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_TRUE(done.fan_extra.empty());
}

TEST(FoldedFanTest, AFanOfMoreThanThreeNeighboursStays) {
  // v's three triangles reach five neighbours (two of them near u2 and u3, wedges 4 and 5 of
  // their own clusters): not a closed fan, nothing to replace
  const Square square = make_square();
  std::vector<float> record = records({1.2f, 1.2f, 0.3f});
  record.insert(record.end(), {0.9f, 0.1f, 0.0f, 0.1f, 0.9f, 0.0f});
  std::vector<std::uint32_t> corners{3, 0, 1, 3, 4, 2, 3, 5, 0};
  const std::vector<std::uint32_t> before = corners;
  static const std::vector<std::uint32_t> wedge_cluster{0, 1, 2, 3, 4, 5};
  const FoldRepair done =
      remove_folds({square.mesh, square.vertex_cluster, 6, wedge_cluster, record, square.vertex_cluster}, corners);
  EXPECT_EQ(corners, before);
  EXPECT_TRUE(done.fan_extra.empty());
}

TEST(FoldedFanTest, NoReplacementWhereTheNeighboursHaveATriangle) {
  const Square square = make_square();
  const std::vector<float> record = records({1.2f, 1.2f, 0.3f});
  // the folded fan, and the neighbours' triangle already there (facing down: a closed bubble)
  std::vector<std::uint32_t> corners{3, 0, 1, 3, 1, 2, 3, 0, 2, 0, 2, 1};
  const std::vector<std::uint32_t> before = corners;
  repair(square, record, corners);
  EXPECT_EQ(corners, before);
}

}  // namespace
}  // namespace octolod::bake
