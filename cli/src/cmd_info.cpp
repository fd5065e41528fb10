// octolod info: what a baked tree holds, from its manifest alone (docs/formats.md): nodes,
// leaves, depth, triangles per leaf, bytes, attribute layout, bake parameters, stage times, and
// the LODs: per chain index and per depth their counts, triangles and error range, the root's
// chain. Given a PLY file instead, what octolod reads from it (cmd_info_ply.cpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "command.h"
#include "commands.h"
#include "octolod/formats/manifest.h"

namespace octolod::cli {
namespace {

// The LODs at one index of the chains (0 = every node's finest) or one octree depth.
struct LodLevel {
  std::uint64_t nodes = 0;  // nodes with a LOD there
  std::uint64_t lods = 0;
  std::uint64_t triangles = 0;  // per index: of that LOD; per depth: of the nodes' finest LODs
  std::uint64_t coarsest_triangles = 0;  // per depth only: of the nodes' coarsest LODs
  std::uint64_t vertices = 0;
  double error_min = 0, error_max = 0;  // model units

  void add_error(double e) {
    error_min = lods == 0 ? e : std::min(error_min, e);
    error_max = lods == 0 ? e : std::max(error_max, e);
  }
};

nlohmann::json level_json(const LodLevel& l, bool by_depth) {
  nlohmann::json j = {{"nodes", l.nodes},
                      {"lods", l.lods},
                      {"triangles", l.triangles},
                      {"vertices", l.vertices},
                      {"error", {{"min", l.error_min}, {"max", l.error_max}}}};
  if (by_depth) j["coarsest_triangles"] = l.coarsest_triangles;
  return j;
}

struct TreeSummary {
  std::uint64_t nodes = 0;
  std::uint64_t leaves = 0;
  std::uint32_t depth = 0;
  std::uint64_t lods = 0;
  std::uint64_t leaf_tris_min = 0, leaf_tris_median = 0, leaf_tris_max = 0;
  std::uint64_t lod_bytes = 0;
  std::uint64_t manifest_bytes = 0;
  std::vector<std::uint64_t> nodes_per_depth;
  std::vector<LodLevel> by_index;  // by LOD index
  std::vector<LodLevel> by_depth;  // by node depth
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
    if (n.lods.empty()) continue;
    if (s.by_index.size() < n.lods.size()) s.by_index.resize(n.lods.size());
    if (s.by_depth.size() <= n.depth) s.by_depth.resize(n.depth + 1);
    LodLevel& d = s.by_depth[n.depth];
    ++d.nodes;
    d.triangles += n.lods.front().triangles;
    d.coarsest_triangles += n.lods.back().triangles;
    d.vertices += n.lods.front().vertices;
    for (std::size_t i = 0; i < n.lods.size(); ++i) {
      const LodInfo& l = n.lods[i];
      LodLevel& x = s.by_index[i];
      x.add_error(l.error);
      ++x.nodes;
      ++x.lods;
      x.triangles += l.triangles;
      x.vertices += l.vertices;
      d.add_error(l.error);
      ++d.lods;
    }
  }
  if (!leaf_tris.empty()) {
    std::sort(leaf_tris.begin(), leaf_tris.end());
    s.leaf_tris_min = leaf_tris.front();
    s.leaf_tris_median = leaf_tris[leaf_tris.size() / 2];
    s.leaf_tris_max = leaf_tris.back();
  }
  return s;
}

nlohmann::json levels_json(const std::vector<LodLevel>& levels, bool by_depth) {
  nlohmann::json out = nlohmann::json::array();
  for (const LodLevel& l : levels) out.push_back(level_json(l, by_depth));
  return out;
}

nlohmann::json root_lods_json(const Manifest& m) {
  nlohmann::json out = nlohmann::json::array();
  if (m.nodes.empty()) return out;
  for (const LodInfo& l : m.nodes[0].lods)
    out.push_back({{"triangles", l.triangles}, {"vertices", l.vertices}, {"error", l.error},
                   {"bytes", l.bytes}, {"file", l.file}});
  return out;
}

void print_levels(const char* title, const char* key, const std::vector<LodLevel>& levels,
                  bool by_depth) {
  if (levels.empty()) return;
  std::printf("%s\n  %-6s %8s %8s %12s %12s %12s  %s\n", title, key, "nodes", "LODs",
              by_depth ? "tris finest" : "triangles", by_depth ? "tris coarsest" : "",
              "vertices", "error min .. max (model units)");
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const LodLevel& l = levels[i];
    if (l.nodes == 0) continue;
    char coarsest[32] = "";
    if (by_depth)
      std::snprintf(coarsest, sizeof coarsest, "%llu", static_cast<unsigned long long>(l.coarsest_triangles));
    std::printf("  %-6zu %8llu %8llu %12llu %12s %12llu  %.6g .. %.6g\n", i,
                static_cast<unsigned long long>(l.nodes), static_cast<unsigned long long>(l.lods),
                static_cast<unsigned long long>(l.triangles), coarsest,
                static_cast<unsigned long long>(l.vertices), l.error_min, l.error_max);
  }
}

}  // namespace

