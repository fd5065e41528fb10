// Folded fans after a vertex clustering. A cell that holds two sheets of the surface (a thin
// part of the model, or two sides of a fold) gives both one representative, placed for their
// quadrics together; a wedge of the sheet it is not on can end with three triangles to three
// neighbours on its own sheet, wound each like its sources, one against the other two: the fan
// folds over itself, its long spokes off the surface (seed 4's 3% cut at another bend
// threshold: a spoke's middle 0.035 from the input, 5.1x the reference's Hausdorff distance).
// Such a fan is replaced by its neighbours' one triangle when that lies nearer the input.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "clustered_output.h"

namespace octolod::bake {

// Replaces, in `corners` (wedge triples of input.output()'s triangles), each folded fan: a wedge with
// exactly three triangles, (v, u1, u2), (v, u2, u3), (v, u3, u1) in some windings, where some
// spoke v-ui runs the same way in both of its triangles, and no triangle joins the clusters of
// u1, u2, u3 yet. The replacement (u1, u2, u3), of each neighbour's first wedge met, is wound
// like most of the fan's outer edges, and is taken when the farthest of its centroid (to the
// input triangles at the four clusters) and of v's input vertices (to it) lies nearer than the
// farthest of the spokes' midpoints (to those input triangles; squared, by 0.95x). The fan's
// edges used an odd number of times are the replacement's, so the boundary mod 2, and with it
// crack-freedom, does not change; each replacement removes two triangles.
struct FoldRepair {
  // per triangle of the old `corners`, its index in the new one (a removed one's: its
  // replacement's, the output triangle nearest its image, for the error bound's hints)
  std::vector<std::uint32_t> index;
  // (cluster of v, new index of its replacement) per replaced fan: v's input vertices lie near
  // the replacement, which has no corner in their cluster; the error bound's fans take it too
  std::vector<std::array<std::uint32_t, 2>> fan_extra;
};
FoldRepair remove_folded_fans(InputDistances& input, std::vector<std::uint32_t>& corners);

}  // namespace octolod::bake
