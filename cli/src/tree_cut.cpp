#include "tree_cut.h"

#include "octolod/bake/simplify.h"

namespace octolod::cli {
namespace {

template <class Choose>
void walk(const Manifest& manifest, std::uint32_t node, const Choose& choose, std::vector<CutEntry>& out) {
  const NodeInfo& info = manifest.nodes[node];
  if (auto lod = choose(info); lod >= 0) {
    out.push_back({node, static_cast<std::uint32_t>(lod)});
    return;
  }
  for (std::int32_t child : info.children)
    if (child >= 0) walk(manifest, static_cast<std::uint32_t>(child), choose, out);
}

}  // namespace

std::vector<CutEntry> uniform_error_cut(const Manifest& manifest, double max_error) {
  std::vector<CutEntry> cut;
  walk(manifest, 0, [&](const NodeInfo& n) -> int {
    for (int l = static_cast<int>(n.lods.size()) - 1; l >= 0; --l)
      if (n.lods[static_cast<std::size_t>(l)].error <= max_error) return l;
    return n.is_leaf() && !n.lods.empty() ? 0 : -1;
  }, cut);
  return cut;
}

std::vector<CutEntry> depth_cut(const Manifest& manifest, std::uint32_t depth) {
  std::vector<CutEntry> cut;
  walk(manifest, 0, [&](const NodeInfo& n) -> int {
    return (n.depth >= depth || n.is_leaf()) && !n.lods.empty() ? 0 : -1;
  }, cut);
  return cut;
}

CutSummary summarize_cut(const Manifest& manifest, std::span<const CutEntry> cut) {
  CutSummary s;
  for (const CutEntry& e : cut) {
    const LodInfo& lod = manifest.nodes[e.node].lods[e.lod];
    s.triangles += lod.triangles;
    s.max_error = std::max(s.max_error, lod.error);
  }
  return s;
}

Result<std::vector<NodeMesh>> load_cut(const std::filesystem::path& root, const Manifest& manifest,
                                       std::span<const CutEntry> cut) {
  std::vector<NodeMesh> meshes;
  meshes.reserve(cut.size());
  for (const CutEntry& e : cut) {
    const LodInfo& lod = manifest.nodes[e.node].lods[e.lod];
    const std::filesystem::path file = root / lod.file;
    Result<NodeMesh> mesh = read_node_file(file, lod.bytes);
    if (!mesh.ok()) return mesh.status();
    OCTOLOD_RETURN_IF_ERROR(check_node_lod(mesh.value(), lod, manifest.layout, file.string()));
    meshes.push_back(std::move(mesh).value());
  }
  return meshes;
}

Result<NodeMesh> load_cut_mesh(const std::filesystem::path& root, const Manifest& manifest,
                               std::span<const CutEntry> cut) {
  Result<std::vector<NodeMesh>> meshes = load_cut(root, manifest, cut);
  if (!meshes.ok()) return meshes.status();
  std::vector<const NodeMesh*> parts;
  parts.reserve(cut.size());
  for (const NodeMesh& mesh : meshes.value()) parts.push_back(&mesh);
  if (parts.empty()) {
    NodeMesh empty;
    empty.layout = manifest.layout;
    return empty;
  }
  return bake::merge_meshes(parts);
}

}  // namespace octolod::cli
