// Procedural sample meshes for `octolod sample`, the tests and the benchmarks: a noise-displaced
// closed rock, an open fBm terrain, a city of flat-shaded boxes, a thin closed tube (a torus 1 unit
// wide and 1,000 long, thinner than the bake's grid cells). Any size from 16 to a billion
// triangles, streamed in bounded memory, bit-identical on every platform, optimization level and
// thread count for the same SampleSpec (own integer hash noise and own sin/cos: only + - * /
// sqrt floor, no libm transcendentals, no std::*_distribution, no fused multiply-add).
// Finer meshes get more noise octaves on the same coarse shape (detail the mesh can resolve).
//
// Coordinates (model units, y up, triangles counter-clockwise seen from outside / above):
//   rock     around the origin, |p| < 1.3: direction d scaled by 1 + 0.3 fBm(d) (star-shaped,
//            never self-intersecting), then by (1, 0.72, 0.86) per axis
//   terrain  x in [0, 100], z in [0, 100 * rows / columns], y in (-7, 21) (typically -7..14)
//   city     12 x 12 lots on the ground plane y = 0 starting at the origin, buildings 3..60 high
//   tube     around the origin: a centre circle in the plane y = 0 of circumference 1000 (radius
//            1000 / 2pi ~ 159.15), tube radius 0.5: x, z in [-159.66, 159.66], y in [-0.5, 0.5]
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "octolod/formats/node_file.h"
#include "octolod/formats/ply.h"
#include "octolod/formats/status.h"
#include "octolod/formats/vertex_layout.h"

namespace octolod::samplegen {

enum class Shape {
  // Closed 2-manifold; a latitude/longitude sphere whose rings have a vertex count proportional
  // to their circumference (no slivers at the poles), zipped together ring by ring. Shared
  // vertices; the only repeated positions are the u = 0 / u = 1 seam copies (longitude 0).
  // Spherical uv (u = longitude / 2pi, v = 1 at the north pole, 0 at the south), analytic
  // normals of the displaced surface, colour by height and noise.
  rock,
  // Open heightfield grid, shared vertices, planar uv (u = x / 100, v = z / 100), analytic
  // normals, colour by height and slope. Its boundary is the rectangle of the grid.
  terrain,
  // A ground quad, then one box per lot (height varies, taller downtown). Every box face has
  // its own 4 vertices with the face normal (flat shading), uv in units of 10 model units per
  // face, one colour per box. Each box is closed on its own.
  city,
  // Closed 2-manifold torus: a (rings + 1) x (segments + 1) grid of shared vertices, the last
  // ring and the last segment the seam copies of the first (same position, normal and colour
  // bits; u or v a full repeat on). Quads about square: segments = sqrt(N / 636.6), at least 8
  // from 48 triangles up (N / 6 below, so that 3 rings fit: 3 at 16). uv: u = centre-line
  // length / 10 (0..100), v = angle around / 2pi (0..1, from the outer equator). Exact normals
  // radial from the centre circle; one paint colour picked by the seed (the only thing the seed
  // changes) with a light band 10 long every 100.
  tube,
};

std::string_view to_string(Shape shape);

struct SampleSpec {
  Shape shape = Shape::rock;
  // Wanted triangle count. Rock and city make exactly this many or one less (odd counts);
  // the terrain, a grid of 2 * columns * rows, is within 3% from 100 triangles up and within
  // 1% from 1000 up; the tube, a grid of 2 * segments * rings, is within `segments` triangles:
  // 8 below 40,000 (so within 1% from 800 up; 16 and 17 make 18), 0.03% from 40,000 up.
  std::uint64_t triangles = 40'000;
  VertexLayout layout{true, true, true};
  std::uint64_t seed = 1;
  // Added (in double) to every position write_sample_ply writes; non-zero writes x, y, z as
  // double: the same model placed far from the origin, as geo-referenced data is (the stream's
  // positions stay as generated).
  std::array<double, 3> offset{0.0, 0.0, 0.0};
  // When not empty, write_sample_ply names this image in a "comment TextureFile" line (the
  // texture its UVs index, relative to the PLY; `octolod sample --texture` writes one).
  std::string texture_file;
};

inline constexpr std::uint64_t kMinTriangles = 16;
// Keeps every vertex index within 32 bits for every shape (the city has 2 vertices per triangle).
inline constexpr std::uint64_t kMaxTriangles = 1'000'000'000;

struct SampleCounts {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
  friend bool operator==(const SampleCounts&, const SampleCounts&) = default;
};

// The exact counts the stream for `spec` emits, without generating anything (O(sqrt(N)) time,
// O(sqrt(N)) memory for the rock's ring table: under 1 ms even for a billion triangles).
// usage error when spec.triangles is outside [kMinTriangles, kMaxTriangles].
Result<SampleCounts> sample_counts(const SampleSpec& spec);

struct SampleBatch {
  enum class Kind { vertices, triangles, end };
  Kind kind = Kind::end;
  // Index of the batch's first vertex / triangle in the stream of them.
  std::uint64_t first = 0;
  // kind == vertices: count * layout.floats() floats in VertexLayout order.
  // Valid until the next call to next() or the stream's destruction.
  std::span<const float> vertices;
  // kind == triangles: 3 vertex indices per triangle, each < counts().vertices.
  std::span<const std::uint32_t> triangles;
};

struct SampleStreamOptions {
  // Upper bound on one batch's data: memory use is about this, whatever the triangle count.
  // Larger batches mean fewer calls. Minimum 4 KiB.
  std::size_t batch_bytes = std::size_t{1} << 20;
  // Threads generating each vertex batch (the calling thread and threads - 1 helpers claiming
  // fixed 1024-vertex chunks). The output is bit-identical for any value; 0 is taken as 1.
  unsigned threads = 1;
};

// Emits all vertices, then all triangles, in batches (like PlyReader), then Kind::end forever.
class SampleStream {
 public:
  static Result<std::unique_ptr<SampleStream>> create(const SampleSpec& spec,
                                                      const SampleStreamOptions& options = {});
  ~SampleStream();
  SampleStream(const SampleStream&) = delete;
  SampleStream& operator=(const SampleStream&) = delete;

