// Triangle soup stage (seed 3.3, 4.2, Table 4.1): split into vertex and triangle index files,
// the window pass and the three sort + dereference passes out of core, the in-core gather, and
// the in-memory reference all give the same records (the same bytes in triangle order);
// failures (out of space, read errors, bad options) clean up.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "octolod/bake/soup.h"
#include "octolod/formats/ply_reader.h"
#include "octolod/formats/ply_writer.h"
#include "ply_test_helpers.h"
#include "record_file.h"
#include "split.h"

namespace octolod::bake {
namespace {

class WorkDir {
 public:
  WorkDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("octolod-soup-" + std::to_string(::getpid()) + "-" + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_ / "work");
  }
  ~WorkDir() { std::filesystem::remove_all(path_); }
  std::filesystem::path file(const std::string& name) const { return path_ / name; }
  // Where the stage's temporary files go.
  std::filesystem::path work() const { return path_ / "work"; }
  std::size_t work_file_count() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(work()),
                                                  std::filesystem::directory_iterator()));
  }

 private:
  std::filesystem::path path_;
};

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string as_string(const std::vector<std::byte>& bytes) {
  return std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

// A soup's records in triangle order (SoupOrder::any's output compared as a set of records).
std::string by_triangle_id(const std::string& soup, VertexLayout layout) {
  const std::size_t rb = soup_record_bytes(layout);
  std::vector<std::string> records;
  for (std::size_t at = 0; at < soup.size(); at += rb) records.push_back(soup.substr(at, rb));
  auto id = [&](const std::string& r) {
    return load_soup_triangle_id(reinterpret_cast<const std::byte*>(r.data()), layout);
  };
  std::sort(records.begin(), records.end(),
            [&](const std::string& a, const std::string& b) { return id(a) < id(b); });
  std::string out;
  for (const std::string& r : records) out += r;
  return out;
}

// A w x h grid of quads (2 triangles each) on a wavy surface, with every attribute, and one
// degenerate triangle (a repeated vertex) appended. Vertex ids are shuffled by a fixed
// permutation (corners far apart: every triangle goes through the sorted passes) unless
// `shuffled` is false (rows in order, as real meshes: the window pass takes them).
struct GridMesh {
  VertexLayout layout{true, true, true};
  std::vector<float> vertices;
  std::vector<std::uint32_t> triangles;
};

GridMesh make_grid(std::uint32_t w, std::uint32_t h, bool shuffled = true) {
  GridMesh m;
  const std::uint32_t n = (w + 1) * (h + 1);
  // Position of grid vertex g in the file: a multiplicative permutation of [0, n).
  std::uint32_t mult = shuffled ? 7919 : 1;
  while (std::gcd(mult, n) != 1) ++mult;
  const auto slot = [&](std::uint32_t g) {
    return static_cast<std::uint32_t>((std::uint64_t{g} * mult) % n);
  };
  m.vertices.resize(std::size_t{n} * m.layout.floats());
  for (std::uint32_t y = 0; y <= h; ++y) {
    for (std::uint32_t x = 0; x <= w; ++x) {
      const std::uint32_t g = y * (w + 1) + x;
      float* v = &m.vertices[std::size_t{slot(g)} * m.layout.floats()];
      const float fx = static_cast<float>(x), fy = static_cast<float>(y);
      const float z = std::sin(fx * 0.1f) * std::cos(fy * 0.07f);
      const float values[11] = {fx, fy, z, 0.0f, 0.0f, 1.0f, fx / static_cast<float>(w),
                                fy / static_cast<float>(h), 0.5f, fx * 0.01f, fy * 0.01f};
      std::copy(values, values + 11, v);
    }
  }
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      const std::uint32_t a = slot(y * (w + 1) + x), b = slot(y * (w + 1) + x + 1);
      const std::uint32_t c = slot((y + 1) * (w + 1) + x), d = slot((y + 1) * (w + 1) + x + 1);
      m.triangles.insert(m.triangles.end(), {a, b, d, a, d, c});
    }
  }
  m.triangles.insert(m.triangles.end(), {slot(0), slot(0), slot(1)});
  return m;
}

void write_mesh(const std::filesystem::path& path, const GridMesh& m) {
  PlyWriteOptions options;
  options.layout = m.layout;
  options.color_type = PlyColorType::float32;  // keeps the floats exact
  const Status st = write_ply(path, options, m.vertices, m.triangles);
  ASSERT_TRUE(st.ok()) << st.message();
}

