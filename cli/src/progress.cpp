#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace octolod::cli {

Progress::Progress(const CommandContext& context)
    : enabled_(context.progress || isatty(STDERR_FILENO) != 0),
      terminal_(isatty(STDERR_FILENO) != 0) {}

void Progress::update(const std::string& stage, std::uint64_t done, std::uint64_t total) {
  if (!enabled_) return;
  auto now = std::chrono::steady_clock::now();
  if (done < total && now - last_ < std::chrono::milliseconds(250)) return;
  last_ = now;
  double percent = total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0;
  std::fprintf(stderr, "%s%s: %llu/%llu (%.0f%%)%s", terminal_ ? "\r" : "", stage.c_str(),
               static_cast<unsigned long long>(done), static_cast<unsigned long long>(total),
               percent, terminal_ ? "\033[K" : "\n");
  std::fflush(stderr);
}

void Progress::finish(const std::string& stage, double seconds) {
  if (!enabled_) return;
  std::fprintf(stderr, "%s%s: done in %.2f s%s\n", terminal_ ? "\r" : "", stage.c_str(), seconds,
               terminal_ ? "\033[K" : "");
}

void Progress::message(const std::string& text) {
  if (enabled_) std::fprintf(stderr, "%s\n", text.c_str());
}

}  // namespace octolod::cli
