// Streaming PLY reader (syntax + semantics): reads a PLY file in bounded portions and hands out
// batches of vertices (in VertexLayout order) and triangles (polygons fan-triangulated), in the
// order the elements appear in the file. Memory never depends on the file's size: the reader
// holds at most PlyReadOptions::buffer_bytes of decoded data plus its file buffer.
//
// Accepted: format ascii | binary_little_endian | binary_big_endian 1.0; comments and obj_info;
// any elements in any order; scalar types char/uchar/short/ushort/int/uint/float/double and
// int8/uint8/int16/uint16/int32/uint32/float32/float64; list properties of any count/item type.
// Kept vertex properties: x,y,z; nx,ny,nz; red,green,blue | diffuse_red,diffuse_green,diffuse_blue
// (alpha read and dropped) as uchar or float; u,v | s,t | texture_u,texture_v |
// texture_s,texture_t. Faces: the list property vertex_indices or vertex_index; texture
// coordinates per corner as the float list texcoord (u, v for every corner, the way MeshLab and
// photogrammetry tools write textured meshes); a colour per face as red,green,blue |
// diffuse_red,diffuse_green,diffuse_blue (alpha dropped), as CAD exports and segmented scans
// have it. Both are PlyInfo::corners. Everything else is skipped.
//
// Errors (Status bad_input unless noted) name the file and the line (ascii) or byte offset
// (binary): a path that is not a regular file (io: check_input_file, input_file.h),
// truncation, bad magic/format line, unknown types, counts the file cannot hold, face lists
// with < 3 or > 2^20 entries, indices negative or >= vertex count, NaN/Inf or values
// beyond ±kMaxVertexValue (1e18, vertex_layout.h), a header over 1 MiB or without end_header,
// declared elements missing. Vertex counts >= 2^32 are `unsupported` (indices are 32-bit).
//
// Details of the contract:
// - Declared counts are checked against the file size in open(), before anything is allocated
//   (binary: exact bytes per entry; ascii: two characters per value; faces: 3 indices).
// - Attributes the faces give their corners (PlyInfo::corners) replace the vertices' own, if
//   any: the layout has them, vertex batches hold zeros in their slots (the vertices' own are
//   skipped), and triangle batches carry each corner's values beside its index
//   (PlyBatch::corner_values). A texcoord list must hold two floats per index of its face,
//   finite and within ±kMaxVertexValue; a face's colour goes to each of its corners. Such a
//   face is decoded whole before it is fanned out, so memory is the batch plus the largest face
//   (at most 2^20 corners).
// - Colours of an integer type are divided by the type's maximum (uchar c -> float(c / 255.0)),
//   float/double colours are kept as they are; info().color_type is float32 when the `red`
//   that is kept (the faces' if they have colours) is a float type, else uchar. An incomplete
//   group (nx without nz, u without v) is skipped.
// - NaN/Inf and magnitudes beyond kMaxVertexValue are rejected in every kept attribute (also
//   after double -> float conversion; positions after the origin is subtracted), not only in
//   positions, so downstream quadrics and distances never overflow.
// - ascii: every element entry is on a line of its own (blank lines between entries are fine);
//   only whitespace may follow the last element. binary: trailing bytes are ignored (some writers
//   pad) and counted (PlyInfo::trailing_bytes), so that a caller can warn: more than padding
//   usually means element counts in the header that are too small.
// - Element entries are counted from 0 in messages ("face 3 of 10" is the fourth face).
// - Elements without properties take no bytes (and no ascii lines).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "octolod/formats/ply.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod {

// The attributes a PLY's faces give each of their corners instead of its vertex's.
struct CornerAttributes {
  bool color = false;  // the face's red, green, blue: one colour for all its corners
  bool uv = false;     // texcoord: (u, v) per corner
  // Floats per corner: r, g, b (color) then u, v (uv), VertexLayout's order. They are the
  // layout's floats from first_offset() on, contiguous (uv follows color in a layout).
  constexpr std::uint32_t floats() const { return (color ? 3u : 0u) + (uv ? 2u : 0u); }
  constexpr bool any() const { return color || uv; }
  // The float offset within a vertex of `layout` (which has these attributes) of the first.
  constexpr std::uint32_t first_offset(VertexLayout layout) const {
    return color ? layout.color_offset() : layout.uv_offset();
  }
  friend constexpr bool operator==(const CornerAttributes&, const CornerAttributes&) = default;
};

