// Fixtures for runtime_tests: a synthetic baked tree held in memory, cameras, a brute-force
// reference selection and the "no holes, no overlap" check of a draw list.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/runtime/camera.h"
#include "octolod/runtime/executor.h"
#include "octolod/runtime/node_source.h"
#include "octolod/runtime/streaming_tree.h"

namespace octolod::runtime::testing {

// A triangle strip of `triangles` triangles whose tight bounds are exactly `box`: vertices run
// from box.min to box.max along the diagonal, odd ones pushed to the box's x minimum.
inline NodeMesh strip_mesh(const Bounds& box, std::uint32_t triangles) {
  NodeMesh mesh;
  const std::uint32_t vertices = triangles + 2;
  for (std::uint32_t i = 0; i < vertices; ++i) {
    const float t = static_cast<float>(i) / static_cast<float>(vertices - 1);
    for (int a = 0; a < 3; ++a) {
      const auto k = static_cast<std::size_t>(a);
      float v = box.min[k] + t * (box.max[k] - box.min[k]);
      if (a == 0 && (i % 2) == 1) v = box.min[k];
      mesh.vertices.push_back(v);
    }
  }
  for (std::uint32_t i = 0; i < triangles; ++i) {
    mesh.indices.push_back(i);
    mesh.indices.push_back(i + 1);
    mesh.indices.push_back(i + 2);
  }
  return mesh;
}

inline std::uint64_t decoded_bytes(std::uint32_t triangles) {
  return (std::uint64_t{triangles + 2} * 3 + std::uint64_t{triangles} * 3) * 4;
}

// A full octree of `levels` levels (3 -> 1 + 8 + 64 nodes) over the cube [0, size]^3, every node
// with two LODs: lods[0] of kFineTriangles (error 0 for leaves, 1% of the cell edge for inner
// nodes) and lods[1] of kCoarseTriangles (error 4% of the cell edge). Node files live in an
// in-memory source as "<path>/lod<i>.bin" ("lod<i>.bin" for the root). Manifest nodes are in
// breadth-first order (parents precede children), unlike the runtime's internal preorder.
struct SyntheticTree {
  static constexpr std::uint32_t kFineTriangles = 64;
  static constexpr std::uint32_t kCoarseTriangles = 16;
  Manifest manifest;
  std::shared_ptr<MemorySource> source = std::make_shared<MemorySource>();

