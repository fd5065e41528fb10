// octolod info: what a baked tree holds, from its manifest alone (docs/formats.md): nodes,
// leaves, depth, triangles per leaf, bytes, attribute layout, bake parameters, stage times.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "command.h"
#include "octolod/formats/manifest.h"

namespace octolod::cli {
namespace {

struct TreeSummary {
  std::uint64_t nodes = 0;
  std::uint64_t leaves = 0;
  std::uint32_t depth = 0;
  std::uint64_t lods = 0;
  std::uint64_t leaf_tris_min = 0, leaf_tris_median = 0, leaf_tris_max = 0;
  std::uint64_t lod_bytes = 0;
  std::uint64_t manifest_bytes = 0;
  std::vector<std::uint64_t> nodes_per_depth;
};

TreeSummary summarize(const Manifest& m) {
  TreeSummary s;
  std::vector<std::uint64_t> leaf_tris;
  for (const NodeInfo& n : m.nodes) {
    ++s.nodes;
    s.depth = std::max(s.depth, n.depth);
    if (s.nodes_per_depth.size() <= n.depth) s.nodes_per_depth.resize(n.depth + 1);
    ++s.nodes_per_depth[n.depth];
    if (n.is_leaf()) {
      ++s.leaves;
      leaf_tris.push_back(n.source_triangles);
    }
    s.lods += n.lods.size();
    for (const LodInfo& l : n.lods) s.lod_bytes += l.bytes;
  }
  if (!leaf_tris.empty()) {
    std::sort(leaf_tris.begin(), leaf_tris.end());
    s.leaf_tris_min = leaf_tris.front();
    s.leaf_tris_median = leaf_tris[leaf_tris.size() / 2];
    s.leaf_tris_max = leaf_tris.back();
  }
  return s;
}

int run_info(const std::string& tree, const CommandContext& context) {
  const std::filesystem::path path = std::filesystem::path(tree) / kManifestFileName;
  Result<Manifest> manifest = read_manifest(path);
  if (!manifest.ok()) return report(manifest.status());
  const Manifest& m = manifest.value();
  TreeSummary s = summarize(m);
  std::error_code ec;
  s.manifest_bytes = std::filesystem::file_size(path, ec);
  const BakeParameters& p = m.parameters;

  if (context.json) {
    print_json({{"tree", tree},
                {"version", m.version},
                {"layout", m.layout.describe()},
                {"floats_per_vertex", m.layout.floats()},
                {"bounds", {{"min", m.bounds.min}, {"max", m.bounds.max}}},
                {"input_vertices", m.input_vertices},
                {"input_triangles", m.input_triangles},
                {"nodes", s.nodes},
                {"leaves", s.leaves},
                {"depth", s.depth},
                {"nodes_per_depth", s.nodes_per_depth},
                {"lods", s.lods},
                {"leaf_triangles",
                 {{"min", s.leaf_tris_min}, {"median", s.leaf_tris_median}, {"max", s.leaf_tris_max}}},
                {"bytes", s.lod_bytes + s.manifest_bytes},
                {"lod_bytes", s.lod_bytes},
                {"manifest_bytes", s.manifest_bytes},
                {"parameters",
                 {{"input", p.input},
                  {"max_tris", p.max_tris},
                  {"max_depth", p.max_depth},
                  {"memory_budget_bytes", p.memory_budget_bytes},
                  {"threads", p.threads},
                  {"method", p.method}}},
                {"stage_seconds", m.stage_seconds},
                {"stats", m.stats}});
    return 0;
  }
  std::printf("tree        %s (manifest version %u)\n", tree.c_str(), m.version);
  std::printf("input       %s: %llu vertices, %llu triangles\n", p.input.c_str(),
              static_cast<unsigned long long>(m.input_vertices),
              static_cast<unsigned long long>(m.input_triangles));
  std::printf("layout      %s (%u floats per vertex)\n", m.layout.describe().c_str(),
              m.layout.floats());
  std::printf("bounds      [%g %g %g] .. [%g %g %g]\n", m.bounds.min[0], m.bounds.min[1],
              m.bounds.min[2], m.bounds.max[0], m.bounds.max[1], m.bounds.max[2]);
  std::printf("nodes       %llu (%llu leaves), depth %u, %llu LODs\n",
              static_cast<unsigned long long>(s.nodes), static_cast<unsigned long long>(s.leaves),
              s.depth, static_cast<unsigned long long>(s.lods));
  std::printf("per depth  ");
  for (std::uint64_t n : s.nodes_per_depth) std::printf(" %llu", static_cast<unsigned long long>(n));
  std::printf("\n");
  std::printf("leaf tris   min %llu, median %llu, max %llu\n",
              static_cast<unsigned long long>(s.leaf_tris_min),
              static_cast<unsigned long long>(s.leaf_tris_median),
              static_cast<unsigned long long>(s.leaf_tris_max));
  std::printf("bytes       %.2f MB (LOD files %.2f MB, manifest %.2f MB)\n",
              static_cast<double>(s.lod_bytes + s.manifest_bytes) / 1e6,
              static_cast<double>(s.lod_bytes) / 1e6, static_cast<double>(s.manifest_bytes) / 1e6);
  std::printf("parameters  max-tris %u, max-depth %u, memory %.1f MiB, threads %u%s%s\n",
              p.max_tris, p.max_depth, static_cast<double>(p.memory_budget_bytes) / (1 << 20),
              p.threads, p.method.empty() ? "" : ", method ", p.method.c_str());
  if (!m.stage_seconds.empty()) {
    std::printf("seconds    ");
    for (const auto& [stage, seconds] : m.stage_seconds) std::printf(" %s %.3f", stage.c_str(), seconds);
    std::printf("\n");
  }
  if (!m.stats.empty()) {
    std::printf("stats      ");
    for (const auto& [name, value] : m.stats) std::printf(" %s %.17g", name.c_str(), value);
    std::printf("\n");
  }
  return 0;
}

}  // namespace

void add_info_command(CLI::App& app, CommandContext& context) {
  auto tree = std::make_shared<std::string>();
  CLI::App* command =
      app.add_subcommand("info", "Summarize a baked tree: nodes, leaves, sizes, parameters, times");
  command->add_option("tree", *tree, "Baked tree directory (holds manifest.json)")->required();
  command->callback([tree, &context] { context.exit_code = run_info(*tree, context); });
}

}  // namespace octolod::cli
