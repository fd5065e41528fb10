// JSON form of the Metro-style reports (octolod/measure/metro.h) shared by `eval` and `compare`.
// Distances in model units, *_relative divided by the bounding-box diagonal of mesh a, angles in
// degrees; attribute fields appear only for the attributes both meshes have.
#pragma once

#include <nlohmann/json.hpp>

#include "octolod/measure/metro.h"

namespace octolod::cli {

nlohmann::json deviation_json(const measure::Deviation& deviation);
nlohmann::json metro_json(const measure::MetroReport& report);

}  // namespace octolod::cli