SoupOptions options_in(const WorkDir& dir, std::uint64_t budget) {
  SoupOptions o;
  o.memory_budget_bytes = budget;
  o.work_dir = dir.work();
  return o;
}

// Tiny mesh, vertex ids as written:
//
//   3 ----- 2
//   | \  1  |        triangle 0: 0 1 2
//   |  \    |        triangle 1: 0 2 3
//   | 0 \   |        triangle 2: 1 1 0  (degenerate, kept)
//   0 ----- 1
//
// Positions only; vertex i is at (i, 10 i, 100 i).
TEST(Soup, DereferenceInMemoryFollowsTheRecordContract) {
  const std::vector<float> vertices = {0, 0, 0, 1, 10, 100, 2, 20, 200, 3, 30, 300};
  const std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 2, 3, 1, 1, 0};
  const VertexLayout layout;
  ASSERT_EQ(soup_record_bytes(layout), 40u);
  const auto soup = dereference_in_memory(vertices, triangles, layout);
  ASSERT_EQ(soup.size(), 3 * 40u);
  for (std::uint32_t t = 0; t < 3; ++t) {
    const std::byte* rec = soup.data() + t * 40;
    EXPECT_EQ(load_soup_triangle_id(rec, layout), TriangleId{t});
    for (int c = 0; c < 3; ++c) {
      float p[3];
      load_soup_corner(rec, layout, c, p);
      const float id = static_cast<float>(triangles[3 * t + static_cast<std::uint32_t>(c)]);
      EXPECT_EQ(p[0], id);
      EXPECT_EQ(p[1], 10 * id);
      EXPECT_EQ(p[2], 100 * id);
    }
  }
}

TEST(Soup, SplitWritesVertexAndTriangleFilesInFileOrder) {
  WorkDir dir;
  const GridMesh mesh = make_grid(20, 10);
  write_mesh(dir.file("grid.ply"), mesh);
  auto split = split_ply_to_files(dir.file("grid.ply"), dir.file("v.bin"), dir.file("t.bin"), 4096);
  ASSERT_TRUE(split.ok()) << split.status().message();
  EXPECT_EQ(split->layout, mesh.layout);
  EXPECT_EQ(split->vertex_count, mesh.vertices.size() / 11);
  EXPECT_EQ(split->triangle_count, mesh.triangles.size() / 3);
  Bounds bounds;
  for (std::size_t i = 0; i < mesh.vertices.size(); i += 11) bounds.extend(&mesh.vertices[i]);
  EXPECT_EQ(split->bounds, bounds);
  EXPECT_EQ(split->bounds.max[0], 20.0f);
  const std::string v = read_bytes(dir.file("v.bin"));
  ASSERT_EQ(v.size(), mesh.vertices.size() * 4);
  EXPECT_EQ(std::memcmp(v.data(), mesh.vertices.data(), v.size()), 0);
  const std::string t = read_bytes(dir.file("t.bin"));
  ASSERT_EQ(t.size(), mesh.triangles.size() / 3 * sizeof(TriangleRecord));
  for (std::size_t i = 0; i < mesh.triangles.size() / 3; ++i) {
    TriangleRecord r;
    std::memcpy(&r, t.data() + i * sizeof r, sizeof r);
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(static_cast<std::uint32_t>(r.corner[c]), mesh.triangles[3 * i + static_cast<std::size_t>(c)]);
    ASSERT_EQ(r.triangle, TriangleId{static_cast<std::uint32_t>(i)});
  }
}

