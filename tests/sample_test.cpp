// octolod::samplegen and `octolod sample`: exact counts, determinism, and the topology each shape
// promises (closed rock with a real uv seam, closed city boxes, open terrain with a rectangular
// boundary, closed tube on its centre circle with seams in u and v), attribute ranges, and a PLY
// round trip through the writer, the reader and the CLI.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "octolod/formats/ply_reader.h"
#include "octolod/samplegen/sample_generator.h"

namespace octolod::samplegen {
namespace {

constexpr VertexLayout kAll{true, true, true};
constexpr VertexLayout kNone{false, false, false};

struct Mesh {
  VertexLayout layout;
  std::vector<float> vertices;
  std::vector<std::uint32_t> triangles;

  std::size_t vertex_count() const { return vertices.size() / layout.floats(); }
  std::size_t triangle_count() const { return triangles.size() / 3; }
  const float* vertex(std::size_t i) const { return vertices.data() + i * layout.floats(); }
  const float* normal(std::size_t i) const { return vertex(i) + VertexLayout::normal_offset(); }
  const float* color(std::size_t i) const { return vertex(i) + layout.color_offset(); }
  const float* uv(std::size_t i) const { return vertex(i) + layout.uv_offset(); }
};

SampleSpec spec_of(Shape shape, std::uint64_t triangles, VertexLayout layout = kAll,
                   std::uint64_t seed = 1) {
  SampleSpec spec;
  spec.shape = shape;
  spec.triangles = triangles;
  spec.layout = layout;
  spec.seed = seed;
  return spec;
}

// Streams the whole sample, checking the batch protocol on the way.
Mesh generate(const SampleSpec& spec, std::size_t batch_bytes = std::size_t{1} << 20,
              unsigned threads = 1) {
  Mesh mesh{spec.layout, {}, {}};
  Result<std::unique_ptr<SampleStream>> stream =
      SampleStream::create(spec, {.batch_bytes = batch_bytes, .threads = threads});
  EXPECT_TRUE(stream.ok()) << stream.status().message();
  if (!stream.ok()) return mesh;
  bool seen_triangles = false;
  for (SampleBatch batch = stream.value()->next(); batch.kind != SampleBatch::Kind::end;
       batch = stream.value()->next()) {
    if (batch.kind == SampleBatch::Kind::vertices) {
      EXPECT_FALSE(seen_triangles) << "vertices after triangles";
      EXPECT_EQ(batch.first, mesh.vertex_count());
      EXPECT_EQ(batch.vertices.size() % spec.layout.floats(), 0u);
      EXPECT_FALSE(batch.vertices.empty());
      mesh.vertices.insert(mesh.vertices.end(), batch.vertices.begin(), batch.vertices.end());
    } else {
      seen_triangles = true;
      EXPECT_EQ(batch.first, mesh.triangle_count());
      EXPECT_FALSE(batch.triangles.empty());
      mesh.triangles.insert(mesh.triangles.end(), batch.triangles.begin(), batch.triangles.end());
    }
  }
  EXPECT_EQ(stream.value()->next().kind, SampleBatch::Kind::end) << "end must be sticky";
  return mesh;
}

using Position = std::array<std::uint32_t, 3>;  // float bit patterns: exact equality
Position position_of(const Mesh& mesh, std::size_t i) {
  const float* p = mesh.vertex(i);
  return {std::bit_cast<std::uint32_t>(p[0]), std::bit_cast<std::uint32_t>(p[1]),
          std::bit_cast<std::uint32_t>(p[2])};
}

// Vertex index -> id of its position (equal positions share an id).
std::vector<std::size_t> position_ids(const Mesh& mesh) {
  std::map<Position, std::size_t> ids;
  std::vector<std::size_t> result(mesh.vertex_count());
  for (std::size_t i = 0; i < result.size(); ++i)
    result[i] = ids.emplace(position_of(mesh, i), ids.size()).first->second;
  return result;
}

// Directed edges keyed by the ids in `key` (positions or indices) over triangles [begin, end).
std::map<std::pair<std::size_t, std::size_t>, int> directed_edges(
    const Mesh& mesh, const std::vector<std::size_t>& key, std::size_t begin, std::size_t end) {
  std::map<std::pair<std::size_t, std::size_t>, int> edges;
  for (std::size_t t = begin; t < end; ++t)
    for (std::size_t c = 0; c < 3; ++c)
      ++edges[{key[mesh.triangles[3 * t + c]], key[mesh.triangles[3 * t + (c + 1) % 3]]}];
  return edges;
}

// Closed and consistently oriented: every directed edge once, its reverse exactly once.
void expect_closed_oriented(const std::map<std::pair<std::size_t, std::size_t>, int>& edges) {
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1) << "directed edge used " << count << " times";
    ASSERT_TRUE(edges.count({edge.second, edge.first})) << "boundary edge: surface not closed";
  }
}

