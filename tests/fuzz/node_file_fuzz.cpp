// libFuzzer harness for the node-file decoder (decode_node_file, formats/src/node_file.cpp): the
// runtime decodes whatever bytes a tree's directory holds, so any bytes must give a valid
// NodeMesh or a Status, never a crash, an out-of-bounds access or undefined behaviour; a mesh it
// accepts must encode to a file that decodes to the same mesh. Inputs whose first byte is odd
// get their checksum made right before decoding, so that mutations reach the checks past it (a
// random file almost never passes the CRC-32).
//
// Build with clang (tests/CMakeLists.txt), ideally with -DOCTOLOD_SANITIZE=ON, then run
//   node_file_fuzz -max_len=65536 -timeout=10 <corpus dir>
// seeded with the node files of small bakes (`octolod bake samples/rock_small.ply ...`).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "octolod/formats/node_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::byte> bytes(reinterpret_cast<const std::byte*>(data), reinterpret_cast<const std::byte*>(data) + size);
  if (size >= 4 && (data[0] & 1u) != 0) {  // (the magic's 'O' is odd: the seeds keep their checksums right)
    const std::uint32_t crc = octolod::crc32(std::span<const std::byte>(bytes).first(size - 4));
    for (std::size_t i = 0; i < 4; ++i) bytes[size - 4 + i] = static_cast<std::byte>(crc >> (8 * i));
  }
  auto mesh = octolod::decode_node_file(bytes, "fuzz.bin");
  if (!mesh.ok()) return 0;
  // The decoder's contract: whole triangles, every index within the vertices.
  if (mesh->indices.size() % 3 != 0) __builtin_trap();
  for (const std::uint32_t index : mesh->indices)
    if (index >= mesh->vertex_count()) __builtin_trap();
  const std::vector<std::byte> encoded = octolod::encode_node_file(mesh.value());
  auto again = octolod::decode_node_file(encoded, "fuzz-again.bin");
  if (!again.ok() || !(again.value() == mesh.value())) __builtin_trap();
  return 0;
}
