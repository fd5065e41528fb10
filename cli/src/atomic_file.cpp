// Output files written whole (atomic_file.h).
#include "atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

namespace octolod::cli {

Status write_file_atomically(const std::filesystem::path& path, std::string_view what,
                             const std::function<bool(std::FILE*)>& write) {
  OCTOLOD_RETURN_IF_ERROR(check_output_file(path, what));
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid());
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (!file) return io_error(path.string() + ": cannot create: " + std::strerror(errno));
  errno = 0;
  bool ok = write(file);
  int error = ok ? 0 : errno;
  if (std::fclose(file) != 0 && ok) ok = false, error = errno;
  std::error_code ec;
  if (ok) {
    std::filesystem::rename(tmp, path, ec);
    if (ec) ok = false, error = ec.value();
  }
  if (ok) return {};
  std::filesystem::remove(tmp, ec);
  return io_error(path.string() + ": writing " + std::string(what) + " failed" +
                  (error != 0 ? std::string(": ") + std::strerror(error) : std::string()));
}

}  // namespace octolod::cli
