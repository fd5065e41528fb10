// Consistency check of a NodeMesh handed to the measuring functions (they accept meshes from any
// source: files, bakes, tests).
#pragma once

#include <string_view>

#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod::measure {

// Coordinates beyond this (model units) are refused: the measuring functions compute squared
// distances in float, and between points this far out those would overflow to infinity.
inline constexpr float kMaxMeasurableCoordinate = 1e18f;

// bad_input, naming `name`, when the vertex floats are not a multiple of the layout, the indices
// not a multiple of 3 or one is out of range, or a position is NaN/Inf or beyond
// ±kMaxMeasurableCoordinate. An empty mesh is fine.
Status check_mesh(const NodeMesh& mesh, std::string_view name);

}  // namespace octolod::measure