std::array<double, 3> face_normal(const Mesh& mesh, std::size_t t) {
  const float* p = mesh.vertex(mesh.triangles[3 * t]);
  const float* q = mesh.vertex(mesh.triangles[3 * t + 1]);
  const float* r = mesh.vertex(mesh.triangles[3 * t + 2]);
  const double e1[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
  const double e2[3] = {double(r[0]) - p[0], double(r[1]) - p[1], double(r[2]) - p[2]};
  return {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
          e1[0] * e2[1] - e1[1] * e2[0]};
}

// Every triangle's geometric normal on the same side as each of its corners' normals.
void expect_normals_follow_the_winding(const Mesh& mesh) {
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::array<double, 3> n = face_normal(mesh, t);
    for (std::size_t c = 0; c < 3; ++c) {
      const float* vn = mesh.normal(mesh.triangles[3 * t + c]);
      ASSERT_GT(n[0] * vn[0] + n[1] * vn[1] + n[2] * vn[2], 0.0) << "triangle " << t;
    }
  }
}

double signed_volume(const Mesh& mesh) {
  double volume = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float* p = mesh.vertex(mesh.triangles[3 * t]);
    const std::array<double, 3> n = face_normal(mesh, t);
    volume += (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / 6.0;
  }
  return volume;
}

std::uint64_t fnv1a(const Mesh& mesh) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](const void* data, std::size_t bytes) {
    for (std::size_t i = 0; i < bytes; ++i) {
      h ^= static_cast<const unsigned char*>(data)[i];
      h *= 1099511628211ull;
    }
  };
  add(mesh.vertices.data(), mesh.vertices.size() * sizeof(float));
  add(mesh.triangles.data(), mesh.triangles.size() * sizeof(std::uint32_t));
  return h;
}

constexpr Shape kShapes[] = {Shape::rock, Shape::terrain, Shape::city, Shape::tube};

TEST(SampleCounts, DeclaredCountsAreEmittedForEveryShapeSizeAndLayout) {
  for (Shape shape : kShapes)
    for (std::uint64_t n : {16u, 17u, 100u, 999u, 12345u, 60000u})
      for (VertexLayout layout :
           {kAll, kNone, VertexLayout{true, false, false}, VertexLayout{false, true, true}}) {
        SCOPED_TRACE(std::string(to_string(shape)) + " N=" + std::to_string(n) + " " +
                     layout.describe());
        const SampleSpec spec = spec_of(shape, n, layout);
        Result<SampleCounts> counts = sample_counts(spec);
        ASSERT_TRUE(counts.ok()) << counts.status().message();
        // A small batch forces many batches of both kinds.
        const Mesh mesh = generate(spec, 4096);
        EXPECT_EQ(mesh.vertex_count(), counts->vertices);
        EXPECT_EQ(mesh.triangle_count(), counts->triangles);
        for (std::uint32_t index : mesh.triangles) ASSERT_LT(index, counts->vertices);
      }
}

