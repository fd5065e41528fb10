// Per-node simplification and LOD chains of the baker (seed 3.5, 4.4, 3.5.3): vertex clustering
// with generalized quadric error metrics (Garland & Heckbert 1998, "Simplifying surfaces with
// color and texture using quadric error metrics"), either the seed's one-representative-per-node
// operator or a grid of cells inside the node (Lindstrom 2000, "Out-of-core simplification of
// large polygonal models"; adaptive on two levels for a wanted triangle count, in the spirit of
// Shaffer & Garland 2001), with the node's boundary locked so that nodes
// simplified independently never crack, and a conservative geometric error per result.
//
// Coordinate space: everything is in model units (the PLY's units, world space of the asset).
// Meshes are octolod::NodeMesh: indexed, interleaved float vertices in VertexLayout order.
//
// Repeated faces. Before either method, a triangle that repeats an earlier one's corner positions
// in the same winding (a duplicated face, whatever its attributes) is dropped: exported assets
// have them, and the grid's output rule would cancel an even number of copies of a face. The
// rules below count each face once.
//
// Crack-freedom contract. The boundary of a node mesh is the set of its edges used by an odd
// number of its triangles (normally: by exactly one), where an edge is keyed by the exact float
// bits of its two end POSITIONS (x,y,z) — vertices that differ only in normal/colour/uv are one
// geometric vertex. Every vertex record whose position lies on a boundary edge is kept
// bit-identical (position and attributes) in every output, and every boundary edge survives.
// Two meshes that share an edge as a boundary (neighbouring octree nodes, with triangles assigned
// to exactly one node) therefore still share it after any number of simplifications, whatever
// each one's method and resolution. Interior attribute seams are not locked: they are kept apart
// as wedges (see SimplifyOptions).
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "octolod/formats/bounds.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod::bake {

enum class ClusterMethod {
  // Lindstrom-style: a grid of cubic cells inside the node, one quadric-optimal representative
  // per cell (inside its cell), locked boundary vertices are their own clusters, triangles whose
  // three corners land in three distinct clusters survive (once per cluster triple when their
  // number is odd; twice, wound both ways, when it is even and both windings occur facing away
  // from each other: a thin sheet such as a wall whose two faces share cells stays, two-sided,
  // while a smooth surface the cells fold is not doubled into a fin). For a wanted triangle count the grid
  // is adaptive: a coarser grid whose cells with the highest quadric error per area (where the
  // surface bends inside the cell) are halved, as many as the count allows. The default.
  grid,
  // The seed's operator (Bade et al. 2006, 3.5): one representative for the whole node from the
  // node's summed quadric (pulled to the cell centre when it falls outside the cell), and every
  // boundary edge (a,b) fanned to it as the triangle (a,b,rep), keeping the edge's winding.
  bade2006,
};

// Which boundary edges of a node other nodes may share: the octree's triangles go to the node
// holding their centroid, so a triangle of another node has its centroid outside the node's
// cell but inside the root's, within a third of its longest edge of the midpoint of each of its
// edges (for the edge a b and the third corner v, centroid - midpoint = ((v - a) + (v - b)) / 6).
// With `reach` at least a third of the input's longest triangle edge (plus rounding), a boundary
// edge whose midpoint lies deeper than `reach` behind every face of the cell that is not on the
// root's surface is used by no other node. Model units.
struct NeighbourReach {
  // Infinity: any boundary edge may be shared.
  double reach = std::numeric_limits<double>::infinity();
  // The root node's cell. Empty: every face of the cell may have a neighbour behind it.
  Bounds root;
};

struct SimplifyOptions {
  ClusterMethod method = ClusterMethod::grid;
  // grid only: the wanted triangle count. The adaptive grid (its coarse resolution and how many
  // cells are halved) is searched so that the output has at most this many triangles when that
  // is possible (the locked boundary alone may exceed it; then the coarsest grid, resolution 1,
  // is used). 0 = use grid_resolution.
  std::uint32_t target_triangles = 0;
  // grid only: a uniform grid with this many cells along the longest side of the clustering
  // domain (the node cell extended by the mesh bounds, since triangles assigned by centroid stick
  // out of their cell). Used when
  // target_triangles == 0; must then be >= 1. Higher = finer, more triangles.
  std::uint32_t grid_resolution = 0;
  // grid only: keep the node's boundary edges (used by one of its triangles) unchanged, so the
  // LODs of neighbouring nodes meet without cracks. false for a node without neighbours, the
  // root, whose boundary is the mesh's own border (an open surface's, a terrain's): it is then
  // clustered like the interior, each boundary edge adding a border quadric (the plane through
  // it perpendicular to its triangle) to its ends' clusters so that the border keeps its place.
  // bade2006 always keeps it (its operator fans it).
  bool lock_boundary = true;
  // grid only, with lock_boundary: which boundary edges other nodes may share. The others, the
  // mesh's own border deep inside the node (a terrain's, a scan's holes), are clustered like the
  // interior with border quadrics, unless the step with them kept has the lower error times
  // triangles (the step is then taken both ways). Default: every boundary edge is kept.
  NeighbourReach neighbours;
};

