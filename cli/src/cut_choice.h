// The `--error E | --level K` choice of a uniform cut, shared by `octolod extract` and
// `octolod export` (tree_cut.h computes the cuts).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "octolod/formats/manifest.h"
#include "octolod/formats/status.h"
#include "tree_cut.h"

namespace octolod::cli {

struct CutChoice {
  std::optional<double> error;         // model units: per node the coarsest LOD with error <= E
  std::optional<std::uint32_t> level;  // octree depth, root = 0
};

// usage error (prefixed with `command_name`) unless exactly one of the two was given and the
// error is a finite distance >= 0.
Status check_cut_choice(const CutChoice& choice, std::string_view command_name);

// The cut `choice` selects in `manifest` (after check_cut_choice); a bad-input error naming
// `tree` (the tree's directory) when the tree has no node LOD to cut (an empty mesh was baked).
Result<std::vector<CutEntry>> select_cut(const Manifest& manifest, const CutChoice& choice, std::string_view tree);

}  // namespace octolod::cli
