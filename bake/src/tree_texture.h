// The input's texture in a baked tree (Manifest::texture): the image a PLY's TextureFile comment
// names (the first of PlyInfo::texture_files), copied into TREE/texture/ so that the tree, which a game or an
// exporter reads without the input, is self-contained.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "octolod/formats/status.h"

namespace octolod::bake {

struct TreeTexture {
  std::string file;     // Manifest::texture: "texture/<file name>", "" when nothing was copied
  std::string warning;  // why a named texture was not copied ("" when it was, or none was named)
};

// Copies the image names[0] names (PlyInfo::texture_files), relative to the directory of `ply`
// (the bake's input), to `tree`/texture/<its file name>. No names: nothing, no warning. Not
// copied, with a warning: an input without UVs (nothing indexes the image), a name that is
// absolute or has a ".." component (a PLY must not make a bake copy files from anywhere else), a
// name that is not a regular file. More than one name: the first is copied, with a warning (a
// tree has one texture; faces whose UVs index another image show the first). Errors: io when
// the copy fails (out of space included), naming both paths.
Result<TreeTexture> copy_tree_texture(const std::filesystem::path& ply, const std::vector<std::string>& names,
                                      bool has_uv, const std::filesystem::path& tree);

}  // namespace octolod::bake
