// libFuzzer harness for the glTF/GLB reader (decode_gltf, Draco primitives included): any input
// must give meshes or a Status, never a crash or an out-of-bounds access.
//
// Build with clang (tests/CMakeLists.txt), ideally with -DOCTOLOD_SANITIZE=ON, then run
//   gltf_reader_fuzz -max_len=16384 -rss_limit_mb=512 -timeout=10 <corpus dir>
// seeded with GLBs from `octolod export` (with and without --draco). Draco's decoder itself is
// not instrumented and trusts some counts in its bitstream (docs/formats.md, "glTF export"), so
// slow units inside libdraco are a known limit, not a reader bug.
#include <cstddef>
#include <cstdint>
#include <span>

#include "octolod/formats/gltf.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto bytes = std::span(reinterpret_cast<const std::byte*>(data), size);
  auto meshes = octolod::decode_gltf(bytes, "fuzz.glb");
  if (!meshes.ok()) return 0;
  // The reader's contract: whole vertices, whole triangles, indices below the vertex count
  // (checked in release builds too, so the fuzzer sees a violation as a crash).
  for (const octolod::NodeMesh& mesh : meshes.value()) {
    if (mesh.vertices.size() % mesh.layout.floats() != 0) __builtin_trap();
    if (mesh.indices.size() % 3 != 0) __builtin_trap();
    for (std::uint32_t index : mesh.indices)
      if (index >= mesh.vertex_count()) __builtin_trap();
  }
  return 0;
}
