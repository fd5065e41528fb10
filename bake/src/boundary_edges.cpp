// Boundary edges of a node mesh by an edge table on position-id pairs (seed 3.5, 4.4).
#include "boundary_edges.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "flat_hash.h"

namespace octolod::bake {
namespace {

// Whether the midpoint of `edge` lies within the reach of the other nodes' side of `cell` (on
// it or beyond included): how deep it lies is its least distance to a face of the cell with
// other cells behind it (not on the root's surface).
bool within_reach(const NodeMesh& mesh, const BoundaryEdge& edge, const Bounds& cell, const NeighbourReach& neighbours) {
  if (neighbours.reach == std::numeric_limits<double>::infinity()) return true;
  const std::size_t stride = mesh.layout.floats();
  const float* a = &mesh.vertices[std::size_t{edge.a} * stride];
  const float* b = &mesh.vertices[std::size_t{edge.b} * stride];
  const Bounds& root = neighbours.root;
  const bool root_known = !root.empty();
  double depth = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 3; ++k) {
    const double middle = 0.5 * (static_cast<double>(a[k]) + b[k]);
    if (!(root_known && cell.min[k] <= root.min[k])) depth = std::min(depth, middle - cell.min[k]);
    if (!(root_known && cell.max[k] >= root.max[k])) depth = std::min(depth, cell.max[k] - middle);
  }
  return depth <= neighbours.reach;
}

}  // namespace

PositionIds make_position_ids(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  const std::size_t vertex_count = mesh.vertex_count();
  const float* base = mesh.vertices.data();
  PositionIds ids;
  ids.of_vertex.resize(vertex_count);
  // first vertex of each position -> its id, through of_vertex of that first vertex
  FlatIdSet table(vertex_count);
  auto hash = [base, stride](std::uint32_t v) {
    std::uint32_t bits[3];
    std::memcpy(bits, base + v * stride, sizeof bits);
    return hash_words(bits, 3);
  };
  auto equal = [base, stride](std::uint32_t a, std::uint32_t b) {
    return std::memcmp(base + a * stride, base + b * stride, 3 * sizeof(float)) == 0;
  };
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    const std::uint32_t first = table.find_or_insert(v, hash, equal);
    ids.of_vertex[v] = first == v ? ids.count++ : ids.of_vertex[first];
  }
  return ids;
}

Boundary find_boundary(const NodeMesh& mesh, const PositionIds& positions, const Bounds& cell,
                       const NeighbourReach& neighbours) {
  // Edge table by a counting sort on the smaller position id: every bucket (the edges of one
  // position, a handful on a surface) sorted by (larger id, corner), so equal edges form runs whose
  // first entry is the edge's first use. Sequential passes instead of a hash table over every
  // corner, whose probes missed the cache.
  const std::size_t corners = mesh.indices.size();
  // every corner's position id, and (as c % 3 costs a division) the corner each corner's edge
  // ends at
  std::vector<std::uint32_t> position(corners);
  for (std::size_t c = 0; c < corners; ++c) position[c] = positions.of_vertex[mesh.indices[c]];
  auto for_each_edge = [&](auto&& f) {  // f(c, a, b): the edge from corner c (position a) to b
    for (std::size_t c = 0; c < corners; c += 3) {
      const std::uint32_t p0 = position[c], p1 = position[c + 1], p2 = position[c + 2];
      f(c, p0, p1), f(c + 1, p1, p2), f(c + 2, p2, p0);
    }
  };
  std::vector<std::uint32_t> bucket_start(std::size_t{positions.count} + 1, 0);
  for_each_edge([&](std::size_t, std::uint32_t pa, std::uint32_t pb) {
    if (pa != pb) ++bucket_start[std::min(pa, pb) + 1];
  });
  for (std::size_t p = 0; p < positions.count; ++p) bucket_start[p + 1] += bucket_start[p];
  // (larger position id << 32 | corner): the corner c is the edge from corner c to corner c+1
  std::vector<std::uint64_t> entries(bucket_start.back());
  std::vector<std::uint32_t> fill(bucket_start.begin(), bucket_start.end() - 1);
  for_each_edge([&](std::size_t c, std::uint32_t pa, std::uint32_t pb) {
    if (pa != pb) entries[fill[std::min(pa, pb)]++] = std::uint64_t{std::max(pa, pb)} << 32 | c;
  });
  std::vector<std::uint32_t> first_corners;  // of the edges used an odd number of times
  for (std::size_t p = 0; p < positions.count; ++p) {
    const auto begin = entries.begin() + bucket_start[p], end = entries.begin() + bucket_start[p + 1];
    // insertion sort: a bucket holds a handful of entries, filled in corner order
    for (auto i = begin; i != end; ++i) {
      const std::uint64_t entry = *i;
      auto j = i;
      for (; j != begin && entry < *(j - 1); --j) *j = *(j - 1);
      *j = entry;
    }
    for (auto run = begin; run != end;) {
      auto next = run + 1;
      while (next != end && (*next >> 32) == (*run >> 32)) ++next;
      if ((next - run) % 2 == 1) first_corners.push_back(static_cast<std::uint32_t>(*run));
      run = next;
    }
  }
  std::sort(first_corners.begin(), first_corners.end());  // order of first use

  Boundary boundary;
  boundary.locked_position.assign(positions.count, 0);
  boundary.edges.reserve(first_corners.size());
  for (const std::uint32_t c : first_corners) {
    const std::uint32_t next = c % 3 == 2 ? c - 2 : c + 1;
    const BoundaryEdge edge{mesh.indices[c], mesh.indices[next], c / 3};
    if (!within_reach(mesh, edge, cell, neighbours)) {
      boundary.free_edges.push_back(edge);
      continue;
    }
    boundary.edges.push_back(edge);
    boundary.locked_position[positions.of_vertex[edge.a]] = 1;
    boundary.locked_position[positions.of_vertex[edge.b]] = 1;
  }
  return boundary;
}

}  // namespace octolod::bake
