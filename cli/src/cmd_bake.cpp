// octolod bake: a PLY mesh of any size becomes an on-disk LOD octree directory within a memory
// budget (octolod/bake/bake.h; docs/design.md stages 1-7): the octree, every node's LOD chain
// (--method), the manifest.
//
// Exit codes: 1 usage, 2 bad input, 3 unsupported, 4 I/O (unwritable output, out of space, the
// input vanishing while read). A failed or interrupted bake publishes nothing and leaves no
// temporary file.
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "command.h"
#include "commands.h"
#include "octolod/bake/bake.h"
#include "progress.h"

namespace octolod::cli {
namespace {

nlohmann::json report_json(const bake::BakeReport& r, const std::string& output) {
  const Manifest& m = r.header;
  return {{"output", output},
          {"input", m.parameters.input},
          {"vertices", m.input_vertices},
          {"triangles", m.input_triangles},
          {"layout", m.layout.describe()},
          {"texture", m.texture},
          {"nodes", r.nodes},
          {"leaves", r.leaves},
          {"depth", r.depth},
          {"bytes", r.bytes},
          {"soup_in_core", r.soup_in_core},
          {"octree_sort_runs", r.sort_runs},
          {"peak_rss_bytes", r.peak_rss_bytes},
          {"parameters",
           {{"max_tris", m.parameters.max_tris},
            {"max_depth", m.parameters.max_depth},
            {"memory_budget_bytes", m.parameters.memory_budget_bytes},
            {"threads", m.parameters.threads},
            {"method", m.parameters.method},
            {"lod_ratio", m.parameters.lod_ratio}}},
          {"lods", r.lods},
          {"root_coarsest_triangles", r.root_coarsest_triangles},
          {"stage_seconds", m.stage_seconds},
          {"stats", m.stats}};
}

// Positions are floats: far from the origin they are far apart. A warning when, at the model's
// largest coordinate (in the tree's frame: double input positions are recentred first), they are
// coarser than 16-bit quantization of its diagonal (2^16 steps across it, as a game's compressed
// meshes keep): the input is better recentred. Nothing for an empty model.
std::optional<std::string> float_precision_warning(const Bounds& bounds) {
  if (bounds.empty()) return std::nullopt;
  const double largest = bounds.largest_magnitude(), diagonal = bounds.diagonal();
  const float at = static_cast<float>(largest);
  const double spacing = static_cast<double>(std::nextafter(at, INFINITY)) - at;  // one float step there
  if (!(spacing * 65536.0 > diagonal)) return std::nullopt;
  char text[320];
  std::snprintf(text, sizeof text,
                "coordinates reach %.3g and the model is %.3g across: stored as floats, positions there are %.3g "
                "apart (1/%.0f of its size); store the positions as double (the bake then recentres them) or "
                "recentre the input for more precision and tighter errors",
                largest, diagonal, spacing, diagonal / spacing);
  return std::string(text);
}

}  // namespace

int run_bake(const BakeArgs& args, const CommandContext& context) {
  Result<std::uint64_t> memory = parse_byte_size(args.memory);
  if (!memory.ok()) return report(memory.status());
  bake::BakeOptions options;
  options.input = args.input;
  options.output = args.output;
  options.max_tris = args.max_tris;
  options.max_depth = args.max_depth;
  options.memory_budget_bytes = memory.value();
  options.program_bytes = bake::kCliProgramBytes;  // --memory caps the whole process
  options.work_dir = args.work_dir;
  options.threads = args.threads;
  options.force_out_of_core = args.out_of_core;
  options.lod_ratio = args.lod_ratio;
  if (args.method == "none") {
    options.lods = false;
  } else {
    std::optional<bake::ClusterMethod> method = bake::parse_method(args.method);
    if (!method) return report(usage_error("unknown --method '" + args.method + "'"));
    options.method = *method;
  }
  options.cleanup_on_signal = true;
  Progress progress(context);
  options.progress = [&](std::string_view stage, std::uint64_t done, std::uint64_t total) {
    progress.update(std::string(stage), done, total);
  };

#ifdef __GLIBC__
  // glibc gives threads that allocate at the same time arenas of their own, and what one arena
  // frees the others do not reuse: each of the bake's threads (node workers, the caller, the
  // sort's loader) kept its own freed node buffers, and the 10M rock at --memory 16M peaked at
  // 48.5 MiB (over budget + 24 MiB + the idle CLI). Two arenas: 42.0 MiB, wall time within the
  // noise (1M rock at 64M: 3.8-4.1 s either way). Before any thread starts.
  mallopt(M_ARENA_MAX, 2);
  // Blocks of 1 MiB and more are mapped for themselves and unmapped when freed. By default glibc
  // raises that threshold (up to 32 MiB) each time such a block is freed, after which the node
  // work's large arrays come from the arenas, whose freed space stays resident between nodes:
  // the 100M rock at --memory 64M peaked at 69.0 MiB, 63.9 with the threshold fixed (and 54 s
  // of system time instead of 104).
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
  Result<bake::BakeReport> baked = bake::bake(options);
  if (!baked.ok()) return report(baked.status());
  const bake::BakeReport& r = baked.value();
  const auto& seconds = r.header.stage_seconds;
  auto stage = [&](const char* name) {
    auto it = seconds.find(name);
    return it == seconds.end() ? 0.0 : it->second;
  };
  progress.finish("bake", stage("total"));
  warn_trailing_bytes(args.input, r.input_trailing_bytes);
  if (const std::optional<std::string> warning = float_precision_warning(r.header.bounds))
    warn(args.input + ": " + *warning);
  if (!r.texture_warning.empty()) warn(args.input + ": " + r.texture_warning);
  if (r.streamed_leaves > 0)
    warn(args.input + ": " + std::to_string(r.streamed_leaves) + (r.streamed_leaves == 1 ? " leaf" : " leaves") +
         " at --max-depth " + std::to_string(r.header.parameters.max_depth) +
         " held more triangles than --memory lets a leaf simplify in memory (the largest " +
         std::to_string(r.largest_streamed_leaf_triangles) + "): built streaming, with a LOD 1 of at most " +
         std::to_string(r.streamed_lod1_triangles) +
         " triangles, a steep step down from LOD 0 for a runtime; a larger --max-depth splits them");
  if (context.json) {
    print_json(report_json(r, args.output));
    return 0;
  }
  std::printf(
      "%s: %llu triangles (%s) -> %llu nodes, %llu leaves, depth %u, %llu LODs (root's coarsest "
      "%llu triangles), %.1f MB in %.2f s (soup %.2f s, octree + overlapping LODs %.2f s, LODs "
      "after the stream %.2f s), peak RSS %.1f MiB\n",
      args.output.c_str(), static_cast<unsigned long long>(r.header.input_triangles),
      (r.header.layout.describe() + (r.header.texture.empty() ? "" : ", texture " + r.header.texture)).c_str(),
      static_cast<unsigned long long>(r.nodes),
      static_cast<unsigned long long>(r.leaves), r.depth,
      static_cast<unsigned long long>(r.lods),
      static_cast<unsigned long long>(r.root_coarsest_triangles),
      static_cast<double>(r.bytes) / 1e6, stage("total"), stage("soup"), stage("octree"),
      stage("lods"), static_cast<double>(r.peak_rss_bytes) / (1 << 20));
  return 0;
}


}  // namespace octolod::cli
