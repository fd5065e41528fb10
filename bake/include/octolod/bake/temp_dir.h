// The bake's temporary directories and atomic publication (docs/design.md stage 6: a bake
// writes to a temporary directory and renames it into place when complete; temporary files
// never outlive the process). `octolod sample` stages its output the same way.
//
// Every temporary directory is named ".octolod-tmp-<pid>-<n>-<purpose>" so that a later bake
// can recognise one left behind by a killed process (SIGKILL cannot be caught) and remove it
// once that pid no longer runs.
//
// SIGINT/SIGTERM: with install_signal_cleanup(), a signal removes every live TempDir and then
// kills the process with the same signal (default action), so the exit status still says
// "killed by SIGINT". The handler itself only sets a flag and writes one byte to a pipe
// (async-signal-safe); a watcher thread does the removal. Code creating files checks
// cleanup_signal_received() so it stops adding new ones meanwhile.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "octolod/formats/status.h"

namespace octolod::bake {

inline constexpr std::string_view kTempDirPrefix = ".octolod-tmp-";

class TempDir {
 public:
  TempDir() = default;
  // Creates "<parent>/.octolod-tmp-<pid>-<n>-<purpose>" (parent must exist). io error naming
  // the path when the system refuses.
  static Result<TempDir> create(const std::filesystem::path& parent, std::string_view purpose);
  ~TempDir() { remove(); }
  TempDir(TempDir&& other) noexcept;
  TempDir& operator=(TempDir&& other) noexcept;
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  bool empty() const { return path_.empty(); }
  // Removes the directory tree now (ignoring errors) and forgets it.
  void remove();
  // Gives up ownership (after renaming the directory elsewhere): nothing is removed.
  std::filesystem::path release();

 private:
  explicit TempDir(std::filesystem::path path);
  std::filesystem::path path_;
};

// Removes the ".octolod-tmp-<pid>-..." entries of `dir` whose process is gone (not the calling
// process's, not those of a running process). Errors are ignored: this is housekeeping.
// Returns how many entries were removed.
int remove_stale_temp_dirs(const std::filesystem::path& dir);

// Whether `target` may be replaced by a bake: it does not exist, or is an empty directory, or a
// directory holding a manifest.json (a previous bake). Anything else (a file, a directory of
// other things) is a usage error, so a typo in -o never deletes a user's directory.
Status check_replaceable(const std::filesystem::path& target);

// Moves the complete directory `staging` to `target` (same file system). When `target` exists
// (see check_replaceable) the two are exchanged atomically (renameat2 RENAME_EXCHANGE; where the
// file system lacks it: old renamed aside, new renamed in, old put back on failure) and the old
// tree is removed afterwards. On error `target` is unchanged and `staging` still exists.
Status publish_directory(const std::filesystem::path& staging,
                         const std::filesystem::path& target);

// Installs the SIGINT/SIGTERM handlers and their watcher thread (once per process; later calls
// do nothing).
void install_signal_cleanup();
// True once SIGINT or SIGTERM arrived after install_signal_cleanup().
bool cleanup_signal_received();
// After cleanup_signal_received(): blocks until the watcher has removed the temporary
// directories and killed the process, so the caller never reports an error of its own (a
// failure caused by the removal) or exits normally in between.
[[noreturn]] void await_signal_cleanup();

}  // namespace octolod::bake
