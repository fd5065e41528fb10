// octolod compare: how good are a baked tree's LODs? For a ladder of uniform cuts (every node at
// one error target), the cut's triangle count and its Metro-style two-sided RMS and Hausdorff
// distance to the input, next to the same numbers for the QSlim-style reference (OpenMesh
// Decimater, octolod/measure/reference.h) at the same triangle count, and their ratios — the
// comparison of seed 002 Tables 5.2 (triangles and time per level) and 5.4 (error per level).
// With --pictures, each cut and its reference are also drawn coloured by their distance to the
// input (error_picture.h), for a technical artist to see where a LOD departs from the model.
//
// Exit codes: 1 usage, 2 a malformed file or an input that is not the one the tree was baked
// from, 4 a file cannot be read.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "command.h"
#include "commands.h"
#include "error_picture.h"
#include "mesh_file.h"
#include "metro_json.h"
#include "octolod/formats/manifest.h"
#include "octolod/measure/metro.h"
#include "octolod/measure/reference.h"
#include "progress.h"
#include "tree_cut.h"

namespace octolod::cli {
namespace {

struct Row {
  double error_target = 0;        // model units
  std::vector<CutEntry> cut;
  CutSummary summary;             // triangles, largest stored error of the cut
  measure::MetroReport cut_metro;
  std::uint64_t reference_triangles = 0;
  measure::MetroReport reference_metro;  // unset (0 samples) without the reference
  std::string picture;                   // its error picture's path (empty without --pictures)
  double picture_scale = 0;              // the distance its colours top out at, model units
};

// Error targets whose uniform cuts come closest (in log scale) to each wanted fraction of the
// input's triangles, chosen among the tree's stored LOD errors (the only values at which a cut
// changes). Ascending, without repeats.
std::vector<double> targets_for_fractions(const Manifest& manifest,
                                          const std::vector<double>& fractions) {
  std::vector<double> candidates{0.0};
  for (const NodeInfo& node : manifest.nodes)
    for (const LodInfo& lod : node.lods) candidates.push_back(lod.error);
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  std::vector<double> triangles;
  triangles.reserve(candidates.size());
  for (double e : candidates)
    triangles.push_back(static_cast<double>(
        std::max<std::uint64_t>(1, summarize_cut(manifest, uniform_error_cut(manifest, e)).triangles)));

  std::vector<double> chosen;
  const double input = static_cast<double>(std::max<std::uint64_t>(1, manifest.input_triangles));
  for (double fraction : fractions) {
    std::size_t best = 0;
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const double distance = std::abs(std::log(triangles[i] / (fraction * input)));
      if (distance < best_distance) {
        best_distance = distance;
        best = i;
      }
    }
    chosen.push_back(candidates[best]);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  return chosen;
}

double bake_seconds(const Manifest& manifest) {
  auto it = manifest.stage_seconds.find("total");
  return it == manifest.stage_seconds.end() ? std::nan("") : it->second;
}

double ratio(double a, double b) { return b > 0 ? a / b : (a > 0 ? std::numeric_limits<double>::infinity() : 1.0); }

double percent_of(std::uint64_t part, std::uint64_t whole) {
  return whole ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

std::string format(const char* spec, double value) {
  char text[64];
  std::snprintf(text, sizeof text, spec, value);
  return text;
}

// One row of cells per cut; the reference columns only when it was run.
void print_table(const std::vector<Row>& rows, const Manifest& manifest, bool markdown,
                 bool with_reference) {
  std::vector<std::vector<std::string>> table{{"error target", "stored max", "triangles",
                                               "% input", "bake s", "RMS", "Hausdorff"}};
  if (with_reference)
    table[0].insert(table[0].end(), {"ref tris", "ref RMS", "ref Hausdorff", "RMS ratio",
                                     "Hausdorff ratio"});
  for (const Row& r : rows) {
    std::vector<std::string> cells{
        format("%.4g", r.error_target), format("%.4g", r.summary.max_error),
        std::to_string(r.summary.triangles),
        format("%.2f", percent_of(r.summary.triangles, manifest.input_triangles)),
        format("%.2f", bake_seconds(manifest)), format("%.4g", r.cut_metro.two_sided.rms),
        format("%.4g", r.cut_metro.two_sided.max)};
    if (with_reference)
      cells.insert(cells.end(),
                   {std::to_string(r.reference_triangles),
                    format("%.4g", r.reference_metro.two_sided.rms),
                    format("%.4g", r.reference_metro.two_sided.max),
                    format("%.2f", ratio(r.cut_metro.two_sided.rms, r.reference_metro.two_sided.rms)),
                    format("%.2f", ratio(r.cut_metro.two_sided.max, r.reference_metro.two_sided.max))});
    table.push_back(std::move(cells));
  }
  for (std::size_t i = 0; i < table.size(); ++i) {
    std::string line = markdown ? "|" : "";
    for (std::size_t c = 0; c < table[i].size(); ++c) {
      if (markdown) {
        line += " " + table[i][c] + " |";
      } else {
        const std::size_t width = table[0][c].size() + 2;
        line += std::string(width > table[i][c].size() ? width - table[i][c].size() : 1, ' ') +
                table[i][c];
      }
    }
    std::printf("%s\n", line.c_str());
    if (markdown && i == 0) {
      std::string rule = "|";
      for (std::size_t c = 0; c < table[0].size(); ++c) rule += "---:|";
      std::printf("%s\n", rule.c_str());
    }
  }
}

// Without the reference, the reference_* and *_ratio fields are left out.
nlohmann::json rows_json(const std::vector<Row>& rows, const Manifest& manifest, bool with_reference) {
  nlohmann::json out = nlohmann::json::array();
  for (const Row& r : rows)
    out.push_back(
        {{"error_target", r.error_target},
         {"stored_max_error", r.summary.max_error},
         {"node_lods", r.cut.size()},
         {"triangles", r.summary.triangles},
         {"percent_of_input", percent_of(r.summary.triangles, manifest.input_triangles)},
         {"rms", r.cut_metro.two_sided.rms},
         {"hausdorff", r.cut_metro.two_sided.max},
         {"cut", metro_json(r.cut_metro)}});
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (!rows[i].picture.empty()) {
      out[i]["picture"] = rows[i].picture;
      out[i]["picture_scale"] = rows[i].picture_scale;
    }
  if (!with_reference) return out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    nlohmann::json& j = out[i];
    j["reference_triangles"] = r.reference_triangles;
    j["reference_rms"] = r.reference_metro.two_sided.rms;
    j["reference_hausdorff"] = r.reference_metro.two_sided.max;
    j["reference"] = metro_json(r.reference_metro);
    j["rms_ratio"] = number_or_null(ratio(r.cut_metro.two_sided.rms, r.reference_metro.two_sided.rms));
    j["hausdorff_ratio"] =
        number_or_null(ratio(r.cut_metro.two_sided.max, r.reference_metro.two_sided.max));
  }
  return out;
}

// One error picture per row into `dir` (which exists), from the overview camera of the input's
// bounds: the row's cut coloured by its distance to the input and the input by its distance to
// the cut, side by side; with the reference, the meshes to the input in the first row (the cut,
// the reference) and the input to each in the second. `scale`: the top of the colour scale, or
// 0 for each picture's largest distance.
Status write_pictures(const std::string& dir, double scale, const std::filesystem::path& root,
                      const Manifest& manifest, const NodeMesh& input, const std::vector<NodeMesh>& references,
                      std::vector<Row>& rows, Progress& progress) {
  const measure::TriangleBvh input_surface(input.vertices, input.layout.floats(), input.indices);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    Row& row = rows[i];
    progress.message("compare: picture " + std::to_string(i + 1) + "/" + std::to_string(rows.size()));
    Result<NodeMesh> cut = load_cut_mesh(root, manifest, row.cut);
    if (!cut.ok()) return cut.status();
    const measure::TriangleBvh cut_surface(cut->vertices, cut->layout.floats(), cut->indices);
    const std::string count = " (" + std::to_string(row.summary.triangles) + " TRIANGLES)";
    std::vector<ErrorPanel> panels{{&cut.value(), &input_surface, "CUT" + count + " TO INPUT"},
                                   {&input, &cut_surface, "INPUT TO CUT"}};
    measure::TriangleBvh reference_surface;
    if (i < references.size()) {
      const NodeMesh& reference = references[i];
      reference_surface = measure::TriangleBvh(reference.vertices, reference.layout.floats(), reference.indices);
      const std::string reference_count = " (" + std::to_string(reference.triangle_count()) + " TRIANGLES)";
      // rows: the meshes to the input, the input to the meshes
      panels = {panels[0], {&reference, &input_surface, "REFERENCE" + reference_count + " TO INPUT"}, panels[1],
                {&input, &reference_surface, "INPUT TO REFERENCE"}};
    }
    Result<ErrorPicture> picture = render_error_picture(panels, 2, input.bounds(), scale);
    if (!picture.ok()) return picture.status();
    row.picture = (std::filesystem::path(dir) / ("cut-" + std::to_string(i + 1) + "-" +
                                                 std::to_string(row.summary.triangles) + ".png"))
                      .string();
    row.picture_scale = picture->scale;
    OCTOLOD_RETURN_IF_ERROR(write_png(row.picture, picture->image));
  }
  return {};
}

}  // namespace