  std::uint32_t node_at(const std::string& path) const {
    for (std::size_t i = 0; i < manifest.nodes.size(); ++i)
      if (manifest.nodes[i].path == path) return static_cast<std::uint32_t>(i);
    ADD_FAILURE() << "no node " << path;
    return 0;
  }
  bool is_ancestor(std::uint32_t ancestor, std::uint32_t node) const {
    for (std::int32_t p = manifest.nodes[node].parent; p >= 0; p = manifest.nodes[static_cast<std::size_t>(p)].parent)
      if (static_cast<std::uint32_t>(p) == ancestor) return true;
    return false;
  }
  std::uint64_t lod_bytes(std::uint32_t node, std::uint32_t lod) const {
    const LodInfo& l = manifest.nodes[node].lods[lod];
    return decoded_bytes(l.triangles);
  }
};

inline SyntheticTree make_full_octree(std::uint32_t levels, float size = 64.0f) {
  SyntheticTree t;
  Manifest& m = t.manifest;
  m.bounds.min = {0, 0, 0};
  m.bounds.max = {size, size, size};
  NodeInfo root;
  root.cell = m.bounds;
  root.bounds = m.bounds;
  m.nodes.push_back(root);
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {  // breadth first
    if (m.nodes[i].depth + 1 >= levels) continue;
    for (std::uint32_t octant = 0; octant < 8; ++octant) {
      NodeInfo child;
      child.depth = m.nodes[i].depth + 1;
      child.parent = static_cast<std::int32_t>(i);
      child.path = (m.nodes[i].path.empty() ? "" : m.nodes[i].path + "/") + std::to_string(octant);
      for (std::size_t a = 0; a < 3; ++a) {
        const float lo = m.nodes[i].cell.min[a], hi = m.nodes[i].cell.max[a], mid = 0.5f * (lo + hi);
        const bool upper = (octant >> a) & 1u;
        child.cell.min[a] = upper ? mid : lo;
        child.cell.max[a] = upper ? hi : mid;
      }
      child.bounds = child.cell;
      m.nodes[i].children[octant] = static_cast<std::int32_t>(m.nodes.size());
      m.nodes.push_back(child);
    }
  }
  for (NodeInfo& n : m.nodes) {
    const double edge = n.cell.max[0] - n.cell.min[0];
    const std::uint32_t tris[2] = {SyntheticTree::kFineTriangles, SyntheticTree::kCoarseTriangles};
    const double errors[2] = {n.is_leaf() ? 0.0 : 0.01 * edge, 0.04 * edge};
    for (std::size_t l = 0; l < 2; ++l) {
      const NodeMesh mesh = strip_mesh(n.bounds, tris[l]);
      LodInfo lod;
      lod.triangles = tris[l];
      lod.vertices = static_cast<std::uint32_t>(mesh.vertex_count());
      lod.error = errors[l];
      std::vector<std::byte> bytes = encode_node_file(mesh);
      lod.bytes = bytes.size();
      lod.file = (n.path.empty() ? "" : n.path + "/") + "lod" + std::to_string(l) + ".bin";
      t.source->put(lod.file, std::move(bytes));
      n.lods.push_back(lod);
    }
    n.source_triangles = SyntheticTree::kFineTriangles;
  }
  return t;
}

// Writes the tree as a baker would: `dir`/manifest.json and every node file below `dir`.
inline void write_tree(const SyntheticTree& t, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  ASSERT_TRUE(write_manifest(dir / std::string(kManifestFileName), t.manifest).ok());
  for (const NodeInfo& n : t.manifest.nodes) {
    for (const LodInfo& lod : n.lods) {
      Result<std::vector<std::byte>> bytes = t.source->read(lod.file, lod.bytes);
      ASSERT_TRUE(bytes.ok());
      const std::filesystem::path file = dir / lod.file;
      std::filesystem::create_directories(file.parent_path());
      std::ofstream out(file, std::ios::binary);
      out.write(reinterpret_cast<const char*>(bytes->data()), static_cast<std::streamsize>(bytes->size()));
      ASSERT_TRUE(out.good()) << file;
    }
  }
}

constexpr float kFovy = 1.0471976f;  // 60 degrees
constexpr float kViewportHeight = 1000.0f;

inline Camera look(glm::vec3 eye, glm::vec3 target) {
  return make_perspective_camera(eye, target, glm::vec3(0, 1, 0), kFovy, 1.0f, 0.01f, 10000.0f,
                                 kViewportHeight);
}

// Screen-space error in pixels of `error` at `distance` for a vertical field of view `fovy`,
// the runtime's formula; for an orthographic view `ortho_height` (> 0) model units high, the
// same at every distance.
inline double sse_pixels(double error, double distance, double fovy = kFovy, double ortho_height = 0.0) {
  if (ortho_height > 0.0) return error * kViewportHeight / ortho_height;
  return error * kViewportHeight / (2.0 * std::tan(fovy / 2.0) * distance);
}

inline double box_distance(const Bounds& b, glm::vec3 p) {
  double sum = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max({static_cast<double>(b.min[static_cast<std::size_t>(a)]) - p[a], 0.0,
                               p[a] - static_cast<double>(b.max[static_cast<std::size_t>(a)])});
    sum += d * d;
  }
  return std::sqrt(sum);
}

