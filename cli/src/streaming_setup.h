// The streaming runtime's options as `octolod render` and `octolod walk` take them from their
// command lines, and the error both give when node LODs failed to load.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "octolod/formats/status.h"
#include "octolod/runtime/streaming_tree.h"

namespace octolod::cli {

// Options with max_resident_bytes parsed from `budget` ("64M": parse_byte_size; at least one
// byte, else a usage error), target_sse_pixels = `sse` (pixels) and a log that prints every
// failed load as a warning on stderr. The rest are StreamingOptions' defaults.
Result<runtime::StreamingOptions> streaming_options(const std::string& budget, double sse);

// bad_input naming `tree`: `failed` node LODs failed to load (the warnings of the options' log
// named them), then what the command did about it (`consequence`).
Status failed_loads_error(const std::string& tree, std::uint64_t failed, std::string_view consequence);

}  // namespace octolod::cli
