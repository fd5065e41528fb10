// Pointer dereferencing (seed 3.3, 4.2.2, Table 4.1), out of core in two steps:
//
// 1. The window pass (octolod's, not the seed's): a mesh's triangles nearly always reference
//    vertices close together in the file, and sweep the vertex ids in file order (a generated
//    or scanned mesh is written row by row, strip by strip). The triangle file and the vertex
//    file are read front to back together, the vertices into a window of consecutive ids; a
//    triangle whose corners are all in the window becomes a soup record at once. The others
//    ("far": corners further apart than the window, or one already slid out of it) go on to
//    step 2. One read of each file instead of three external sorts.
// 2. The seed's three passes for the far triangles. A working record entering pass c
// (c = 0, 1, 2) holds the corners already dereferenced, the vertex ids still to go, and the
// triangle id:
//   [corner 0 .. corner c-1: layout.floats() floats each][vertex id c .. 2: u32 each][triangle id]
// so pass 0's input is exactly a TriangleRecord and pass 2's output exactly a soup record.
// Each pass replaces vertex id c (which the input is sorted by) by the vertex record, reading
// the vertex file once, front to back.
#pragma once

#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include "octolod/bake/external_sort.h"
#include "octolod/bake/soup.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"
#include "page_array.h"
#include "record_file.h"

namespace octolod::bake {

// Bytes of a working record with `filled` (0..3) corners dereferenced.
constexpr std::size_t working_record_bytes(VertexLayout layout, int filled) {
  return static_cast<std::size_t>(filled) * layout.bytes() +
         static_cast<std::size_t>(3 - filled) * 4 + 4;
}
// Byte offset of the vertex id that pass `corner` dereferences (the sort key of that pass).
constexpr std::size_t working_vertex_id_offset(VertexLayout layout, int corner) {
  return static_cast<std::size_t>(corner) * layout.bytes();
}

// Where a dereference writes its records: reserve() room for between 1 and `max_records`
// records, fill a prefix, commit() it. Implemented over a RecordSorter (the next pass's sort,
// zero-copy), a RecordWriter (the soup file) or a caller's sink.
class RecordOutput {
 public:
  virtual ~RecordOutput() = default;
  virtual Result<std::span<std::byte>> reserve(std::size_t max_records) = 0;
  virtual Status commit(std::size_t records) = 0;
};

struct WindowStats {
  std::uint64_t near = 0;  // triangles written to the output
  std::uint64_t far = 0;   // triangles handed to the far sink
};

// The window pass, fed with triangles (TriangleRecords, any order) as they come: `vertices`
// is the vertex file (layout.bytes() records) positioned at its start, read into a window of
// `window_vertices` vertices (a power of two; window_vertices * layout.bytes() bytes of
// memory) that only slides forward, to cover the largest id of each near triangle as it
// comes. Near triangles go to `out` as soup records in the order they were added, far ones to
// `far` (batches of whole TriangleRecords, valid during the call only). The references must
// outlive the object; io error if the vertex file is shorter than an id needs.
class WindowDereferencer {
 public:
  using FarFn = std::function<Status(std::span<const TriangleRecord>)>;
  WindowDereferencer(VertexLayout layout, std::size_t window_vertices, RecordReader& vertices,
                     RecordOutput& out, FarFn far);

  Status add(std::span<const TriangleRecord> triangles);
  // Hands out the last far triangles.
  Status finish();
  const WindowStats& stats() const { return stats_; }

 private:
  Status fill_to(std::uint64_t keep, std::uint64_t last);
  Status flush_far();

  VertexLayout layout_;
  std::size_t window_vertices_;
  RecordReader& vertices_;
  RecordOutput& out_;
  FarFn far_;
  PageArray<std::byte> window_;  // vertex v in slot v % window_vertices_ while in the window
  std::uint64_t end_ = 0;        // the window holds [end_ - window_vertices_, end_) (from 0)
  std::vector<TriangleRecord> far_batch_;
  WindowStats stats_;
};

// Out-of-core pass `corner`: `sorted` yields working records with `corner` corners filled, in
// ascending order of vertex id `corner`; `vertices` is the vertex file (layout.bytes() records)
// positioned at its start. Output records (one more corner filled) go to `out`. io error if
// the vertex file is shorter than an id needs.
Status dereference_pass(int corner, VertexLayout layout, RecordSorter& sorted,
                        RecordReader& vertices, RecordOutput& out);

// In-core: `sorted` yields TriangleRecords in output order; each becomes a soup record with its
// three corners copied from `vertices` (vertex_count * layout.floats() floats), written to
// `out`. Ids were checked against the vertex count by the PLY reader.
Status dereference_in_core(VertexLayout layout, std::span<const float> vertices,
                           RecordSorter& sorted, RecordOutput& out);

}  // namespace octolod::bake
