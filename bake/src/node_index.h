// Turns a node's triangle soup records back into an indexed mesh (seed 4.3: a leaf's triangles
// become the node's finest LOD). Corners whose vertex records are bit-identical (all
// layout.floats() floats) become one vertex, so a vertex shared in the PLY is shared again and a
// vertex split by an attribute seam (same position, other normal or UV) stays split.
//
// Deterministic: vertices are numbered in order of first appearance (triangle by triangle,
// corner 0, 1, 2), indices keep the records' triangle order and winding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "octolod/formats/node_file.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::bake {

// Reusable: keeps its hash table between calls, so indexing node after node allocates only when
// a node is larger than every earlier one.
class NodeIndexer {
 public:
  // `records` holds whole soup records of soup_record_bytes(layout) bytes (octolod/bake/soup.h).
  // The mesh's previous contents are replaced (its capacity is reused).
  void index(std::span<const std::byte> records, VertexLayout layout, NodeMesh& mesh);

 private:
  std::vector<std::uint32_t> slots_;  // open addressing: vertex index + 1, 0 = empty
};

}  // namespace octolod::bake
