// The `--error E | --level K` choice of a uniform cut, shared by `octolod extract` and
// `octolod export` (tree_cut.h computes the cuts).
#pragma once

#include <cstdint>
#include <filesystem>
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

// A tree's manifest and the cut `choice` selects in it.
struct ChosenCut {
  Manifest manifest;
  std::vector<CutEntry> cut;  // never empty
};

// Reads the manifest of the tree at `tree` (its directory) and selects the cut `choice` gives
// (after check_cut_choice). Errors: those of read_tree_manifest, a usage error when the level is
// deeper than the tree's deepest node, and bad_input naming `tree` when the tree
// has no node LOD to cut (an empty mesh was baked).
Result<ChosenCut> read_chosen_cut(const std::filesystem::path& tree, const CutChoice& choice);

}  // namespace octolod::cli
