// The grid's cells split where they hold opposite facings (cluster_grid.cpp,
// split_opposite_facings; simplify.cpp takes the split step where the plain one drops surface):
// a tube thinner than the cells keeps its wall instead of collapsing onto its axis.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "cluster.h"
#include "octolod/bake/simplify.h"
#include "octolod/measure/metro.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A tube along x, `length` long and `radius` in radius, `segments` around and `rings` along, open at
// both ends, wound outwards; positions only.
NodeMesh tube(float length, float radius, int segments, int rings) {
  NodeMesh mesh;
  mesh.layout = {false, false, false};
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double angle = 2.0 * kPi * j / segments;
      mesh.vertices.insert(mesh.vertices.end(), {length * static_cast<float>(i) / static_cast<float>(rings - 1),
                                                 radius * static_cast<float>(std::cos(angle)),
                                                 radius * static_cast<float>(std::sin(angle))});
    }
  const auto id = [segments](int i, int j) { return static_cast<std::uint32_t>(i * segments + (j % segments)); };
  for (int i = 0; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j)
      mesh.indices.insert(mesh.indices.end(), {id(i, j), id(i, j + 1), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j)});
  return mesh;
}

double area(const NodeMesh& mesh) { return surface_area(face_normals(mesh)); }

// The largest distance of an output vertex from the tube's axis, and the smallest.
std::pair<double, double> radial_range(const NodeMesh& mesh) {
  double lo = INFINITY, hi = 0.0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float* p = &mesh.vertices[v * mesh.layout.floats()];
    const double r = std::hypot(p[1], p[2]);
    lo = std::min(lo, r), hi = std::max(hi, r);
  }
  return {lo, hi};
}

TEST(FacingSplit, PositionFacingsAreUnitSumsOfTheirTrianglesNormals) {
  const NodeMesh mesh = tube(1.0f, 0.5f, 8, 3);
  const PositionIds positions = make_position_ids(mesh);
  const std::vector<std::array<float, 3>> facing = position_facings(mesh, positions, face_normals(mesh));
  ASSERT_EQ(facing.size(), positions.count);
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float* p = &mesh.vertices[v * mesh.layout.floats()];
    const std::array<float, 3>& f = facing[positions.of_vertex[v]];
    // outwards, perpendicular to the axis: the radial direction
    EXPECT_NEAR(f[0] * f[0] + f[1] * f[1] + f[2] * f[2], 1.0, 1e-5) << "vertex " << v;
    EXPECT_NEAR(f[1] * p[1] / 0.5 + f[2] * p[2] / 0.5, 1.0, 0.05) << "vertex " << v;
  }
}

TEST(FacingSplit, ATubeThinnerThanTheCellsKeepsItsWall) {
  // 10 long, 0.1 across: at an eighth of its triangles the cells are wider than the tube, and
  // every cell holds both sides of it. Whole, a cell's vertices all go to one cluster and the
  // wall collapses onto the axis; split, each side keeps a cluster.
  const NodeMesh input = tube(10.0f, 0.05f, 16, 201);
  const std::uint32_t target = static_cast<std::uint32_t>(input.triangle_count() / 8);
  const PreparedNode whole = prepare_node(input, input.bounds());
  ASSERT_TRUE(whole.facing.empty()) << "prepare_node leaves the cells whole";
  const NodeMesh plain =
      build_clustered_mesh(whole.mesh(), whole.face_normal, adaptive_grid_clustering(whole, target, SearchCount::kept),
                           whole.origin)
          .mesh;
  // (flattened into a two-sided ribbon: both sides counted, about half the tube's area)
  ASSERT_LT(area(plain), 0.6 * area(input)) << "the plain grid no longer collapses this tube: the test needs a thinner one";
  ASSERT_LT(radial_range(plain).first, 0.02);

  auto simplified = simplify_node(input, input.bounds(), [&] {
    SimplifyOptions options;
    options.target_triangles = target;
    return options;
  }());
  ASSERT_TRUE(simplified.ok()) << simplified.status().message();
  const NodeMesh& out = simplified->mesh;
  EXPECT_LE(out.triangle_count(), target);
  EXPECT_GE(out.triangle_count(), target / 4);
  EXPECT_GT(area(out), 0.8 * area(input));
  const auto [lo, hi] = radial_range(out);
  EXPECT_GT(lo, 0.02) << "a vertex fell onto the axis";
  EXPECT_LT(hi, 0.06);
  // the ribbon is off by about the radius (0.05); four sides by about a quarter of it
  EXPECT_LT(simplified->error_bound, 0.02);
  auto measured = measure::evaluate(input, out);
  ASSERT_TRUE(measured.ok()) << measured.status().message();
  EXPECT_LE(measured->two_sided.max, simplified->error_bound * 1.0001) << "the stored bound is an upper bound";
}

}  // namespace
}  // namespace octolod::bake
