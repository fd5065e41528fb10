// The triangle soup stage of the baker (seed 3.3, 4.2, Table 4.1): a PLY file of shared
// vertices and indexed faces becomes a file with one self-contained record per triangle, so
// later stages (octree build, clustering) never need random access to the vertices.
//
// Out of core (the vertices do not fit in half the budget):
//   split        the PLY is streamed in portions: vertices into a vertex file (records in file
//                order), triangles (3 vertex ids + triangle id) straight into
//   window pass  which reads the vertex file front to back into a window of consecutive ids (a
//                quarter of the budget) as the triangles come; each triangle whose corners are
//                all in the window becomes a soup record at once. Real meshes reference
//                vertices near each other and in file order, so this is nearly every triangle.
//                (A PLY whose faces come before its last vertex has its triangles written to a
//                triangle index file first, the seed's split, and read back for the pass);
//   3 passes     the seed's, for the rest ("far" triangles): for corner i = 0, 1, 2, external
//                merge sort by corner i's vertex id, the vertex file scanned in order alongside,
//                the vertex record written into corner i (each sorted stream feeds the next
//                pass's sort directly, no intermediate file).
// In core (the vertices fit in half the budget): the vertices are kept in memory and the
// triangle records, in triangle order, take all three corners from memory.
// SoupOrder::by_triangle gives the same bytes on every path, whatever the budget and thread
// count; SoupOrder::any the same records in an order that depends on the path and the budget
// (never on the thread count).
// Attributes the faces give their corners (PlyInfo::corners: texture coordinates per corner,
// colours per face) go from the split to a file of their own in triangle order; the records are
// then produced in triangle order (SoupOrder::by_triangle, whatever was asked) and each corner's
// values written into its record on the way out, so the soup is that of the same mesh with a
// vertex per wedge.
//
// The soup file (a temporary: raw native little-endian records, no header) holds
// triangle_count records of soup_record_bytes(layout) bytes:
//   corner 0: layout.floats() floats, corner 1: same, corner 2: same, triangle id: u32
// Corners are in the original winding; floats are the PLY's values in VertexLayout order
// (model units, colours 0..1); the triangle id is the triangle's index in the PLY's stream of
// triangles (polygons fan-triangulated). Degenerate triangles (a repeated vertex id, or
// coincident positions) are kept: the clustering stage drops them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include "octolod/bake/external_sort.h"
#include "octolod/bake/temp_file.h"
#include "octolod/formats/bounds.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::bake {

// Index of a vertex in the PLY's vertex element (0-based).
enum class VertexId : std::uint32_t {};
// Index of a triangle in the PLY's stream of triangles after fan triangulation (0-based).
enum class TriangleId : std::uint32_t {};

// One record of the triangle index file: 16 bytes, native little-endian.
struct TriangleRecord {
  VertexId corner[3];
  TriangleId triangle;
};
static_assert(sizeof(TriangleRecord) == 16);

// Bytes of one soup record.
constexpr std::size_t soup_record_bytes(VertexLayout layout) { return 3 * layout.bytes() + 4; }
// Byte offset of corner c (0..2) within a soup record.
constexpr std::size_t soup_corner_offset(VertexLayout layout, int corner) {
  return static_cast<std::size_t>(corner) * layout.bytes();
}
// Byte offset of the triangle id within a soup record.
constexpr std::size_t soup_triangle_id_offset(VertexLayout layout) { return 3 * layout.bytes(); }

