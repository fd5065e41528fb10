// octolod render: one picture of a baked tree as the streaming runtime selects it for a camera.
// The tree is opened with octolod::runtime's StreamingTree on a SynchronousExecutor and updated
// until every LOD the view wants has loaded, so the picture shows the settled cut (no
// fallbacks), rendered with real OpenGL offscreen and tinted by detail level (or in the tree's
// texture or its own colours).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "command.h"
#include "commands.h"
#include "frame_render.h"
#include "offscreen_renderer.h"
#include "octolod/runtime/streaming_tree.h"
#include "streaming_setup.h"
#include "texture_image.h"
#include "view_camera.h"

namespace octolod::cli {
namespace {

// Updates until a frame neither issues nor waits for a load. Each update installs what the
// previous run_pending() loaded and queues at most max_loads_in_flight more, so a cut of n node
// LODs settles in about n / max_loads_in_flight updates; the bound only stops a pathological
// budget from cycling forever.
constexpr int kMaxUpdates = 4096;
constexpr std::uint32_t kLoadsPerUpdate = 256;

Result<runtime::Camera> parse_camera(const std::string& text, const Bounds& bounds, const Lens& lens) {
  std::vector<float> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    float v = 0;
    try {
      v = std::stof(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v))
      return usage_error("--camera: '" + item + "' is not a number (expected eye_x,eye_y,eye_z,target_x,target_y,target_z)");
    values.push_back(v);
  }
  if (values.size() != 6)
    return usage_error("--camera: expected 6 comma-separated numbers eye_x,eye_y,eye_z,target_x,target_y,target_z, got " +
                       std::to_string(values.size()));
  const glm::vec3 eye(values[0], values[1], values[2]), target(values[3], values[4], values[5]);
  if (!(glm::length(target - eye) > 0.0f)) return usage_error("--camera: eye and target must differ");
  return fitted_camera(eye, target, bounds, lens);
}

// Per detail level (FramePainter::detail_level): nodes drawn and their triangles.
struct LevelCount {
  std::uint64_t nodes = 0;
  std::uint64_t triangles = 0;
};

}  // namespace