// The seed's out-of-core passes with a 1 MiB budget (dozens of runs, multi-pass merges) write
// exactly the bytes the in-core path and the in-memory dereference produce: 300K triangles,
// shuffled vertex ids (nearly all far for the window pass).
TEST(Soup, OutOfCoreWithTinyBudgetIsBitIdenticalToInCore) {
  WorkDir dir;
  constexpr std::uint32_t kW = 500, kH = 300;
  const GridMesh mesh = make_grid(kW, kH);
  const std::uint64_t triangles = 2u * kW * kH + 1;
  write_mesh(dir.file("grid.ply"), mesh);
  const std::string expected =
      as_string(dereference_in_memory(mesh.vertices, mesh.triangles, mesh.layout));
  {
    auto a = build_soup(dir.file("grid.ply"), options_in(dir, 256u << 20));
    ASSERT_TRUE(a.ok()) << a.status().message();
    EXPECT_TRUE(a->in_core);
    EXPECT_EQ(a->triangle_count, triangles);
    EXPECT_EQ(a->vertex_count, (kW + 1) * (kH + 1));
    EXPECT_EQ(a->layout, mesh.layout);
    EXPECT_TRUE(read_bytes(a->soup.path()) == expected);

    SoupOptions tiny = options_in(dir, 1u << 20);  // the "1M-sized buffers"
    tiny.order = SoupOrder::by_triangle;
    auto b = build_soup(dir.file("grid.ply"), tiny);
    ASSERT_TRUE(b.ok()) << b.status().message();
    EXPECT_FALSE(b->in_core);
    EXPECT_TRUE(read_bytes(b->soup.path()) == expected);
    EXPECT_GT(b->far_triangles, triangles * 96 / 100);
    ASSERT_EQ(b->sorts.size(), 4u);  // three passes, then the order sort
    for (std::size_t i = 0; i < 4; ++i) {
      const SortStats& s = b->sorts[i];
      EXPECT_FALSE(s.in_core);
      EXPECT_GT(s.runs, 20u);
      EXPECT_GE(s.merge_passes, 2u);
      EXPECT_EQ(s.records, i < 3 ? b->far_triangles : triangles);
    }
    EXPECT_EQ(b->bounds, a->bounds);
  }
  EXPECT_EQ(dir.work_file_count(), 0u);  // results destroyed: soups removed too
}

// Every path and order, one or two threads, budgets from the minimum up, shuffled or in-order
// vertex ids: the same records; in triangle order the same bytes; in any order the same bytes
// for one or two threads.
TEST(Soup, EveryPathOrderAndThreadCountGivesTheSameRecords) {
  WorkDir dir;
  for (const bool shuffled : {true, false}) {
    const GridMesh mesh = make_grid(100, 60, shuffled);
    write_mesh(dir.file("grid.ply"), mesh);
    const std::string expected =
        as_string(dereference_in_memory(mesh.vertices, mesh.triangles, mesh.layout));
    for (const SoupOrder order : {SoupOrder::any, SoupOrder::by_triangle}) {
      for (const std::uint64_t budget : {kMinSoupBudget, std::uint64_t{1} << 20}) {
        for (const bool force : {false, true}) {
          std::string one_thread;
          for (const unsigned threads : {1u, 2u}) {
            SoupOptions options = options_in(dir, budget);
            options.order = order;
            options.force_out_of_core = force;
            options.threads = threads;
            auto r = build_soup(dir.file("grid.ply"), options);
            ASSERT_TRUE(r.ok()) << r.status().message();
            EXPECT_EQ(r->in_core, !force && budget > kMinSoupBudget);
            const std::string soup = read_bytes(r->soup.path());
            const auto where = ::testing::Message()
                               << "shuffled " << shuffled << " any " << (order == SoupOrder::any)
                               << " budget " << budget << " force " << force << " threads "
                               << threads;
            if (order == SoupOrder::by_triangle) {
              EXPECT_TRUE(soup == expected) << where;
            } else {
              EXPECT_TRUE(by_triangle_id(soup, mesh.layout) == expected) << where;
            }
            if (threads == 1) one_thread = soup;
            EXPECT_TRUE(soup == one_thread) << where;
            EXPECT_GE(r->seconds.total, r->seconds.sort);
            // In-order rows: the window pass takes every triangle of the grid (a quad spans
            // 102 ids, the grid 6161, the window 512 or 4096); only the degenerate one appended
            // last reaches back to vertex 0.
            if (!r->in_core && !shuffled) {
              EXPECT_EQ(r->far_triangles, 1u) << where;
            }
          }
        }
      }
    }
  }
}

