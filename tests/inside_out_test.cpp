// Triangles turned inside out among their neighbours (bake/src/inside_out.h): re-wound when
// every neighbour runs their shared edges the same way and faces the other way; two-sided sheets
// and consistently wound folds stay as they are. The LOD chains' check is cluster_test.cpp's
// LodTest.NoLodTriangleFacesAgainstItsVertexNormals.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include "inside_out.h"
#include "wedges.h"

namespace octolod::bake {
namespace {

// A middle triangle (a, b, c) in z = 0 and a neighbour across each of its edges, seen from +z:
//
//        f     c
//          \  / \   e
//           \/   \ /
//           a-----b
//             \ /
//              d
//
// The neighbours (b, a, d), (c, b, e), (a, c, f) face +z.
enum Corner : std::uint32_t { a, b, c, d, e, f };

// The patch's vertex records in `layout`: normals (0, 0, 1), uv (0, 0).
NodeMesh patch(std::initializer_list<std::uint32_t> middle, VertexLayout layout = {false, false, false},
               bool middle_behind_a_seam = false) {
  NodeMesh mesh;
  mesh.layout = layout;
  const std::array<std::array<float, 3>, 6> position{
      {{0.0f, 0.0f, 0.0f}, {2.0f, 0.0f, 0.0f}, {1.0f, 2.0f, 0.0f}, {1.0f, -1.0f, 0.0f}, {2.5f, 1.5f, 0.0f}, {-0.5f, 1.5f, 0.0f}}};
  for (const auto& p : position) {
    mesh.vertices.insert(mesh.vertices.end(), p.begin(), p.end());
    if (layout.normal) mesh.vertices.insert(mesh.vertices.end(), {0.0f, 0.0f, 1.0f});
    if (layout.uv) mesh.vertices.insert(mesh.vertices.end(), {0.0f, 0.0f});
  }
  mesh.indices = {b, a, d, c, b, e, a, c, f};
  if (!middle_behind_a_seam) {
    mesh.indices.insert(mesh.indices.end(), middle);
    return mesh;
  }
  // the middle triangle on the other side of a uv seam: corners of its own at the same positions
  const std::size_t stride = layout.floats();
  for (const std::uint32_t corner : middle) {
    std::vector<float> record(mesh.vertices.begin() + static_cast<std::ptrdiff_t>(corner * stride),
                              mesh.vertices.begin() + static_cast<std::ptrdiff_t>((corner + 1) * stride));
    record[stride - 1] = 1.0f;
    mesh.indices.push_back(static_cast<std::uint32_t>(mesh.vertex_count()));
    mesh.vertices.insert(mesh.vertices.end(), record.begin(), record.end());
  }
  return mesh;
}

double facing_z(const NodeMesh& mesh, std::size_t t) {
  const std::size_t stride = mesh.layout.floats();
  const std::uint32_t* corner = &mesh.indices[3 * t];
  return triangle_normal(&mesh.vertices[corner[0] * stride], &mesh.vertices[corner[1] * stride],
                         &mesh.vertices[corner[2] * stride])[2];
}

TEST(InsideOutTest, ATriangleWoundAgainstItsThreeNeighboursIsRewound) {
  NodeMesh mesh = patch({a, c, b});  // faces -z, runs every shared edge as its neighbour does
  ASSERT_LT(facing_z(mesh, 3), 0.0);
  EXPECT_EQ(rewind_inside_out(mesh), 1u);
  for (std::size_t t = 0; t < 4; ++t) EXPECT_GT(facing_z(mesh, t), 0.0) << "triangle " << t;
  EXPECT_EQ(std::vector<std::uint32_t>(mesh.indices.begin(), mesh.indices.begin() + 9),
            (std::vector<std::uint32_t>{b, a, d, c, b, e, a, c, f}))
      << "the neighbours stay as they are";
}

TEST(InsideOutTest, TwoNeighboursSufficeOneDoesNot) {
  NodeMesh two = patch({a, c, b});
  two.indices.erase(two.indices.begin() + 3, two.indices.begin() + 6);  // no neighbour across b-c
  NodeMesh one = two;
  one.indices.erase(one.indices.begin() + 3, one.indices.begin() + 6);  // nor across c-a
  EXPECT_EQ(rewind_inside_out(two), 1u);
  EXPECT_GT(facing_z(two, 2), 0.0);
  EXPECT_EQ(rewind_inside_out(one), 0u);
  EXPECT_LT(facing_z(one, 1), 0.0);
}

TEST(InsideOutTest, NeighboursBehindAnAttributeSeamCount) {
  NodeMesh mesh = patch({a, c, b}, {false, false, true}, true);
  EXPECT_EQ(rewind_inside_out(mesh), 1u);
  EXPECT_GT(facing_z(mesh, 3), 0.0);
}

TEST(InsideOutTest, ATwoSidedSheetIsLeftAlone) {
  // the middle triangle both ways: each copy runs the other's edges the other way
  NodeMesh mesh = patch({a, b, c, a, c, b});
  const NodeMesh before = mesh;
  EXPECT_EQ(rewind_inside_out(mesh), 0u);
  EXPECT_EQ(mesh, before);
}

TEST(InsideOutTest, AConsistentlyWoundFoldIsLeftAlone) {
  // A flattened closed part: the top (a, b, c) faces +z, the three faces down to an apex just
  // below it face -z, and every edge is run both ways. Each face faces against all its
  // neighbours, and none is inside out.
  NodeMesh mesh;
  mesh.layout = {false, false, false};
  mesh.vertices = {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 1.0f, 2.0f, 0.0f, 1.0f, 0.7f, -0.1f};
  mesh.indices = {a, b, c, b, a, d, c, b, d, a, c, d};
  const NodeMesh before = mesh;
  EXPECT_EQ(rewind_inside_out(mesh), 0u);
  EXPECT_EQ(mesh, before);
}

TEST(InsideOutTest, AMiswoundTriangleThatFacesLikeItsNeighboursIsLeftAlone) {
  // (a, c, b) runs every shared edge as its neighbour does, but d, e and f lie inside the middle
  // triangle: the neighbours face -z as it does (they fold over it), and re-winding it would
  // turn it against them
  NodeMesh mesh = patch({a, c, b});
  const std::array<std::array<float, 2>, 3> inside{{{1.0f, 0.5f}, {1.2f, 0.8f}, {0.8f, 0.8f}}};
  for (std::size_t i = 0; i < 3; ++i) {
    mesh.vertices[(d + i) * 3] = inside[i][0];
    mesh.vertices[(d + i) * 3 + 1] = inside[i][1];
  }
  for (std::size_t t = 0; t < 4; ++t) ASSERT_LT(facing_z(mesh, t), 0.0) << "triangle " << t;
  const NodeMesh before = mesh;
  EXPECT_EQ(rewind_inside_out(mesh), 0u);
  EXPECT_EQ(mesh, before);
}

TEST(InsideOutTest, WithNormalsAFoldThatFacesAgainstThemIsRewound) {
  // c moved across a-b: (a, b, c) is wound consistently with its neighbours but faces -z, against
  // them and against its corners' normals (+z). Without normals the winding is all there is to
  // go by, and it is consistent.
  const VertexLayout with_normals{true, false, false};
  for (const VertexLayout layout : {with_normals, VertexLayout{false, false, false}}) {
    NodeMesh mesh = patch({a, b, c}, layout);
    mesh.vertices[c * layout.floats() + 1] = -0.5f;
    ASSERT_LT(facing_z(mesh, 3), 0.0);
    for (std::size_t t = 0; t < 3; ++t) ASSERT_GT(facing_z(mesh, t), 0.0) << "triangle " << t;
    const bool normals = layout.normal;
    EXPECT_EQ(rewind_inside_out(mesh), normals ? 1u : 0u) << "normals " << normals;
    EXPECT_EQ(facing_z(mesh, 3) > 0.0, normals);
  }
}

TEST(InsideOutTest, ASheetsBackCopyIsLeftAloneWhateverItsNormals) {
  // the back copy (a, c, b) faces -z against normals of +z, and its neighbours face +z; re-wound,
  // it would repeat the front copy (a repeated face, which the next step drops)
  NodeMesh mesh = patch({a, b, c, a, c, b}, {true, false, false});
  const NodeMesh before = mesh;
  EXPECT_EQ(rewind_inside_out(mesh), 0u);
  EXPECT_EQ(mesh, before);
}

}  // namespace
}  // namespace octolod::bake
