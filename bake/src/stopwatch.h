// Adds the wall time of a scope to a running total: the sorters' SortStats::seconds.
#pragma once

#include <chrono>

namespace octolod::bake {

class Stopwatch {
 public:
  // `total` (seconds) must outlive the stopwatch; it grows when the stopwatch is destroyed.
  explicit Stopwatch(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~Stopwatch() {
    total_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  Stopwatch(const Stopwatch&) = delete;
  Stopwatch& operator=(const Stopwatch&) = delete;

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace octolod::bake
