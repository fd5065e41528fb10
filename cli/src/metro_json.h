// JSON form of the Metro-style reports (octolod/measure/metro.h) shared by `eval` and `compare`.
// Distances in model units, *_relative divided by the bounding-box diagonal of mesh a, angles in
// degrees; attribute fields appear only for the attributes both meshes have.
#pragma once

#include <array>

#include <nlohmann/json.hpp>

#include "octolod/measure/metro.h"

namespace octolod::cli {

nlohmann::json deviation_json(const measure::Deviation& deviation);
nlohmann::json metro_json(const measure::MetroReport& report);

// The report's points (where each max is, and its closest point) moved from the frame of meshes
// relative to `origin` into the files' coordinates (cli/src/mesh_file.h).
void place_maxima(measure::MetroReport& report, const std::array<double, 3>& origin);

}  // namespace octolod::cli
