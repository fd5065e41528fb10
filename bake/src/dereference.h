// Pointer dereferencing (seed 3.3, 4.2.2, Table 4.1). A working record entering pass c
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

// Receives consecutive output records; the span is valid during the call only.
using RecordSink = std::function<Status(std::span<const std::byte> records)>;

// Out-of-core pass `corner`: `sorted` yields working records with `corner` corners filled, in
// ascending order of vertex id `corner`; `vertices` is the vertex file (layout.bytes() records)
// positioned at its start. Output records (one more corner filled) go to `sink` in batches built
// in `scratch` (at least one output record). io error if the vertex file is shorter than an id.
Status dereference_pass(int corner, VertexLayout layout, RecordSorter& sorted,
                        RecordReader& vertices, std::span<std::byte> scratch,
                        const RecordSink& sink);

// In-core: `sorted` yields TriangleRecords in output order; each becomes a soup record with its
// three corners copied from `vertices` (vertex_count * layout.floats() floats), handed to `sink`
// in batches built in `scratch` (at least one soup record). Ids were checked against the vertex
// count by the PLY reader.
Status dereference_in_core(VertexLayout layout, std::span<const float> vertices,
                           RecordSorter& sorted, std::span<std::byte> scratch,
                           const RecordSink& sink);

}  // namespace octolod::bake
