// From a clustering of a node mesh's vertices to the simplified mesh (seed 3.5, 4.4; Garland &
// Heckbert 1998; wedges as in Hoppe 1999, "New quadric metric for simplifying meshes with
// appearance attributes"): the step the grid method shares with any other vertex clustering.
//
// A wedge is a set of corners of one cluster connected through original edges inside that
// cluster (union-find on vertex ids). Corners on the two sides of a uv/normal/colour seam are
// different vertex ids joined by no edge, so they stay different wedges and the seam is never
// averaged across. The cluster gets one position (from its summed position-only quadric), each
// wedge one attribute vector (from its own generalized quadric with that position fixed).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "boundary_edges.h"
#include "error_bound.h"
#include "flat_hash.h"
#include "octolod/formats/node_file.h"

namespace octolod::bake {

// Welds vertices whose records (all floats) have identical bits; the first occurrence keeps its
// relative order, indices are remapped. Identical records are one wedge of one vertex.
NodeMesh weld_identical_vertices(const NodeMesh& mesh);
// The same, or nothing when no two records are identical (the mesh is its own welded form):
// what the simplifier uses to avoid a copy of its input in the common case.
std::optional<NodeMesh> weld_if_needed(const NodeMesh& mesh);
// Whether weld_if_needed may weld: false when no two vertex records of `mesh` are identical;
// true when two are, or when a position holds more vertices than this check compares (then
// weld_if_needed decides). From its position ids (make_position_ids(mesh)): only records at one
// position can be identical, so a vertex alone at its position (the most) is settled without
// hashing its record. Linear in the vertex count.
bool may_have_identical_records(const NodeMesh& mesh, const PositionIds& positions);
// The mesh whose triangles are `corners` (indices of `records`, layout.floats() floats each;
// three per triangle): the records they use, in their order, and the corners renumbered to them.
NodeMesh mesh_of_used_records(VertexLayout layout, std::span<const float> records,
                              std::span<const std::uint32_t> corners);
// `mesh` without the triangles that repeat an earlier one's corner positions in the same cyclic
// order (a duplicated face, whatever its attributes), its vertices that only they used removed
// (the others keep their order); nothing when no triangle repeats one. Duplicate faces are common
// in exported assets, and under build_clustered_mesh's mod-2 rule an even number of copies of a
// face cancels: a mesh whose every face is doubled would never simplify. `positions`:
// make_position_ids(mesh). The same face wound the other way (a two-sided sheet) is no repeat.
std::optional<NodeMesh> without_repeated_triangles(const NodeMesh& mesh, const PositionIds& positions);

struct ClampBox {
  std::array<double, 3> min;
  std::array<double, 3> max;
};

struct Clustering {
  std::vector<std::uint32_t> of_vertex;  // cluster of each vertex; clusters in output order
  std::uint32_t count = 0;
  // Per cluster: 1 when its vertices are kept verbatim (locked boundary: every vertex record its
  // own wedge, bit-identical). Otherwise its position lies in box (local coordinates): the
  // quadric minimizer pulled into it towards the cluster's mean, or the cluster's vertex with the
  // least quadric error when that is lower.
  std::vector<std::uint8_t> locked;
  std::vector<ClampBox> box;
  // Optional: the position quadrics (quadric_doubles(3) doubles each) of the first clusters,
  // as many as it holds, summed as build_clustered_mesh sums them (add_plane_quadrics over each
  // cluster's vertices), which sums those of the others; and their minimizers nearest the
  // clusters' means (3 doubles each, read for the clusters of more than one vertex). (The
  // adaptive grid's coarse clusters that it leaves whole, which come first in key order, have
  // them already.)
  std::vector<double> quadric;
  std::vector<double> minimizer;
};

// The position of an unlocked cluster (local coordinates, as its n = 3 position `quadric`):
// the quadric's minimizer nearest to `mean` (the cluster's mean), pulled into `box` along the
// segment from the mean when it falls outside (a fold or a crease inside the cell: the planes
// meet far away), unless `best_vertex` (a position of one of the cluster's own vertices, which
// lie on the input surface, then its quadric error; error +infinity for none) has a lower
// quadric error than that point. `minimizer`: that minimizer when the caller has it (else null).
void place_representative(const double* quadric, const double* mean, const ClampBox& box,
                          const double* best_vertex, double* x, const double* minimizer = nullptr);

// Builds the clustered mesh. `origin` (model units) is subtracted from positions for the quadric
// arithmetic; clamp boxes are relative to it. Triangles: a triangle survives when its corners are
// in three distinct clusters; the surviving triangles are grouped per cluster triple, and each
// triple keeps kept_copies of them (below): the output is the mod-2 image of the input plus
// two-sided sheets, so its boundary (edges used an odd number of times) is exactly the image of
// the input's boundary and nothing opens. A kept triangle takes its wedges from its first source
// triangle, and the orientation whose normal agrees with the area-weighted normals of its source
// triangles (flipped triangles are re-wound, not dropped: dropping would open the surface); of a
// two-sided pair, the copy facing like the sources that wind like the sorted triple takes the
// first such source's wedges, the other copy the first opposite source's, wound the other way.
// Triangles with two corners at bit-identical positions are dropped (their edges cancel mod 2).
// Then the diagonals of bent quads that pass further from the input than the other diagonal
// would are flipped (diagonal_flips.h), and folded three-triangle fans replaced by their
// neighbours' triangle (folded_fans.h); neither changes the boundary mod 2. Unused vertices are
// removed; output vertices are in (cluster, smallest vertex id of the wedge) order. Last,
// triangles turned inside out among their neighbours are re-wound (inside_out.h).
struct ClusteredMesh {
  NodeMesh mesh;
  // Per input triangle: an output triangle at or next to its image (the image itself when it
  // survived, or the triangle a flip made of it, or the replacement of the folded fan it was in;
  // else one sharing an image edge, else one at an image vertex), kNoTriangle when there is none.
  // Only a hint for hausdorff_upper_bound: any output triangle gives a valid bound.
  std::vector<std::uint32_t> nearby_output_triangle;
  // The fan of every cluster: the output triangles with a corner at it, and the replacement of
  // a folded fan of one of its wedges (CSR: fan_triangle [fan_offset[c], fan_offset[c+1])), and
  // each input vertex's cluster: where the error bound looks for the output triangles nearest an
  // input vertex.
  std::vector<std::uint32_t> vertex_cluster;
  std::vector<std::uint32_t> fan_offset;
  std::vector<std::uint32_t> fan_triangle;

