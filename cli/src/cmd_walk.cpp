// octolod walk: replays a camera path against a baked tree at a fixed frame rate, streaming the
// real node files through loader threads (octolod::runtime), and reports per-frame and summary
// paging statistics — the camera-path measurements of seeds 000 and 003 and Holst & Schumann.
// A walk over which node LODs failed to load still writes its report and outputs, then exits 2
// (bad input): the tree is damaged, the measurement is not of a clean run.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <glm/glm.hpp>

#include "atomic_file.h"
#include "command.h"
#include "commands.h"
#include "frame_render.h"
#include "image.h"
#include "line_chart.h"
#include "octolod/formats/input_file.h"
#include "octolod/formats/manifest.h"
#include "octolod/runtime/streaming_tree.h"
#include "streaming_setup.h"
#include "view_camera.h"

namespace octolod::cli {
namespace {

// Selection runs for a 1920x1080 view with a 60 degree vertical field of view; --frames-png
// pictures are rendered at half that size with the same projection. (Named fields: a positional
// {fov, 1920, 1080} put 1,920 into Lens::ortho_height when that field was added, and every path
// was walked as an orthographic view 1,920 units high.)
constexpr Lens kLens{.fovy_radians = 1.0471976f, .ortho_height = 0.0f, .width = 1920, .height = 1080};
constexpr int kFrameWidth = 960;
constexpr int kFrameHeight = 540;

struct Key {
  glm::vec3 eye;
  glm::vec3 target;
};

glm::vec3 vec(const nlohmann::json& j) {
  return glm::vec3(j.at(0).get<float>(), j.at(1).get<float>(), j.at(2).get<float>());
}

// {"keyframes": [{"eye": [x,y,z], "target": [x,y,z]}, ...]} in model units, at least two.
Result<std::vector<Key>> read_keyframes(const std::string& file) {
  OCTOLOD_RETURN_IF_ERROR(check_input_file(file, "the camera path"));
  std::ifstream in(file);
  if (!in) return io_error(file + ": cannot open camera path: " + std::strerror(errno));
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);  // its errors give the line and column
  } catch (const nlohmann::json::exception& e) {
    return bad_input_error(file + ": not valid JSON: " + without_json_tag(e.what()));
  }
  std::vector<Key> keys;
  try {
    for (const auto& k : doc.at("keyframes")) keys.push_back({vec(k.at("eye")), vec(k.at("target"))});
  } catch (const nlohmann::json::exception& e) {
    return bad_input_error(file + ": expected {\"keyframes\": [{\"eye\": [x,y,z], \"target\": [x,y,z]}, ...]}: " +
                           without_json_tag(e.what()));
  }
  if (keys.size() < 2) return bad_input_error(file + ": a camera path needs at least two keyframes");
  return keys;
}

// One camera per frame. Built-in paths are sized from the model's bounds: centre c, radius r
// (half the diagonal).
Result<std::vector<runtime::Camera>> camera_path(const std::string& kind, const Bounds& bounds,
                                                 std::uint32_t frames) {
  const ModelSphere sphere = model_sphere(bounds);
  const glm::vec3 c = sphere.center;
  const float r = sphere.radius;
  std::vector<Key> keys;
  std::vector<Key> per_frame;
  auto t_of = [&](std::uint32_t i) {
    return frames > 1 ? static_cast<float>(i) / static_cast<float>(frames - 1) : 0.0f;
  };
  if (kind == "orbit") {  // one turn at 2.2 r, slightly above
    for (std::uint32_t i = 0; i < frames; ++i) {
      const float a = 6.2831853f * static_cast<float>(i) / static_cast<float>(frames);
      per_frame.push_back({c + 2.2f * r * glm::vec3(std::cos(a), 0.35f, std::sin(a)), c});
    }
  } else if (kind == "far-to-near") {  // from 12 r to 0.6 r, geometric, looking at the centre
    const glm::vec3 dir = glm::normalize(glm::vec3(0.6f, 0.35f, 1.0f));
    for (std::uint32_t i = 0; i < frames; ++i)
      per_frame.push_back({c + dir * (12.0f * r * std::pow(0.05f, t_of(i))), c});
  } else if (kind == "flythrough") {
    // A straight low pass that skims the model (closest approach 0.9 r from the centre, so it
    // grazes the surface), looking partly ahead and partly at the model: the view sweeps from a
    // distant overview over close-ups to looking back, and the model never leaves the picture.
    const glm::vec3 along = glm::normalize(glm::vec3(0.8f, 0.0f, 0.6f));
    const glm::vec3 side = c + r * glm::vec3(-0.54f, 0.2f, 0.72f);
    const glm::vec3 from = side - 2.4f * r * along, to = side + 2.4f * r * along;
    for (std::uint32_t i = 0; i < frames; ++i) {
      const glm::vec3 eye = from + (to - from) * t_of(i);
      per_frame.push_back({eye, 0.4f * (eye + r * along) + 0.6f * c});
    }
  } else {
    Result<std::vector<Key>> read = read_keyframes(kind);
    if (!read.ok()) return read.status();
    keys = std::move(read).value();
    for (std::uint32_t i = 0; i < frames; ++i) {  // linear between keyframes, evenly spread
      const float s = t_of(i) * static_cast<float>(keys.size() - 1);
      const auto k = std::min(static_cast<std::size_t>(s), keys.size() - 2);
      const float f = s - static_cast<float>(k);
      per_frame.push_back({keys[k].eye + (keys[k + 1].eye - keys[k].eye) * f,
                           keys[k].target + (keys[k + 1].target - keys[k].target) * f});
    }
  }
  std::vector<runtime::Camera> cameras;
  for (const Key& k : per_frame) {
    if (!(glm::length(k.target - k.eye) > 0.0f))
      return bad_input_error(kind + ": a keyframe's eye and target coincide");
    cameras.push_back(look_at_camera(k.eye, k.target, kLens, 1e-3f * r, 100.0f * r));
  }
  return cameras;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5))];
}

