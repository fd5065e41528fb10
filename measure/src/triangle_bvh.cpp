// TriangleBvh: binned SAH build (Wald 2007) along the widest axis and nearest-first closest-point
// traversal with Ericson's point-triangle distance (Real-Time Collision Detection, 5.1.5).
#include "octolod/measure/triangle_bvh.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include <glm/geometric.hpp>

namespace octolod::measure {
namespace {

constexpr int kBins = 16;
// Leaves hold at most this many triangles unless their centroids coincide.
constexpr std::uint32_t kMaxLeafTriangles = 4;
// Below this depth splits follow the SAH; deeper ones split at the object median, which bounds
// the depth (and the traversal stack) by kSahDepth + log2(n) even for adversarial inputs.
constexpr std::uint32_t kSahDepth = 40;
constexpr std::size_t kStackSize = 128;

struct Box {
  glm::vec3 min{std::numeric_limits<float>::max()};
  glm::vec3 max{std::numeric_limits<float>::lowest()};

  void extend(glm::vec3 p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void extend(const Box& b) {
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  float half_area() const {
    glm::vec3 e = glm::max(max - min, glm::vec3(0.0f));
    return e.x * e.y + e.y * e.z + e.z * e.x;
  }
};

// Squared distance from p to the box [lo, hi] (0 inside).
inline float box_distance2(glm::vec3 p, glm::vec3 lo, glm::vec3 hi) {
  glm::vec3 d = glm::max(glm::max(lo - p, p - hi), glm::vec3(0.0f));
  return glm::dot(d, d);
}

// Closest point on the segment [a, b] to p, as the weight t of b (point = a + t (b - a)).
inline float segment_parameter(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
  glm::vec3 ab = b - a;
  float len2 = glm::dot(ab, ab);
  if (!(len2 > 0.0f)) return 0.0f;
  return std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f);
}

// Ericson 5.1.5 ClosestPtPointTriangle, returning barycentric weights of a, b, c. Voronoi
// regions of the vertices and edges are tested first, so only the interior case divides by the
// (area-proportional) denominator; for a degenerate triangle whose float noise lands there, the
// closest of the three edges is taken instead.
inline glm::vec3 closest_barycentric(glm::vec3 p, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
  glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return {1.0f, 0.0f, 0.0f};
  glm::vec3 bp = p - b;
  float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return {0.0f, 1.0f, 0.0f};
  float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    float v = d1 / (d1 - d3);
    return {1.0f - v, v, 0.0f};
  }
  glm::vec3 cp = p - c;
  float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return {0.0f, 0.0f, 1.0f};
  float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    float w = d2 / (d2 - d6);
    return {1.0f - w, 0.0f, w};
  }
  float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0.0f, 1.0f - w, w};
  }
  float denom = va + vb + vc;
  if (denom > 0.0f && std::isfinite(denom)) {
    float v = vb / denom, w = vc / denom;
    return {1.0f - v - w, v, w};
  }
  // Degenerate: best of the three edges.
  float tab = segment_parameter(p, a, b), tbc = segment_parameter(p, b, c),
        tca = segment_parameter(p, c, a);
  glm::vec3 qab = a + tab * (b - a), qbc = b + tbc * (c - b), qca = c + tca * (a - c);
  float dab = glm::dot(p - qab, p - qab), dbc = glm::dot(p - qbc, p - qbc),
        dca = glm::dot(p - qca, p - qca);
  if (dab <= dbc && dab <= dca) return {1.0f - tab, tab, 0.0f};
  if (dbc <= dca) return {0.0f, 1.0f - tbc, tbc};
  return {tca, 0.0f, 1.0f - tca};
}

// A node to build: its triangles refs[begin, end) and the union of their boxes (its parent's
// SAH sweep has it: min and max are exact, so the union of the bins' boxes is that box).
struct BuildTask {
  std::uint32_t node, begin, end, depth;
  Box bounds;
};

}  // namespace

