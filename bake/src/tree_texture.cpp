#include "tree_texture.h"

#include <system_error>

namespace octolod::bake {

namespace fs = std::filesystem;

namespace {

// The copy of `name` (the first TextureFile) and why it was not made.
Result<TreeTexture> copy_first(const fs::path& ply, const std::string& name, bool has_uv, const fs::path& tree) {
  TreeTexture texture;
  const std::string named = "its TextureFile comment names '" + name + "'";
  if (!has_uv) {
    texture.warning = named + ", but it has no texture coordinates: no texture in the tree";
    return texture;
  }
  const fs::path relative = fs::path(name).lexically_normal();
  bool escapes = relative.is_absolute() || relative.has_root_name() || relative.empty();
  for (const fs::path& part : relative) escapes = escapes || part == "..";
  if (escapes) {
    texture.warning = named + ", which is not a path inside the PLY's directory: not copied into the tree";
    return texture;
  }
  const fs::path source = ply.parent_path() / relative;
  std::error_code ec;
  if (!fs::is_regular_file(source, ec)) {
    texture.warning = named + ", but '" + source.string() + "' is not a file: no texture in the tree";
    return texture;
  }
  const fs::path directory = tree / "texture";
  fs::create_directories(directory, ec);
  if (!ec) fs::copy_file(source, directory / relative.filename(), fs::copy_options::overwrite_existing, ec);
  if (ec)
    return io_error("cannot copy the texture '" + source.string() + "' into '" + directory.string() +
                    "': " + ec.message());
  texture.file = "texture/" + relative.filename().string();
  return texture;
}

}  // namespace

Result<TreeTexture> copy_tree_texture(const fs::path& ply, const std::vector<std::string>& names, bool has_uv,
                                      const fs::path& tree) {
  if (names.empty()) return TreeTexture{};
  Result<TreeTexture> texture = copy_first(ply, names.front(), has_uv, tree);
  if (!texture.ok() || names.size() == 1) return texture;
  const std::string several = "its header names " + std::to_string(names.size()) +
                              " textures (TextureFile comments); a tree carries one, the first ('" + names.front() +
                              "'): faces whose UVs index another show it instead";
  texture->warning = texture->warning.empty() ? several : several + "; and " + texture->warning;
  return texture;
}

}  // namespace octolod::bake
