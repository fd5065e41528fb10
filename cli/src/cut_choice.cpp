// The `--error E | --level K` choice of a uniform cut (cut_choice.h).
#include "cut_choice.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace octolod::cli {

Status check_cut_choice(const CutChoice& choice, std::string_view command_name) {
  if (choice.error.has_value() == choice.level.has_value())
    return usage_error(std::string(command_name) + ": give exactly one of --error E or --level K");
  if (choice.error && !(*choice.error >= 0 && std::isfinite(*choice.error)))
    return usage_error("--error must be a finite distance >= 0 (model units)");
  return {};
}

Result<ChosenCut> read_chosen_cut(const std::filesystem::path& tree, const CutChoice& choice) {
  Result<Manifest> manifest = read_tree_manifest(tree);
  if (!manifest.ok()) return manifest.status();
  if (choice.level) {
    std::uint32_t deepest = 0;
    for (const NodeInfo& node : manifest->nodes) deepest = std::max(deepest, node.depth);
    if (*choice.level > deepest)
      return usage_error("--level " + std::to_string(*choice.level) + ": the deepest level of " + tree.string() +
                         " is " + std::to_string(deepest) + " (the root is 0)");
  }
  std::vector<CutEntry> cut =
      choice.error ? uniform_error_cut(manifest.value(), *choice.error) : depth_cut(manifest.value(), *choice.level);
  if (cut.empty())
    return bad_input_error(tree.string() + ": the tree has no node LODs (an empty mesh was baked)");
  return ChosenCut{std::move(manifest.value()), std::move(cut)};
}

}  // namespace octolod::cli
