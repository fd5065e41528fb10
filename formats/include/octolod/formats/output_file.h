// Where octolod's writers may put an output file. Every output (PLY, glTF, PNG, CSV) is written
// to a temporary sibling and renamed over its path once complete, so a failed or interrupted
// command leaves the earlier file as it was. A rename replaces whatever the path names: over a
// device such as /dev/null it would replace the device node itself (as root; a plain user is
// refused by /dev's permissions), over a FIFO the FIFO.
#pragma once

#include <filesystem>
#include <string_view>

#include "octolod/formats/status.h"

namespace octolod {

// io_error naming `path` and `what` (e.g. "the PLY") when an output cannot go there: its
// directory does not exist, or `path` exists and is not a regular file after symlinks (a
// directory, a device, a FIFO, a socket). A missing path or a regular file passes.
Status check_output_file(const std::filesystem::path& path, std::string_view what);

}  // namespace octolod