TriangleBvh::TriangleBvh(std::span<const float> vertices, std::uint32_t stride_floats,
                         std::span<const std::uint32_t> indices) {
  assert(stride_floats >= 3 && "TriangleBvh: a vertex needs at least x,y,z");
  assert(indices.size() % 3 == 0 && "TriangleBvh: indices must hold 3 per triangle");
  assert(indices.size() / 3 < kNoTriangle && "TriangleBvh: too many triangles");
  const std::size_t vertex_count = vertices.size() / stride_floats;
  auto position = [&](std::uint32_t v) {
    assert(v < vertex_count && "TriangleBvh: vertex index out of range");
    (void)vertex_count;
    const float* f = vertices.data() + std::size_t{v} * stride_floats;
    return glm::vec3(f[0], f[1], f[2]);
  };
  std::vector<Triangle> triangles(indices.size() / 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    triangles[t] = {position(indices[3 * t]), position(indices[3 * t + 1]),
                    position(indices[3 * t + 2]), static_cast<std::uint32_t>(t)};
  build(std::move(triangles));
}

void TriangleBvh::build(std::vector<Triangle> triangles) {
  const auto n = static_cast<std::uint32_t>(triangles.size());
  if (n == 0) return;

  // per-triangle bounds and centroids, referenced through `refs` while partitioning
  std::vector<Box> boxes(n);
  std::vector<glm::vec3> centroids(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const Triangle& tri = triangles[t];
    boxes[t].min = glm::min(tri.a, glm::min(tri.b, tri.c));
    boxes[t].max = glm::max(tri.a, glm::max(tri.b, tri.c));
    centroids[t] = (boxes[t].min + boxes[t].max) * 0.5f;
  }
  std::vector<std::uint32_t> refs(n);
  for (std::uint32_t t = 0; t < n; ++t) refs[t] = t;
  // the task for refs[begin, end) where no sweep gave its bounds: the root and the children of
  // the splits without one (coincident centroids, the object median)
  auto task_of = [&](std::uint32_t node, std::uint32_t begin, std::uint32_t end, std::uint32_t depth) {
    BuildTask task{node, begin, end, depth, {}};
    for (std::uint32_t i = begin; i < end; ++i) task.bounds.extend(boxes[refs[i]]);
    return task;
  };
  std::vector<std::uint8_t> bin(n);  // per triangle: its bin in the last node binned

  nodes_.clear();
  nodes_.reserve(std::size_t{n} / 2 + 1);
  nodes_.push_back({});
  std::vector<BuildTask> tasks{task_of(0, 0, n, 0)};
  while (!tasks.empty()) {
    const BuildTask task = tasks.back();
    tasks.pop_back();

    Node& node = nodes_[task.node];
    node.min = task.bounds.min;
    node.max = task.bounds.max;
    const std::uint32_t count = task.end - task.begin;
    auto make_leaf = [&] {
      node.first = task.begin;
      node.count = count;
    };
    if (count <= kMaxLeafTriangles) {
      make_leaf();
      continue;
    }

    Box centroid_bounds;
    for (std::uint32_t i = task.begin; i < task.end; ++i) centroid_bounds.extend(centroids[refs[i]]);
    glm::vec3 extent = centroid_bounds.max - centroid_bounds.min;
    int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    if (!(extent[axis] > 0.0f)) {
      // every centroid coincides: no split separates them; split the range in two anyway so
      // leaves stay small (only the box test prunes here)
      std::uint32_t mid = task.begin + count / 2;
      node.first = static_cast<std::uint32_t>(nodes_.size());
      node.count = 0;
      std::uint32_t left = node.first;
      nodes_.push_back({});
      nodes_.push_back({});
      tasks.push_back(task_of(left, task.begin, mid, task.depth + 1));
      tasks.push_back(task_of(left + 1, mid, task.end, task.depth + 1));
      continue;
    }

    std::uint32_t mid = task.begin;
    Box below, above;  // the bounds of the SAH split's two sides
    if (task.depth < kSahDepth) {
      // binned SAH along the widest centroid axis (all three cost the bake's small, many builds
      // 3.5% of its time and made no query measurably faster: docs/benchmarks.md)
      std::array<Box, kBins> bin_box;
      std::array<std::uint32_t, kBins> bin_count{};
      const float lo = centroid_bounds.min[axis], scale = static_cast<float>(kBins) / extent[axis];
      for (std::uint32_t i = task.begin; i < task.end; ++i) {
        const std::uint32_t r = refs[i];
        const auto b = static_cast<std::size_t>(std::min(kBins - 1, static_cast<int>((centroids[r][axis] - lo) * scale)));
        bin[r] = static_cast<std::uint8_t>(b);
        bin_box[b].extend(boxes[r]);
        ++bin_count[b];
      }
      // sweep from the right, then from the left. An empty bin changes nothing: the cost to its
      // right is the next one's, and the split after it costs what the split before it did (the
      // earlier one wins a tie), so it is skipped (a node of tens of triangles leaves most empty).
      std::array<float, kBins> right_cost{};
      std::array<Box, kBins> right_box;  // the union of bins b and up
      Box acc;
      std::uint32_t acc_count = 0;
      for (std::size_t b = kBins - 1; b > 0; --b) {
        if (bin_count[b] == 0) {
          right_cost[b] = b + 1 < kBins ? right_cost[b + 1] : 0.0f;
          right_box[b] = acc;
          continue;
        }
        acc.extend(bin_box[b]);
        acc_count += bin_count[b];
        right_cost[b] = acc.half_area() * static_cast<float>(acc_count);
        right_box[b] = acc;
      }
      float best_cost = std::numeric_limits<float>::infinity();
      std::size_t best_split = 0;
      acc = Box{};
      acc_count = 0;
      for (std::size_t b = 0; b + 1 < kBins; ++b) {
        if (bin_count[b] == 0) continue;
        acc.extend(bin_box[b]);
        acc_count += bin_count[b];
        if (acc_count == count) continue;
        const float cost = acc.half_area() * static_cast<float>(acc_count) + right_cost[b + 1];
        if (cost < best_cost) best_cost = cost, best_split = b + 1, below = acc;
      }
      if (best_split > 0) {
        auto it = std::partition(refs.begin() + task.begin, refs.begin() + task.end,
                                 [&](std::uint32_t r) { return bin[r] < best_split; });
        mid = static_cast<std::uint32_t>(it - refs.begin());
        above = right_box[best_split];
      }
    }
    node.first = static_cast<std::uint32_t>(nodes_.size());
    node.count = 0;
    std::uint32_t left = node.first;
    nodes_.push_back({});
    nodes_.push_back({});
    if (mid == task.begin || mid == task.end) {
      // object median along the widest centroid axis
      mid = task.begin + count / 2;
      std::nth_element(refs.begin() + task.begin, refs.begin() + mid, refs.begin() + task.end,
                       [&](std::uint32_t l, std::uint32_t r) {
                         return centroids[l][axis] < centroids[r][axis];
                       });
      tasks.push_back(task_of(left, task.begin, mid, task.depth + 1));
      tasks.push_back(task_of(left + 1, mid, task.end, task.depth + 1));
    } else {
      tasks.push_back({left, task.begin, mid, task.depth + 1, below});
      tasks.push_back({left + 1, mid, task.end, task.depth + 1, above});
    }
  }

  // triangles in leaf order, so a leaf reads one contiguous run
  triangles_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) triangles_[i] = triangles[refs[i]];
  nodes_.shrink_to_fit();
}

