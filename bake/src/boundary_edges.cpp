// Boundary edges of a node mesh by an edge table (flat hash) on position-id pairs (seed 3.5, 4.4).
#include "boundary_edges.h"

#include <algorithm>
#include <cstring>

#include "flat_hash.h"

namespace octolod::bake {

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

Boundary find_boundary(const NodeMesh& mesh, const PositionIds& positions) {
  // Edge table keyed on (smaller, larger) position id: uses and first corner per edge, edges in
  // order of first use.
  struct EdgeRecord {
    std::uint32_t uses;
    std::uint32_t first_corner;  // 3 * triangle + k: the edge runs from corner k to corner k+1
  };
  std::vector<EdgeRecord> records;
  records.reserve(mesh.indices.size() / 2 + 16);
  FlatHashMap<2> table(mesh.indices.size());
  for (std::size_t c = 0; c < mesh.indices.size(); ++c) {
    const std::size_t next = c % 3 == 2 ? c - 2 : c + 1;
    const std::uint32_t pa = positions.of_vertex[mesh.indices[c]];
    const std::uint32_t pb = positions.of_vertex[mesh.indices[next]];
    if (pa == pb) continue;
    bool inserted = false;
    const std::uint32_t r = table.find_or_insert({std::min(pa, pb), std::max(pa, pb)},
                                                 static_cast<std::uint32_t>(records.size()), inserted);
    if (inserted) records.push_back({0, static_cast<std::uint32_t>(c)});
    ++records[r].uses;
  }

  Boundary boundary;
  boundary.locked_position.assign(positions.count, 0);
  for (const EdgeRecord& record : records) {
    if (record.uses % 2 == 0) continue;
    const std::uint32_t c = record.first_corner;
    const std::uint32_t next = c % 3 == 2 ? c - 2 : c + 1;
    const BoundaryEdge edge{mesh.indices[c], mesh.indices[next]};
    boundary.edges.push_back(edge);
    boundary.locked_position[positions.of_vertex[edge.a]] = 1;
    boundary.locked_position[positions.of_vertex[edge.b]] = 1;
  }
  return boundary;
}

}  // namespace octolod::bake
