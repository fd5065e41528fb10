// Soup record files without their repeated faces: the streamed nodes' counterpart of
// without_repeated_triangles (wedges.h), which holds its node in memory. A face the input holds
// twice would cancel under the clustering's mod-2 output rule (its triple's copies), and its
// edges, used twice, would no longer be found as the node's boundary (streamed_leaf.h locks the
// edges used an odd number of times), so the streamed LODs are built from the faces once each.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "octolod/bake/temp_file.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::bake {

// A copy of the soup record file `records` (soup_record_bytes(layout) bytes each, no header)
// without every record whose corner positions (their bits) repeat an earlier record's in the
// same cyclic order, whatever its attributes and triangle id (the same face wound the other
// way, a two-sided sheet, is no repeat); the others in their order, byte for byte. Nothing when
// no record repeats one (the file is its own copy). Found by an external sort of one 44-byte
// record per face by the hash of its positions (external_sort.h, one thread, temporary files in
// `work_dir`), then of the repeats' record numbers. Memory: `sort_budget_bytes` for the sorts
// and the files' buffers together (external_sort.h's minimum for sort_records, about 64 KiB),
// and the distinct faces of one hash, one in practice. Deterministic. Errors: io naming the
// file; usage when the budget is below that minimum.
Result<std::optional<TempFile>> without_repeated_records(const std::filesystem::path& records, VertexLayout layout,
                                                         const std::filesystem::path& work_dir,
                                                         std::uint64_t sort_budget_bytes);

}  // namespace octolod::bake
