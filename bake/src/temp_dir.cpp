// Temporary directories, stale-directory housekeeping, atomic publication and SIGINT/SIGTERM
// cleanup of the bake (docs/design.md stage 6), see temp_dir.h.
#include "octolod/bake/temp_dir.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace octolod::bake {
namespace {

namespace fs = std::filesystem;

// Live temporary directories, for the signal watcher.
struct Registry {
  std::mutex mutex;
  std::vector<fs::path> paths;
};
Registry& registry() {
  static Registry* r = new Registry;  // never destroyed: the watcher may outlive main()
  return *r;
}

void register_path(const fs::path& p) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.paths.push_back(p);
}

void unregister_path(const fs::path& p) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  auto it = std::find(r.paths.begin(), r.paths.end(), p);
  if (it != r.paths.end()) r.paths.erase(it);
}

std::atomic<int> g_signal{0};
int g_pipe[2] = {-1, -1};

extern "C" void on_cleanup_signal(int sig) {
  const int saved_errno = errno;
  int expected = 0;
  if (g_signal.compare_exchange_strong(expected, sig)) {
    const char byte = 1;
    [[maybe_unused]] ssize_t n = ::write(g_pipe[1], &byte, 1);
  }
  errno = saved_errno;
}

// Waits for the handler's byte, removes the registered directories, then dies by the signal.
void watch_signals() {
  char byte;
  while (::read(g_pipe[0], &byte, 1) < 0 && errno == EINTR) {
  }
  const int sig = g_signal.load();
  // Workers may still be creating a file or two: a few rounds catch those.
  for (int round = 0; round < 3; ++round) {
    std::vector<fs::path> paths;
    {
      Registry& r = registry();
      std::lock_guard lock(r.mutex);
      paths = r.paths;
    }
    for (const fs::path& p : paths) {
      std::error_code ignored;
      fs::remove_all(p, ignored);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, sig);
  ::pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
  ::raise(sig);
  std::_Exit(128 + sig);  // only if the signal was somehow ignored
}

// "<pid>" of ".octolod-tmp-<pid>-...", or 0.
pid_t temp_dir_pid(const std::string& name) {
  if (name.rfind(kTempDirPrefix, 0) != 0) return 0;
  const char* digits = name.c_str() + kTempDirPrefix.size();
  char* end = nullptr;
  const long pid = std::strtol(digits, &end, 10);
  if (end == digits || *end != '-' || pid <= 0) return 0;
  return static_cast<pid_t>(pid);
}

bool process_gone(pid_t pid) { return ::kill(pid, 0) != 0 && errno == ESRCH; }

Status rename_error(const fs::path& from, const fs::path& to, int error) {
  return io_error("cannot rename '" + from.string() + "' to '" + to.string() +
                  "': " + std::strerror(error));
}

}  // namespace

TempDir::TempDir(fs::path path) : path_(std::move(path)) { register_path(path_); }

Result<TempDir> TempDir::create(const fs::path& parent, std::string_view purpose) {
  static std::atomic<std::uint64_t> counter{0};
  const fs::path path =
      parent / (std::string(kTempDirPrefix) + std::to_string(::getpid()) + "-" +
                std::to_string(counter.fetch_add(1)) + "-" + std::string(purpose));
  std::error_code ec;
  fs::remove_all(path, ec);  // a leftover of an earlier process that had our pid
  if (!fs::create_directory(path, ec) || ec) {
    return io_error("cannot create temporary directory '" + path.string() +
                    "': " + (ec ? ec.message() : std::string("it already exists")));
  }
  return TempDir(path);
}

TempDir::TempDir(TempDir&& other) noexcept : path_(std::move(other.path_)) {
  other.path_.clear();
}

TempDir& TempDir::operator=(TempDir&& other) noexcept {
  if (this != &other) {
    remove();
    path_ = std::move(other.path_);
    other.path_.clear();
  }
  return *this;
}

void TempDir::remove() {
  if (path_.empty()) return;
  std::error_code ignored;
  fs::remove_all(path_, ignored);
  unregister_path(path_);
  path_.clear();
}

fs::path TempDir::release() {
  unregister_path(path_);
  fs::path p = std::move(path_);
  path_.clear();
  return p;
}

int remove_stale_temp_dirs(const fs::path& dir) {
  std::error_code ec;
  int removed = 0;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const pid_t pid = temp_dir_pid(it->path().filename().string());
    if (pid == 0 || pid == ::getpid() || !process_gone(pid)) continue;
    std::error_code ignored;
    if (fs::remove_all(it->path(), ignored) > 0) ++removed;
  }
  return removed;
}

Status check_replaceable(const fs::path& target) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(target, ec);
  if (ec && ec != std::errc::no_such_file_or_directory)
    return io_error("cannot inspect '" + target.string() + "': " + ec.message());
  if (!fs::exists(st)) return {};
  if (!fs::is_directory(st))
    return usage_error("output '" + target.string() + "' exists and is not a directory");
  if (fs::exists(target / "manifest.json", ec)) return {};
  if (fs::is_empty(target, ec) && !ec) return {};
  return usage_error("output directory '" + target.string() +
                     "' is not empty and holds no manifest.json: refusing to replace it");
}

Status publish_directory(const fs::path& staging, const fs::path& target) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(target, ec))) {
    if (::rename(staging.c_str(), target.c_str()) != 0) return rename_error(staging, target, errno);
    return {};
  }
  OCTOLOD_RETURN_IF_ERROR(check_replaceable(target));
  if (::renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) == 0) {
    fs::remove_all(staging, ec);  // now the old tree
    return {};
  }
  if (errno != EINVAL && errno != ENOSYS) return rename_error(staging, target, errno);
  // No atomic exchange on this file system: old aside, new in, old removed.
  const fs::path aside = staging.string() + "-old";
  if (::rename(target.c_str(), aside.c_str()) != 0) return rename_error(target, aside, errno);
  if (::rename(staging.c_str(), target.c_str()) != 0) {
    const int error = errno;
    ::rename(aside.c_str(), target.c_str());
    return rename_error(staging, target, error);
  }
  fs::remove_all(aside, ec);
  return {};
}

void install_signal_cleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (::pipe2(g_pipe, O_CLOEXEC) != 0) return;
    std::thread(watch_signals).detach();
    struct sigaction action {};
    action.sa_handler = on_cleanup_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
  });
}

bool cleanup_signal_received() { return g_signal.load(std::memory_order_relaxed) != 0; }

void await_signal_cleanup() {
  assert(cleanup_signal_received() && "await_signal_cleanup() without a signal would never return");
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}

}  // namespace octolod::bake
