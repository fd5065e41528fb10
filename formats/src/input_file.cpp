#include "octolod/formats/input_file.h"

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
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

Result<std::vector<std::byte>> read_input_file(const std::filesystem::path& path, std::string_view what) {
  OCTOLOD_RETURN_IF_ERROR(check_input_file(path, what));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return io_error(path.string() + ": cannot open: " + std::strerror(errno));
  std::vector<std::byte> bytes;
  std::array<std::byte, 1 << 16> chunk;
  std::size_t n;
  while ((n = std::fread(chunk.data(), 1, chunk.size(), f)) > 0)
    bytes.insert(bytes.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n));
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return io_error(path.string() + ": read failed");
  return bytes;
}

}  // namespace octolod
