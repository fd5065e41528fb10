// libFuzzer harness for PlyReader (as meshoptimizer fuzzes each decoder): any input must give
// batches or a Status, never a crash, a hang or a large allocation. The reader takes a path,
// so each input goes into an in-memory file (memfd) reached through /proc/self/fd.
//
// Build with clang (tests/CMakeLists.txt), ideally with -DOCTOLOD_SANITIZE=ON, then run
//   ply_reader_fuzz -max_len=8192 -rss_limit_mb=256 <corpus dir>
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "octolod/formats/ply_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const int fd = memfd_create("ply_reader_fuzz", 0);
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  if (fd < 0) return 0;
  if (ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) return 0;

  // A small batch size makes fans span batches and exercises every resume path; double
  // positions are recentred as the bake reads them.
  octolod::PlyReadOptions options;
  options.buffer_bytes = 4096;
  options.recentre_double_positions = true;
  auto reader = octolod::PlyReader::open(path, options);
  if (!reader.ok()) return 0;
  const octolod::PlyInfo& info = reader.value()->info();
  const std::size_t floats = info.layout.floats();
  for (;;) {
    auto batch = reader.value()->next();
    if (!batch.ok() || batch->kind == octolod::PlyBatch::Kind::end) break;
    // The reader's contract: whole vertices, and indices below the vertex count (checked in
    // release builds too, so the fuzzer sees a violation as a crash).
    if (batch->vertices.size() % floats != 0) __builtin_trap();
    for (std::uint32_t index : batch->triangles)
      if (index >= info.vertex_count) __builtin_trap();
    // Corner values: corners.floats() per corner (none without attributes on the faces); finite
    // and in range.
    if (batch->corner_values.size() != info.corners.floats() * batch->triangles.size()) __builtin_trap();
    for (float value : batch->corner_values)
      if (!(std::abs(value) <= octolod::kMaxVertexValue)) __builtin_trap();
  }
  return 0;
}