TEST(SampleCounts, TriangleCountIsWithinOnePercentAtEveryScale) {
  for (Shape shape : kShapes)
    for (std::uint64_t n : {std::uint64_t{100}, std::uint64_t{101}, std::uint64_t{1'000},
                            std::uint64_t{77'777}, std::uint64_t{1'000'000},
                            std::uint64_t{12'345'678}, std::uint64_t{100'000'000}, kMaxTriangles}) {
      // The tube is within 8 triangles below 40K: 1% only from 800 up (its own test below).
      if (shape == Shape::tube && n < 800) continue;
      const Result<SampleCounts> counts = sample_counts(spec_of(shape, n));
      ASSERT_TRUE(counts.ok());
      const double relative =
          std::fabs(static_cast<double>(counts->triangles) - static_cast<double>(n)) /
          static_cast<double>(n);
      EXPECT_LE(relative, 0.01) << to_string(shape) << " N=" << n << " made " << counts->triangles;
      EXPECT_LT(counts->vertices, std::uint64_t{1} << 32);
    }
}

TEST(SampleCounts, RockAndCityHitTheTargetOrOneBelow) {
  for (Shape shape : {Shape::rock, Shape::city})
    for (std::uint64_t n = kMinTriangles; n < 400; ++n) {
      const Result<SampleCounts> counts = sample_counts(spec_of(shape, n));
      ASSERT_TRUE(counts.ok());
      EXPECT_TRUE(counts->triangles == n || counts->triangles + 1 == n)
          << to_string(shape) << " N=" << n << " made " << counts->triangles;
    }
}

TEST(SampleCounts, TerrainIsWithinThreePercentFromAHundredAndOnePercentFromAThousand) {
  for (std::uint64_t n = 100; n < 5000; ++n) {
    const Result<SampleCounts> counts = sample_counts(spec_of(Shape::terrain, n));
    ASSERT_TRUE(counts.ok());
    ASSERT_LE(std::fabs(static_cast<double>(counts->triangles) - static_cast<double>(n)),
              (n < 1000 ? 0.03 : 0.01) * static_cast<double>(n))
        << "N=" << n << " made " << counts->triangles;
  }
}

TEST(SampleCounts, TubeIsWithinOneSegmentsWorthOfTriangles) {
  // 2 * segments * rings with rings rounded: off by at most `segments` triangles, 8 below 40K.
  for (std::uint64_t n = kMinTriangles; n < 40'000; ++n) {
    const Result<SampleCounts> counts = sample_counts(spec_of(Shape::tube, n));
    ASSERT_TRUE(counts.ok());
    const std::uint64_t made = counts->triangles;
    ASSERT_LE(made > n ? made - n : n - made, n < 18 ? 2u : 8u) << "N=" << n << " made " << made;
    if (n >= 800) {
      ASSERT_LE(std::fabs(static_cast<double>(made) - static_cast<double>(n)),
                0.01 * static_cast<double>(n))
          << "N=" << n << " made " << made;
    }
  }
  EXPECT_EQ(sample_counts(spec_of(Shape::tube, 16))->triangles, 18u) << "3 segments x 3 rings";
  for (std::uint64_t n : {std::uint64_t{40'000}, std::uint64_t{64'000}, std::uint64_t{77'777},
                          std::uint64_t{1'000'000}, std::uint64_t{12'345'678}, kMaxTriangles}) {
    const Result<SampleCounts> counts = sample_counts(spec_of(Shape::tube, n));
    ASSERT_TRUE(counts.ok());
    EXPECT_LE(std::fabs(static_cast<double>(counts->triangles) - static_cast<double>(n)),
              3e-4 * static_cast<double>(n))
        << "N=" << n << " made " << counts->triangles;
    EXPECT_LT(counts->vertices, std::uint64_t{1} << 32);
  }
  // The facing-split benchmark's tube: 10 segments x 3,200 rings, (3,201 x 11 vertices).
  EXPECT_EQ(sample_counts(spec_of(Shape::tube, 64'000)).value(), (SampleCounts{35'211, 64'000}));
}

TEST(SampleCounts, OutOfRangeTargetsAreUsageErrors) {
  for (std::uint64_t n : {std::uint64_t{0}, kMinTriangles - 1, kMaxTriangles + 1}) {
    const Result<SampleCounts> counts = sample_counts(spec_of(Shape::rock, n));
    ASSERT_FALSE(counts.ok());
    EXPECT_EQ(counts.status().code(), ErrorCode::usage);
    EXPECT_FALSE(SampleStream::create(spec_of(Shape::city, n)).ok());
  }
}

TEST(SampleDeterminism, SameSpecSameBytesWhateverTheBatchSizeAndThreads) {
  for (Shape shape : kShapes) {
    const SampleSpec spec = spec_of(shape, 50000, kAll, 42);
    const std::uint64_t reference = fnv1a(generate(spec));
    EXPECT_EQ(fnv1a(generate(spec, 4096)), reference) << to_string(shape);
    EXPECT_EQ(fnv1a(generate(spec, std::size_t{1} << 20, 2)), reference) << to_string(shape);
    EXPECT_EQ(fnv1a(generate(spec, 100000, 3)), reference) << to_string(shape);
  }
}

TEST(SampleDeterminism, PinnedChecksumsSameOnEveryPlatform) {
  // The generator uses only integer hashing and + - * / sqrt floor, so these are the same bits
  // on every IEEE-754 platform. A change here changes every sample asset: update deliberately.
  EXPECT_EQ(fnv1a(generate(spec_of(Shape::rock, 1000, kAll, 1))), 16370689929761296235u);
  EXPECT_EQ(fnv1a(generate(spec_of(Shape::terrain, 1000, kAll, 1))), 16028795320873989745u);
  EXPECT_EQ(fnv1a(generate(spec_of(Shape::city, 1000, kAll, 1))), 13755169068196887386u);
  EXPECT_EQ(fnv1a(generate(spec_of(Shape::tube, 1000, kAll, 1))), 10283928412738255103u);
}

TEST(SampleDeterminism, DifferentSeedDifferentMeshSameCounts) {
  for (Shape shape : kShapes) {
    const Mesh a = generate(spec_of(shape, 5000, kAll, 1));
    const Mesh b = generate(spec_of(shape, 5000, kAll, 2));
    EXPECT_NE(fnv1a(a), fnv1a(b)) << to_string(shape);
    EXPECT_EQ(a.vertex_count(), b.vertex_count());
    EXPECT_EQ(a.triangles, b.triangles) << "connectivity depends on N only";
  }
}

TEST(SampleDeterminism, SeedsDifferingOnlyInTheHighBitsDiffer) {
  const Mesh a = generate(spec_of(Shape::terrain, 2000, kNone, 7));
  const Mesh b = generate(spec_of(Shape::terrain, 2000, kNone, 7 + (std::uint64_t{1} << 40)));
  EXPECT_NE(a.vertices, b.vertices);
}

TEST(SampleDeterminism, AttributeSubsetsShareTheSameValues) {
  // Dropping an attribute removes its floats and changes nothing else.
  for (Shape shape : kShapes) {
    const Mesh all = generate(spec_of(shape, 3000, kAll));
    const Mesh uv_only = generate(spec_of(shape, 3000, VertexLayout{false, false, true}));
    ASSERT_EQ(all.vertex_count(), uv_only.vertex_count());
    EXPECT_EQ(all.triangles, uv_only.triangles);
    for (std::size_t i = 0; i < all.vertex_count(); ++i)
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(all.vertex(i)[k], uv_only.vertex(i)[k]);
        if (k < 2) {
          ASSERT_EQ(all.uv(i)[k], uv_only.uv(i)[k]);
        }
      }
  }
}

TEST(SampleRock, IsClosedManifoldOrientedOutwardByPosition) {
  for (std::uint64_t n : {16u, 100u, 2000u, 50000u}) {
    SCOPED_TRACE("N=" + std::to_string(n));
    const Mesh mesh = generate(spec_of(Shape::rock, n));
    expect_closed_oriented(directed_edges(mesh, position_ids(mesh), 0, mesh.triangle_count()));
    EXPECT_GT(signed_volume(mesh), 0.5) << "normals must point outward (volume of a ~unit rock)";
    // Euler characteristic of a sphere, counting positions (the seam copies are one point).
    const std::vector<std::size_t> ids = position_ids(mesh);
    const std::set<std::size_t> points(ids.begin(), ids.end());
    const std::size_t edges = mesh.triangle_count() * 3 / 2;
    EXPECT_EQ(static_cast<long>(points.size()) - static_cast<long>(edges) +
                  static_cast<long>(mesh.triangle_count()),
              2);
  }
}

TEST(SampleRock, OnlyRepeatedPositionsAreSeamCopiesWithUZeroAndOne) {
  const Mesh mesh = generate(spec_of(Shape::rock, 20000));
  std::map<Position, std::vector<std::size_t>> by_position;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
    by_position[position_of(mesh, i)].push_back(i);
  std::size_t seam_pairs = 0;
  for (const auto& [position, copies] : by_position) {
    if (copies.size() == 1) continue;
    ASSERT_EQ(copies.size(), 2u) << "a position repeated more than twice";
    const std::size_t a = copies[0], b = copies[1];
    EXPECT_EQ(mesh.uv(a)[0], 0.0f);
    EXPECT_EQ(mesh.uv(b)[0], 1.0f);
    EXPECT_EQ(mesh.uv(a)[1], mesh.uv(b)[1]);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(mesh.normal(a)[k], mesh.normal(b)[k]) << "seam copies differ only in uv";
      EXPECT_EQ(mesh.color(a)[k], mesh.color(b)[k]);
    }
    ++seam_pairs;
  }
  // One seam copy per ring (every ring but the poles).
  EXPECT_GT(seam_pairs, 50u);
  EXPECT_EQ(mesh.vertex_count() - seam_pairs, by_position.size());
}

TEST(SampleRock, NoTriangleStraddlesTheSeam) {
  // A triangle's u values span less than half a turn: the seam is a real uv discontinuity.
  const Mesh mesh = generate(spec_of(Shape::rock, 5000));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    float lo = 2, hi = -1;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint32_t v = mesh.triangles[3 * t + c];
      if (mesh.uv(v)[1] == 0.0f || mesh.uv(v)[1] == 1.0f) continue;  // poles have no longitude
      lo = std::min(lo, mesh.uv(v)[0]);
      hi = std::max(hi, mesh.uv(v)[0]);
    }
    ASSERT_LT(hi - lo, 0.5f) << "triangle " << t;
  }
}

TEST(SampleCity, EveryBoxIsClosedAndFlatShaded) {
  const Mesh mesh = generate(spec_of(Shape::city, 12 * 40 + 2));
  const std::vector<std::size_t> ids = position_ids(mesh);
  // Ground first (2 triangles here), then 12 triangles per box.
  const std::size_t ground_triangles = mesh.triangle_count() % 12;
  ASSERT_EQ(ground_triangles, 2u);
  for (std::size_t first = ground_triangles; first < mesh.triangle_count(); first += 12) {
    SCOPED_TRACE("box starting at triangle " + std::to_string(first));
    const auto edges = directed_edges(mesh, ids, first, first + 12);
    expect_closed_oriented(edges);
    EXPECT_EQ(edges.size(), 36u);  // 18 box edges (12 cube edges + 6 face diagonals), both ways
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::array<double, 3> n = face_normal(mesh, t);
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (std::size_t c = 0; c < 3; ++c)
      for (std::size_t k = 0; k < 3; ++k)
        ASSERT_NEAR(mesh.normal(mesh.triangles[3 * t + c])[k], n[k] / length, 1e-6)
            << "vertex normals are the face normal (flat shading), triangle " << t;
  }
}

TEST(SampleCity, BoxesHaveOneColourAndDistinctBoxesVary) {
  const Mesh mesh = generate(spec_of(Shape::city, 12 * 30 + 2));
  const std::size_t ground_vertices = mesh.vertex_count() - 24 * 30;
  std::set<std::array<float, 3>> colours;
  for (std::size_t box = 0; box < 30; ++box) {
    const std::size_t first = ground_vertices + 24 * box;
    for (std::size_t v = first; v < first + 24; ++v)
      for (int k = 0; k < 3; ++k) ASSERT_EQ(mesh.color(v)[k], mesh.color(first)[k]);
    colours.insert({mesh.color(first)[0], mesh.color(first)[1], mesh.color(first)[2]});
  }
  EXPECT_GT(colours.size(), 10u);
}

TEST(SampleTerrain, IsOpenWithTheGridRectangleAsBoundary) {
  const Mesh mesh = generate(spec_of(Shape::terrain, 20000));
  std::vector<std::size_t> index(mesh.vertex_count());
  for (std::size_t i = 0; i < index.size(); ++i) index[i] = i;
  EXPECT_EQ(position_ids(mesh), index) << "terrain vertices are all distinct";
  const auto edges = directed_edges(mesh, index, 0, mesh.triangle_count());
  float min_x = 1e30f, max_x = -1e30f, min_z = 1e30f, max_z = -1e30f;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    min_x = std::min(min_x, mesh.vertex(i)[0]), max_x = std::max(max_x, mesh.vertex(i)[0]);
    min_z = std::min(min_z, mesh.vertex(i)[2]), max_z = std::max(max_z, mesh.vertex(i)[2]);
  }
  EXPECT_EQ(min_x, 0.0f);
  EXPECT_EQ(max_x, 100.0f);
  std::size_t boundary = 0;
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1);
    if (edges.count({edge.second, edge.first})) continue;
    ++boundary;
    for (std::size_t v : {edge.first, edge.second}) {
      const float x = mesh.vertex(v)[0], z = mesh.vertex(v)[2];
      ASSERT_TRUE(x == min_x || x == max_x || z == min_z || z == max_z)
          << "boundary vertex " << v << " inside the grid";
    }
  }
  // A columns x rows grid: 2 (columns + rows) boundary edges, (columns+1)(rows+1) vertices.
  bool grid_found = false;
  for (std::size_t columns = 1; columns <= boundary / 2; ++columns) {
    const std::size_t rows = boundary / 2 - columns;
    if ((columns + 1) * (rows + 1) == mesh.vertex_count() &&
        2 * columns * rows == mesh.triangle_count())
      grid_found = true;
  }
  EXPECT_TRUE(grid_found) << boundary << " boundary edges";
  EXPECT_EQ(boundary % 2, 0u);
}

