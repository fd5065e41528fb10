// Peak resident set size of the process, for the bake's stats and the --memory checks.
#pragma once

#include <cstdint>

namespace octolod::bake {

// The process's peak resident set size so far, in bytes (getrusage ru_maxrss).
std::uint64_t peak_rss_bytes();

}  // namespace octolod::bake