int run_info(const std::string& tree, const CommandContext& context) {
  std::error_code status_error;
  const std::filesystem::file_status status = std::filesystem::status(tree, status_error);
  if (std::filesystem::is_regular_file(status)) return run_ply_info(tree, context);
  if (!std::filesystem::exists(status))
    return report(io_error("'" + tree + "' does not exist (info takes a baked tree's directory or a PLY file)"));
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
                {"origin", m.origin},
                {"texture", m.texture},
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
                {"parameters", nlohmann::json::parse(bake_parameters_to_json(p))},
                {"stage_seconds", m.stage_seconds},
                {"stats", m.stats},
                {"lod_levels", levels_json(s.by_index, false)},
                {"lod_depths", levels_json(s.by_depth, true)},
                {"root_lods", root_lods_json(m)}});
    return 0;
  }
  std::printf("tree        %s (manifest version %u)\n", tree.c_str(), m.version);
  std::printf("input       %s: %llu vertices, %llu triangles\n", p.input.c_str(),
              static_cast<unsigned long long>(m.input_vertices),
              static_cast<unsigned long long>(m.input_triangles));
  std::printf("layout      %s (%u floats per vertex)\n", m.layout.describe().c_str(),
              m.layout.floats());
  if (m.origin != std::array<double, 3>{0.0, 0.0, 0.0})
    std::printf("origin      [%.17g %.17g %.17g] (positions below and in the node files are relative to it)\n",
                m.origin[0], m.origin[1], m.origin[2]);
  if (!m.texture.empty())
    std::printf("texture     %s (v up: (0, 0) is the image's lower-left corner)\n", m.texture.c_str());
  if (m.bounds.empty())
    std::printf("bounds      empty (no triangles)\n");
  else
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
  std::printf("parameters  max-tris %u, max-depth %u, memory %.1f MiB, threads %u", p.max_tris, p.max_depth,
              static_cast<double>(p.memory_budget_bytes) / (1 << 20), p.threads);
  if (!p.method.empty()) std::printf(", method %s, lod-ratio %g", p.method.c_str(), p.lod_ratio);
  std::printf("\n");
  print_levels("LOD index (0 = each node's finest)", "index", s.by_index, false);
  print_levels("per depth", "depth", s.by_depth, true);
  if (!m.nodes.empty() && !m.nodes[0].lods.empty()) {
    std::printf("root LODs  ");
    for (const LodInfo& l : m.nodes[0].lods)
      std::printf(" %u tris (error %.6g)", l.triangles, l.error);
    std::printf("\n");
  }
  if (!m.stage_seconds.empty()) {
    std::printf("seconds    ");
    for (const auto& [stage, seconds] : m.stage_seconds) std::printf(" %s %.3f", stage.c_str(), seconds);
    std::printf("\n");
  }
  if (!m.stats.empty()) {
    std::printf("stats      ");
    for (const auto& [name, value] : m.stats) {
      if (value == std::floor(value) && std::fabs(value) < 0x1p53)  // counts and bytes: every digit
        std::printf(" %s %.0f", name.c_str(), value);
      else  // seconds and ratios
        std::printf(" %s %.6g", name.c_str(), value);
    }
    std::printf("\n");
  }
  return 0;
}

}  // namespace octolod::cli