// A mesh whose rows are in order but with triangles reaching across the whole vertex file (as
// a mesh stitched from parts): the window pass takes the rows, the far ones take the three
// passes (with the degenerate triangle appended after the grid, which reaches back to vertex
// 0), the soup is the in-memory one.
TEST(Soup, WindowPassAndSortedPassesShareTheTriangles) {
  WorkDir dir;
  GridMesh mesh = make_grid(300, 100, false);
  const std::uint32_t n = 301 * 101;
  for (std::uint32_t k = 0; k < 500; ++k)
    mesh.triangles.insert(mesh.triangles.end(), {k * 50, n - 1 - k * 7, n / 2 + k});
  write_mesh(dir.file("grid.ply"), mesh);
  const std::string expected =
      as_string(dereference_in_memory(mesh.vertices, mesh.triangles, mesh.layout));
  for (const SoupOrder order : {SoupOrder::any, SoupOrder::by_triangle}) {
    SoupOptions options = options_in(dir, 1u << 20);
    options.force_out_of_core = true;
    options.order = order;
    auto r = build_soup(dir.file("grid.ply"), options);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->far_triangles, 501u);
    ASSERT_GE(r->sorts.size(), 3u);
    EXPECT_EQ(r->sorts[0].records, 501u);
    const std::string soup = read_bytes(r->soup.path());
    EXPECT_TRUE((order == SoupOrder::any ? by_triangle_id(soup, mesh.layout) : soup) == expected);
  }
  EXPECT_EQ(dir.work_file_count(), 0u);
}

TEST(Soup, SinkReceivesTheSoupInsteadOfAFile) {
  WorkDir dir;
  const GridMesh mesh = make_grid(60, 40);
  write_mesh(dir.file("grid.ply"), mesh);
  const std::string expected =
      as_string(dereference_in_memory(mesh.vertices, mesh.triangles, mesh.layout));
  for (const bool force : {false, true}) {
    std::string received;
    SoupOptions options = options_in(dir, kMinSoupBudget * 4);
    options.force_out_of_core = force;
    options.sink = [&](std::span<const std::byte> records) {
      EXPECT_EQ(records.size() % soup_record_bytes(mesh.layout), 0u);
      received.append(reinterpret_cast<const char*>(records.data()), records.size());
      return Status{};
    };
    // Told once, before any record, what the stage leaves of the budget: out of core about
    // half (a consumer can sort beside it), in core about one io buffer.
    int starts = 0;
    options.sink_start = [&](const SoupSinkStart& start) {
      ++starts;
      EXPECT_TRUE(received.empty());
      EXPECT_EQ(start.in_core, !force);
      if (force) {
        EXPECT_GE(start.free_budget_bytes, options.memory_budget_bytes / 4);
      } else {
        EXPECT_LT(start.free_budget_bytes, options.memory_budget_bytes / 4);
      }
      return Status{};
    };
    auto r = build_soup(dir.file("grid.ply"), options);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(starts, 1);
    EXPECT_TRUE(r->soup.empty());
    EXPECT_TRUE(by_triangle_id(received, mesh.layout) == expected);
    EXPECT_EQ(dir.work_file_count(), 0u);
    // A sink_start's error ends the stage before any record, and cleans up.
    options.sink_start = [](const SoupSinkStart&) { return bad_input_error("no room"); };
    received.clear();
    auto refused = build_soup(dir.file("grid.ply"), options);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().message(), "no room");
    EXPECT_TRUE(received.empty());
    EXPECT_EQ(dir.work_file_count(), 0u);
    options.sink_start = nullptr;
    // A sink's error ends the stage with it, and cleans up.
    options.sink = [](std::span<const std::byte>) { return bad_input_error("sink says no"); };
    auto failed = build_soup(dir.file("grid.ply"), options);
    ASSERT_FALSE(failed.ok());
    EXPECT_EQ(failed.status().message(), "sink says no");
    EXPECT_EQ(dir.work_file_count(), 0u);
  }
}

