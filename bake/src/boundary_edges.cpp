// Boundary edges of a node mesh by an edge table sorted on position-id pairs (seed 3.5, 4.4).
#include "boundary_edges.h"

#include <algorithm>
#include <cstring>
#include <unordered_map>

namespace octolod::bake {
namespace {

struct PositionKey {
  std::uint32_t bits[3];
  friend bool operator==(const PositionKey&, const PositionKey&) = default;
};

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (std::uint32_t b : k.bits) {
      h ^= b;
      h *= 0xFF51AFD7ED558CCDull;
      h ^= h >> 32;
    }
    return static_cast<std::size_t>(h);
  }
};

}  // namespace

PositionIds make_position_ids(const NodeMesh& mesh) {
  const std::size_t stride = mesh.layout.floats();
  const std::size_t vertex_count = mesh.vertex_count();
  PositionIds ids;
  ids.of_vertex.resize(vertex_count);
  std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> table;
  table.reserve(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    PositionKey key;
    std::memcpy(key.bits, &mesh.vertices[v * stride], sizeof key.bits);
    const auto [it, inserted] = table.try_emplace(key, ids.count);
    if (inserted) ++ids.count;
    ids.of_vertex[v] = it->second;
  }
  return ids;
}

Boundary find_boundary(const NodeMesh& mesh, const PositionIds& positions) {
  // Edge table: (smaller position id, larger position id, corner index), sorted, so the uses of
  // one edge form a run whose first entry is its first use.
  struct EdgeUse {
    std::uint64_t key;
    std::uint32_t corner;  // 3 * triangle + k: the edge runs from corner k to corner k+1
  };
  std::vector<EdgeUse> uses;
  uses.reserve(mesh.indices.size());
  for (std::size_t c = 0; c < mesh.indices.size(); ++c) {
    const std::size_t next = c % 3 == 2 ? c - 2 : c + 1;
    const std::uint32_t pa = positions.of_vertex[mesh.indices[c]];
    const std::uint32_t pb = positions.of_vertex[mesh.indices[next]];
    if (pa == pb) continue;
    const std::uint64_t key = (static_cast<std::uint64_t>(std::min(pa, pb)) << 32) | std::max(pa, pb);
    uses.push_back({key, static_cast<std::uint32_t>(c)});
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return x.key != y.key ? x.key < y.key : x.corner < y.corner;
  });

  std::vector<std::uint32_t> first_corners;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    if ((j - i) % 2 == 1) first_corners.push_back(uses[i].corner);
    i = j;
  }
  std::sort(first_corners.begin(), first_corners.end());

  Boundary boundary;
  boundary.locked_position.assign(positions.count, 0);
  boundary.edges.reserve(first_corners.size());
  for (std::uint32_t c : first_corners) {
    const std::uint32_t next = c % 3 == 2 ? c - 2 : c + 1;
    const BoundaryEdge edge{mesh.indices[c], mesh.indices[next]};
    boundary.edges.push_back(edge);
    boundary.locked_position[positions.of_vertex[edge.a]] = 1;
    boundary.locked_position[positions.of_vertex[edge.b]] = 1;
  }
  return boundary;
}

}  // namespace octolod::bake