int run_compare(const CompareArgs& args, const CommandContext& context) {
  for (double e : args.errors)
    if (!(e >= 0 && std::isfinite(e)))
      return report(usage_error("--errors: every target must be a finite distance >= 0"));
  for (double f : args.fractions)
    if (!(f > 0 && f <= 1))
      return report(usage_error("--fractions: every fraction must be in (0, 1]"));
  Progress progress(context);
  const std::filesystem::path root = args.tree;
  Result<Manifest> manifest = read_tree_manifest(root);
  if (!manifest.ok()) return report(manifest.status());
  if (!args.pictures.empty()) {  // before the long work: a directory that cannot be made fails now
    std::error_code ec;
    std::filesystem::create_directories(args.pictures, ec);
    if (ec) return report(io_error(args.pictures + ": cannot create the pictures' directory: " + ec.message()));
  }
  if (manifest->nodes.empty() || manifest->input_triangles == 0)
    return report(bad_input_error(args.tree + ": the tree holds no triangles"));
  Result<MeshFile> input = read_mesh_file(args.input, manifest->origin);  // in the tree's frame
  if (!input.ok()) return report(input.status());
  if (input->mesh.triangle_count() != manifest->input_triangles)
    return report(bad_input_error(
        args.input + " has " + std::to_string(input->mesh.triangle_count()) +
        " triangles, but the tree at " + args.tree + " was baked from " +
        std::to_string(manifest->input_triangles) + " (" + manifest->parameters.input + ")"));

  std::vector<double> targets = args.errors;
  if (targets.empty()) targets = targets_for_fractions(manifest.value(), args.fractions);
  std::vector<Row> rows;
  for (double target : targets) {
    Row row;
    row.error_target = target;
    row.cut = uniform_error_cut(manifest.value(), target);
    row.summary = summarize_cut(manifest.value(), row.cut);
    rows.push_back(std::move(row));
  }
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    return a.summary.triangles > b.summary.triangles;
  });
  // derived targets that select the same cut (same triangle count) show once: the smallest
  // target that gives it
  if (args.errors.empty())
    rows.erase(std::unique(rows.begin(), rows.end(),
                           [](const Row& a, const Row& b) { return a.cut == b.cut; }),
               rows.end());

  measure::MetroOptions metro;
  metro.samples = args.samples;
  std::vector<std::uint32_t> counts;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    Row& row = rows[i];
    progress.message("compare: cut " + std::to_string(i + 1) + "/" + std::to_string(rows.size()) +
                     " (error " + std::to_string(row.error_target) + ", " +
                     std::to_string(row.summary.triangles) + " triangles)");
    Result<NodeMesh> cut = load_cut_mesh(root, manifest.value(), row.cut);
    if (!cut.ok()) return report(cut.status());
    Result<measure::MetroReport> m = measure::evaluate(input->mesh, cut.value(), metro);
    if (!m.ok())
      return report(Status(m.status().code(), m.status().message() + " (a = " + args.input +
                                                   ", b = the cut at error " +
                                                   std::to_string(row.error_target) + ")"));
    row.cut_metro = m.value();
    place_maxima(row.cut_metro, manifest->origin);
    counts.push_back(static_cast<std::uint32_t>(
        std::clamp<std::uint64_t>(row.summary.triangles, 1, 0xFFFFFFFFu)));
  }

  measure::ReferenceStats reference_stats;
  std::vector<NodeMesh> references;  // one per row, with the reference
  if (!args.no_reference && !rows.empty()) {
    progress.message("compare: reference decimation to " + std::to_string(counts.size()) +
                     " triangle counts");
    Result<std::vector<NodeMesh>> ladder = measure::reference_simplify_ladder(input->mesh, counts, &reference_stats);
    if (!ladder.ok())
      return report(Status(ladder.status().code(), args.input + ": " + ladder.status().message()));
    references = std::move(ladder).value();
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const NodeMesh& reference = references[i];
      rows[i].reference_triangles = reference.triangle_count();
      Result<measure::MetroReport> m = measure::evaluate(input->mesh, reference, metro);
      if (!m.ok())
        return report(Status(m.status().code(), m.status().message() + " (a = " + args.input +
                                                     ", b = its reference at " +
                                                     std::to_string(counts[i]) + " triangles)"));
      rows[i].reference_metro = m.value();
      place_maxima(rows[i].reference_metro, manifest->origin);
    }
  }

  if (!args.pictures.empty()) {
    const Status written = write_pictures(args.pictures, args.picture_scale, root, manifest.value(), input->mesh, references, rows, progress);
    if (!written.ok()) return report(written);
  }

  if (context.json) {
    print_json({{"input", args.input},
                {"tree", args.tree},
                {"input_triangles", manifest->input_triangles},
                {"method", manifest->parameters.method},
                {"bake_seconds", number_or_null(bake_seconds(manifest.value()))},
                {"diagonal", rows.empty() ? 0.0 : rows.front().cut_metro.diagonal},
                {"reference_seconds", number_or_null(!args.no_reference ? reference_stats.seconds : std::nan(""))},
                {"rows", rows_json(rows, manifest.value(), !args.no_reference)}});
    return 0;
  }
  if (!args.markdown)
    std::printf("%s (%llu triangles) vs %s (method %s); distances in model units, diagonal %.6g\n",
                args.input.c_str(), static_cast<unsigned long long>(manifest->input_triangles),
                args.tree.c_str(),
                manifest->parameters.method.empty() ? "none" : manifest->parameters.method.c_str(),
                rows.empty() ? 0.0 : rows.front().cut_metro.diagonal);
  print_table(rows, manifest.value(), args.markdown, !args.no_reference);
  for (const Row& r : rows)
    if (!r.picture.empty())
      std::printf("picture %s: %llu triangles, colours 0 .. %.4g model units\n", r.picture.c_str(),
                  static_cast<unsigned long long>(r.summary.triangles), r.picture_scale);
  return 0;
}


}  // namespace octolod::cli
