// octolod export: writes one uniform cut of a baked tree (every node at one error target, or at
// one octree depth) as a glTF/GLB file with one mesh per node LOD, optionally Draco-compressed —
// for viewing a bake in any glTF viewer or handing a fixed LOD to an engine.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "command.h"
#include "commands.h"
#include "octolod/formats/gltf.h"
#include "octolod/formats/manifest.h"
#include "cut_choice.h"
#include "tree_cut.h"

namespace octolod::cli {
namespace {

// "root/lod1", "3/5/lod0": the node's directory and the LOD index.
std::string mesh_name(const NodeInfo& node, std::uint32_t lod) {
  return (node.path.empty() ? std::string("root") : node.path) + "/lod" + std::to_string(lod);
}

}  // namespace

int run_export(const ExportArgs& args, const CommandContext& context) {
  const auto start = std::chrono::steady_clock::now();
  const std::filesystem::path root = args.tree;
  Result<ChosenCut> chosen = read_chosen_cut(root, args.cut);
  if (!chosen.ok()) return report(chosen.status());
  const Manifest& manifest = chosen->manifest;
  const std::vector<CutEntry>& cut = chosen->cut;
  Result<std::vector<NodeMesh>> meshes = load_cut(root, manifest, cut);
  if (!meshes.ok()) return report(meshes.status());

  GltfWriteOptions options;
  options.binary = std::filesystem::path(args.output).extension() == ".glb";
  options.draco = args.draco;
  options.draco_options = args.draco_options;
  options.translation = manifest.origin;
  // the tree's texture as the meshes' material: a tree whose image glTF cannot embed (not PNG
  // or JPEG) or that lost it still exports, untextured, with a warning
  if (manifest.has_texture()) {
    Result<GltfTexture> texture = read_gltf_texture(root / manifest.texture);
    if (texture.ok())
      options.texture = std::move(texture).value();
    else
      warn(texture.status().message() + ": the glTF has no texture");
  }
  std::uint64_t triangles = 0, vertices = 0;
  for (std::size_t i = 0; i < cut.size(); ++i) {
    options.names.push_back(mesh_name(manifest.nodes[cut[i].node], cut[i].lod));
    triangles += meshes.value()[i].triangle_count();
    vertices += meshes.value()[i].vertex_count();
  }
  const Status written = write_gltf(args.output, meshes.value(), options);
  if (!written.ok()) return report(written);

  const Result<std::uint64_t> written_bytes = written_file_size(args.output);
  if (!written_bytes.ok()) return report(written_bytes.status());
  const std::uint64_t bytes = written_bytes.value();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const CutSummary summary = summarize_cut(manifest, cut);
  if (context.json) {
    print_json({{"file", args.output},
                {"format", options.binary ? "glb" : "gltf"},
                {"draco", args.draco},
                {"texture", options.texture ? options.texture->name : ""},
                {"meshes", cut.size()},
                {"triangles", triangles},
                {"vertices", vertices},
                {"max_error", summary.max_error},
                {"bytes", bytes},
                {"seconds", seconds}});
  } else {
    std::printf("%s: %zu meshes, %llu triangles, max error %g, %.2f MB%s%s in %.2f s\n",
                args.output.c_str(), cut.size(), static_cast<unsigned long long>(triangles),
                summary.max_error, static_cast<double>(bytes) / 1e6, args.draco ? " (Draco)" : "",
                options.texture ? (", texture " + options.texture->name).c_str() : "", seconds);
  }
  return 0;
}


}  // namespace octolod::cli