TEST(Soup, MeshSinkReceivesTheIndexedMeshInsteadOfRecords) {
  WorkDir dir;
  const GridMesh mesh = make_grid(60, 40);
  write_mesh(dir.file("grid.ply"), mesh);
  SoupOptions options = options_in(dir, kMinSoupBudget * 4);
  int records = 0;
  options.sink = [&](std::span<const std::byte>) {
    ++records;
    return Status{};
  };
  std::vector<float> vertices;
  std::vector<std::uint32_t> triangles;
  options.mesh_sink.accepts = [&](VertexLayout layout, std::uint64_t v, std::uint64_t t) {
    EXPECT_EQ(layout, mesh.layout);
    EXPECT_EQ(v, mesh.vertices.size() / mesh.layout.floats());
    EXPECT_EQ(t, mesh.triangles.size() / 3);
    return true;
  };
  options.mesh_sink.consume = [&](const SoupMesh& m) {
    vertices.assign(m.vertices.begin(), m.vertices.end());
    triangles.assign(m.triangles.begin(), m.triangles.end());
    EXPECT_LE(m.free_budget_bytes, options.memory_budget_bytes -
                                        vertices.size() * sizeof(float) -
                                        triangles.size() * sizeof(std::uint32_t));
    return Status{};
  };
  auto r = build_soup(dir.file("grid.ply"), options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->mesh_consumed);
  EXPECT_TRUE(r->in_core);
  EXPECT_TRUE(r->soup.empty());
  EXPECT_EQ(records, 0);
  EXPECT_EQ(vertices, mesh.vertices);
  EXPECT_EQ(triangles, mesh.triangles);
  EXPECT_EQ(dir.work_file_count(), 0u);
  // Refused (or out of core): the records path, and consume's error ends the stage.
  options.mesh_sink.accepts = [](VertexLayout, std::uint64_t, std::uint64_t) { return false; };
  auto refused = build_soup(dir.file("grid.ply"), options);
  ASSERT_TRUE(refused.ok());
  EXPECT_FALSE(refused->mesh_consumed);
  EXPECT_GT(records, 0);
  options.mesh_sink.accepts = [](VertexLayout, std::uint64_t, std::uint64_t) { return true; };
  options.mesh_sink.consume = [](const SoupMesh&) { return bad_input_error("mesh says no"); };
  auto failed = build_soup(dir.file("grid.ply"), options);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.status().message(), "mesh says no");
  EXPECT_EQ(dir.work_file_count(), 0u);
}

TEST(Soup, FacesBeforeVerticesGiveTheSameSoup) {
  WorkDir dir;
  const std::string ply =
      "ply\nformat ascii 1.0\nelement face 3\nproperty list uchar int vertex_indices\n"
      "element vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
      "3 4 1 2\n4 0 2 3 4\n3 3 3 1\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n";
  std::ofstream(dir.file("f.ply"), std::ios::binary) << ply;
  const std::vector<float> vertices = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5f, 0.5f, 1};
  // Fan triangulation of the quad: (0 2 3) (0 3 4).
  const std::vector<std::uint32_t> triangles = {4, 1, 2, 0, 2, 3, 0, 3, 4, 3, 3, 1};
  const std::string expected =
      as_string(dereference_in_memory(vertices, triangles, VertexLayout{}));
  for (const bool force : {false, true}) {
    SoupOptions options = options_in(dir, 1u << 20);
    options.force_out_of_core = force;
    options.order = SoupOrder::by_triangle;
    // The quad fans out into more triangles than the 3 faces declared: a mesh sink is never
    // handed a truncated mesh, the stage reads the PLY again for the records path.
    options.mesh_sink.accepts = [](VertexLayout, std::uint64_t, std::uint64_t) { return true; };
    options.mesh_sink.consume = [](const SoupMesh&) {
      ADD_FAILURE() << "mesh sink called for a fanned-out polygon";
      return Status{};
    };
    auto r = build_soup(dir.file("f.ply"), options);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_FALSE(r->mesh_consumed);
    EXPECT_EQ(r->triangle_count, 4u);
    EXPECT_TRUE(read_bytes(r->soup.path()) == expected);
  }
}