  ImageHints hints() const { return {nearby_output_triangle, vertex_cluster, fan_offset, fan_triangle}; }
};
// `face_normal`: face_normals(mesh). `free_border`: the boundary edges clustered like the
// interior (PreparedNode::free_border), which add their border quadrics (add_plane_quadrics).
ClusteredMesh build_clustered_mesh(const NodeMesh& mesh, std::span<const std::array<double, 3>> face_normal,
                                   const Clustering& clustering, const std::array<double, 3>& origin,
                                   std::span<const BoundaryEdge> free_border = {});

// The cross product of the edges from p0 of the triangle (p0, p1, p2), each the position (first
// three floats, model units) of a vertex record, in double: its normal times twice its area.
std::array<double, 3> triangle_normal(const float* p0, const float* p1, const float* p2);

// triangle_normal of every triangle of `mesh`.
std::vector<std::array<double, 3>> face_normals(const NodeMesh& mesh);

// The area of the triangles whose face_normals these are.
double surface_area(std::span<const std::array<double, 3>> face_normal);

// Per position, the unit sum of the face_normals (area-weighted normals) of the triangles
// using it; zero where they cancel or the triangles are degenerate.
std::vector<std::array<float, 3>> position_facings(const NodeMesh& mesh, const PositionIds& positions,
                                                   std::span<const std::array<double, 3>> face_normal);

// The mod-2 output rule's orientation (build_clustered_mesh): a source triangle whose corners
// fall in the distinct clusters (c0, c1, c2) winds like their sorted triple iff (c0, c1, c2)
// is an even permutation of it.
template <class Id>
bool winds_like_sorted(Id c0, Id c1, Id c2) {
  return (c0 < c1) + (c1 < c2) + (c2 < c0) == 2;
}

// The cluster triple (c0, c1, c2) in ascending order: the key of the output rule's tables.
inline std::array<std::uint32_t, 3> sorted_triple(std::uint32_t c0, std::uint32_t c1, std::uint32_t c2) {
  std::array<std::uint32_t, 3> triple{c0, c1, c2};
  std::sort(triple.begin(), triple.end());
  return triple;
}

// How many triangles build_clustered_mesh keeps for one cluster triple: one when its sources
// are odd in number (the mod-2 image); two, wound opposite ways, when they are even, both
// windings occur among them and the sources of the two windings face away from each other (a
// thin sheet, e.g. a wall whose two faces fall into the same cells, is kept two-sided:
// cancelling it would drop its whole area, and the pair adds nothing to the boundary mod 2);
// none otherwise: all wind the same way (a surface folded onto itself twice), or both windings
// face the same way (the clustering folded a smooth surface across the triple: a pair there
// stands out of the surface as a fin; on 1M rocks these were 99.6% of the pairs, and one of
// them made a 10% cut's Hausdorff distance 4.2x the reference's).
inline unsigned kept_copies(bool odd, bool like_sorted_seen, bool opposite_seen, bool sides_face_away) {
  if (odd) return 1;
  return like_sorted_seen && opposite_seen && sides_face_away ? 2 : 0;
}

// Triangles the output rule keeps (kept_copies summed over the triples), counted from the
// sources without building the mesh: what the resolution searches evaluate. Without the
// sources' normals it counts a pair for every even triple with both windings, so it is an upper
// bound: the output also drops the pairs whose two sides face the same way (about 0.5% of the
// triangles of a rock's LODs, 0.3% of a city's).
template <std::size_t W>
class KeptTriangleCounter {
 public:
  using Key = typename FlatHashMap<W>::Key;
  // Room for `max_keys` distinct triples.
  explicit KeptTriangleCounter(std::size_t max_keys) : table_(max_keys) {}
  // One source of the triple `key`, winding like its sorted order or not.
  void add(const Key& key, bool like_sorted) {
    bool inserted = false;
    const std::uint32_t index = table_.find_or_insert(key, static_cast<std::uint32_t>(state_.size()), inserted);
    if (inserted) state_.push_back(0);
    std::uint8_t& state = state_[index];
    kept_ -= copies(state);
    state = static_cast<std::uint8_t>((state ^ kOdd) | (like_sorted ? kLike : kOpposite));
    kept_ += copies(state);
  }
  bool contains(const Key& key) const { return table_.find(key) != FlatHashMap<W>::kMissing; }
  std::size_t distinct() const { return state_.size(); }
  std::size_t kept() const { return kept_; }