TEST(SampleTerrain, NormalsAgreeWithTheSurface) {
  // Analytic normals vs the triangles' geometric normals: same hemisphere, mostly close.
  const Mesh mesh = generate(spec_of(Shape::terrain, 200000));
  std::size_t close = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::array<double, 3> n = face_normal(mesh, t);
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const float* vn = mesh.normal(mesh.triangles[3 * t]);
    const double cosine = (n[0] * vn[0] + n[1] * vn[1] + n[2] * vn[2]) / length;
    ASSERT_GT(n[1], 0.0) << "terrain triangles face up";
    ASSERT_GT(cosine, 0.0) << "triangle " << t;
    if (cosine > 0.95) ++close;
  }
  EXPECT_GT(close, mesh.triangle_count() * 9 / 10);
}

// The tube's centre circle: radius 1000 / 2pi in the plane y = 0, around the origin.
constexpr double kTubeCentreRadius = 1000.0 / (2.0 * 3.14159265358979323846);
constexpr double kTubeRadius = 0.5;

// The point of the tube's centre circle nearest to p (p off the y axis).
std::array<double, 3> nearest_on_centre_circle(const float* p) {
  const double from_axis = std::sqrt(double(p[0]) * p[0] + double(p[2]) * p[2]);
  return {p[0] * kTubeCentreRadius / from_axis, 0.0, p[2] * kTubeCentreRadius / from_axis};
}

