// Metro-style pictures for `octolod compare --pictures`: meshes in a grid of panels, all seen by
// one camera that frames the model, every sampled point of each coloured by its distance to
// another surface (heat_scale.h: blue none, red the top of the scale), the scale drawn under
// them. Both directions of a comparison show: a LOD coloured by its distance to the input shows
// where it strays from the model; the input coloured by its distance to the LOD shows what the
// LOD lost (a building that vanished is red there and absent from the LOD's own panel).
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
  const NodeMesh* mesh = nullptr;                 // drawn; model units; borrowed for the call
  const measure::TriangleBvh* surface = nullptr;  // its distances are to this one, in the same frame
  std::string caption;                            // at the panel's top left (draw_text's font)
};

struct ErrorPicture {
  Image image;
  // The distance at the top of the colour scale, model units: the one given, else the largest
  // sampled distance of all panels (at the points of a grid on each triangle: so it can differ
  // either way from a Metro Hausdorff, which samples at random), and at least a millionth of
  // the frame's diagonal (so float noise stays blue).
  double scale = 0.0;
};

// Pixels of one panel of an error picture.
inline constexpr int kErrorPanelWidth = 800, kErrorPanelHeight = 600;

// Renders the panels, `columns` to a row, each kErrorPanelWidth x kErrorPanelHeight pixels, as
// framing_camera(frame) sees them. Each panel's surface is sampled on a grid of points at most
// 1/200 of the frame's diagonal apart on each triangle (at most 32 x 32 cells a triangle; a
// triangle already that small is sampled at its corners), every point coloured by its distance to
// the nearest point of the panel's `surface` over the panels' shared scale (colours interpolated
// between the points; `scale` > 0 fixes the top of the scale, so that pictures of several runs
// compare, farther points drawn red). The scale's bar and its ends' values go under the panels: the
// picture is (columns x kErrorPanelWidth) x (rows x kErrorPanelHeight + 48) pixels. Memory: one
// panel's samples at a time, about 70 bytes each, and 4 bytes per sample of every panel. Fails
// (ErrorCode::unsupported) when no OpenGL context can be created.
Result<ErrorPicture> render_error_picture(std::span<const ErrorPanel> panels, int columns, const Bounds& frame,
                                          double scale = 0.0);

}  // namespace octolod::cli
