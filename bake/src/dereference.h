// Pointer dereferencing (seed 3.3, 4.2.2, Table 4.1). A working record entering pass c
// (c = 0, 1, 2) holds the corners already dereferenced, the vertex ids still to go, and the
// triangle id:
//   [corner 0 .. corner c-1: layout.floats() floats each][vertex id c .. 2: u32 each][triangle id]
// so pass 0's input is exactly a TriangleRecord and pass 2's output exactly a soup record.
// Each pass replaces vertex id c (which the input is sorted by) by the vertex record, reading
// the vertex file once, front to back.
#pragma once

#include <cstddef>
#include <span>

#include "octolod/bake/external_sort.h"
#include "octolod/bake/soup.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"
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

// Sort key of SoupOrder::by_last_corner for working records with two corners filled:
// (vertex id of corner 2 << 32) | triangle id. (Input already in triangle order, as in the
// in-core path, needs only corner 2's id: the sort is stable.)
SortKeyFn last_corner_key(VertexLayout layout, int filled);

// Where a dereference writes its records: reserve() room for between 1 and `max_records`
// records, fill a prefix, commit() it. Implemented over a RecordSorter (the next pass's sort,
// zero-copy), a RecordWriter (the soup file) or a caller's sink.
class RecordOutput {
 public:
  virtual ~RecordOutput() = default;
  virtual Result<std::span<std::byte>> reserve(std::size_t max_records) = 0;
  virtual Status commit(std::size_t records) = 0;
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