 private:
  static constexpr std::uint8_t kOdd = 1, kLike = 2, kOpposite = 4;
  static unsigned copies(std::uint8_t state) {
    return kept_copies(state & kOdd, state & kLike, state & kOpposite, true);
  }
  FlatHashMap<W> table_;
  std::vector<std::uint8_t> state_;  // per triple in order of first source
  std::size_t kept_ = 0;
};

// A kept cluster triple's triangle with corners `corner` at the vertex records `record`, to
// face like `facing` (model space; its sources' area-weighted normals, each in its own winding):
// false when two corners have bit-identical positions (the triangle is dropped), else true with
// corners 1 and 2 swapped where its normal points away from `facing` (re-wound, not dropped:
// dropping would open the surface).
bool orient_kept_triangle(const std::array<const float*, 3>& record, const std::array<double, 3>& facing,
                          std::array<std::uint32_t, 3>& corner);

// The sources of one cluster triple as the output rule counts them (build_clustered_mesh and the
// streamed leaf): how many, how many wind like the sorted triple, which winding came first, and
// their area-weighted normals: in the sorted triple's winding (all of them, and those winding
// like it), and each in its own winding (which way the input surface faces there).
struct TripleSources {
  std::uint32_t count = 0;
  std::uint32_t like_sorted = 0;
  bool first_is_like = false;
  std::array<double, 3> normal{};
  std::array<double, 3> like_normal{};
  std::array<double, 3> own_normal{};