TEST(SampleTube, IsClosedManifoldOrientedOutwardByPosition) {
  for (std::uint64_t n : {16u, 100u, 2000u, 50000u}) {
    SCOPED_TRACE("N=" + std::to_string(n));
    const Mesh mesh = generate(spec_of(Shape::tube, n));
    const std::vector<std::size_t> ids = position_ids(mesh);
    // Every edge, by position, used exactly twice: once each way.
    expect_closed_oriented(directed_edges(mesh, ids, 0, mesh.triangle_count()));
    // Inscribed in the torus (volume 2 pi^2 R r^2 = 250 pi): below it, and positive (outward).
    const double volume = signed_volume(mesh);
    EXPECT_GT(volume, 0.0) << "triangles must be counter-clockwise seen from outside";
    EXPECT_LT(volume, 250.0 * 3.14159265358979323846);
    // Euler characteristic of a torus, counting positions (the seam copies are one point).
    const std::set<std::size_t> points(ids.begin(), ids.end());
    const std::size_t edges = mesh.triangle_count() * 3 / 2;
    EXPECT_EQ(static_cast<long>(points.size()) - static_cast<long>(edges) +
                  static_cast<long>(mesh.triangle_count()),
              0);
  }
}

TEST(SampleTube, VerticesLieHalfAUnitFromTheCentreCircleWithRadialNormals) {
  for (std::uint64_t n : {16u, 1000u, 64000u}) {
    SCOPED_TRACE("N=" + std::to_string(n));
    const Mesh mesh = generate(spec_of(Shape::tube, n));
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
      const float* p = mesh.vertex(i);
      const std::array<double, 3> c = nearest_on_centre_circle(p);
      const double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
      const double distance = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      ASSERT_NEAR(distance, kTubeRadius, 1e-4) << "vertex " << i;
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(mesh.normal(i)[k], d[k] / distance, 1e-4) << "vertex " << i << " axis " << k;
    }
  }
}

TEST(SampleTube, NormalsAgreeWithTheWinding) {
  // Every triangle's geometric normal on the same side as each of its corners' normals, down
  // to the 3 x 3 prism ring at N = 16 whose triangles span a third of the circle.
  for (std::uint64_t n : {16u, 100u, 2000u, 64000u}) {
    SCOPED_TRACE("N=" + std::to_string(n));
    expect_normals_follow_the_winding(generate(spec_of(Shape::tube, n)));
  }
}

