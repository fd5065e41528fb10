// Exact vertex-record deduplication of soup records into a NodeMesh (seed 4.3), see
// node_index.h. Open addressing with linear probing over the vertex records' bit patterns.
#include "node_index.h"

#include <cstring>

#include "flat_hash.h"
#include "octolod/bake/soup.h"

namespace octolod::bake {
namespace {

// Hashes the position only: vertices that differ elsewhere (a seam) share a probe sequence and
// are told apart by the full comparison.
std::uint64_t hash_position(const float* v) {
  std::uint32_t words[3];
  std::memcpy(words, v, sizeof words);
  return hash_words(words, 3);
}

}  // namespace

void NodeIndexer::index(std::span<const std::byte> records, VertexLayout layout,
                        NodeMesh& mesh) {
  const std::size_t record_bytes = soup_record_bytes(layout);
  const std::size_t triangles = records.size() / record_bytes;
  const std::size_t floats = layout.floats();
  mesh.layout = layout;
  mesh.vertices.clear();
  mesh.indices.clear();
  mesh.indices.reserve(3 * triangles);
  // At most 3 * triangles vertices: keep the table under half full.
  std::size_t table = 16;
  while (table < 6 * triangles) table *= 2;
  slots_.assign(table, 0);
  const std::size_t mask = table - 1;

  float corner[VertexLayout{true, true, true}.floats()];
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::byte* record = records.data() + t * record_bytes;
    for (int c = 0; c < 3; ++c) {
      load_soup_corner(record, layout, c, corner);
      std::size_t slot = static_cast<std::size_t>(hash_position(corner)) & mask;
      for (;;) {
        const std::uint32_t entry = slots_[slot];
        if (entry == 0) {
          const auto index = static_cast<std::uint32_t>(mesh.vertices.size() / floats);
          slots_[slot] = index + 1;
          mesh.vertices.insert(mesh.vertices.end(), corner, corner + floats);
          mesh.indices.push_back(index);
          break;
        }
        const float* existing = mesh.vertices.data() + std::size_t{entry - 1} * floats;
        if (std::memcmp(existing, corner, floats * sizeof(float)) == 0) {
          mesh.indices.push_back(entry - 1);
          break;
        }
        slot = (slot + 1) & mask;
      }
    }
  }
}

}  // namespace octolod::bake
