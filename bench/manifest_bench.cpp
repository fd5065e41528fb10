// Benchmark of opening a tree's manifest (what `StreamingTree::open` reads first): reads
// TREE/manifest.json N times with read_tree_manifest and prints the fastest and the median time,
// MB/s, nodes and LODs per second, and the peak RSS (getrusage: one manifest at a time).
//
//   manifest_bench TREE [--repeat 7]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "octolod/formats/manifest.h"
#include "peak_rss_mib.h"

namespace {

int usage_error() {
  std::fprintf(stderr, "usage: manifest_bench TREE [--repeat N]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage_error();
  const std::filesystem::path tree = argv[1];
  int repeat = 7;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    else return usage_error();
  }
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(tree / octolod::kManifestFileName, ec);
  if (ec) {
    std::fprintf(stderr, "%s: %s\n", (tree / octolod::kManifestFileName).c_str(), ec.message().c_str());
    return 1;
  }
  std::vector<double> seconds;
  std::size_t nodes = 0, lods = 0;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    auto manifest = octolod::read_tree_manifest(tree);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (!manifest.ok()) {
      std::fprintf(stderr, "%s\n", manifest.status().message().c_str());
      return 1;
    }
    nodes = manifest->nodes.size();
    lods = 0;
    for (const auto& node : manifest->nodes) lods += node.lods.size();
  }
  std::sort(seconds.begin(), seconds.end());
  const double fastest = seconds.front(), median = seconds[seconds.size() / 2];
  const double mb = static_cast<double>(bytes) / 1e6;
  std::printf("manifest %.1f MB, %zu nodes, %zu LODs, %d reads: fastest %.3f s, median %.3f s (%.0f MB/s, %.2fM nodes/s "
              "at the median), peak RSS %.1f MiB\n",
              mb, nodes, lods, repeat, fastest, median, mb / median, static_cast<double>(nodes) / median / 1e6,
              peak_rss_mib());
  return 0;
}