TEST(SampleTube, OnlyRepeatedPositionsAreSeamCopiesAFullRepeatApartInUv) {
  // (rings + 1) x (segments + 1) vertices over rings x segments points: ring `rings` repeats
  // ring 0 with u = 100 for 0, segment `segments` repeats segment 0 with v = 1 for 0.
  const Mesh mesh = generate(spec_of(Shape::tube, 5000));
  std::map<Position, std::vector<std::size_t>> by_position;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
    by_position[position_of(mesh, i)].push_back(i);
  for (const auto& [position, copies] : by_position) {
    ASSERT_LE(copies.size(), 4u);
    for (std::size_t copy : copies) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(mesh.normal(copy)[k], mesh.normal(copies[0])[k]) << "copies differ only in uv";
        EXPECT_EQ(mesh.color(copy)[k], mesh.color(copies[0])[k]);
      }
      for (int k = 0; k < 2; ++k) {
        const float difference = std::fabs(mesh.uv(copy)[k] - mesh.uv(copies[0])[k]);
        EXPECT_TRUE(difference == 0.0f || difference == (k == 0 ? 100.0f : 1.0f))
            << "uv " << k << " of copies " << copies[0] << ", " << copy;
      }
    }
  }
  const std::size_t points = by_position.size();
  // points = rings x segments; vertices = (rings + 1) x (segments + 1).
  bool grid_found = false;
  for (std::size_t segments = 3; segments * 3 <= points; ++segments)
    if (points % segments == 0 &&
        (points / segments + 1) * (segments + 1) == mesh.vertex_count() &&
        2 * points == mesh.triangle_count())
      grid_found = true;
  EXPECT_TRUE(grid_found) << points << " points, " << mesh.vertex_count() << " vertices";
  // No triangle straddles a seam: each spans a sliver of u's 0..100 and v's 0..1.
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 2; ++k) {
      float lo = 1e30f, hi = -1e30f;
      for (std::size_t c = 0; c < 3; ++c) {
        lo = std::min(lo, mesh.uv(mesh.triangles[3 * t + c])[k]);
        hi = std::max(hi, mesh.uv(mesh.triangles[3 * t + c])[k]);
      }
      ASSERT_LT(hi - lo, k == 0 ? 50.0f : 0.5f) << "triangle " << t;
    }
}

TEST(SampleTube, BenchmarkTubeHasAboutSquareQuads) {
  // At 64K: 10 segments (0.31 around) x 3,200 rings (0.31 along): sides within 1.5x of each
  // other, the diagonals sqrt 2 longer, so every edge within 2.5x of every other.
  const Mesh mesh = generate(spec_of(Shape::tube, 64000, kNone));
  double shortest = 1e30, longest = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (std::size_t c = 0; c < 3; ++c) {
      const float* p = mesh.vertex(mesh.triangles[3 * t + c]);
      const float* q = mesh.vertex(mesh.triangles[3 * t + (c + 1) % 3]);
      const double dx = double(q[0]) - p[0], dy = double(q[1]) - p[1], dz = double(q[2]) - p[2];
      const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
      shortest = std::min(shortest, length), longest = std::max(longest, length);
    }
  EXPECT_LT(longest, 2.5 * shortest) << shortest << " .. " << longest;
}

TEST(SampleTube, SeedChangesOnlyTheColour) {
  const Mesh a = generate(spec_of(Shape::tube, 3000, kAll, 1));
  const Mesh b = generate(spec_of(Shape::tube, 3000, kAll, 2));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  EXPECT_EQ(a.triangles, b.triangles);
  bool colour_differs = false;
  for (std::size_t i = 0; i < a.vertex_count(); ++i) {
    for (std::uint32_t k = 0; k < 3; ++k) ASSERT_EQ(a.vertex(i)[k], b.vertex(i)[k]);
    for (std::uint32_t k = 0; k < 3; ++k) ASSERT_EQ(a.normal(i)[k], b.normal(i)[k]);
    for (std::uint32_t k = 0; k < 2; ++k) ASSERT_EQ(a.uv(i)[k], b.uv(i)[k]);
    for (std::uint32_t k = 0; k < 3; ++k) colour_differs |= a.color(i)[k] != b.color(i)[k];
  }
  EXPECT_TRUE(colour_differs);
}

TEST(SampleAttributes, TrianglesNonDegenerateNormalsUnitColoursInRange) {
  for (Shape shape : kShapes)
    for (std::uint64_t n : {16u, 500u, 40000u}) {
      SCOPED_TRACE(std::string(to_string(shape)) + " N=" + std::to_string(n));
      const Mesh mesh = generate(spec_of(shape, n));
      for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const std::uint32_t* tri = &mesh.triangles[3 * t];
        ASSERT_TRUE(tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]);
        const std::array<double, 3> fn = face_normal(mesh, t);
        ASSERT_GT(std::sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]), 1e-9)
            << "degenerate triangle " << t;
      }
      for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
        for (std::uint32_t k = 0; k < mesh.layout.floats(); ++k)
          ASSERT_TRUE(std::isfinite(mesh.vertex(i)[k]));
        const float* nrm = mesh.normal(i);
        ASSERT_NEAR(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2], 1.0, 1e-5);
        for (int k = 0; k < 3; ++k) {
          ASSERT_GE(mesh.color(i)[k], 0.0f);
          ASSERT_LE(mesh.color(i)[k], 1.0f);
        }
      }
    }
}

TEST(SampleAttributes, RockVertexNormalsFaceOutwardAlongTheSurface) {
  expect_normals_follow_the_winding(generate(spec_of(Shape::rock, 50000)));
}

