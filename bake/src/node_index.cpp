// Exact vertex-record deduplication of soup records into a NodeMesh (seed 4.3), see
// node_index.h. Open addressing with linear probing over the vertex records' bit patterns.
#include "node_index.h"

#include <cassert>
#include <cstring>

#include "flat_hash.h"
#include "octolod/bake/soup.h"

namespace octolod::bake {
namespace {

// The indexing loop for records of FLOATS floats per vertex: fixed-size copies and compares
// compile to a few moves instead of library calls (30M corners for 10M triangles).
template <std::size_t FLOATS>
void index_records(std::span<const std::byte> records, VertexLayout layout, NodeMesh& mesh,
                   std::vector<std::uint32_t>& slots) {
  const std::size_t record_bytes = soup_record_bytes(layout);
  const std::size_t triangles = records.size() / record_bytes;
  const std::size_t mask = slots.size() - 1;
  float corner[FLOATS];
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::byte* record = records.data() + t * record_bytes;
    for (int c = 0; c < 3; ++c) {
      std::memcpy(corner, record + soup_corner_offset(layout, c), sizeof corner);
      // Hashes the position only: vertices that differ elsewhere (a seam) share a probe
      // sequence and are told apart by the full comparison.
      std::uint32_t position[3];
      std::memcpy(position, corner, sizeof position);
      std::size_t slot = static_cast<std::size_t>(hash_words(position, 3)) & mask;
      for (;;) {
        const std::uint32_t entry = slots[slot];
        if (entry == 0) {
          const auto index = static_cast<std::uint32_t>(mesh.vertices.size() / FLOATS);
          slots[slot] = index + 1;
          mesh.vertices.insert(mesh.vertices.end(), corner, corner + FLOATS);
          mesh.indices.push_back(index);
          break;
        }
        const float* existing = mesh.vertices.data() + std::size_t{entry - 1} * FLOATS;
        if (std::memcmp(existing, corner, sizeof corner) == 0) {
          mesh.indices.push_back(entry - 1);
          break;
        }
        slot = (slot + 1) & mask;
      }
    }
  }
}

}  // namespace

void NodeIndexer::index(std::span<const std::byte> records, VertexLayout layout,
                        NodeMesh& mesh) {
  const std::size_t triangles = records.size() / soup_record_bytes(layout);
  mesh.layout = layout;
  mesh.vertices.clear();
  mesh.indices.clear();
  mesh.indices.reserve(3 * triangles);
  // At most 3 * triangles vertices: keep the table under half full.
  std::size_t table = 16;
  while (table < 6 * triangles) table *= 2;
  slots_.assign(table, 0);
  // Position 3 floats, normal 3, colour 3, UV 2: every layout has one of these sizes.
  switch (layout.floats()) {
    case 3: return index_records<3>(records, layout, mesh, slots_);
    case 5: return index_records<5>(records, layout, mesh, slots_);
    case 6: return index_records<6>(records, layout, mesh, slots_);
    case 8: return index_records<8>(records, layout, mesh, slots_);
    case 9: return index_records<9>(records, layout, mesh, slots_);
    case 11: return index_records<11>(records, layout, mesh, slots_);
  }
  assert(false && "NodeIndexer: a vertex layout of an unexpected size");
}

}  // namespace octolod::bake
