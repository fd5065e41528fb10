// Octree leaves too large to hold in memory (issue 4 item 6: a node whose input exceeds the
// budget is clustered streaming, memory proportional to the output). A leaf at --max-depth
// cannot split, so its cell may get any share of the input; past the in-memory leaf cap the
// OctreeBuilder hands its soup records to a LeafRecordSpill (a file) and the leaf's LODs are
// built from that file in passes of bounded memory:
//
//   LOD 0  the original triangles: chunks of the records indexed one at a time (NodeIndexer;
//          a vertex shared by two chunks is stored once per chunk) and appended to one node
//          file (NodeFileWriter), so readers see an ordinary node file.
//   LOD 1  vertex clustering on a uniform grid inside the node (Lindstrom 2000, "Out-of-core
//          simplification of large polygonal models"), from the records without repeated faces
//          (repeated_records.h: a copy of the file when some repeat): the node's boundary edges
//          (used by an odd number of its triangles, vertex identity = position bits, as
//          find_boundary) are found by an external sort of edge records and stay unchanged (their
//          positions are clusters of their own, vertex records kept bit-identical), so cuts mixing
//          this leaf's LODs with its neighbours' never crack. Every other corner falls in its grid
//          cell; a cell's position comes from its area-weighted plane quadric (quadric.h) as in the
//          in-memory grid (place_representative). Its corners are split into wedges by their
//          attributes (streamed_leaf.cpp, AttributeWedges: a corner joins a wedge whose first
//          corner is within 60 degrees of normal and 0.25 of every colour and uv channel, so the
//          two sides of a seam are never averaged; the in-memory grid's wedges follow the mesh's
//          edges, which streaming cannot hold), each wedge the area-weighted mean of its corners'
//          attributes (normals renormalized, colours clamped). Triangles whose corners fall in
//          three distinct clusters survive as build_clustered_mesh's rule keeps them (kept_copies
//          per cluster triple: once when odd, a two-sided pair for a thin sheet), with the wedges
//          of a source triangle. The resolution is searched by counting passes (a resolution whose
//          distinct cluster triples pass twice the limit counts as too fine, so memory stays
//          bounded by the limit) for at most min(max_lod1_triangles, lod.reduction x the input)
//          triangles. Its error bound is the max over chunks of hausdorff_upper_bound(chunk,
//          LOD 1): the distance from the input decomposes over any partition of the input.
//   LOD 2+ build_lods from LOD 1 and its error, in memory.
//
// The same path builds an internal node whose children's LODs are too large to merge in memory
// (lod_tree.h; StreamedLeafOptions::merged_children): their triangles are its records, and it
// gets no LOD 0 of its own.
//
// Memory: one chunk of records and its indexed mesh, the grid's occupied cells (about LOD 1's
// vertices) and candidate triangles (at most 2 x the limit), the boundary's positions, LOD 1 and
// its chain, and the sorts' budget (the repeated faces', then the edges'). Not bounded: a leaf
// whose locked boundary alone keeps more than the limit gets no LOD 1, and its parent then merges
// its LOD 0 from the file.
// Deterministic: a pure function of the record file and options.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "octolod/bake/simplify.h"
#include "octolod/bake/temp_file.h"
#include "octolod/formats/manifest.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"
#include "record_file.h"

namespace octolod::bake {

// Collects the soup records of one oversize leaf into a temporary file in `work_dir`, then
// orders them by triangle id (the records arrive in stream order, where equal keys may come in
// any order) so the leaf's file, and everything built from it, is the same on any schedule.
class LeafRecordSpill {
 public:
  LeafRecordSpill(std::filesystem::path work_dir, VertexLayout layout, std::size_t buffer_bytes,
                  std::uint64_t sort_budget_bytes);
  // Whole soup records (soup_record_bytes(layout) each); the first call opens the file.
  Status append(std::span<const std::byte> records);
  // The leaf's records ordered by triangle id, in a file owned by the caller; the spill is
  // ready for the next leaf.
  Result<TempFile> finish();

 private:
  std::filesystem::path work_dir_;
  VertexLayout layout_;
  std::size_t buffer_bytes_;
  std::uint64_t sort_budget_bytes_;
  TempFile file_;
  std::optional<RecordWriter> writer_;
  bool in_order_ = true;  // the records so far came by increasing triangle id
  bool any_ = false;
  std::uint32_t last_id_ = 0;
};

struct StreamedLeafOptions {
  VertexLayout layout;  // of the soup records
  Bounds cell;          // the leaf's octree cell, model units
  bool build_lods = true;  // false: LOD 0 only
  LodOptions lod;          // the chain's method, limits and reduction (the chain starts at LOD 1)
  // Triangles held in memory at once (a chunk of records and its indexed mesh, about 3 soup
  // records per triangle); LOD 0 stores a vertex once per chunk that uses it. >= 1.
  std::uint64_t chunk_triangles = 1 << 16;
  // The most triangles LOD 1 may have (its chain is built in memory). >= 1.
  std::uint64_t max_lod1_triangles = 1 << 14;
  std::filesystem::path work_dir;          // the edge sort's temporary files
  std::uint64_t sort_budget_bytes = 4 << 20;  // the edge sort's memory (external_sort.h)
  // The records are an internal node's merged children (lod_tree.h: their LODs too large to
  // simplify in memory), not a leaf's original triangles: no LOD 0 is written (lod0 stays
  // empty), LOD 1 and its chain are the node's LODs, and every error adds input_error (the
  // largest error of the merged LODs). build_lods must be true.
  bool merged_children = false;
  double input_error = 0.0;
};

struct StreamedLeafLods {
  LodInfo lod0;     // written to root / dir / "lod0.olod", error 0
  Bounds lod0_bounds;
  std::vector<Lod> coarser;  // LOD 1, 2, ... (not written), errors in model units
};

// Writes LOD 0 of the leaf whose soup records (ordered by triangle id) are in the file
// `records` to root / dir / "lod0.olod" and returns it with the leaf's coarser LODs. No LOD 1
// when even the coarsest grid keeps more than the triangle limit (the locked boundary
// dominates). With options.merged_children, no LOD 0: `coarser` holds the node's LODs, or
// nothing when no LOD 1 could be built. Errors: io naming the file; bad_input for a non-finite
// position.
Result<StreamedLeafLods> build_streamed_leaf(const std::filesystem::path& records,
                                             const std::filesystem::path& root,
                                             const std::string& dir,
                                             const StreamedLeafOptions& options);

}  // namespace octolod::bake
