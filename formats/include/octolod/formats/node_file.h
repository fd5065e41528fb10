// Node LOD files: one indexed mesh (one LOD of one octree node) in a compact, versioned,
// checksummed binary file that loads with one read. Layout (little-endian), see docs/formats.md:
//   header  56 bytes: magic "OCTOLOD\0", version u32, layout mask u32, vertex_count u32,
//           index_count u32, index_bytes u32 (2 or 4), reserved u32, bounds min/max 6 x f32
//   vertices  vertex_count * layout.floats() f32, interleaved (VertexLayout order)
//   indices   index_count * index_bytes, 3 per triangle
//   crc32     u32 (IEEE) over everything before it
// Positions are stored exactly (float32), so vertices shared by neighbouring nodes stay
// bit-identical and cuts stay crack-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "octolod/formats/bounds.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod {

// An indexed triangle mesh with interleaved vertices: the unit of work of the LOD stages and
// the GPU-ready payload of the runtime.
struct NodeMesh {
  VertexLayout layout;
  std::vector<float> vertices;          // vertex_count() * layout.floats()
  std::vector<std::uint32_t> indices;   // 3 per triangle, each < vertex_count()

  std::size_t vertex_count() const { return layout.floats() ? vertices.size() / layout.floats() : 0; }
  std::size_t triangle_count() const { return indices.size() / 3; }
  Bounds bounds() const;
  friend bool operator==(const NodeMesh&, const NodeMesh&) = default;
};

inline constexpr std::uint32_t kNodeFileVersion = 1;
inline constexpr std::size_t kNodeFileHeaderBytes = 56;

// Serialized size of `mesh`, for budgeting before encoding.
std::size_t node_file_size(const NodeMesh& mesh);
std::vector<std::byte> encode_node_file(const NodeMesh& mesh);
// `name` is used in error messages (usually the file path), with the byte offset. Errors:
// bad_input for a wrong magic, mask, size, reserved field (not 0), checksum, a non-finite vertex
// float, a position outside the header's bounds or an index out of range; unsupported for
// another version.
Result<NodeMesh> decode_node_file(std::span<const std::byte> bytes, std::string_view name);

Status write_node_file(const std::filesystem::path& path, const NodeMesh& mesh);
// The bytes of the file at `path`, read whole, whose size is known up front (a manifest's
// LodInfo::bytes). Errors: io naming the path when it cannot be opened or read, is not a regular
// file (a FIFO would block, a device never end) or ends before its size; check_node_file_size's
// for a file of any other size, found by fstat before anything is allocated or read, so a
// swapped or corrupt file costs no more memory than the manifest says.
Result<std::vector<std::byte>> read_node_file_bytes(const std::filesystem::path& path,
                                                    std::uint64_t expected_bytes);
// bad_input naming `name` (the node file) and both sizes unless `actual_bytes` is the
// `expected_bytes` the manifest lists for it: another size is another LOD's file, a truncated or
// padded one, or an edited manifest.
Status check_node_file_size(std::string_view name, std::uint64_t actual_bytes, std::uint64_t expected_bytes);
// decode_node_file of the file at `path` read whole at the size it has (read_node_file_bytes'
// errors but the size check): a node file without its manifest entry.
Result<NodeMesh> read_node_file(const std::filesystem::path& path);
// decode_node_file of read_node_file_bytes(path, expected_bytes): a manifest's node LOD.
Result<NodeMesh> read_node_file(const std::filesystem::path& path, std::uint64_t expected_bytes);

// Writes a node file piece by piece, for a mesh too large to hold at once (a streamed octree
// leaf): the counts and bounds up front, then every vertex, then every index, in order. The
// bytes equal write_node_file's for the same mesh (bounds = the mesh's, or all zero when it has
// no vertex). Memory: one buffer of at most 1 MiB. Not thread-safe; one writer per file.
class NodeFileWriter {
 public:
  // Creates (truncates) `path`. io error naming the path when the system refuses.
  static Result<NodeFileWriter> create(const std::filesystem::path& path, VertexLayout layout,
                                       std::uint32_t vertex_count, std::uint32_t index_count,
                                       const Bounds& bounds);
  NodeFileWriter(NodeFileWriter&&) noexcept;
  NodeFileWriter& operator=(NodeFileWriter&&) noexcept;
  ~NodeFileWriter();  // an unfinished file is removed

  // Whole vertices (layout.floats() floats each); asserted not to pass vertex_count.
  Status append_vertices(std::span<const float> vertices);
  // After every vertex: indices (each < vertex_count); asserted not to pass index_count.
  Status append_indices(std::span<const std::uint32_t> indices);
  // After every index: the checksum, then closes. The file's size in bytes.
  Result<std::uint64_t> finish();

 private:
  struct File;  // the open file and what is left to write (node_file.cpp)
  explicit NodeFileWriter(std::unique_ptr<File> file);
  std::unique_ptr<File> file_;
};

// CRC-32 (IEEE 802.3, reflected, as zlib's crc32) of `bytes`, continuing from `crc`.
std::uint32_t crc32(std::span<const std::byte> bytes, std::uint32_t crc = 0);

}  // namespace octolod