  // One more source, winding like the sorted triple iff `like`, its normal `source_normal`
  // (triangle_normal, in its own winding). True when it is the first source of its winding: the
  // one whose corners append_kept_triangles takes for that winding.
  bool add(bool like, const std::array<double, 3>& source_normal) {
    const bool first = like ? like_sorted == 0 : count == like_sorted;
    if (count == 0) first_is_like = like;
    ++count;
    like_sorted += like;
    for (std::size_t i = 0; i < 3; ++i) normal[i] += like ? source_normal[i] : -source_normal[i];
    for (std::size_t i = 0; i < 3; ++i) own_normal[i] += source_normal[i];
    if (like)
      for (std::size_t i = 0; i < 3; ++i) like_normal[i] += source_normal[i];
    return first;
  }
  unsigned copies() const {
    // the opposite sources' normals, each in its own winding, sum to like_normal - normal
    double facing = 0.0;
    for (std::size_t i = 0; i < 3; ++i) facing += like_normal[i] * (like_normal[i] - normal[i]);
    return kept_copies(count % 2 == 1, like_sorted > 0, like_sorted < count, facing < 0.0);
  }
};

// Appends to `out` the corners of the triangles the output rule keeps for one triple (copies()
// of them). `like` and `opposite` are the corners, in their source's order, of the first source
// of each winding (the one of a winding without sources is not read); `record(corner)` is a
// corner's vertex record (const float*). The one copy takes the first source's corners, a
// pair's front copy the `like` ones and its back copy the `opposite` ones wound against the
// front; the front is oriented by orient_kept_triangle (nothing is appended when it drops it):
// the one copy to face like all its sources, each in its own winding, a pair's front like its
// `like` sources. (Not the sum in the sorted triple's winding: where the clustering folds the
// surface across a triple, sources of both windings face the same way, and that sum, pointing
// against the larger winding's area, turned the copy inside out, to be drawn from behind or
// culled among neighbours that face out; inside_out.h repairs what is left.)
template <class Record>
void append_kept_triangles(const TripleSources& sources, const std::array<std::uint32_t, 3>& like,
                           std::array<std::uint32_t, 3> opposite, const Record& record,
                           std::vector<std::uint32_t>& out) {
  const unsigned copies = sources.copies();
  if (copies == 0) return;
  const bool front_like = copies == 2 || sources.first_is_like;
  std::array<std::uint32_t, 3> front = front_like ? like : opposite;
  const std::array<std::uint32_t, 3> unturned = front;
  if (!orient_kept_triangle({record(front[0]), record(front[1]), record(front[2])},
                            copies == 1 ? sources.own_normal : sources.like_normal, front))
    return;
  out.insert(out.end(), front.begin(), front.end());
  if (copies == 1) return;
  if (front != unturned) std::swap(opposite[1], opposite[2]);
  out.insert(out.end(), opposite.begin(), opposite.end());
}

// The weight of a border quadric per squared length of its edge (add_plane_quadrics): heavy
// enough to hold a border cluster on the border line, light enough that the pseudo-inverse
// (quadric.h, kPseudoInverseThreshold) still sees the surface's planes next to it. The 1M
// terrain's root chain at 1 / 10 / 100, measured with every node's border free (branch
// wip/neighbour-reach): LOD 0 error 1.505 / 1.502 / 1.576, the coarsest's 17.0 / 14.1 / 14.6; as
// it is (only the root's border free) at 10: 1.51 and 13.4, without border quadrics 2.77 and 36.8.
inline constexpr double kBorderWeight = 10.0;

// The position quadrics of a clustering: every triangle with a positive area adds its plane
// quadric (quadric.h, n = 3; the plane through corner 0 relative to `origin`, model units)
// weighted by its area to quadrics[cluster[v]] (quadric_doubles(3) doubles per cluster) for each
// corner v with counted[v], once per such corner, and that area to areas[cluster[v]] when
// `areas` is not null. `normals` from face_normals(mesh). Every edge of `border` (boundary edges
// clustered like the interior) adds to the clusters of its counted ends the quadric of the plane
// through it perpendicular to its triangle, weighted by kBorderWeight times its length squared
// (Garland & Heckbert 1997's boundary constraint): without it a border cluster's
// representative, the minimizer of its surface planes alone, lies anywhere along the surface,
// up to a cell inside the border, and the border erodes.
void add_plane_quadrics(const NodeMesh& mesh, std::span<const std::array<double, 3>> normals,
                        const std::vector<std::uint32_t>& cluster, const std::vector<std::uint8_t>& counted,
                        const std::array<double, 3>& origin, double* quadrics, double* areas,
                        std::span<const BoundaryEdge> border = {});

// Post-processing of a solved attribute vector in VertexLayout order (after the position):
// normals renormalized (`fallback_normal` when zero), colours clamped to 0..1.
void finish_attributes(VertexLayout layout, const double* fallback_normal, double* attributes);

}  // namespace octolod::bake