// Attributes per face corner (a texcoord list per face, a colour per face; vertices without
// them: test::write_face_attribute_ply) give the soup of the same mesh with a vertex per wedge, on
// every path and in every order, with or without a sink; a mesh sink is never offered a mesh
// whose attributes are per corner. The mesh has a UV seam: the right half's triangles use copies
// of their vertices with u + 1, which the file welds back to one vertex each when the UVs are on
// the faces; with face colours, every 97 triangles have another colour.
TEST(Soup, CornerAttributesGiveTheSoupOfTheirWedges) {
  WorkDir dir;
  GridMesh grid = make_grid(100, 60);
  const std::size_t floats = grid.layout.floats();
  const auto n = static_cast<std::uint32_t>(grid.vertices.size() / floats);
  for (std::uint32_t v = 0; v < n; ++v) {
    grid.vertices.insert(grid.vertices.end(), grid.vertices.begin() + v * floats,
                         grid.vertices.begin() + (v + 1) * floats);
    grid.vertices[grid.vertices.size() - 2] += 1.0f;
  }
  for (std::size_t t = 0; t + 3 < grid.triangles.size(); t += 3)  // the degenerate one stays
    if (grid.vertices[grid.triangles[t] * floats] >= 50.0f)
      for (std::size_t c = 0; c < 3; ++c) grid.triangles[t + c] += n;
  const test::TestMesh coloured = test::with_face_colours(grid.layout, grid.vertices, grid.triangles);
  ASSERT_EQ(coloured.layout, grid.layout);
  for (const CornerAttributes corners : {CornerAttributes{.uv = true}, CornerAttributes{.color = true},
                                         CornerAttributes{.color = true, .uv = true}}) {
    const std::vector<float>& vertices = corners.color ? coloured.vertices : grid.vertices;
    const std::vector<std::uint32_t>& triangles = corners.color ? coloured.triangles : grid.triangles;
    const auto file = dir.file("corner.ply");
    test::write_face_attribute_ply(file, grid.layout, vertices, triangles, corners);
    auto reader = PlyReader::open(file);
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    const std::uint64_t file_vertices = reader.value()->info().vertex_count;
    reader.value().reset();
    if (corners.uv) {
      EXPECT_EQ(file_vertices, n);  // the copies welded back
    }
    const std::string expected = as_string(dereference_in_memory(vertices, triangles, grid.layout));
    for (const SoupOrder order : {SoupOrder::any, SoupOrder::by_triangle}) {
      for (const std::uint64_t budget : {kMinSoupBudget, std::uint64_t{1} << 20}) {
        for (const bool force : {false, true}) {
          for (const bool sink : {false, true}) {
            if (sink && budget == kMinSoupBudget) continue;  // the sink's path is the file's
            const auto where = ::testing::Message()
                               << "colour " << corners.color << " uv " << corners.uv << " any "
                               << (order == SoupOrder::any) << " budget " << budget << " force " << force
                               << " sink " << sink;
            SoupOptions options = options_in(dir, budget);
            options.order = order;
            options.force_out_of_core = force;
            std::string received;
            if (sink) {
              options.sink = [&](std::span<const std::byte> records) {
                received.append(reinterpret_cast<const char*>(records.data()), records.size());
                return Status{};
              };
            }
            options.mesh_sink.accepts = [](VertexLayout, std::uint64_t, std::uint64_t) { return true; };
            options.mesh_sink.consume = [](const SoupMesh&) {
              ADD_FAILURE() << "mesh sink called for attributes per corner";
              return Status{};
            };
            auto r = build_soup(file, options);
            ASSERT_TRUE(r.ok()) << r.status().message() << where;
            EXPECT_EQ(r->layout, grid.layout) << where;
            EXPECT_EQ(r->in_core, !force && budget > kMinSoupBudget) << where;
            EXPECT_EQ(r->vertex_count, file_vertices) << where;
            const std::string soup = sink ? received : read_bytes(r->soup.path());
            // corner values are patched in in triangle order, whatever order was asked for
            EXPECT_TRUE(soup == expected) << where;
          }
          EXPECT_EQ(dir.work_file_count(), 0u);
        }
      }
    }
  }
}

TEST(Soup, EmptyMeshGivesAnEmptySoup) {
  WorkDir dir;
  PlyWriteOptions write_options;
  ASSERT_TRUE(write_ply(dir.file("empty.ply"), write_options, {}, {}).ok());
  for (const bool force : {false, true}) {
    SoupOptions options = options_in(dir, 1u << 20);
    options.force_out_of_core = force;
    auto r = build_soup(dir.file("empty.ply"), options);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->triangle_count, 0u);
    EXPECT_EQ(r->vertex_count, 0u);
    EXPECT_TRUE(r->bounds.empty());
    EXPECT_EQ(std::filesystem::file_size(r->soup.path()), 0u);
  }
}

