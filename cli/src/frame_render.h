// Pictures of what the streaming runtime selected: one frame's draw list rendered offscreen with
// real OpenGL (offscreen_renderer.h), every node tinted by its detail level (lod_tint), so a
// picture shows which LODs the cut is made of. Shared by `octolod render` and
// `octolod walk --frames-png`.
#pragma once

#include <cstdint>
#include <vector>

#include "image.h"
#include "octolod/formats/manifest.h"
#include "octolod/formats/status.h"
#include "octolod/runtime/camera.h"
#include "octolod/runtime/streaming_tree.h"

namespace octolod::cli {

class FramePainter {
 public:
  // Reads the tree's shape from `manifest` (the one the StreamingTree was opened with); keeps no
  // reference to it.
  explicit FramePainter(const Manifest& manifest);

  // Detail level of a drawn node LOD: the node's height above the deepest leaf below it plus the
  // LOD index. 0 is a leaf's original triangles; every level above is at least one simplification
  // step coarser. This is the level a picture's tint encodes.
  std::uint32_t detail_level(const runtime::DrawItem& draw) const;

  // How the nodes are drawn: by default tinted by their detail level, half the tint and half
  // their own colours (white without).
  struct Style {
    bool cull_back_faces = false;    // RenderView::cull_back_faces
    const Image* texture = nullptr;  // the tree's texture (decoded): nodes with UVs show it
    bool own_colors = false;         // the nodes' own colours alone, no tint
  };

  // Renders `frame.draws` as seen by `camera` into a width x height picture (pixels). The
  // camera's projection should have aspect width / height. Fails (ErrorCode::unsupported) only
  // when no OpenGL context can be created.
  Result<Image> paint(const runtime::FrameResult& frame, const runtime::Camera& camera, int width, int height,
                      const Style& style) const;

 private:
  std::vector<std::uint32_t> height_;  // per manifest node
};

}  // namespace octolod::cli
