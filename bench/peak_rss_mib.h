// The benchmarks' peak RSS line: the process's peak resident set size so far, in MiB
// (getrusage; ru_maxrss is in KiB on Linux).
#pragma once

#include <sys/resource.h>

inline double peak_rss_mib() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}