// Copies corner c's layout.floats() floats out of a soup record.
inline void load_soup_corner(const std::byte* record, VertexLayout layout, int corner, float* out) {
  std::memcpy(out, record + soup_corner_offset(layout, corner), layout.bytes());
}
// Writes the soup record of triangle `triangle` whose corners are the vertices corner_ids[0..2]
// of `vertices` (layout.floats() floats per vertex) to `record` (soup_record_bytes(layout) bytes).
inline void store_soup_record(std::byte* record, VertexLayout layout, const float* vertices,
                              const std::uint32_t* corner_ids, std::uint32_t triangle) {
  for (int c = 0; c < 3; ++c)
    std::memcpy(record + soup_corner_offset(layout, c),
                vertices + std::size_t{corner_ids[c]} * layout.floats(), layout.bytes());
  std::memcpy(record + soup_triangle_id_offset(layout), &triangle, sizeof triangle);
}
inline TriangleId load_soup_triangle_id(const std::byte* record, VertexLayout layout) {
  std::uint32_t id;
  std::memcpy(&id, record + soup_triangle_id_offset(layout), sizeof id);
  return TriangleId{id};
}

enum class SoupOrder {
  // The order each path produces at no extra cost: in core triangle order; out of core the
  // window pass's triangles in triangle order, then the far ones by corner 2's vertex id (then
  // triangle id). Deterministic for the same input and budget. For a later stage that sorts
  // the soup again (the octree).
  any,
  // Ascending triangle id: the PLY's triangle order. Out of core, one more external sort.
  by_triangle,
};

// Called from the calling thread as the stage advances: stage is "split", "dereference" (the
// in-core gather or the window pass), "dereference 0..2" (the passes over the far triangles)
// or "order"; `done` of `total` items (vertices + triangles for the split, triangles after).
using SoupProgressFn =
    std::function<void(std::string_view stage, std::uint64_t done, std::uint64_t total)>;

// What SoupOptions::sink_start learns before the first record reaches the sink.
struct SoupSinkStart {
  VertexLayout layout;
  Bounds bounds;                     // of every vertex (as SoupResult::bounds), model units
  bool in_core = false;              // which path feeds the sink
  // Bytes of memory_budget_bytes the stage leaves unused while it feeds the sink: what the
  // sink's consumer may hold meanwhile, the two together within the budget. The out-of-core
  // path leaves about half the budget; the in-core path about one io buffer (1 MiB at most).
  std::uint64_t free_budget_bytes = 0;
};

// The indexed mesh the in-core path hands to SoupMeshSink::consume instead of a soup.
struct SoupMesh {
  VertexLayout layout;
  std::span<const float> vertices;           // vertex_count * layout.floats(), PLY order
  std::span<const std::uint32_t> triangles;  // 3 vertex ids (< vertex count) per triangle, in
                                             // PLY triangle order: triangle id = index / 3
  Bounds bounds;                             // as SoupResult::bounds, model units
  // Bytes of memory_budget_bytes the stage leaves unused during consume(): the budget minus
  // the two arrays above.
  std::uint64_t free_budget_bytes = 0;
};

// A consumer that can work from the indexed mesh itself (the bake's in-memory octree), which
// saves producing soup records at all. Both functions are called from the calling thread.
struct SoupMeshSink {
  // Whether the consumer takes a mesh of `vertex_count` vertices and up to `triangle_count`
  // triangles: the mesh (vertex_count * layout.bytes() + 12 bytes per triangle) and whatever
  // the consumer allocates must fit in memory_budget_bytes together.
  std::function<bool(VertexLayout layout, std::uint64_t vertex_count,
                     std::uint64_t triangle_count)>
      accepts;
  // Receives the mesh (valid during the call only). An error it returns ends build_soup.
  std::function<Status(const SoupMesh& mesh)> consume;
};

