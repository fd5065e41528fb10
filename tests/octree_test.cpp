// The octree's building blocks (seed 3.4, 4.3): Morton keys, the root cube and its cells, the
// one-pass OctreeBuilder, and the exact vertex dedup that turns leaf records into a NodeMesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "morton.h"
#include "node_index.h"
#include "octolod/bake/soup.h"
#include "octree_build.h"
#include "record_file.h"
#include "streamed_leaf.h"

namespace octolod::bake {
namespace {

TEST(Morton, OctantBitsAreXThenYThenZ) {
  EXPECT_EQ(morton_encode(1, 0, 0), 1u);
  EXPECT_EQ(morton_encode(0, 1, 0), 2u);
  EXPECT_EQ(morton_encode(0, 0, 1), 4u);
  EXPECT_EQ(morton_encode(2, 0, 0), 8u);
  // The top level of a 21-level key is its three highest bits.
  const std::uint32_t top = 1u << 20;
  EXPECT_EQ(morton_encode(top, top, top) >> 60, 7u);
  EXPECT_EQ(morton_encode(0x1fffff, 0x1fffff, 0x1fffff), (std::uint64_t{1} << 63) - 1);
}

TEST(Morton, QuantizerPutsBoundsCornersInTheFirstAndLastCells) {
  Bounds b;
  b.min = {-1, 0, 2};
  b.max = {3, 1, 2.5f};
  const RootCube cube = RootCube::around(b);
  const MortonQuantizer q(cube, 3);
  const double lo[3] = {-1, 0, 2};
  const double hi[3] = {3, 0, 2};  // max x face: the last cell in x
  EXPECT_EQ(q.key(lo), 0u);
  EXPECT_EQ(q.key(hi), morton_encode(7, 0, 0));
  const double outside[3] = {-5, 9, 2};  // clamped
  EXPECT_EQ(q.key(outside), morton_encode(0, 7, 0));
}

// A flat model (a city: 3,500 wide, 60 high, in the upper half of its cube in x) keeps its
// centroids' keys in the same order and equality with the bits all of them share dropped, and
// expand gives the keys back; the upper y levels and x's top level are what is dropped. A model
// filling its cube drops nothing.
TEST(Morton, VaryingKeyBitsDropOnlyWhatEveryCentroidShares) {
  constexpr std::uint32_t kDepth = 10;
  Bounds flat;
  flat.min = {2500, 0, -1750};
  flat.max = {4500, 60, 1750};
  Bounds cube_bounds = flat;
  cube_bounds.min[0] = 0;  // the cube reaches further in x than the model
  const RootCube cube = RootCube::around(cube_bounds);
  const MortonQuantizer quantizer(cube, kDepth);
  const VaryingKeyBits varying(quantizer, kDepth, flat);
  EXPECT_FALSE(varying.keeps_every_bit());
  // y spans 60 / 4500 of the cube: its top 6 levels are constant; x spans 2500..4500 of
  // 0..4500, so only its first level is (upper half: a constant 1)
  EXPECT_EQ(varying.bits(), 3 * kDepth - 6 - 1);

  std::uint64_t state = 12345;
  auto next = [&](float lo, float hi) {
    state = state * 6364136223846793005u + 1442695040888963407u;
    return lo + (hi - lo) * static_cast<float>(state >> 40) / static_cast<float>(1u << 24);
  };
  std::vector<std::uint64_t> keys;
  for (int t = 0; t < 20000; ++t) {
    float corners[3][3];
    for (auto& corner : corners)  // the bounds' corners and faces included
      for (std::size_t a = 0; a < 3; ++a)
        corner[a] = t % 7 == 0 ? (t % 2 ? flat.max[a] : flat.min[a]) : next(flat.min[a], flat.max[a]);
    keys.push_back(centroid_key(quantizer, corners[0], corners[1], corners[2]));
  }
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    const std::uint64_t a = keys[i], b = keys[i + 1];
    const std::uint64_t ca = varying.compact(a), cb = varying.compact(b);
    ASSERT_LT(ca, std::uint64_t{1} << varying.bits());
    ASSERT_EQ(a < b, ca < cb) << i;
    ASSERT_EQ(a == b, ca == cb) << i;
    ASSERT_EQ(varying.expand(ca), a) << i;
  }