void write_csv_row(std::ostream& csv, std::uint32_t frame, const runtime::FrameStats& s) {
  csv << frame << ',' << s.visited << ',' << s.culled << ',' << s.wanted << ',' << s.drawn_nodes << ','
      << s.drawn_triangles << ',' << s.resident_bytes << ',' << s.reserved_bytes << ','
      << s.loads_issued << ',' << s.loads_completed << ',' << s.loads_cancelled << ',' << s.loads_failed
      << ',' << s.loads_over_budget
      << ',' << s.cache_hits << ',' << s.cache_misses << ',' << s.second_chance_hits << ','
      << s.fallbacks << ',' << s.holes << ',' << s.coarsening << ',' << s.selection_ms << ','
      << s.selection_cpu_ms << ',' << s.cover_checks << ',' << s.covers_out_of_checks << '\n';
}

}  // namespace

int run_walk(const WalkArgs& args, const CommandContext& context) {
  Result<runtime::StreamingOptions> streaming = streaming_options(args.budget, args.sse);
  if (!streaming.ok()) return report(streaming.status());
  if (args.frames_png_every == 0) return report(usage_error("--frames-png-every must be at least 1"));
  for (const auto& [path, what] : {std::pair{args.csv, "the CSV"}, std::pair{args.plot, "the charts"}})
    if (!path.empty())  // before the replay: an output that has nowhere to go fails now
      if (const Status usable = check_output_file(path, what); !usable.ok()) return report(usable);
  if (!args.frames_png.empty()) {
    std::error_code error;
    std::filesystem::create_directories(args.frames_png, error);
    if (error) return report(io_error(args.frames_png + ": cannot create directory: " + error.message()));
  }

  runtime::StreamingOptions& options = streaming.value();
  options.prefetch = !args.no_prefetch;
  options.max_loads_in_flight = args.loads_in_flight;
  auto executor = std::make_shared<runtime::ThreadPoolExecutor>(args.threads);
  Result<std::unique_ptr<runtime::StreamingTree>> opened =
      runtime::StreamingTree::open_directory(args.tree, executor, options);
  if (!opened.ok()) return report(opened.status());
  runtime::StreamingTree& tree = *opened.value();
  Result<std::vector<runtime::Camera>> cameras = camera_path(args.path, tree.manifest().bounds, args.frames);
  if (!cameras.ok()) return report(cameras.status());

  // replay at a fixed frame rate: loads progress on the loader threads between frames. Rendering
  // a --frames-png picture pauses the replay clock (the loaders keep running meanwhile, so those
  // frames see more loads completed than a real-time renderer would).
  const FramePainter painter(tree.manifest());
  std::vector<runtime::FrameStats> stats;
  stats.reserve(args.frames);
  std::uint32_t pictures = 0;
  auto start = std::chrono::steady_clock::now();
  std::chrono::steady_clock::duration paused{};
  for (std::uint32_t i = 0; i < args.frames; ++i) {
    if (args.fps > 0) {
      std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                std::chrono::duration<double>(i / args.fps)));
    }
    const runtime::FrameResult& frame = tree.update(cameras.value()[i]);
    stats.push_back(frame.stats);
    if (!args.frames_png.empty() && i % args.frames_png_every == 0) {
      const auto render_start = std::chrono::steady_clock::now();
      Result<Image> image = painter.paint(frame, cameras.value()[i], kFrameWidth, kFrameHeight, {});
      if (!image.ok()) return report(image.status());
      char name[32];
      std::snprintf(name, sizeof name, "frame_%06u.png", static_cast<unsigned>(i));
      const Status written = write_png(std::filesystem::path(args.frames_png) / name, image.value());
      if (!written.ok()) return report(written);
      ++pictures;
      const auto render_time = std::chrono::steady_clock::now() - render_start;
      start += render_time;
      paused += render_time;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!args.csv.empty()) {  // whole or not at all, after the replay
    std::ostringstream csv;
    csv << "frame,visited,culled,wanted,drawn_nodes,drawn_triangles,resident_bytes,reserved_bytes,"
           "loads_issued,loads_completed,loads_cancelled,loads_failed,loads_over_budget,cache_hits,cache_misses,"
           "second_chance_hits,fallbacks,holes,coarsening,selection_ms,selection_cpu_ms,cover_checks,"
           "covers_out_of_checks\n";
    for (std::uint32_t i = 0; i < stats.size(); ++i) write_csv_row(csv, i, stats[i]);
    const std::string text = std::move(csv).str();
    const Status written = write_file_atomically(args.csv, "the CSV", [&](std::FILE* file) {
      return std::fwrite(text.data(), 1, text.size(), file) == text.size();
    });
    if (!written.ok()) return report(written);
  }

  // summary
  std::uint64_t max_resident = 0, hits = 0, misses = 0, second_chance = 0, issued = 0, loads = 0,
                cancelled = 0, failed = 0;
  double resident_sum = 0, triangles_sum = 0, max_coarsening = 1;
  std::uint32_t waiting_frames = 0, fallback_frames = 0, hole_frames = 0, over_budget_frames = 0;
  std::uint32_t max_cover_checks = 0, out_of_checks_frames = 0;  // covers by resident descendants
  std::vector<double> ms, cpu_ms;
  for (const runtime::FrameStats& s : stats) {
    max_resident = std::max(max_resident, s.resident_bytes);
    resident_sum += static_cast<double>(s.resident_bytes);
    triangles_sum += static_cast<double>(s.drawn_triangles);
    hits += s.cache_hits;
    misses += s.cache_misses;
    second_chance += s.second_chance_hits;
    issued += s.loads_issued;
    loads += s.loads_completed;
    cancelled += s.loads_cancelled;
    failed += s.loads_failed;
    waiting_frames += s.waiting_on_io > 0 ? 1u : 0u;
    fallback_frames += (s.fallbacks > 0 || s.holes > 0) ? 1u : 0u;
    hole_frames += s.holes > 0 ? 1u : 0u;
    over_budget_frames += s.loads_over_budget > 0 ? 1u : 0u;
    max_cover_checks = std::max(max_cover_checks, s.cover_checks);
    out_of_checks_frames += s.covers_out_of_checks > 0 ? 1u : 0u;
    max_coarsening = std::max(max_coarsening, static_cast<double>(s.coarsening));
    ms.push_back(s.selection_ms);
    cpu_ms.push_back(s.selection_cpu_ms);
  }
  const double n = static_cast<double>(stats.size());
  const double hit_rate = hits + misses > 0 ? static_cast<double>(hits) / static_cast<double>(hits + misses) : 1.0;
  nlohmann::json doc{{"tree", args.tree},
                     {"path", args.path},
                     {"frames", stats.size()},
                     {"fps", args.fps},
                     {"seconds", seconds},
                     {"threads", args.threads},
                     {"budget_bytes", options.max_resident_bytes},
                     {"target_sse_pixels", args.sse},
                     {"prefetch", !args.no_prefetch},
                     {"loads_in_flight", args.loads_in_flight},
                     {"max_resident_bytes", max_resident},
                     {"mean_resident_bytes", resident_sum / n},
                     {"frames_waiting_on_io", waiting_frames},
                     {"fallback_frames", fallback_frames},
                     {"hole_frames", hole_frames},
                     {"frames_over_budget", over_budget_frames},
                     {"max_cover_checks", max_cover_checks},
                     {"frames_out_of_cover_checks", out_of_checks_frames},
                     {"loads", loads},
                     {"loads_issued", issued},
                     {"loads_cancelled", cancelled},
                     {"loads_failed", failed},
                     {"hits", hits},
                     {"misses", misses},
                     {"second_chance_hits", second_chance},
                     {"hit_rate", hit_rate},
                     {"max_coarsening", max_coarsening},
                     {"selection_ms_p50", percentile(ms, 0.5)},
                     {"selection_ms_p99", percentile(ms, 0.99)},
                     {"selection_ms_max", ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end())},
                     {"selection_cpu_ms_p50", percentile(cpu_ms, 0.5)},
                     {"selection_cpu_ms_p99", percentile(cpu_ms, 0.99)},
                     {"selection_cpu_ms_max", cpu_ms.empty() ? 0.0 : *std::max_element(cpu_ms.begin(), cpu_ms.end())},
                     {"mean_drawn_triangles", triangles_sum / n},
                     {"frames_png", pictures},
                     {"render_seconds", std::chrono::duration<double>(paused).count()}};

  if (!args.plot.empty()) {
    std::vector<ChartSeries> series(5);
    series[0] = {"DRAWN TRIANGLES", {}, 0x3070e0, -1};
    series[1] = {"RESIDENT MB", {}, 0x20a050, static_cast<double>(options.max_resident_bytes) / 1048576.0};
    series[2] = {"FALLBACK DRAWS", {}, 0xe07020, -1};
    series[3] = {"LOADS COMPLETED", {}, 0x8040c0, -1};
    series[4] = {"SELECTION MS", {}, 0xc03040, -1};
    for (const runtime::FrameStats& s : stats) {
      series[0].values.push_back(static_cast<double>(s.drawn_triangles));
      series[1].values.push_back(static_cast<double>(s.resident_bytes) / 1048576.0);
      series[2].values.push_back(s.fallbacks);
      series[3].values.push_back(s.loads_completed);
      series[4].values.push_back(s.selection_ms);
    }
    const Status written = write_png(args.plot, draw_line_charts(series, 960, 110));
    if (!written.ok()) return report(written);
  }

  if (context.json) {
    print_json(doc);
  } else {
    std::printf("%s: %s, %zu frames in %.1f s, budget %.1f MB, target %.2f px\n", args.tree.c_str(),
                args.path.c_str(), stats.size(), seconds, static_cast<double>(options.max_resident_bytes) / 1048576.0,
                args.sse);
    std::printf("  resident: max %.1f MB, mean %.1f MB; mean drawn triangles %.0f\n",
                static_cast<double>(max_resident) / 1048576.0, resident_sum / n / 1048576.0, triangles_sum / n);
    std::printf("  loads %llu (cancelled %llu, failed %llu); hits %llu, misses %llu, hit rate %.3f, "
                "second chance %llu\n",
                static_cast<unsigned long long>(loads), static_cast<unsigned long long>(cancelled),
                static_cast<unsigned long long>(failed), static_cast<unsigned long long>(hits),
                static_cast<unsigned long long>(misses), hit_rate, static_cast<unsigned long long>(second_chance));
    std::printf("  frames waiting on I/O %u, frames with fallbacks %u (with holes %u), frames with loads the "
                "budget had no room for %u\n",
                waiting_frames, fallback_frames, hole_frames, over_budget_frames);
    std::printf("  covers by resident descendants: at most %u checks a frame (cap %u), frames that gave one up %u\n",
                max_cover_checks, options.max_cover_checks_per_frame, out_of_checks_frames);
    std::printf("  selection ms: p50 %.4f, p99 %.4f, max %.4f (thread CPU: p50 %.4f, p99 %.4f, max %.4f)\n",
                percentile(ms, 0.5), percentile(ms, 0.99), ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end()),
                percentile(cpu_ms, 0.5), percentile(cpu_ms, 0.99),
                cpu_ms.empty() ? 0.0 : *std::max_element(cpu_ms.begin(), cpu_ms.end()));
  }
  if (failed > 0) return report(failed_loads_error(args.tree, failed, "the walk drew fallbacks for them"));
  return 0;
}


}  // namespace octolod::cli