inline bool visible(const Frustum& f, const Bounds& b) {
  const glm::vec3 lo(b.min[0], b.min[1], b.min[2]), hi(b.max[0], b.max[1], b.max[2]);
  return classify_box(f, 0.5f * (lo + hi), 0.5f * (hi - lo)) != Containment::outside;
}

// The cut written the obvious recursive way, from the manifest (tight bounds of the synthetic
// tree nest, so node bounds are subtree bounds), for `camera` whose projection has the vertical
// field of view `fovy` (or which is orthographic, `ortho_height` model units high: sse_pixels):
// {manifest node -> lod}.
inline void reference_cut(const Manifest& m, const Camera& camera, double target, std::uint32_t node,
                          std::map<std::uint32_t, std::uint32_t>& out, double fovy = kFovy,
                          double ortho_height = 0.0) {
  const NodeInfo& n = m.nodes[node];
  if (!visible(extract_frustum(camera.projection * camera.view), n.bounds)) return;
  const double d = std::max(box_distance(n.bounds, camera.position), 1e-3);
  for (std::size_t l = n.lods.size(); l-- > 0;) {
    if (sse_pixels(n.lods[l].error, d, fovy, ortho_height) <= target) {
      out[node] = static_cast<std::uint32_t>(l);
      return;
    }
  }
  if (n.is_leaf()) {
    out[node] = 0;
    return;
  }
  for (std::int32_t c : n.children)
    if (c >= 0) reference_cut(m, camera, target, static_cast<std::uint32_t>(c), out, fovy, ortho_height);
}

inline std::map<std::uint32_t, std::uint32_t> draws_of(const FrameResult& frame) {
  std::map<std::uint32_t, std::uint32_t> out;
  for (const DrawItem& d : frame.draws) out[d.node] = d.lod;
  return out;
}

// No holes and no overlap: every leaf inside the frustum has itself or exactly one ancestor
// drawn, no drawn node is an ancestor of another, every draw has a mesh.
inline void expect_covering_cut(const SyntheticTree& t, const FrameResult& frame, const Camera& camera) {
  const Frustum f = extract_frustum(camera.projection * camera.view);
  std::set<std::uint32_t> drawn;
  for (const DrawItem& d : frame.draws) {
    ASSERT_TRUE(d.mesh) << "draw of node " << d.node << " without a mesh";
    EXPECT_TRUE(drawn.insert(d.node).second) << "node " << d.node << " drawn twice";
  }
  for (std::uint32_t a : drawn)
    for (std::uint32_t b : drawn)
      EXPECT_FALSE(t.is_ancestor(a, b)) << "node " << a << " overlaps its descendant " << b;
  for (std::size_t i = 0; i < t.manifest.nodes.size(); ++i) {
    const NodeInfo& leaf = t.manifest.nodes[i];
    if (!leaf.is_leaf() || !visible(f, leaf.bounds)) continue;
    bool covered = drawn.count(static_cast<std::uint32_t>(i)) > 0;
    for (std::int32_t p = leaf.parent; p >= 0 && !covered; p = t.manifest.nodes[static_cast<std::size_t>(p)].parent)
      covered = drawn.count(static_cast<std::uint32_t>(p)) > 0;
    EXPECT_TRUE(covered) << "visible leaf " << leaf.path << " is a hole";
  }
}

// Steps frames, running every posted load between them, until a frame issues nothing and has
// nothing in flight. Returns that settled frame.
inline const FrameResult& settle(StreamingTree& tree, SynchronousExecutor& executor, const Camera& camera,
                                 int max_frames = 50) {
  const FrameResult* frame = &tree.update(camera);
  for (int i = 0; i < max_frames; ++i) {
    if (frame->stats.loads_in_flight == 0 && frame->stats.loads_issued == 0 &&
        frame->stats.loads_completed == 0)
      break;
    executor.run_pending();
    frame = &tree.update(camera);
  }
  return *frame;
}

}  // namespace octolod::runtime::testing
