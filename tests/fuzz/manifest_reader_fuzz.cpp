// libFuzzer harness for the manifest reader (manifest_from_json: the JSON reader,
// formats/src/json_reader.h, and its SAX handler, formats/src/manifest_sax.h): any text must
// give a valid Manifest or a Status, never a crash, an out-of-bounds access or undefined
// behaviour; a manifest it accepts must read back the same after being written.
//
// Build with clang (tests/CMakeLists.txt), ideally with -DOCTOLOD_SANITIZE=ON, then run
//   manifest_reader_fuzz -max_len=65536 -timeout=10 <corpus dir>
// seeded with manifest.json files of small bakes (`octolod bake samples/rock_small.ply ...`).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "octolod/formats/manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto manifest = octolod::manifest_from_json(text, "fuzz.json");
  if (!manifest.ok()) return 0;
  // The reader's contract (validate): a root first, parents before their children.
  if (manifest->nodes.empty() || manifest->nodes[0].parent != -1) __builtin_trap();
  const std::string written = octolod::manifest_to_json(manifest.value());
  auto again = octolod::manifest_from_json(written, "fuzz-again.json");
  if (!again.ok() || octolod::manifest_to_json(again.value()) != written) __builtin_trap();
  return 0;
}