  const SampleSpec& spec() const;
  const SampleCounts& counts() const;
  SampleBatch next();

 private:
  class Impl;
  explicit SampleStream(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Called with the vertices + triangles emitted so far and their total, after every batch.
using SampleProgress = std::function<void(std::uint64_t done, std::uint64_t total)>;

// Streams the sample into a PLY file (uchar colours; the header's comment is the `octolod sample`
// command that reproduces it). Encoding and writing run on a thread of their own, overlapping
// generation; memory stays at a few batches. `progress` is called on the calling thread.
// The file appears only when complete (PlyWriter's temporary + rename). I/O errors name the file.
Status write_sample_ply(const SampleSpec& spec, const std::filesystem::path& path,
                        PlyFormat format = PlyFormat::binary_little_endian,
                        const SampleProgress& progress = {},
                        const SampleStreamOptions& stream_options = {});

// The whole sample as one indexed mesh in memory (spec.layout; colours as floats 0..1, the
// stream's values): for tests and benchmarks of algorithms that take a NodeMesh. Memory is the
// full mesh (about (floats per vertex x 4) x triangles / 2 + 12 x triangles bytes), so keep
// spec.triangles to what fits. Errors as SampleStream::create.
Result<NodeMesh> generate_sample_mesh(const SampleSpec& spec);

// Command-line vocabulary, shared by `octolod sample` and the benchmarks. All return usage
// errors that quote the text.
// "rock" | "terrain" | "city" | "tube".
Result<Shape> parse_shape(std::string_view text);
// "200000", "2e5", "200K", "20M", "1.5G" (decimal suffixes K = 1e3, M = 1e6, G = 1e9); the value
// is rounded to an integer and must be in [kMinTriangles, kMaxTriangles].
Result<std::uint64_t> parse_triangle_count(std::string_view text);
// Comma-separated subset of normal,color,uv (also "colour"); "" or "none" is positions only.
Result<VertexLayout> parse_attributes(std::string_view text);

}  // namespace octolod::samplegen