struct SoupOptions {
  // Cap on all buffers of the stage together: PLY reader, file buffers, sorts, and in core the
  // vertex array. Must be at least kMinSoupBudget. Larger budgets mean fewer sorted runs and,
  // once the vertices fit in half of it, the in-core path.
  std::uint64_t memory_budget_bytes = std::uint64_t{64} << 20;
  // Where the temporary files go (vertex file, sorted runs, the soup); the system temporary
  // directory when empty. Must exist.
  std::filesystem::path work_dir;
  // Threads for sorting runs (1 or 2 are useful); the output does not depend on it.
  unsigned threads = 2;
  SoupOrder order = SoupOrder::any;
  // Take the out-of-core three-pass path even when the vertices would fit (tests, benchmarks).
  bool force_out_of_core = false;
  // Positions declared double become relative to the first vertex rounded to whole units
  // before they are rounded to float (PlyReadOptions::recentre_double_positions): the records,
  // bounds and everything after are in that frame, SoupResult::origin says where it lies.
  bool recentre_double_positions = true;
  SoupProgressFn progress;
  // When set, the soup records are handed to `sink` in order, in batches of whole records
  // (valid during the call only), instead of being written to a file: a later stage can start
  // its own sort without the soup ever touching the disk. SoupResult::soup is then empty. An
  // error the sink returns ends build_soup with that error. Called from the calling thread.
  std::function<Status(std::span<const std::byte> records)> sink;
  // Optional, with `sink`: called once, before the first record reaches `sink` (also when
  // there are none), once every vertex has been read (out of core possibly while the faces are
  // still being read). An error it returns ends build_soup with that error.
  std::function<Status(const SoupSinkStart& start)> sink_start;
  // Optional: when the vertices fit (the in-core path), the faces give their corners no
  // attributes (PlyInfo::corners), and mesh_sink.accepts the PLY's declared vertex and face
  // counts, the split keeps the triangles in memory and mesh_sink.consume gets the mesh; no soup
  // record is produced (SoupResult::soup empty, `sink` never called, SoupResult::mesh_consumed
  // set). If the faces fan out into more triangles than declared, the PLY is read again for the
  // records path.
  SoupMeshSink mesh_sink;
};

inline constexpr std::uint64_t kMinSoupBudget = 256 * 1024;

struct SoupStageSeconds {
  double split = 0;        // reading the PLY, writing the vertex file (wall; sorting and the
                           // window pass run from the split excluded)
  double sort = 0;         // inside the external sorts (run formation and merging)
  double dereference = 0;  // scanning vertices and writing corners (sorting excluded)
  double total = 0;        // wall time of build_soup, SoupMeshSink::consume excluded
};

struct SoupResult {
  TempFile soup;  // the soup file (empty with SoupOptions::sink); removed when this result is
                  // destroyed unless released
  VertexLayout layout;
  std::uint64_t vertex_count = 0;
  std::uint64_t triangle_count = 0;
  Bounds bounds;         // of every vertex in the file (unreferenced ones included), model units
  // The input's point that the positions are relative to (SoupOptions::recentre_double_positions).
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  // Bytes after the input's last element, which the reader ignores (PlyInfo::trailing_bytes).
  std::uint64_t input_trailing_bytes = 0;
  bool in_core = false;  // which path was taken
  bool mesh_consumed = false;  // SoupOptions::mesh_sink received the mesh (in core only)
  // Out of core: triangles the window pass left to the three sorted passes.
  std::uint64_t far_triangles = 0;
  SoupStageSeconds seconds;
  std::vector<SortStats> sorts;  // one per external sort, in the order they ran
};

// Builds the soup of `ply` (see the top of this file). Errors: the PLY reader's (bad_input,
// unsupported, io, naming the file), io naming the temporary file the system refused
// (including out of space), usage for a budget under kMinSoupBudget or a missing work_dir,
// unsupported for 2^32 triangles or more. On error no temporary file is left behind.
Result<SoupResult> build_soup(const std::filesystem::path& ply, const SoupOptions& options);

// The soup of a mesh held in memory, as build_soup writes it with SoupOrder::by_triangle for
// the same vertices (layout.floats() per vertex) and triangles (3 vertex ids each, every one <
// vertex count): triangle_count * soup_record_bytes(layout) bytes. For tests and small meshes.
std::vector<std::byte> dereference_in_memory(std::span<const float> vertices,
                                             std::span<const std::uint32_t> triangles,
                                             VertexLayout layout);

}  // namespace octolod::bake