struct SimplifyResult {
  // Welded indexed mesh, same layout as the input. Vertex order: sorted by cluster (coarse cells,
  // then halved cells, in grid order, then locked vertices in input order), so the same input and options give the same
  // bytes on any thread. Normals unit length, colours in 0..1, no triangle with two corners at
  // the same position, no triangle repeated with the same winding (a two-sided sheet has each
  // of its triangles once per winding).
  NodeMesh mesh;
  // Upper bound, in model units, of the one-sided Hausdorff distance from the input surface to
  // the output surface: max over points x of the input of dist(x, output). 0 when the output is
  // the input. Infinity when the output is empty but the input was not.
  double error_bound = 0.0;
};

// Simplifies one node's mesh. `cell` is the node's octree cell (model units); the input's
// triangles may stick out of it. Wedges: corners of a cluster connected through original edges
// inside the cluster share one attribute value (solved from their own quadric with the position
// fixed); corners on the other side of a uv/normal/colour seam keep their own value, so seams are
// never averaged across. Positions come from the cluster's position-only quadric (the geometric
// error is what the runtime's screen-space error uses), the minimizer nearest the cluster's mean
// when the quadric is singular (flat or linear clusters), pulled into the cluster's cell along
// the segment from the cluster's mean when it falls outside; one of the cluster's own vertices
// instead when its quadric error is lower than that point's.
// Errors: bad_input when the mesh is inconsistent (vertex array not a multiple of the layout,
// index out of range, non-finite position); usage when the options are meaningless.
Result<SimplifyResult> simplify_node(const NodeMesh& input, const Bounds& cell,
                                     const SimplifyOptions& options);

struct LodOptions {
  // Method of every step (target_triangles / grid_resolution are chosen by build_lods).
  ClusterMethod method = ClusterMethod::grid;
  // The chain stops once a LOD has at most this many triangles: a distant asset costs a few
  // hundred triangles. Lower = longer chains (more files, more bake time).
  std::uint32_t min_triangles = 256;
  // An internal node's input (include_input false) is simplified whenever it has more than this
  // many triangles, even when min_triangles is higher: its LOD 0 then stands for its children at
  // a coarser level instead of repeating their triangles.
  std::uint32_t input_min_triangles = 256;
  // Each LOD has at most this fraction of the previous LOD's triangles; the chain stops when a
  // step cannot get there (the locked boundary dominates). In (0, 1).
  double reduction = 0.5;
  // Upper limit of the number of LODs returned (including the input when include_input).
  std::uint32_t max_lods = 16;
  // true (leaves): LOD 0 is the input itself, with input_error. false (internal nodes, whose
  // input is merge_meshes of one LOD per child, lod_tree.h): LOD 0 is the first
  // simplification of the input, which only has to be smaller than the input (not `reduction`
  // times smaller); when even that fails (or the input is already at most
  // input_min_triangles), LOD 0 is the input itself, so an internal node always gets at least
  // one LOD.
  bool include_input = true;
  // SimplifyOptions::lock_boundary of every step: false only for the root.
  bool lock_boundary = true;
  // SimplifyOptions::neighbours of every step.
  NeighbourReach neighbours;
};

struct Lod {
  NodeMesh mesh;
  // Conservative geometric error of this LOD relative to the ORIGINAL surface, model units:
  // input_error + the sum of the error bounds of the steps that led here (triangle inequality).
  double error = 0.0;
};

// Successively coarser LODs of one node, each simplified from the previous one (sequential
// simplification, seed 3.5.3). `input_error` is the error of `input` relative to the original
// surface (0 for a leaf's original triangles; for an internal node the max error of the
// children's LODs it was merged from). Errors as simplify_node.
Result<std::vector<Lod>> build_lods(NodeMesh input, double input_error, const Bounds& cell,
                                    const LodOptions& options);

// Concatenates meshes of the same layout (asserted) and welds vertices whose records (all floats)
// have identical bits, keeping the first occurrence's position in the output order. Triangles
// keep their order (mesh 0's first). Used to build an internal node's input from its children.
NodeMesh merge_meshes(std::span<const NodeMesh* const> meshes);

}  // namespace octolod::bake