TEST(SampleParse, TriangleCountsAcceptPlainExponentAndDecimalSuffixes) {
  const std::pair<const char*, std::uint64_t> cases[] = {
      {"200000", 200000}, {"2e5", 200000},   {"200K", 200000},   {"200k", 200000},
      {"20M", 20000000},  {"1.5M", 1500000}, {"1G", 1000000000}, {"16", 16}};
  for (const auto& [text, expected] : cases) {
    Result<std::uint64_t> parsed = parse_triangle_count(text);
    ASSERT_TRUE(parsed.ok()) << text << ": " << parsed.status().message();
    EXPECT_EQ(parsed.value(), expected) << text;
  }
  for (const char* bad : {"", "abc", "20X", "-5", "15", "2G", "1e300", "nan", "20 M", "M"}) {
    Result<std::uint64_t> parsed = parse_triangle_count(bad);
    ASSERT_FALSE(parsed.ok()) << "'" << bad << "' accepted";
    EXPECT_EQ(parsed.status().code(), ErrorCode::usage);
  }
}

TEST(SampleParse, AttributesAndShapes) {
  EXPECT_EQ(parse_attributes("normal,color,uv").value(), kAll);
  EXPECT_EQ(parse_attributes("uv,normal").value(), (VertexLayout{true, false, true}));
  EXPECT_EQ(parse_attributes("colour").value(), (VertexLayout{false, true, false}));
  EXPECT_EQ(parse_attributes("none").value(), kNone);
  EXPECT_EQ(parse_attributes("").value(), kNone);
  for (const char* bad : {"normals", "normal,", ",uv", "normal,,uv", "position"})
    EXPECT_FALSE(parse_attributes(bad).ok()) << bad;
  EXPECT_EQ(parse_shape("terrain").value(), Shape::terrain);
  EXPECT_EQ(parse_shape("tube").value(), Shape::tube);
  EXPECT_FALSE(parse_shape("Rock").ok());
}

TEST(SampleParse, EveryShapeRoundTripsAndTheUnknownShapeErrorListsThemAll) {
  const Result<Shape> unknown = parse_shape("moon");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.status().code(), ErrorCode::usage);
  EXPECT_NE(unknown.status().message().find("'moon'"), std::string::npos);
  for (Shape shape : kShapes) {
    EXPECT_EQ(parse_shape(to_string(shape)).value(), shape);
    EXPECT_NE(unknown.status().message().find(to_string(shape)), std::string::npos)
        << to_string(shape) << " missing in: " << unknown.status().message();
  }
}

class SampleFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("octolod-sample-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  // The PLY stores colours as uchar: compare them to half a step, everything else exactly.
  static void expect_same_mesh(const PlyMesh& read, const Mesh& expected) {
    ASSERT_EQ(read.info.layout, expected.layout);
    ASSERT_EQ(read.vertices.size(), expected.vertices.size());
    EXPECT_EQ(read.triangles, expected.triangles);
    const std::uint32_t floats = expected.layout.floats();
    const std::uint32_t color = expected.layout.color_offset();
    for (std::size_t i = 0; i < expected.vertices.size(); ++i) {
      const std::uint32_t k = static_cast<std::uint32_t>(i % floats);
      if (expected.layout.color && k >= color && k < color + 3)
        ASSERT_NEAR(read.vertices[i], expected.vertices[i], 0.5 / 255 + 1e-6) << "float " << i;
      else
        ASSERT_EQ(read.vertices[i], expected.vertices[i]) << "float " << i;
    }
  }

  std::filesystem::path dir_;
};

TEST_F(SampleFiles, WrittenPlyReadsBackWithTheSameData) {
  for (PlyFormat format : {PlyFormat::binary_little_endian, PlyFormat::ascii})
    for (Shape shape : kShapes) {
      SCOPED_TRACE(std::string(to_string(shape)) + " " + std::string(to_string(format)));
      const SampleSpec spec = spec_of(shape, 3000, kAll, 9);
      const std::filesystem::path path = dir_ / "sample.ply";
      std::uint64_t last_done = 0, last_total = 0;
      ASSERT_TRUE(
          write_sample_ply(spec, path, format, [&](std::uint64_t done, std::uint64_t total) {
            EXPECT_GT(done, last_done);
            last_done = done, last_total = total;
          }).ok());
      Result<PlyMesh> read = read_ply(path);
      ASSERT_TRUE(read.ok()) << read.status().message();
      EXPECT_EQ(read->info.format, format);
      expect_same_mesh(read.value(), generate(spec));
      EXPECT_EQ(last_done, last_total);
      EXPECT_EQ(last_total, read->info.vertex_count + read->triangles.size() / 3);
    }
}