int run_render(const RenderArgs& args, const CommandContext& context) {
  Result<runtime::StreamingOptions> streaming = streaming_options(args.budget, args.sse);
  if (!streaming.ok()) return report(streaming.status());
  if (args.width < 16 || args.width > 8192 || args.height < 16 || args.height > 8192)
    return report(usage_error("--width and --height must be within 16..8192 pixels"));
  if (!(args.fov_degrees > 1.0 && args.fov_degrees < 179.0))
    return report(usage_error("--fov must be between 1 and 179 degrees"));
  if (args.output.empty()) return report(usage_error("-o FILE.png is required"));

  const auto start = std::chrono::steady_clock::now();
  runtime::StreamingOptions& options = streaming.value();  // a failed load: the command fails after the loop
  options.prefetch = false;  // one view: load what it draws, nothing around it
  options.max_loads_in_flight = kLoadsPerUpdate;
  auto executor = std::make_shared<runtime::SynchronousExecutor>();
  Result<std::unique_ptr<runtime::StreamingTree>> opened =
      runtime::StreamingTree::open_directory(args.tree, executor, options);
  if (!opened.ok()) return report(opened.status());
  runtime::StreamingTree& tree = *opened.value();
  std::optional<Image> texture;
  if (args.texture) {
    const Manifest& manifest = tree.manifest();
    if (!manifest.has_texture())
      return report(usage_error("--texture: " + args.tree + " has no texture (its input's PLY named none in a "
                                "TextureFile comment, or it has no UVs)"));
    Result<Image> decoded = read_texture_image(std::filesystem::path(args.tree) / manifest.texture);
    if (!decoded.ok()) return report(decoded.status());
    texture = std::move(decoded).value();
  }
  if (args.colors && !tree.manifest().layout.color)
    return report(usage_error("--colors: " + args.tree + " has no colours (its input's PLY had none, per vertex or per face)"));

  Lens lens;
  lens.fovy_radians = static_cast<float>(args.fov_degrees * 3.14159265358979 / 180.0);
  lens.width = args.width;
  lens.height = args.height;
  if (args.ortho) lens.ortho_height = framing_ortho_height(tree.manifest().bounds, lens.aspect());
  Result<runtime::Camera> camera = args.camera.empty() ? Result<runtime::Camera>(framing_camera(tree.manifest().bounds, lens))
                                                       : parse_camera(args.camera, tree.manifest().bounds, lens);
  if (!camera.ok()) return report(camera.status());

  // select and load until the cut is complete
  std::uint64_t loads = 0, failed = 0;
  int updates = 1;
  const runtime::FrameResult* frame = &tree.update(camera.value());
  for (; updates < kMaxUpdates; ++updates) {
    if (frame->stats.loads_in_flight == 0 && frame->stats.loads_issued == 0) break;
    executor->run_pending();
    frame = &tree.update(camera.value());
    loads += frame->stats.loads_completed;
    failed += frame->stats.loads_failed;
  }
  if (failed > 0)
    return report(failed_loads_error(args.tree, failed, "no picture written"));
  const runtime::FrameStats& stats = frame->stats;
  const bool complete = stats.loads_in_flight == 0 && stats.loads_issued == 0;
  if (!complete)
    warn(args.tree + ": loads still pending after " + std::to_string(updates) +
         " updates; the picture shows fallbacks");

  // picture
  const FramePainter painter(tree.manifest());
  const FramePainter::Style style{.cull_back_faces = args.cull_back_faces,
                                  .texture = texture ? &texture.value() : nullptr,
                                  .own_colors = args.colors};
  Result<Image> image = painter.paint(*frame, camera.value(), args.width, args.height, style);
  if (!image.ok()) return report(image.status());
  const Status written = write_png(args.output, image.value());
  if (!written.ok()) return report(written);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // summary
  std::vector<LevelCount> levels;
  for (const runtime::DrawItem& draw : frame->draws) {
    const std::uint32_t level = painter.detail_level(draw);
    if (levels.size() <= level) levels.resize(level + 1);
    levels[level].nodes += 1;
    levels[level].triangles += draw.mesh ? draw.mesh->triangle_count() : 0;
  }
  const glm::vec3 eye = camera->position;
  nlohmann::json histogram = nlohmann::json::array();
  for (std::size_t level = 0; level < levels.size(); ++level) {
    if (levels[level].nodes == 0) continue;
    const glm::vec3 tint = lod_tint(level);
    char hex[8];
    std::snprintf(hex, sizeof hex, "#%02x%02x%02x", static_cast<unsigned>(std::lround(tint.r * 255.0f)),
                  static_cast<unsigned>(std::lround(tint.g * 255.0f)), static_cast<unsigned>(std::lround(tint.b * 255.0f)));
    histogram.push_back({{"level", level}, {"nodes", levels[level].nodes}, {"triangles", levels[level].triangles},
                         {"tint", hex}});
  }
  if (context.json) {
    print_json({{"tree", args.tree},
                {"output", args.output},
                {"width", args.width},
                {"height", args.height},
                {"eye", {eye.x, eye.y, eye.z}},
                {"fov_degrees", args.ortho ? nlohmann::json() : nlohmann::json(args.fov_degrees)},
                {"orthographic", args.ortho},
                {"texture", args.texture},
                {"colors", args.colors},
                {"view_height", args.ortho ? nlohmann::json(lens.ortho_height) : nlohmann::json()},
                {"target_sse_pixels", args.sse},
                {"budget_bytes", options.max_resident_bytes},
                {"updates", updates},
                {"complete", complete},
                {"nodes_drawn", stats.drawn_nodes},
                {"triangles", stats.drawn_triangles},
                {"fallbacks", stats.fallbacks},
                {"holes", stats.holes},
                {"culled", stats.culled},
                {"coarsening", stats.coarsening},
                {"loads", loads},
                {"resident_bytes", stats.resident_bytes},
                {"lod_histogram", histogram},
                {"seconds", seconds}});
  } else {
    std::printf("%s -> %s (%dx%d), eye (%.4g, %.4g, %.4g), %u updates%s\n", args.tree.c_str(), args.output.c_str(),
                args.width, args.height, static_cast<double>(eye.x), static_cast<double>(eye.y),
                static_cast<double>(eye.z), static_cast<unsigned>(updates), complete ? "" : " (incomplete)");
    std::printf("  drawn: %u nodes, %llu triangles, %u fallbacks; %llu loads, %.1f MB resident\n",
                stats.drawn_nodes, static_cast<unsigned long long>(stats.drawn_triangles), stats.fallbacks,
                static_cast<unsigned long long>(loads),
                static_cast<double>(stats.resident_bytes) / 1048576.0);
    for (const nlohmann::json& level : histogram)
      std::printf("  level %u (%s): %llu nodes, %llu triangles\n", level["level"].get<unsigned>(),
                  level["tint"].get<std::string>().c_str(), level["nodes"].get<unsigned long long>(),
                  level["triangles"].get<unsigned long long>());
  }
  return 0;
}


}  // namespace octolod::cli
