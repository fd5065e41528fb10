// octolod extract: the mesh the runtime would draw for one uniform cut of a baked tree — every
// node at one error target (the coarsest LOD with stored error <= E) or at one octree depth —
// as a single welded PLY: the node LODs' vertices that are bit-identical (the locked seams
// between nodes) become shared vertices, so the file is as closed as the input was.
//
// Exit codes: 1 usage, 2 a malformed manifest or node file, 4 a file cannot be read or the
// output written (nothing is left behind then).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "command.h"
#include "commands.h"
#include "mesh_file.h"
#include "octolod/formats/manifest.h"
#include "progress.h"
#include "cut_choice.h"
#include "tree_cut.h"

namespace octolod::cli {

int run_extract(const ExtractArgs& args, const CommandContext& context) {
  const auto start = std::chrono::steady_clock::now();
  const std::filesystem::path root = args.tree;
  Result<ChosenCut> chosen = read_chosen_cut(root, args.cut);
  if (!chosen.ok()) return report(chosen.status());
  const Manifest& manifest = chosen->manifest;
  const std::vector<CutEntry>& cut = chosen->cut;
  Progress progress(context);
  progress.message("extract: " + std::to_string(cut.size()) + " node LODs");
  Result<NodeMesh> mesh = load_cut_mesh(root, manifest, cut);
  if (!mesh.ok()) return report(mesh.status());
  // the tree's texture named relative to the cut, so that a viewer finds it
  std::string texture;
  if (manifest.has_texture()) {
    const std::filesystem::path output_dir = std::filesystem::absolute(args.output).lexically_normal().parent_path();
    texture = std::filesystem::absolute(root / manifest.texture).lexically_normal().lexically_relative(output_dir).generic_string();
  }
  const Status written = write_mesh_file(args.output, mesh.value(), args.ascii, PlyColorType::uchar,
                                         manifest.origin, texture);
  if (!written.ok()) return report(written);

  const Result<std::uint64_t> written_bytes = written_file_size(args.output);
  if (!written_bytes.ok()) return report(written_bytes.status());
  const std::uint64_t bytes = written_bytes.value();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.finish("extract", seconds);
  const CutSummary summary = summarize_cut(manifest, cut);
  const double percent = manifest.input_triangles
                             ? 100.0 * static_cast<double>(mesh->triangle_count()) /
                                   static_cast<double>(manifest.input_triangles)
                             : 0.0;
  if (context.json) {
    nlohmann::json lods = nlohmann::json::array();
    for (const CutEntry& e : cut)
      lods.push_back({{"node", manifest.nodes[e.node].path}, {"lod", e.lod}});
    print_json({{"file", args.output},
                {"node_lods", cut.size()},
                {"lods", lods},
                {"triangles", mesh->triangle_count()},
                {"vertices", mesh->vertex_count()},
                {"input_triangles", manifest.input_triangles},
                {"percent_of_input", percent},
                {"max_error", summary.max_error},
                {"layout", mesh->layout.describe()},
                {"texture", texture},
                {"bytes", bytes},
                {"seconds", seconds}});
  } else {
    std::printf("%s: %zu node LODs, %zu triangles (%.2f%% of the input), %zu vertices, "
                "max stored error %g, %.2f MB in %.2f s\n",
                args.output.c_str(), cut.size(), mesh->triangle_count(), percent,
                mesh->vertex_count(), summary.max_error, static_cast<double>(bytes) / 1e6,
                seconds);
  }
  return 0;
}


}  // namespace octolod::cli