TEST_F(SampleFiles, AnOffsetWritesDoublePositionsOfTheSameModel) {
  // The rock 4,000 km out: positions are double, each the generated float plus the offset;
  // read back relative to the offset they are the generated floats (within the doubles'
  // 2^-30 there), every other value bit for bit.
  SampleSpec spec = spec_of(Shape::rock, 3000, kAll, 9);
  spec.offset = {4.0e6, -5.0e5, 1234.0};
  const std::filesystem::path path = dir_ / "far.ply";
  ASSERT_TRUE(write_sample_ply(spec, path, PlyFormat::binary_little_endian).ok());
  PlyReadOptions framed;
  framed.position_origin = spec.offset;
  Result<PlyMesh> read = read_ply(path, framed);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_TRUE(read->info.double_positions);
  const Mesh expected = generate(spec);
  ASSERT_EQ(read->vertices.size(), expected.vertices.size());
  EXPECT_EQ(read->triangles, expected.triangles);
  const std::uint32_t floats = expected.layout.floats(), color = expected.layout.color_offset();
  for (std::size_t i = 0; i < expected.vertices.size(); ++i) {
    const std::uint32_t k = static_cast<std::uint32_t>(i % floats);
    if (k < 3) ASSERT_NEAR(read->vertices[i], expected.vertices[i], 1e-9) << "float " << i;
    else if (k >= color && k < color + 3) ASSERT_NEAR(read->vertices[i], expected.vertices[i], 0.5 / 255 + 1e-6);
    else ASSERT_EQ(read->vertices[i], expected.vertices[i]) << "float " << i;
  }
}

TEST_F(SampleFiles, CommittedSmallRockIsTheGeneratorsOutput) {
  // samples/rock_small.ply must be regenerated whenever the generator changes; its header
  // comment is the command that reproduces it.
  const std::filesystem::path committed =
      std::filesystem::path(__FILE__).parent_path().parent_path() / "samples" / "rock_small.ply";
  if (!std::filesystem::exists(committed)) GTEST_SKIP() << committed << " not found";
  const std::filesystem::path fresh = dir_ / "rock_small.ply";
  ASSERT_TRUE(write_sample_ply(spec_of(Shape::rock, 40000, kAll, 1), fresh).ok());
  std::ifstream a(committed, std::ios::binary), b(fresh, std::ios::binary);
  const std::string committed_bytes{std::istreambuf_iterator<char>(a), {}};
  const std::string fresh_bytes{std::istreambuf_iterator<char>(b), {}};
  EXPECT_LT(committed_bytes.size(), std::size_t{2} << 20);
  EXPECT_TRUE(committed_bytes == fresh_bytes)
      << "regenerate: octolod sample --shape rock --triangles 40K -o samples/rock_small.ply";
}

TEST_F(SampleFiles, UnwritableDestinationIsAnIoError) {
  const Status status = write_sample_ply(spec_of(Shape::rock, 100), dir_ / "missing" / "x.ply");
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), ErrorCode::io);
  EXPECT_NE(status.message().find("missing"), std::string::npos) << status.message();
}

// Runs the CLI; returns its exit code and stdout.
std::pair<int, std::string> run_cli(const std::string& arguments) {
  const char* cli = std::getenv("OCTOLOD_CLI");
  if (cli == nullptr) return {-1, ""};
  const std::string command = std::string(cli) + " " + arguments + " 2>/dev/null";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, ""};
  std::string output;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;)
    output.append(buffer, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST_F(SampleFiles, CliWritesTheGeneratorsMeshAndReportsJson) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  const std::filesystem::path path = dir_ / "city.ply";
  const auto [code, output] = run_cli(
      "sample --shape city --triangles 2.5K --attributes uv,normal "
      "--seed 5 -o " +
      path.string() + " --json");
  ASSERT_EQ(code, 0) << output;
  Result<PlyMesh> read = read_ply(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->info.format, PlyFormat::binary_little_endian);
  const SampleSpec spec = spec_of(Shape::city, 2500, VertexLayout{true, false, true}, 5);
  expect_same_mesh(read.value(), generate(spec));
  for (const std::string& field : std::vector<std::string>{
           "\"file\"", "\"shape\": \"city\"",
           "\"vertices\": " + std::to_string(read->info.vertex_count), "\"triangles\": 2500",
           "\"attributes\": \"position,normal,uv\"",
           "\"bytes\": " + std::to_string(std::filesystem::file_size(path)), "\"seconds\""})
    EXPECT_NE(output.find(field), std::string::npos) << field << " missing in " << output;
}

TEST_F(SampleFiles, CliAsciiDefaultsToAllAttributes) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  const std::filesystem::path path = dir_ / "rock.ply";
  ASSERT_EQ(run_cli("sample --shape rock --triangles 500 --ascii -o " + path.string()).first, 0);
  Result<PlyMesh> read = read_ply(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->info.format, PlyFormat::ascii);
  expect_same_mesh(read.value(), generate(spec_of(Shape::rock, 500)));
}

TEST_F(SampleFiles, CliExitCodesUsageAndIo) {
  if (std::getenv("OCTOLOD_CLI") == nullptr) GTEST_SKIP() << "OCTOLOD_CLI not set";
  const std::string out = " -o " + (dir_ / "x.ply").string();
  EXPECT_EQ(run_cli("sample --shape moon --triangles 100" + out).first, 1);
  EXPECT_EQ(run_cli("sample --shape rock --triangles 10" + out).first, 1);
  EXPECT_EQ(run_cli("sample --shape rock --triangles 1e4 --attributes bogus" + out).first, 1);
  EXPECT_EQ(run_cli("sample --shape rock --triangles 100").first, 1) << "-o is required";
  EXPECT_EQ(
      run_cli("sample --shape rock --triangles 100 -o " + (dir_ / "no" / "x.ply").string()).first,
      4);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.ply"));
}

}  // namespace
}  // namespace octolod::samplegen
