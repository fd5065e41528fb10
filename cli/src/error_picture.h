// Metro-style pictures for `octolod compare --pictures`: meshes side by side, seen by one camera
// that frames the input, every sampled point coloured by its distance to the input's surface
// (heat_scale.h: blue none, red the top of the scale), the scale drawn under them.
#pragma once

#include <span>
#include <string>

#include "image.h"
#include "octolod/formats/bounds.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"
#include "octolod/measure/triangle_bvh.h"

namespace octolod::cli {

struct ErrorPanel {
  const NodeMesh* mesh = nullptr;  // model units, the frame of `surface`; borrowed for the call
  std::string caption;             // drawn at the panel's top left (draw_text's font)
};

struct ErrorPicture {
  Image image;
  // The distance at the top of the colour scale, model units: the largest sampled distance of
  // all panels (one-sided, from the panels' surfaces to `surface`, at the points of a grid on
  // each triangle: so it can differ either way from a Metro Hausdorff, which samples at random
  // both ways), and at least a millionth of the frame's diagonal (so float noise stays blue).
  double scale = 0.0;
};

// Renders the panels (each panel_width x panel_height pixels, left to right) as
// framing_camera(frame) sees them, their surfaces sampled on a grid of points at most 1/200 of
// the frame's diagonal apart on each triangle (at most 32 x 32 cells a triangle), every point
// coloured by its distance to the nearest point of `surface` over the panels' shared scale (the
// colours interpolated between the points), with the scale's bar and its ends' values under
// them (the picture is (panel count x panel_width) x (panel_height + 48) pixels). Memory: the
// samples, about 50 bytes each. Fails (ErrorCode::unsupported) when no OpenGL context can be
// created.
Result<ErrorPicture> render_error_picture(std::span<const ErrorPanel> panels, const measure::TriangleBvh& surface,
                                          const Bounds& frame, int panel_width, int panel_height);

}  // namespace octolod::cli