TEST(Soup, ProgressReportsEveryStage) {
  WorkDir dir;
  const GridMesh mesh = make_grid(100, 60);  // more vertices than the window: far triangles
  write_mesh(dir.file("grid.ply"), mesh);
  std::set<std::string> stages;
  SoupOptions options = options_in(dir, 1u << 20);
  options.force_out_of_core = true;
  options.order = SoupOrder::by_triangle;
  std::uint64_t last_total = 0, last_done = 0;
  options.progress = [&](std::string_view stage, std::uint64_t done, std::uint64_t total) {
    stages.insert(std::string(stage));
    EXPECT_LE(done, total);
    last_done = done;
    last_total = total;
  };
  auto r = build_soup(dir.file("grid.ply"), options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(stages, (std::set<std::string>{"split", "dereference", "dereference 0",
                                           "dereference 1", "dereference 2", "order"}));
  EXPECT_EQ(last_done, r->triangle_count);
  EXPECT_EQ(last_total, r->triangle_count);
}

TEST(Soup, BadOptionsAreUsageErrors) {
  WorkDir dir;
  const GridMesh mesh = make_grid(4, 4);
  write_mesh(dir.file("grid.ply"), mesh);
  auto small = build_soup(dir.file("grid.ply"), options_in(dir, kMinSoupBudget - 1));
  ASSERT_FALSE(small.ok());
  EXPECT_EQ(small.status().code(), ErrorCode::usage);
  SoupOptions missing = options_in(dir, 1u << 20);
  missing.work_dir = dir.file("no-such-dir");
  auto m = build_soup(dir.file("grid.ply"), missing);
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.status().code(), ErrorCode::usage);
  EXPECT_NE(m.status().message().find("no-such-dir"), std::string::npos);
  auto absent = build_soup(dir.file("absent.ply"), options_in(dir, 1u << 20));
  ASSERT_FALSE(absent.ok());
  EXPECT_NE(absent.status().message().find("absent.ply"), std::string::npos);
}

// Out of space at any point of the out-of-core path (vertex file, runs, merges, soup): an io
// error naming a temporary file, and nothing left in the work directory.
TEST(Soup, OutOfSpaceAnywhereIsAnIoErrorAndLeavesNoFiles) {
  WorkDir dir;
  const GridMesh mesh = make_grid(100, 60);
  write_mesh(dir.file("grid.ply"), mesh);
  SoupOptions options = options_in(dir, kMinSoupBudget);
  options.force_out_of_core = true;
  options.order = SoupOrder::by_triangle;
  std::uint64_t total_written = 0;
  {
    auto r = build_soup(dir.file("grid.ply"), options);
    ASSERT_TRUE(r.ok());
    for (const SortStats& s : r->sorts) total_written += s.bytes_written;
  }
  for (std::uint64_t after = 0; after < total_written; after += total_written / 13 + 1) {
    Status failure;
    {
      ScopedIoFault fault(ScopedIoFault::Op::write, after, ENOSPC);
      auto r = build_soup(dir.file("grid.ply"), options);
      if (!r.ok()) failure = r.status();
    }
    ASSERT_FALSE(failure.ok()) << "fault after " << after;
    EXPECT_EQ(failure.code(), ErrorCode::io);
    EXPECT_NE(failure.message().find("No space left on device"), std::string::npos);
    EXPECT_NE(failure.message().find(dir.work().string()), std::string::npos) << failure.message();
    EXPECT_EQ(dir.work_file_count(), 0u) << "fault after " << after;
  }
}

TEST(Soup, ReadErrorIsAnIoErrorAndLeavesNoFiles) {
  WorkDir dir;
  const GridMesh mesh = make_grid(100, 60);
  write_mesh(dir.file("grid.ply"), mesh);
  SoupOptions options = options_in(dir, kMinSoupBudget);
  options.force_out_of_core = true;
  for (const std::uint64_t after : {std::uint64_t{0}, std::uint64_t{100000}, std::uint64_t{1000000}}) {
    Status failure;
    {
      ScopedIoFault fault(ScopedIoFault::Op::read, after, EIO);
      auto r = build_soup(dir.file("grid.ply"), options);
      if (!r.ok()) failure = r.status();
    }
    ASSERT_FALSE(failure.ok());
    EXPECT_EQ(failure.code(), ErrorCode::io);
    EXPECT_EQ(dir.work_file_count(), 0u);
  }
}

TEST(Soup, ReleasedSoupOutlivesTheResult) {
  WorkDir dir;
  const GridMesh mesh = make_grid(4, 4);
  write_mesh(dir.file("grid.ply"), mesh);
  std::filesystem::path kept;
  {
    auto r = build_soup(dir.file("grid.ply"), options_in(dir, 1u << 20));
    ASSERT_TRUE(r.ok());
    kept = r->soup.release();
  }
  EXPECT_EQ(std::filesystem::file_size(kept), 33u * soup_record_bytes(mesh.layout));
  std::filesystem::remove(kept);
}

}  // namespace
}  // namespace octolod::bake
