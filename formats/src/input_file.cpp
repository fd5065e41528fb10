#include "octolod/formats/input_file.h"

#include <string>
#include <system_error>

namespace octolod {

Status check_input_file(const std::filesystem::path& path, std::string_view what) {
  const std::string cannot = path.string() + ": cannot read " + std::string(what) + ": ";
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) return io_error(cannot + "it does not exist");
  if (ec) return io_error(cannot + ec.message());
  if (status.type() == std::filesystem::file_type::directory) return io_error(cannot + "it is a directory");
  if (status.type() != std::filesystem::file_type::regular)
    return io_error(cannot + "it is not a regular file (a device, FIFO or socket)");
  return {};
}

}  // namespace octolod
