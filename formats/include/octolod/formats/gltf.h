// glTF 2.0 export and import of node meshes: GLB (binary container) or .gltf (JSON with the
// buffer embedded as a base64 data URI), optionally with Draco-compressed primitives
// (KHR_draco_mesh_compression). See docs/formats.md, section "glTF export".
//
// What is written, per NodeMesh i: glTF node i (named names[i]) referencing glTF mesh i with one
// triangle primitive; attributes POSITION (vec3 float, with min/max), NORMAL (vec3 float),
// COLOR_0 (vec3 float, linear 0..1), TEXCOORD_0 (vec2 float) as the mesh's VertexLayout has them;
// indices uint16 when every vertex index fits below 65535, else uint32. Positions are in model
// units; node transforms are identity but for GltfWriteOptions::translation. Without Draco the
// attribute values are copied bit-exactly (one interleaved buffer view per mesh), but for v:
// glTF's texture space has v down, octolod's (as PLY's) v up, so TEXCOORD_0 is (u, 1 - v) and the
// reader turns it back (exactly for v in [0.5, 2], else within half a float step of 1 - v). With GltfWriteOptions::texture, one material (the image as its base
// colour, not metallic) on every primitive with TEXCOORD_0. A mesh without triangles becomes a
// node without a mesh.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"

namespace octolod {

// Draco's encoder holds tables of 2^bits entries per quantized attribute: 30 bits took 3.7 GB
// and 35 s for a 6K-triangle cut, 24 (a float's precision) 68 MB. Bits are capped there.
inline constexpr int kMaxDracoBits = 24;

// Draco quantization bits per attribute (1..kMaxDracoBits; 0 = keep float32 unquantized,
// which Draco only compresses losslessly and poorly). A value is reproduced within half a
// quantization step. Positions of all meshes in one file share one grid, the bounding cube of
// all of them, so a vertex shared by two meshes (neighbouring octree nodes) stays identical and
// an exported cut stays crack-free; their error is (largest extent of the union bounds) /
// (2^bits - 1) / 2. The defaults keep a 1 m asset within 0.03 mm; on the 200K-triangle rock
// sample (all attributes) they make the GLB 14x smaller (6.81 MB -> 0.48 MB).
struct DracoOptions {
  int position_bits = 14;  // 14: error < extent / 32766
  int normal_bits = 10;    // octahedral; 10 bits: about 0.2 degree
  int color_bits = 8;      // 8: the precision of the PLY's uchar colours
  int uv_bits = 12;        // 12: 1/8190 of the UV range, sub-texel up to 4K textures
  // 0 (fastest, larger) .. 10 (slowest, smallest), like draco_encoder -cl. Decoding speed
  // follows the same setting.
  int compression_level = 7;
};

// An image to texture the exported meshes with (GltfWriteOptions::texture).
struct GltfTexture {
  std::string name;       // the image's name in the file (e.g. its file name)
  std::string mime_type;  // "image/png" or "image/jpeg", the types glTF 2.0's core allows
  std::vector<std::byte> bytes;  // the image file's bytes, embedded as they are
};

// Reads an image file for GltfWriteOptions::texture, named by its file name. unsupported unless
// its bytes begin as a PNG's or a JPEG's do; io errors name the file.
Result<GltfTexture> read_gltf_texture(const std::filesystem::path& path);

struct GltfWriteOptions {
  // true: GLB (one binary file). false: .gltf JSON with the buffer embedded as a data URI
  // (about 4/3 larger; handy for diffing and debugging).
  bool binary = true;
  // Compress every primitive with Draco (KHR_draco_mesh_compression, listed as required: there
  // is no uncompressed fallback). Lossy by the quantization in `draco_options`; vertex and
  // triangle order change, vertices on non-manifold edges may be duplicated. Every triangle is
  // kept except those repeating a vertex index (Edgebreaker cannot encode them).
  bool draco = false;
  DracoOptions draco_options;
  // Node and mesh names: empty (names "mesh_0", "mesh_1", ...) or exactly one per mesh.
  std::vector<std::string> names;
  // Every node's translation (model units): where the meshes' (0, 0, 0) lies, e.g. a baked
  // tree's Manifest::origin; the positions stay float relative to it. Zeros: no translation.
  std::array<double, 3> translation{0.0, 0.0, 0.0};
  // Embedded in the file's buffer (GLB: the BIN chunk; .gltf: its data URI) as the base colour
  // texture of the primitives that have TEXCOORD_0: the image their UVs index, e.g. a baked tree's
  // Manifest::texture. Empty: no material, no image.
  std::optional<GltfTexture> texture;
};

// Encodes `meshes` into the bytes of a GLB file (options.binary) or a .gltf file. Errors:
// usage when names.size() is neither 0 nor meshes.size() or a Draco setting is out of range;
// bad_input when a mesh is inconsistent (vertices not a multiple of the layout, an index out of
// range, more than 2^31 - 1 vertices or indices).
Result<std::vector<std::byte>> encode_gltf(std::span<const NodeMesh> meshes,
                                           const GltfWriteOptions& options);

// Same as encode_gltf, streamed into a temporary sibling (path + ".tmp-<pid>") that is renamed
// over `path` once complete; on any error no file is left. io errors name the file.
Status write_gltf(const std::filesystem::path& path, std::span<const NodeMesh> meshes,
                  const GltfWriteOptions& options);

// Decodes a self-contained GLB or .gltf file (buffers in the GLB BIN chunk or in data URIs):
// one NodeMesh per glTF mesh, in the order of the file's `meshes` array; node transforms are not
// applied. Reads what write_gltf writes and simple files of other writers: triangle primitives
// (several per mesh are concatenated; the layout is the attributes all of them have), float or
// normalized unsigned byte/short colours (vec3 or vec4, alpha dropped) and UVs, uint8/16/32 or
// absent indices, byte strides, Draco-compressed primitives. Errors: bad_input for malformed data
// (message names `name` and what was wrong), unsupported for valid glTF that octolod does not
// handle (sparse accessors, non-triangle modes, external buffers).
Result<std::vector<NodeMesh>> decode_gltf(std::span<const std::byte> bytes, std::string_view name);

// Reads a .glb or .gltf file; like decode_gltf, and additionally resolves buffer URIs relative to
// the file's directory. Errors name the file.
Result<std::vector<NodeMesh>> read_gltf(const std::filesystem::path& path);

}  // namespace octolod
