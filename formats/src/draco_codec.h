// Draco payloads of glTF primitives (KHR_draco_mesh_compression): NodeMesh <-> Draco bitstream.
// Private to octolod_formats; keeps Draco's headers out of everything else.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "octolod/formats/bounds.h"
#include "octolod/formats/gltf.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod::detail {

// Draco attribute unique ids as the glTF extension's "attributes" object lists them; -1 when
// the attribute is absent.
struct DracoAttributeIds {
  int position = -1;
  int normal = -1;
  int color = -1;
  int uv = -1;
};

struct DracoPayload {
  std::vector<std::byte> bytes;
  DracoAttributeIds ids;
};

// The cube every mesh of one file quantizes its positions in: a shared grid, so a vertex shared
// by two meshes (neighbouring octree nodes) decodes to the same position in both and a cut stays
// crack-free. `range` is the cube's edge in model units (> 0).
struct DracoPositionGrid {
  std::array<float, 3> origin{0, 0, 0};
  float range = 1;
  static DracoPositionGrid enclosing(const Bounds& bounds);
};

// Encodes a mesh with at least one triangle; `name` names the mesh in error messages.
Result<DracoPayload> draco_encode(const NodeMesh& mesh, const DracoOptions& options,
                                  const DracoPositionGrid& grid, std::string_view name);

// Decodes a Draco mesh; the attributes present in `ids` form the result's layout. `name` names
// the primitive in error messages (bad_input on any inconsistency).
Result<NodeMesh> draco_decode(std::span<const std::byte> bytes, const DracoAttributeIds& ids,
                              std::string_view name);

}  // namespace octolod::detail
