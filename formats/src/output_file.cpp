#include "octolod/formats/output_file.h"

#include <string>
#include <system_error>

namespace octolod {

Status check_output_file(const std::filesystem::path& path, std::string_view what) {
  const std::string cannot = path.string() + ": cannot write " + std::string(what) + ": ";
  const std::filesystem::path parent = std::filesystem::absolute(path).parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(parent, ec))
    return io_error(cannot + "directory " + parent.string() + " does not exist");
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::directory) return io_error(cannot + "it is a directory");
  if (std::filesystem::exists(status) && status.type() != std::filesystem::file_type::regular)
    return io_error(cannot + "it is not a regular file (a device, FIFO or socket), and outputs are "
                             "written whole, then renamed over their path");
  return {};
}

}  // namespace octolod
