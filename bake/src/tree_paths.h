// Where a node's files live in a baked tree (docs/formats.md): a node's directory is its octant
// path from the root, and its LOD i is the file "lod<i>.olod" in it. Paths are relative to the
// tree root and '/'-separated, as the manifest lists them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace octolod::bake {

// The directory of the node at `depth` whose octants from the root are `prefix` (3 bits per
// level, the root's child first: morton.h): "" for the root, else e.g. "3/5".
std::string node_path(std::uint64_t prefix, std::uint32_t depth);

// LOD `index` of the node whose directory is `dir`: "lod2.olod" for the root, "3/5/lod2.olod".
std::string lod_file_name(std::string_view dir, std::size_t index);

}  // namespace octolod::bake
