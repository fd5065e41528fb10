// Whether octolod's readers may read a path: only regular files are inputs. A directory would
// read as a failed read, a FIFO would block until a writer comes, a device such as /dev/zero never
// ends.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string_view>
#include <vector>

#include "octolod/formats/status.h"

namespace octolod {

// io_error "<path>: cannot read <what>: ..." (e.g. what = "the PLY") unless `path` names a
// regular file after symlinks: it does not exist, it is a directory, it is a device, FIFO or
// socket, or the system cannot tell (its message).
Status check_input_file(const std::filesystem::path& path, std::string_view what);

// The whole of the regular file `path` (check_input_file first, with `what`); read errors are io
// naming the file. For inputs that are read whole anyway (a glTF, an image to embed).
Result<std::vector<std::byte>> read_input_file(const std::filesystem::path& path, std::string_view what);

}  // namespace octolod
