// Human progress on stderr: shown when --progress is given or stderr is a terminal, never on
// stdout (which belongs to --json output).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "command.h"

namespace octolod::cli {

class Progress {
 public:
  explicit Progress(const CommandContext& context);
  bool enabled() const { return enabled_; }
  // "<stage>: <done>/<total> (<percent>%)", rate-limited to a few updates per second.
  void update(const std::string& stage, std::uint64_t done, std::uint64_t total);
  // A finished stage on its own line.
  void finish(const std::string& stage, double seconds);
  void message(const std::string& text);

 private:
  bool enabled_ = false;
  bool terminal_ = false;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace octolod::cli
