#include "frame_render.h"

#include <algorithm>

#include "offscreen_renderer.h"

namespace octolod::cli {

FramePainter::FramePainter(const Manifest& manifest) : height_(manifest.nodes.size(), 0) {
  // Parents precede children in the manifest: walking backwards sees every child first.
  for (std::size_t i = manifest.nodes.size(); i-- > 0;) {
    const std::int32_t parent = manifest.nodes[i].parent;
    if (parent < 0) continue;
    std::uint32_t& up = height_[static_cast<std::size_t>(parent)];
    up = std::max(up, height_[i] + 1);
  }
}

std::uint32_t FramePainter::detail_level(const runtime::DrawItem& draw) const {
  return (draw.node < height_.size() ? height_[draw.node] : 0) + draw.lod;
}

Result<Image> FramePainter::paint(const runtime::FrameResult& frame, const runtime::Camera& camera, int width,
                                  int height, const Style& style) const {
  std::vector<RenderItem> items;
  items.reserve(frame.draws.size());
  for (const runtime::DrawItem& draw : frame.draws) {
    if (!draw.mesh) continue;
    if (style.texture != nullptr && draw.mesh->layout.uv)
      items.push_back({.mesh = draw.mesh.get(), .tint_share = 0.0f, .texture = style.texture});
    else if (style.own_colors)
      items.push_back({.mesh = draw.mesh.get(), .tint_share = 0.0f});
    else
      items.push_back({.mesh = draw.mesh.get(), .tint = lod_tint(detail_level(draw))});
  }
  RenderView view;
  view.view = camera.view;
  view.projection = camera.projection;
  view.width = width;
  view.height = height;
  view.cull_back_faces = style.cull_back_faces;
  return render_offscreen(items, view);
}

}  // namespace octolod::cli
