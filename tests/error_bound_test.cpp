// The conservative step error (bake/src/error_bound.h): never below the true one-sided
// Hausdorff distance, and close to it where an input triangle reaches across output edges,
// with and without the clustering's hints. The bound along whole LOD chains is checked by
// LodTest.EveryLodErrorBoundsTheMeasuredHausdorff (cluster_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "error_bound.h"
#include "octolod/measure/triangle_bvh.h"
#include "part_bound.h"

namespace octolod::bake {
namespace {

using Point = std::array<float, 3>;

NodeMesh triangles(const std::vector<std::array<Point, 3>>& corners) {
  NodeMesh mesh;
  mesh.layout = {false, false, false};
  for (const auto& triangle : corners)
    for (const Point& p : triangle) {
      mesh.indices.push_back(static_cast<std::uint32_t>(mesh.vertex_count()));
      mesh.vertices.insert(mesh.vertices.end(), p.begin(), p.end());
    }
  return mesh;
}

// The unit square at height z as two triangles split along its diagonal (0,0) - (1,1).
std::vector<std::array<Point, 3>> square(float z) {
  return {{{{0, 0, z}, {1, 0, z}, {1, 1, z}}}, {{{0, 0, z}, {1, 1, z}, {0, 1, z}}}};
}

// max over points of `input` (a dense barycentric grid on each triangle) of the distance to
// `output`: the true one-sided Hausdorff distance from below.
double sampled_hausdorff(const NodeMesh& input, const NodeMesh& output) {
  const measure::TriangleBvh bvh(output.vertices, output.layout.floats(), output.indices);
  constexpr int kSteps = 60;
  double worst = 0.0;
  for (std::size_t t = 0; t < input.triangle_count(); ++t) {
    const float* c[3];
    for (std::size_t k = 0; k < 3; ++k) c[k] = &input.vertices[input.indices[3 * t + k] * input.layout.floats()];
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; i + j <= kSteps; ++j) {
        const float u = static_cast<float>(i) / kSteps, v = static_cast<float>(j) / kSteps, w = 1.0f - u - v;
        const glm::vec3 p(u * c[0][0] + v * c[1][0] + w * c[2][0], u * c[0][1] + v * c[1][1] + w * c[2][1],
                          u * c[0][2] + v * c[1][2] + w * c[2][2]);
        worst = std::max(worst, static_cast<double>(bvh.closest(p).distance));
      }
  }
  return worst;
}

// One input triangle 0.01 above the square, reaching across its diagonal: a corner of one
// output triangle is 0.5 from the other, so one output triangle for the whole input triangle
// bounds it by about 0.5; the pieces over each output triangle bound it by 0.01.
const std::vector<std::array<Point, 3>> kStraddling{{{{0.1f, 0.1f, 0.01f}, {0.9f, 0.2f, 0.01f}, {0.2f, 0.9f, 0.01f}}}};

TEST(ErrorBound, AStraddlingTriangleIsBoundedByItsDistanceNotItsReach) {
  const NodeMesh input = triangles(kStraddling);
  const NodeMesh output = triangles(square(0.0f));
  const double bound = hausdorff_upper_bound(input, output);
  EXPECT_GE(bound, 0.01 * (1.0 - 1e-6));
  EXPECT_LE(bound, 0.0101);
}

TEST(ErrorBound, DoesNotGrowWithTheDistanceFromTheOrigin) {
  // The straddling triangle and the square in sixty-fourths (the height 1/64), then the same
  // 4096 units away: shifted exactly, the same geometry, the same bound. The margin for
  // distances measured in float (8 float epsilons of the largest coordinate: 0.0039 there, a
  // quarter of the distance) belongs to the stored errors once, not to every step's bound.
  auto scene = [](float offset) {
    auto at = [offset](float x, float y, float z) { return Point{x + offset, y + offset, z}; };
    const float h = 1.0f / 64.0f;
    return std::pair{triangles({{{at(0.125f, 0.125f, h), at(0.875f, 0.1875f, h), at(0.1875f, 0.875f, h)}}}),
                     triangles({{{at(0, 0, 0), at(1, 0, 0), at(1, 1, 0)}}, {{at(0, 0, 0), at(1, 1, 0), at(0, 1, 0)}}})};
  };
  const auto [input, output] = scene(0.0f);
  const auto [far_input, far_output] = scene(4096.0f);
  const double bound = hausdorff_upper_bound(input, output);
  EXPECT_NEAR(bound, 1.0 / 64.0, 1e-7);
  EXPECT_EQ(hausdorff_upper_bound(far_input, far_output), bound);
  EXPECT_NEAR(float_measurement_margin(far_input.bounds()), 8.0 * std::numeric_limits<float>::epsilon() * 4096.875, 1e-12);
}

TEST(ErrorBound, HintsGiveTheSameBoundAsQueries) {
  // The hints name only the lower-right output triangle as the input triangle's image; the
  // corners' nearest triangles (the upper-left one for the corner above it) complete the pieces.
  const NodeMesh input = triangles(kStraddling);
  const NodeMesh output = triangles(square(0.0f));
  const std::vector<std::uint32_t> image{0};
  const std::vector<std::uint32_t> vertex_cluster{0, 0, 0};
  const std::vector<std::uint32_t> fan_offset{0, 1};
  const std::vector<std::uint32_t> fan_triangle{0};
  const ImageHints hints{image, vertex_cluster, fan_offset, fan_triangle};
  const double hinted = hausdorff_upper_bound(input, output, hints);
  EXPECT_GE(hinted, 0.01 * (1.0 - 1e-6));
  EXPECT_LE(hinted, 0.0101);
  EXPECT_NEAR(hinted, hausdorff_upper_bound(input, output), 1e-9);
  // a caller that gives up above a distance gets the bound up to it, +infinity beyond
  EXPECT_EQ(hausdorff_upper_bound(input, output, hints, hinted), hinted);
  EXPECT_EQ(hausdorff_upper_bound(input, output, hints, 0.5 * hinted), std::numeric_limits<double>::infinity());
}

TEST(ErrorBound, AFoldInTheOutputDoesNotHideTheDistance) {
  // Over the lower-right half the output has a second sheet 0.3 higher, facing the same way:
  // the prism pieces overlap there (their areas add up to more than the input's), so the bound
  // does not use them; it stays at the true 0.01 and above it.
  auto folded = square(0.0f);
  folded.push_back({{{0, 0, 0.3f}, {1, 0, 0.3f}, {1, 1, 0.3f}}});
  const NodeMesh input = triangles(kStraddling);
  const NodeMesh output = triangles(folded);
  const double bound = hausdorff_upper_bound(input, output);
  EXPECT_GE(bound, 0.01 * (1.0 - 1e-6));
  EXPECT_LE(bound, 0.011);
}

TEST(PartBound, ThePrismPiecesCountOnlyOnceTheyProvablyCoverThePart) {
  // The square's two triangles tile the straddling triangle's shadow: its bound is its height,
  // and a sheet 0.3 higher over the lower-right half, listed after them, is not looked at. Listed
  // before them, the sheet and the lower-right triangle have exactly the part's area between them
  // (the diagonal halves it) though half of it lies under neither; the areas alone would pass,
  // the missing triangle across the diagonal does not. The same without the upper-left triangle.
  const std::vector<Triangle3d> output{{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}},
                                       {{{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
                                       {{{0, 0, 0.3}, {1, 0, 0.3}, {1, 1, 0.3}}}};
  const PartBounder bounder(output);
  const Triangle3d part{{{0.1, 0.1, 0.01}, {0.9, 0.2, 0.01}, {0.2, 0.9, 0.01}}};
  const std::vector<std::uint32_t> square{0, 1}, square_first{0, 1, 2}, sheet_first{2, 0, 1}, half_and_sheet{0, 2};
  EXPECT_NEAR(std::sqrt(bounder.prism_bound2(part, square, 0.0)), 0.01, 1e-9);
  EXPECT_NEAR(std::sqrt(bounder.prism_bound2(part, square_first, 0.0)), 0.01, 1e-9);
  EXPECT_EQ(bounder.prism_bound2(part, sheet_first, 0.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(bounder.prism_bound2(part, half_and_sheet, 0.0), std::numeric_limits<double>::infinity());
}

TEST(PartBound, APartWoundTheOtherWayIsCoveredByTheCandidatesFacingAway) {
  // The straddling part wound clockwise faces away from the square: the square's triangles
  // tile its shadow all the same (for the part wound back), and bound it by its height.
  const std::vector<Triangle3d> output{{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}}, {{{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}}};
  const PartBounder bounder(output);
  const Triangle3d part{{{0.1, 0.1, 0.01}, {0.2, 0.9, 0.01}, {0.9, 0.2, 0.01}}};
  const std::vector<std::uint32_t> square{0, 1};
  EXPECT_NEAR(std::sqrt(bounder.prism_bound2(part, square, 0.0)), 0.01, 1e-9);
}

// The unit square at height 0 as an n x n grid of quads, two triangles each; with `wound` false
// for a triangle, that triangle wound the other way.
std::vector<Triangle3d> square_grid(int n, const std::vector<bool>& wound) {
  std::vector<Triangle3d> grid;
  auto at = [n](int i, int j) { return Vec3d{static_cast<double>(i) / n, static_cast<double>(j) / n, 0.0}; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      for (Triangle3d t : {Triangle3d{at(i, j), at(i + 1, j), at(i + 1, j + 1)}, Triangle3d{at(i, j), at(i + 1, j + 1), at(i, j + 1)}}) {
        if (!wound[grid.size()]) std::swap(t[1], t[2]);
        grid.push_back(t);
      }
  return grid;
}

TEST(PartBound, AnOutputWoundAtRandomTilesThePartsShadowAsWoundConsistently) {
  // A 4 x 4 grid under the straddling part with half its triangles wound the other way: the
  // pieces over the triangles facing like the part leave holes, over those facing away the
  // rest. The bounder re-winds the output consistently and the part is bounded by its height
  // either way round.
  constexpr int kGrid = 4;
  std::vector<bool> consistent(2 * kGrid * kGrid, true), mixed(2 * kGrid * kGrid, true);
  std::minstd_rand coin(1);
  for (std::size_t t = 0; t < mixed.size(); ++t) mixed[t] = coin() % 2 == 0;
  const std::vector<Triangle3d> good = square_grid(kGrid, consistent), bad = square_grid(kGrid, mixed);
  std::vector<std::uint32_t> all(good.size());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<std::uint32_t>(t);
  const Triangle3d part{{{0.1, 0.1, 0.01}, {0.9, 0.2, 0.01}, {0.2, 0.9, 0.01}}};
  const Triangle3d reversed{part[0], part[2], part[1]};
  const PartBounder consistent_bounder(good), mixed_bounder(bad);
  EXPECT_NEAR(std::sqrt(consistent_bounder.prism_bound2(part, all, 0.0)), 0.01, 1e-9);
  EXPECT_NEAR(std::sqrt(mixed_bounder.prism_bound2(part, all, 0.0)), 0.01, 1e-9);
  EXPECT_NEAR(std::sqrt(mixed_bounder.prism_bound2(reversed, all, 0.0)), 0.01, 1e-9);
  // distances do not depend on the winding
  for (std::uint32_t t : all) EXPECT_EQ(mixed_bounder.distance2(part[1], t), consistent_bounder.distance2(part[1], t));
}

TEST(PartBound, TheNeighboursWalkFromOneCandidateToTheWholeShadow) {
  // One grid triangle under the part's first corner: its piece ends at its sides inside the
  // part, and the walk across them and on reaches every triangle under the part (an 8 x 8 grid:
  // the part lies over dozens), bounding it by its height. Offered again, a piece's triangle
  // does not count twice. With the grid's centre cut out, the walk runs out: not covered.
  constexpr int kGrid = 8;
  const std::vector<Triangle3d> grid = square_grid(kGrid, std::vector<bool>(2 * kGrid * kGrid, true));
  const Triangle3d part{{{0.1, 0.1, 0.01}, {0.9, 0.2, 0.01}, {0.2, 0.9, 0.01}}};
  const PartBounder bounder(grid);
  const std::uint32_t under_first_corner = 0;  // the lower-right half of the quad at (0, 0)
  ASSERT_LT(bounder.distance2(part[0], under_first_corner), 0.011 * 0.011);
  PartBounder::Prism prism(bounder, part, 0.0);
  EXPECT_FALSE(prism.offer(under_first_corner));
  EXPECT_FALSE(prism.offer(under_first_corner));
  EXPECT_TRUE(prism.offer_neighbours());
  EXPECT_NEAR(std::sqrt(prism.bound2()), 0.01, 1e-9);

  std::vector<Triangle3d> holed;
  for (std::size_t t = 0; t < grid.size(); ++t)
    if (t / 2 != (kGrid / 2) * kGrid + kGrid / 2) holed.push_back(grid[t]);  // without quad (4, 4)
  const PartBounder holed_bounder(holed);
  PartBounder::Prism around_the_hole(holed_bounder, part, 0.0);
  EXPECT_FALSE(around_the_hole.offer(under_first_corner));
  EXPECT_FALSE(around_the_hole.offer_neighbours());
  EXPECT_EQ(around_the_hole.bound2(), std::numeric_limits<double>::infinity());
}

TEST(ErrorBound, AGapInTheOutputIsMeasuredAcrossIt) {
  // Only the lower-right output triangle: the input's corner above the diagonal is about 0.5
  // from it. The bound covers the gap (no piece there) and stays close to the true distance.
  const NodeMesh input = triangles(kStraddling);
  const NodeMesh output = triangles({square(0.0f)[0]});
  const double bound = hausdorff_upper_bound(input, output);
  const double measured = sampled_hausdorff(input, output);
  EXPECT_GE(bound + float_measurement_margin(input.bounds()), measured);
  EXPECT_LE(bound, measured * 1.05);
}

TEST(ErrorBound, NeverBelowTheSampledDistanceOnABumpyGrid) {
  // A bumpy 12 x 12 height field against a coarse 3 x 3 one, both ways up: every input triangle
  // reaches across several output edges, some output triangles stand steep under them.
  auto height = [](float x, float y, float amplitude) {
    return amplitude * std::sin(7.0f * x) * std::cos(5.0f * y + 1.0f);
  };
  auto grid = [&](int n, float amplitude) {
    std::vector<std::array<Point, 3>> corners;
    auto point = [&](int i, int j) {
      const float x = static_cast<float>(i) / static_cast<float>(n), y = static_cast<float>(j) / static_cast<float>(n);
      return Point{x, y, height(x, y, amplitude)};
    };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        corners.push_back({point(i, j), point(i + 1, j), point(i + 1, j + 1)});
        corners.push_back({point(i, j), point(i + 1, j + 1), point(i, j + 1)});
      }
    return corners;
  };
  for (const float amplitude : {0.05f, 0.3f}) {
    const NodeMesh fine = triangles(grid(12, amplitude));
    const NodeMesh coarse = triangles(grid(3, amplitude));
    for (const auto& [input, output] : {std::pair{&fine, &coarse}, std::pair{&coarse, &fine}}) {
      const double bound = hausdorff_upper_bound(*input, *output);
      const double measured = sampled_hausdorff(*input, *output);
      EXPECT_GE(bound + float_measurement_margin(input->bounds()), measured) << "amplitude " << amplitude;
      EXPECT_LE(bound, measured * 1.5) << "amplitude " << amplitude;
    }
  }
}

}  // namespace
}  // namespace octolod::bake
