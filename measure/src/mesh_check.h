// Consistency check of a NodeMesh handed to the measuring functions (they accept meshes from any
// source: files, bakes, tests).
#pragma once

#include <string_view>

#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod::measure {

// bad_input, naming `name`, when the vertex floats are not a multiple of the layout, the indices
// not a multiple of 3 or one is out of range, or a position is NaN/Inf or beyond
// ±kMaxVertexValue (vertex_layout.h: the measuring functions compute squared distances in
// float, which would overflow to infinity between points that far out). An empty mesh is fine.
Status check_mesh(const NodeMesh& mesh, std::string_view name);

}  // namespace octolod::measure
