// glTF's texture space has v down (its origin at the image's top-left corner, glTF 2.0 section
// 3.8.4 "Images"); octolod's UVs, as PLY's, MeshLab's and OpenGL's, have v up (the origin at the
// lower-left corner). A UV crosses between the two as (u, 1 - v), either way.
#pragma once

#include <cstddef>

#include "octolod/formats/node_file.h"

namespace octolod::detail {

inline void flip_v(NodeMesh& mesh) {
  if (!mesh.layout.uv) return;
  const std::size_t floats = mesh.layout.floats();
  for (std::size_t at = mesh.layout.uv_offset() + 1; at < mesh.vertices.size(); at += floats)
    mesh.vertices[at] = 1.0f - mesh.vertices[at];
}

}  // namespace octolod::detail
