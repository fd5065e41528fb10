// QSlim-style reference simplification (Garland & Heckbert, "Surface simplification using quadric
// error metrics", SIGGRAPH 1997) via OpenMesh's Decimater: the baseline a baked LOD is compared
// against (`octolod reference`, then `octolod eval`). Greedy half-edge collapses ordered by the
// quadric error (ModQuadricT), vetoing collapses that flip a face normal (ModNormalFlippingT) or
// that raise a vertex above valence 16 (valence_limit.h: unlimited, the decimater turns cubic
// where collapses gather hubs, as on an open tube; the limit never binds on the sample rock,
// city or terrain).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod::measure {

struct ReferenceStats {
  std::uint64_t input_triangles = 0;
  std::uint64_t welded_vertices = 0;     // distinct positions after welding
  // Triangles OpenMesh could not add to its manifold half-edge mesh (non-manifold edges or
  // vertices); they are kept as detached, unsimplified copies.
  std::uint64_t detached_triangles = 0;
  // Triangles of the result (reference_simplify_ladder: of the coarsest result).
  std::uint64_t output_triangles = 0;
  double seconds = 0.0;                  // wall time
};

// Simplifies `input` to about `target_triangles` triangles.
//
// - Vertices are welded by exact position first, so attribute seams (UV/normal/colour splits)
//   do not become mesh boundaries that block collapses. Degenerate triangles (two corners at one
//   position) are dropped.
// - The decimation stops at the target or earlier when no legal collapse is left (boundaries,
//   normal flips), so the result can stay above the target; on closed manifold meshes it lands
//   within one or two triangles of it. Edge collapses never remove a connected component: a
//   closed component stops as a tetrahedron (4 triangles), so a mesh of many small closed parts
//   (the sample city's boxes) cannot go below 4 triangles per part. A target >= the welded
//   triangle count returns the welded mesh unsimplified.
// - Attributes (the output has the input's layout): each output vertex takes the input's
//   attributes interpolated barycentrically at the closest point of the input surface
//   (TriangleBvh) — correct for positions that moved off the input, and it never mixes values
//   across a seam (but a vertex on a seam takes one side's values, so seams are not kept as
//   splits). Normals are renormalized, colours clamped to 0..1.
// - Output: only vertices some triangle uses, in the order of the welded input's first
//   occurrences; triangles keep the winding of the input.
//
// Errors: usage for target_triangles == 0; bad_input for an inconsistent mesh (vertices not a
// multiple of the layout, indices out of range or not 3 per triangle, non-finite positions).
// `stats` may be null. Memory: about 250 bytes per input triangle (OpenMesh's half-edge mesh
// with its status and quadric properties, plus the attribute TriangleBvh).
Result<NodeMesh> reference_simplify(const NodeMesh& input, std::uint32_t target_triangles,
                                    ReferenceStats* stats = nullptr);

// The same for several targets at once (e.g. the triangle counts of a ladder of baked cuts): one
// decimation runs down through the targets from the largest to the smallest and takes a snapshot
// at each, so the cost is about that of the smallest target alone. result[i] belongs to
// targets[i] (any order, repeats allowed) and equals reference_simplify(input, targets[i]) up to
// the decimater's heap being rebuilt between targets (ties may break differently).
// Errors: as reference_simplify; usage when `targets` is empty or holds a 0.
Result<std::vector<NodeMesh>> reference_simplify_ladder(const NodeMesh& input,
                                                        std::span<const std::uint32_t> targets,
                                                        ReferenceStats* stats = nullptr);

}  // namespace octolod::measure
