// The streaming runtime's options from a command line (streaming_setup.h).
#include "streaming_setup.h"

#include "command.h"

namespace octolod::cli {

Result<runtime::StreamingOptions> streaming_options(const std::string& budget, double sse) {
  Result<std::uint64_t> bytes = parse_byte_size(budget);
  if (!bytes.ok()) return bytes.status();
  if (bytes.value() == 0) return usage_error("--budget must be at least one byte");
  runtime::StreamingOptions options;
  options.max_resident_bytes = bytes.value();
  options.target_sse_pixels = sse;
  options.log = [](std::string_view message) { warn(std::string(message)); };
  return options;
}

Status failed_loads_error(const std::string& tree, std::uint64_t failed, std::string_view consequence) {
  return bad_input_error(tree + ": " + std::to_string(failed) + " node LOD(s) failed to load (the warnings above name them); " +
                         std::string(consequence));
}

}  // namespace octolod::cli