struct PlyInfo {
  std::filesystem::path path;
  PlyFormat format = PlyFormat::ascii;
  std::uint64_t vertex_count = 0;  // as declared in the header
  std::uint64_t face_count = 0;    // polygons as declared (triangles after fan-out may be more)
  VertexLayout layout;             // which attributes the file has (all three colour channels,
                                   // all normal components, both uv components are required)
  PlyColorType color_type = PlyColorType::uchar;  // on-disk colour type when layout.color
  std::uint64_t header_bytes = 0;  // bytes up to and including the end_header line
  bool double_positions = false;   // x, y or z is declared double (float64)
  // What the faces give their corners (texcoord, face colours): layout has them, but the vertex
  // batches' slots for them are not the corners' values, PlyBatch::corner_values are.
  CornerAttributes corners;
  // The images the texture coordinates index, as the header's "comment TextureFile <name>" lines
  // name them (MeshLab's and photogrammetry tools' convention; the keyword in any case), in
  // order, usually relative to the PLY's directory; empty when the header names none. Several
  // go with a face property (texnumber) saying which image a face's UVs index.
  std::vector<std::string> texture_files;
  // What the reader skips, in header order: properties of the vertex and face elements as
  // "vertex.quality", "face.texnumber" (including the vertices' own colours or UVs that the
  // faces' replace, and incomplete groups such as a lone nx), other elements as "element camera".
  std::vector<std::string> skipped;
  // Subtracted from every position before it is rounded to float (PlyReadOptions): the decoded
  // positions are relative to it. Zeros unless an origin applies; with recentre_double_positions
  // it is known once the first vertex batch has been returned.
  std::array<double, 3> position_origin{0.0, 0.0, 0.0};
  // Binary: the bytes after the last element, which are ignored; known once next() has returned
  // Kind::end (0 before, and always 0 for ascii, which refuses anything but whitespace there).
  std::uint64_t trailing_bytes = 0;
};

struct PlyReadOptions {
  // Upper bound on decoded data held per batch. Larger batches mean fewer calls; memory is
  // this plus a fixed 64 KiB file buffer. Minimum 4 KiB.
  std::size_t buffer_bytes = std::size_t{1} << 20;
  // Positions declared double are decoded relative to the first vertex's position rounded to
  // whole units (info().position_origin): floats keep 24 bits of a coordinate, so 4,000 km from
  // the origin (geo-referenced data) they are 0.25 apart, while relative to a point of the model
  // they keep its detail. Float positions are decoded as they are (they hold no more).
  bool recentre_double_positions = false;
  // When set, subtracted from every position instead (double or float): to read a second mesh in
  // the frame of a first (info().position_origin of its reader) or of a baked tree.
  std::optional<std::array<double, 3>> position_origin;
};

struct PlyBatch {
  enum class Kind { vertices, triangles, end };
  Kind kind = Kind::end;
  // Index of the first vertex / triangle of this batch within the file's stream of them.
  std::uint64_t first = 0;
  // kind == vertices: count * layout.floats() floats. Valid until the next call to next().
  std::span<const float> vertices;
  // kind == triangles: count * 3 vertex indices, each < info().vertex_count.
  std::span<const std::uint32_t> triangles;
  // kind == triangles and info().corners.any(): count * 3 * info().corners.floats() floats, the
  // values of each corner in the order of `triangles`; empty otherwise. Valid until the next
  // call to next().
  std::span<const float> corner_values;
};

class PlyReader {
 public:
  // Opens the file and parses the header.
  static Result<std::unique_ptr<PlyReader>> open(const std::filesystem::path& path,
                                                 const PlyReadOptions& options = {});
  virtual ~PlyReader() = default;

  const PlyInfo& info() const { return info_; }

  // The next batch in file order; Kind::end after the last element, then end forever.
  // After an error the reader is unusable.
  virtual Result<PlyBatch> next() = 0;

 protected:
  PlyInfo info_;
};

// Convenience for tests and small files: the whole mesh in memory, as an indexed mesh of
// wedges. Without attributes on the faces the vertices are the file's. With them
// (info.corners.any()) every distinct pair of a vertex and a corner's values becomes one vertex
// (the file's vertex with those values), numbered in the order the triangles first use them;
// vertices no triangle uses are dropped.
struct PlyMesh {
  PlyInfo info;
  std::vector<float> vertices;          // layout.floats() per vertex (info.vertex_count of them
                                        // unless info.corners.any())
  std::vector<std::uint32_t> triangles;  // 3 per triangle
};
// (buffer_bytes of `options` is ignored: the whole mesh is held anyway.)
Result<PlyMesh> read_ply(const std::filesystem::path& path, const PlyReadOptions& options = {});

}  // namespace octolod