  const VaryingKeyBits full(quantizer, kDepth, cube_bounds);
  EXPECT_EQ(full.bits(), 3 * kDepth - 6);  // only y is flat
  Bounds solid;
  solid.min = {0, 0, 0};
  solid.max = {1, 1, 1};
  const MortonQuantizer solid_quantizer(RootCube::around(solid), kDepth);
  const VaryingKeyBits every(solid_quantizer, kDepth, solid);
  EXPECT_TRUE(every.keeps_every_bit());
  EXPECT_EQ(every.compact(keys[5]), keys[5]);
  EXPECT_EQ(every.expand(keys[5]), keys[5]);
}

TEST(Morton, ChildCellsNestInTheirParentAndTileIt) {
  Bounds b;
  b.min = {0.1f, -3, 7};
  b.max = {1.3f, 2, 7.5f};
  const RootCube cube = RootCube::around(b);
  const Bounds root = cube.cell(0, 0);
  for (std::size_t a = 0; a < 3; ++a) {
    EXPECT_LE(root.min[a], b.min[a]);
    EXPECT_GE(root.max[a], b.max[a]);
  }
  for (std::uint64_t parent = 0; parent < 64; ++parent) {
    const Bounds p = cube.cell(parent, 2);
    for (std::uint64_t octant = 0; octant < 8; ++octant) {
      const Bounds c = cube.cell(parent << 3 | octant, 3);
      for (std::size_t a = 0; a < 3; ++a) {
        EXPECT_GE(c.min[a], p.min[a]);
        EXPECT_LE(c.max[a], p.max[a]);
        const bool upper = ((octant >> a) & 1u) != 0;
        EXPECT_EQ(upper ? c.max[a] : c.min[a], upper ? p.max[a] : p.min[a]);
      }
    }
  }
}

// Records of 8 bytes holding an id (their own index unless given), keys given directly.
struct Stream {
  std::vector<std::byte> records;
  std::vector<std::uint64_t> keys;
  void add(std::uint64_t key) { add(key, keys.size()); }
  void add(std::uint64_t key, std::uint64_t id) {
    keys.push_back(key);
    // resize + memcpy: GCC 12 -O3 misreports vector::insert of 8 bytes as -Wstringop-overflow
    const std::size_t at = records.size();
    records.resize(at + sizeof id);
    std::memcpy(records.data() + at, &id, sizeof id);
  }
};

struct BuiltTree {
  OctreeNodes nodes;
  std::map<std::int32_t, std::vector<std::uint64_t>> leaves;  // node -> record ids
};

BuiltTree build(const Stream& s, std::uint32_t max_tris, std::uint32_t max_depth,
                std::size_t batch) {
  BuiltTree t;
  OctreeBuilder builder(max_tris, max_depth, 8, 0,
                        [&](std::int32_t node, std::vector<std::byte>&& records) {
                          auto& ids = t.leaves[node];
                          EXPECT_TRUE(ids.empty()) << "leaf " << node << " handed out twice";
                          for (std::size_t i = 0; i < records.size(); i += 8) {
                            std::uint64_t id;
                            std::memcpy(&id, records.data() + i, 8);
                            ids.push_back(id);
                          }
                          return Status{};
                        });
  for (std::size_t i = 0; i < s.keys.size(); i += batch) {
    const std::size_t n = std::min(batch, s.keys.size() - i);
    EXPECT_TRUE(builder
                    .push(std::span(s.records).subspan(i * 8, n * 8),
                          std::span(s.keys).subspan(i, n))
                    .ok());
  }
  EXPECT_TRUE(builder.finish().ok());
  t.nodes = builder.nodes();
  return t;
}

// Forgetting finished nodes (the bake's mode): every node is seen held in the LeafFn call
// after its creation, with its parent, prefix and depth; what stays held is the open path (at
// most one node per level and the leaf); size() keeps counting every node; the leaves are the
// same as when the tree is kept whole.
TEST(OctreeBuilder, ForgettingFinishedNodesKeepsOnlyTheOpenPathAndTheSameLeaves) {
  Stream s;
  for (std::uint64_t k : {001u, 001u, 005u, 005u, 032u, 060u, 067u}) s.add(k);
  const BuiltTree whole = build(s, 2, 2, 3);
  std::map<std::int32_t, std::vector<std::uint64_t>> leaves;
  std::size_t seen = 0;
  OctreeBuilder* self = nullptr;
  OctreeBuilder builder(2, 2, 8, 0, [&](std::int32_t node, std::vector<std::byte>&& records) {
    const OctreeNodes& nodes = self->nodes();
    for (; seen < nodes.size(); ++seen) {
      EXPECT_TRUE(nodes.holds(seen)) << "node " << seen << " forgotten before it was seen";
      if (!nodes.holds(seen)) continue;
      EXPECT_EQ(nodes[seen].parent, whole.nodes[seen].parent);
      EXPECT_EQ(nodes[seen].prefix, whole.nodes[seen].prefix);
      EXPECT_EQ(nodes[seen].depth, whole.nodes[seen].depth);
    }
    EXPECT_LE(nodes.held(), 2u + 1u) << "more than the open path and the leaf";
    for (std::size_t i = 0; i < records.size(); i += 8) {
      std::uint64_t id;
      std::memcpy(&id, records.data() + i, 8);
      leaves[node].push_back(id);
    }
    return Status{};
  });
  self = &builder;
  builder.forget_finished_nodes();
  ASSERT_TRUE(builder.push(s.records, s.keys).ok());
  ASSERT_TRUE(builder.finish().ok());
  EXPECT_EQ(builder.nodes().size(), whole.nodes.size());
  EXPECT_EQ(builder.nodes().held(), 0u);
  EXPECT_EQ(leaves, whole.leaves);
}

//  depth 2, keys = 2 levels (6 bits): octant of level 1 in bits 3..5, level 2 in bits 0..2.
//  root (7 records, max_tris 2) splits; child 0 holds 4 -> splits into 0/1 (2), 0/5 (2);
//  child 3 holds 1 (leaf); child 6 holds 2 (leaf).
TEST(OctreeBuilder, SplitsNodesOverMaxTrisAndHandsOutEveryRecordOnce) {
  Stream s;
  for (std::uint64_t k : {001u, 001u, 005u, 005u, 032u, 060u, 067u}) s.add(k);
  for (std::size_t batch : {1u, 3u, 100u}) {
    const BuiltTree t = build(s, 2, 2, batch);
    ASSERT_EQ(t.nodes.size(), 6u);
    EXPECT_EQ(t.nodes[0].path(), "");
    EXPECT_FALSE(t.nodes[0].leaf);
    EXPECT_EQ(t.nodes[0].triangles, 7u);
    EXPECT_EQ(t.nodes[1].path(), "0");
    EXPECT_EQ(t.nodes[1].triangles, 4u);
    EXPECT_EQ(t.nodes[2].path(), "0/1");
    EXPECT_EQ(t.nodes[3].path(), "0/5");
    EXPECT_EQ(t.nodes[4].path(), "3");
    EXPECT_EQ(t.nodes[5].path(), "6");
    // children by their parent links, octant = the last 3 bits of the prefix
    std::map<std::int32_t, std::map<std::uint64_t, std::int32_t>> children;
    for (std::size_t i = 1; i < t.nodes.size(); ++i)
      children[t.nodes[i].parent][t.nodes[i].prefix & 7u] = static_cast<std::int32_t>(i);
    EXPECT_EQ(children[0], (std::map<std::uint64_t, std::int32_t>{{0, 1}, {3, 4}, {6, 5}}));
    EXPECT_EQ(children[1], (std::map<std::uint64_t, std::int32_t>{{1, 2}, {5, 3}}));
    EXPECT_EQ(children.count(4), 0u);
    EXPECT_EQ(t.nodes[3].parent, 1);
    const std::map<std::int32_t, std::vector<std::uint64_t>> expected{
        {2, {0, 1}}, {3, {2, 3}}, {4, {4}}, {5, {5, 6}}};
    EXPECT_EQ(t.leaves, expected);
  }
}

TEST(OctreeBuilder, LeavesAtMaxDepthKeepEverything) {
  Stream s;
  for (int i = 0; i < 10; ++i) s.add(012u);  // all in 1/2
  s.add(013u);
  const BuiltTree t = build(s, 3, 2, 4);
  ASSERT_EQ(t.nodes.size(), 4u);  // root, 1, 1/2 (10 records), 1/3
  EXPECT_EQ(t.nodes[2].path(), "1/2");
  EXPECT_TRUE(t.nodes[2].leaf);
  EXPECT_EQ(t.nodes[2].triangles, 10u);
  EXPECT_EQ(t.leaves.at(2).size(), 10u);
  EXPECT_EQ(t.leaves.at(3), std::vector<std::uint64_t>{10});
}

// Ids of 8-byte Stream records.
std::vector<std::uint64_t> record_ids(std::span<const std::byte> records) {
  std::vector<std::uint64_t> ids(records.size() / 8);
  std::memcpy(ids.data(), records.data(), records.size());
  return ids;
}

// A leaf at max depth over its cap goes to the spill: its buffered records, then every later
// record of its cell, in stream order, and finish() once the stream leaves the cell; the tree is
// the same as without a cap. Records in 1/2: 10 (max_tris 3, max_depth 2; ids 9..0, so stream
// order is not id order), then one in 1/3.
TEST(OctreeBuilder, LeafAtMaxDepthOverTheCapGoesToTheSpillInStreamOrder) {
  Stream s;
  for (int i = 0; i < 10; ++i) s.add(012u, 9 - static_cast<std::uint64_t>(i));
  s.add(013u);
  for (std::uint64_t cap : {9u, 10u}) {
    for (std::size_t batch : {1u, 4u, 100u}) {
      std::vector<std::int32_t> handed_out;
      std::vector<std::uint64_t> spilled;
      std::vector<std::string> finished;
      OctreeBuilder* builder_ptr = nullptr;
      OctreeBuilder builder(
          3, 2, 8, 0,
          [&](std::int32_t node, std::vector<std::byte>&&) {
            handed_out.push_back(node);
            return Status{};
          },
          {cap,
           [&](const OctreeNode& node, std::span<const std::byte> records, std::size_t count) {
             EXPECT_EQ(node.path(), "1/2");
             EXPECT_EQ(records.size(), count * 8);
             for (std::uint64_t id : record_ids(records)) spilled.push_back(id);
             return Status{};
           },
           [&](std::int32_t node) {
             const OctreeNode& n = builder_ptr->nodes()[static_cast<std::size_t>(node)];
             finished.push_back(n.path() + " " + std::to_string(n.triangles) + (n.leaf ? " leaf" : ""));
             return Status{};
           }});
      builder_ptr = &builder;
      Status st;
      for (std::size_t i = 0; i < s.keys.size() && st.ok(); i += batch) {
        const std::size_t n = std::min(batch, s.keys.size() - i);
        st = builder.push(std::span(s.records).subspan(i * 8, n * 8),
                          std::span(s.keys).subspan(i, n));
      }
      ASSERT_TRUE(st.ok() && builder.finish().ok());
      ASSERT_EQ(builder.nodes().size(), 4u);  // the tree of LeavesAtMaxDepthKeepEverything
      EXPECT_EQ(builder.nodes()[2].triangles, 10u);
      if (cap == 10) {  // exactly at the cap: in memory
        EXPECT_TRUE(spilled.empty() && finished.empty());
        EXPECT_EQ(handed_out, (std::vector<std::int32_t>{2, 3}));
        continue;
      }
      EXPECT_EQ(spilled, (std::vector<std::uint64_t>{9, 8, 7, 6, 5, 4, 3, 2, 1, 0})) << "batch " << batch;
      EXPECT_EQ(finished, std::vector<std::string>{"1/2 10 leaf"}) << "batch " << batch;
      EXPECT_EQ(handed_out, (std::vector<std::int32_t>{3})) << "batch " << batch;
    }
  }
}

// max_tris + 1 triangles at max depth always stay in memory (a split's last child may take
// them all): a lower cap is raised to that. An error of the spill ends the build.
TEST(OctreeBuilder, LeafCapIsNeverBelowMaxTrisPlusOne) {
  Stream s;
  for (int i = 0; i < 5; ++i) s.add(010u);  // all in 1/0: root and 1 split at 4 records
  std::vector<std::string> spilled;
  OctreeBuilder builder(
      3, 2, 8, 0, [](std::int32_t, std::vector<std::byte>&&) { return Status{}; },
      {2,
       [&](const OctreeNode& node, std::span<const std::byte>, std::size_t count) {
         spilled.push_back(node.path() + " " + std::to_string(count));
         return io_error("disk full");
       },
       [](std::int32_t) { return Status{}; }});
  EXPECT_TRUE(builder.push(std::span(s.records).first(4 * 8), std::span(s.keys).first(4)).ok());
  EXPECT_TRUE(spilled.empty());
  EXPECT_EQ(builder.push(std::span(s.records).subspan(4 * 8), std::span(s.keys).subspan(4)).code(),
            ErrorCode::io);
  EXPECT_EQ(spilled, std::vector<std::string>{"1/0 4"});
}

// Equal keys may arrive in any order (the soup's order depends on its path): a leaf hands
// them out by the tie value (the u32 at tie_offset 0, the id's low half), also after a split
// replayed them.
TEST(OctreeBuilder, EqualKeysComeOutByTheirTieValue) {
  Stream s;
  for (const auto& [key, id] : std::vector<std::pair<std::uint64_t, std::uint64_t>>{
           {001, 9}, {001, 3}, {001, 5}, {002, 1}, {005, 8}, {005, 2}, {005, 7}, {005, 0}})
    s.add(key, id);
  for (std::size_t batch : {1u, 3u, 100u}) {
    const BuiltTree t = build(s, 3, 2, batch);  // root and child 0 split: leaves 0/1, 0/2, 0/5
    const std::map<std::int32_t, std::vector<std::uint64_t>> expected{
        {2, {3, 5, 9}}, {3, {1}}, {4, {0, 2, 7, 8}}};
    EXPECT_EQ(t.leaves, expected);
  }
}

TEST(OctreeBuilder, SmallInputIsASingleRootLeaf) {
  Stream s;
  for (std::uint64_t k : {0u, 0777u, 0123u}) s.add(k);
  std::sort(s.keys.begin(), s.keys.end());
  const BuiltTree t = build(s, 3, 3, 2);
  ASSERT_EQ(t.nodes.size(), 1u);
  EXPECT_TRUE(t.nodes[0].leaf);
  EXPECT_EQ(t.leaves.at(0).size(), 3u);
}

TEST(OctreeBuilder, DepthZeroKeepsEverythingInTheRoot) {
  Stream s;
  for (int i = 0; i < 5; ++i) s.add(0);
  const BuiltTree t = build(s, 1, 0, 2);
  ASSERT_EQ(t.nodes.size(), 1u);
  EXPECT_EQ(t.leaves.at(0).size(), 5u);
}

TEST(OctreeBuilder, LeafErrorEndsTheBuild) {
  OctreeBuilder builder(1, 1, 8, 0, [](std::int32_t, std::vector<std::byte>&&) {
    return io_error("disk full");
  });
  Stream s;
  s.add(0);
  s.add(1);
  s.add(2);
  const Status st = builder.push(s.records, s.keys);
  EXPECT_EQ(st.code(), ErrorCode::io);
}

// Two triangles sharing edge (1,2):   0 --- 1      records: (0,1,2), (2,1,3)
//                                     |   / |      vertex 1 of the second triangle has another
//                                     | /   |      uv (a seam): it stays a separate vertex.
//                                     2 --- 3
TEST(NodeIndexer, MergesBitIdenticalCornersAndKeepsSeams) {
  const VertexLayout layout{false, false, true};  // position + uv
  const std::vector<float> vertices = {0, 1, 0, 0, 1,  1, 1, 0, 1, 1,  0, 0, 0, 0, 0,
                                       1, 0, 0, 1, 0,  1, 1, 0, 0.5f, 1};
  const std::vector<std::uint32_t> triangles = {0, 1, 2, 2, 4, 3};
  const std::vector<std::byte> soup =
      dereference_in_memory(vertices, triangles, layout);
  NodeIndexer indexer;
  NodeMesh mesh;
  indexer.index(soup, layout, mesh);
  EXPECT_EQ(mesh.layout, layout);
  EXPECT_EQ(mesh.indices, (std::vector<std::uint32_t>{0, 1, 2, 2, 3, 4}));
  ASSERT_EQ(mesh.vertex_count(), 5u);
  const std::vector<float> expected = {0, 1, 0, 0, 1,  1, 1, 0, 1, 1,  0, 0, 0, 0, 0,
                                       1, 1, 0, 0.5f, 1,  1, 0, 0, 1, 0};
  EXPECT_EQ(mesh.vertices, expected);

  // Reuse: a second, smaller node replaces the first.
  indexer.index(std::span(soup).first(soup_record_bytes(layout)), layout, mesh);
  EXPECT_EQ(mesh.indices, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(mesh.vertex_count(), 3u);
}

// Triangle ids of a file of soup records.
std::vector<std::uint32_t> file_triangle_ids(const std::filesystem::path& file, VertexLayout layout) {
  std::vector<std::uint32_t> ids;
  auto reader = RecordReader::open(file, soup_record_bytes(layout), 4096);
  EXPECT_TRUE(reader.ok());
  if (!reader.ok()) return ids;
  for (;;) {
    auto block = reader->read();
    EXPECT_TRUE(block.ok());
    if (!block.ok() || block->empty()) return ids;
    for (std::size_t i = 0; i < block->size(); i += soup_record_bytes(layout))
      ids.push_back(static_cast<std::uint32_t>(load_soup_triangle_id(block->data() + i, layout)));
  }
}

// A leaf's spilled records come back ordered by triangle id whatever order the stream brought
// them in (equal keys), with their bytes; the spill is reusable, and a temporary file it made
// is gone once its TempFile is.
TEST(LeafRecordSpill, OrdersTheRecordsByTriangleId) {
  const VertexLayout layout;
  const std::vector<float> vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint32_t corners[3] = {0, 1, 2};
  const std::filesystem::path dir = ::testing::TempDir();
  LeafRecordSpill spill(dir, layout, 4096, 1 << 16);
  for (const std::vector<std::uint32_t>& order :
       {std::vector<std::uint32_t>{7, 3, 9, 1, 5, 0}, std::vector<std::uint32_t>{0, 2, 4, 6}}) {
    for (std::size_t first = 0; first < order.size(); first += 4) {  // appended in two runs
      std::vector<std::byte> records;
      for (std::size_t i = first; i < std::min(order.size(), first + 4); ++i) {
        records.resize(records.size() + soup_record_bytes(layout));
        store_soup_record(records.data() + records.size() - soup_record_bytes(layout), layout,
                          vertices.data(), corners, order[i]);
      }
      ASSERT_TRUE(spill.append(records).ok());
    }
    auto file = spill.finish();
    ASSERT_TRUE(file.ok()) << file.status().message();
    std::vector<std::uint32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(file_triangle_ids(file->path(), layout), sorted);
    const std::filesystem::path path = file->path();
    file = TempFile{};
    EXPECT_FALSE(std::filesystem::exists(path));
  }
}

}  // namespace
}  // namespace octolod::bake
