// Output files that appear whole or not at all: written to a "<path>.tmp-<pid>" sibling and
// renamed over `path` once complete, so an interrupted or failed command never leaves a partial
// file nor replaces an earlier good one.
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string_view>

#include "octolod/formats/output_file.h"
#include "octolod/formats/status.h"

namespace octolod::cli {

// Calls write(file) on the open temporary sibling; false from it (or a failed close or rename)
// removes the temporary and returns io_error naming `path`, what was written (`what`, e.g. "the
// PNG") and errno's reason. First check_output_file (output_file.h), which a command also calls
// before its long work.
Status write_file_atomically(const std::filesystem::path& path, std::string_view what,
                             const std::function<bool(std::FILE*)>& write);

}  // namespace octolod::cli