TriangleBvh::Hit TriangleBvh::closest(glm::vec3 p, float max_distance) const {
  Hit hit;
  if (nodes_.empty()) return hit;
  float best2 = max_distance * max_distance;
  std::uint32_t best_leaf_index = kNoTriangle;
  glm::vec3 best_bary{0.0f};

  struct Entry {
    std::uint32_t node;
    float distance2;
  };
  std::array<Entry, kStackSize> stack;
  std::size_t top = 0;
  float root2 = box_distance2(p, nodes_[0].min, nodes_[0].max);
  if (!(root2 < best2)) return hit;
  stack[top++] = {0, root2};
  while (top > 0) {
    Entry e = stack[--top];
    if (!(e.distance2 < best2)) continue;
    const Node* node = &nodes_[e.node];
    // descend nearest-first, pushing the farther child
    while (node->count == 0) {
      const Node& l = nodes_[node->first];
      const Node& r = nodes_[node->first + 1];
      float dl = box_distance2(p, l.min, l.max);
      float dr = box_distance2(p, r.min, r.max);
      std::uint32_t near = node->first, far = node->first + 1;
      if (dr < dl) {
        std::swap(near, far);
        std::swap(dl, dr);
      }
      if (!(dl < best2)) {
        node = nullptr;
        break;
      }
      if (dr < best2) {
        assert(top < kStackSize && "TriangleBvh: traversal stack overflow");
        stack[top++] = {far, dr};
      }
      node = &nodes_[near];
    }
    if (!node) continue;
    for (std::uint32_t i = node->first; i < node->first + node->count; ++i) {
      const Triangle& t = triangles_[i];
      glm::vec3 bary = closest_barycentric(p, t.a, t.b, t.c);
      glm::vec3 q = bary.x * t.a + bary.y * t.b + bary.z * t.c;
      glm::vec3 d = p - q;
      float d2 = glm::dot(d, d);
      if (d2 < best2) {
        best2 = d2;
        best_leaf_index = i;
        best_bary = bary;
      }
    }
  }
  if (best_leaf_index == kNoTriangle) return hit;
  const Triangle& t = triangles_[best_leaf_index];
  hit.triangle = t.index;
  hit.barycentric = best_bary;
  hit.point = best_bary.x * t.a + best_bary.y * t.b + best_bary.z * t.c;
  hit.distance = std::sqrt(best2);
  return hit;
}

}  // namespace octolod::measure
