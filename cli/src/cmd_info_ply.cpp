// octolod info FILE.ply: what octolod reads from a PLY, from its header alone (any size, no
// pass over the body): the declared counts, the attributes it keeps and where they come from
// (the vertices or the faces), the textures the header names, and what it skips, so that a user
// sees before a bake whether their colours, UVs or other properties make it into the tree.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "command.h"
#include "commands.h"
#include "octolod/formats/ply_reader.h"

namespace octolod::cli {
namespace {

// Where the colours and UVs come from: "face" / "corner" (PlyInfo::corners), "vertex", "none".
std::string color_source(const PlyInfo& info) {
  return !info.layout.color ? "none" : info.corners.color ? "face" : "vertex";
}
std::string uv_source(const PlyInfo& info) {
  return !info.layout.uv ? "none" : info.corners.uv ? "corner" : "vertex";
}

std::string joined(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
  return text;
}

}  // namespace

int run_ply_info(const std::string& ply, const CommandContext& context) {
  PlyReadOptions header_only;
  header_only.buffer_bytes = 4096;
  Result<std::unique_ptr<PlyReader>> reader = PlyReader::open(ply, header_only);
  if (!reader.ok()) return report(reader.status());
  const PlyInfo& info = reader.value()->info();
  const std::string colors = color_source(info), uvs = uv_source(info);
  const char* color_type = info.color_type == PlyColorType::uchar ? "uchar" : "float";
  if (context.json) {
    print_json({{"ply", ply},
                {"format", std::string(to_string(info.format))},
                {"header_bytes", info.header_bytes},
                {"vertices", info.vertex_count},
                {"faces", info.face_count},
                {"layout", info.layout.describe()},
                {"floats_per_vertex", info.layout.floats()},
                {"colors", colors},
                {"color_type", info.layout.color ? nlohmann::json(color_type) : nlohmann::json()},
                {"uvs", uvs},
                {"double_positions", info.double_positions},
                {"texture_files", info.texture_files},
                {"skipped", info.skipped}});
    return 0;
  }
  std::printf("ply         %s (%s, header %llu bytes)\n", ply.c_str(), std::string(to_string(info.format)).c_str(),
              static_cast<unsigned long long>(info.header_bytes));
  std::printf("declared    %llu vertices, %llu faces (polygons are fanned into triangles)\n",
              static_cast<unsigned long long>(info.vertex_count), static_cast<unsigned long long>(info.face_count));
  std::printf("layout      %s (%u floats per vertex)\n", info.layout.describe().c_str(), info.layout.floats());
  if (info.layout.color)
    std::printf("colours     per %s (%s)%s\n", colors.c_str(), color_type,
                info.corners.color ? ": each corner takes its face's, replacing the vertices' own, if any" : "");
  if (info.layout.uv)
    std::printf("uvs         per %s%s\n", uvs.c_str(),
                info.corners.uv ? " (texcoord), replacing the vertices' own, if any" : "");
  if (info.double_positions)
    std::printf("positions   double: the bake recentres them on the first vertex before rounding to float\n");
  for (const std::string& texture : info.texture_files) std::printf("texture     %s\n", texture.c_str());
  std::printf("skipped     %s\n", info.skipped.empty() ? "nothing" : joined(info.skipped).c_str());
  return 0;
}

}  // namespace octolod::cli
