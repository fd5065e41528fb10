// Node directories and LOD file names of a baked tree, see tree_paths.h.
#include "tree_paths.h"

namespace octolod::bake {

std::string node_path(std::uint64_t prefix, std::uint32_t depth) {
  std::string p;
  for (std::uint32_t k = 0; k < depth; ++k) {
    if (!p.empty()) p += '/';
    p += static_cast<char>('0' + ((prefix >> (3 * (depth - 1 - k))) & 7u));
  }
  return p;
}

std::string lod_file_name(std::string_view dir, std::size_t index) {
  std::string file(dir);
  if (!file.empty()) file += '/';
  return file + "lod" + std::to_string(index) + ".olod";
}

}  // namespace octolod::bake
