// cover_bench: what StreamingOptions::max_cover_checks_per_frame costs and what it saves, on a
// baked tree. A wanted LOD with no resident LOD of its node may be drawn by resident descendants
// (a cover); the cap bounds the nodes checked for covers per update(), and a cover past it is
// given up for the nearest resident ancestor (coarser). Each path replays once per cap (r = half
// the bounds' diagonal; cameras look at the centre, 1920x1080 at 60 degrees):
//   dive        from 6 r to 0.7 r in 60 frames, 60 there, back to 6 r in 30, 30 there, from four
//               directions: the pull-back wants coarser LODs above a resident fine cut;
//   dive-small  the same under --small-budget-mb, where the cut is relaxed to fit and often missing;
//   teleport    90 frames at 0.7 r, then 60 at 3 r on the same line of sight, four directions;
//   skim-small  two turns along the surface at 0.75 r under --small-budget-mb (the budget churns),
//               each followed by a pull-back to 4 r in 15 frames;
//   cold-jump   the worst case, staged: see make_paths.
// Loads run between frames on this thread (at most --loads-per-frame, outside the timing), so
// the replay is deterministic: every cap sees the same loads in the same frames until the cap
// changes what is drawn, and a cap that never runs out replays the unlimited run exactly.
// Prints per path and cap, over all frames: frames with cache misses and with cover checks;
// update()'s thread CPU p50/p99/max ms (FrameStats::selection_cpu_ms) and wall max; cover checks
// per frame p99/max; at the frame where the unlimited run checked the most (the jump, one per
// run), this cap's checks (max over runs) and CPU ms (mean over runs); frames with covers given
// up (covers_out_of_checks > 0) and the covers given up; frames whose drawn triangles differ from
// the unlimited run's; and the triangles drawn in the frames that gave up against the unlimited
// run's same frames (what giving up cost on screen; 1 = nothing).
//
//   cover_bench TREE [--budget-mb 256] [--small-budget-mb 32] [--loads-per-frame 8 (0: all)] [--sse 2]
//                    [--caps 0,64,512,4096,32768,unlimited] [--paths dive,teleport,...]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "octolod/formats/manifest.h"
#include "octolod/runtime/streaming_tree.h"
#include "percentile.h"

namespace {

using namespace octolod;
using namespace octolod::runtime;

constexpr std::uint32_t kUnlimited = std::numeric_limits<std::uint32_t>::max();

// Runs posted loads only when asked, at most `n` at a time: a loader that keeps up with n loads
// per frame. A task left queued takes the most important request when it runs (LoadQueue).
class SteppedExecutor final : public Executor {
 public:
  void post(std::function<void()> task) override {
    std::lock_guard lock(mutex_);
    tasks_.push_back(std::move(task));
  }
  // n == 0: until none is queued.
  void run(std::uint32_t n) {
    for (std::uint32_t i = 0; n == 0 || i < n; ++i) {
      std::function<void()> task;
      {
        std::lock_guard lock(mutex_);
        if (tasks_.empty()) return;
        task = std::move(tasks_.front());
        tasks_.pop_front();
      }
      task();
    }
  }

 private:
  std::mutex mutex_;
  std::deque<std::function<void()>> tasks_;
};

// A camera path and the options it runs under. Each run replays on a freshly opened tree (a cold
// cache); a path's numbers are over all its runs' frames.
struct Path {
  const char* name;
  std::uint64_t budget_mb;
  std::vector<std::vector<Camera>> runs;
  bool prefetch = true;
  std::uint32_t loads_per_frame = 0;  // 0: all that are queued
  std::uint32_t loads_in_flight = StreamingOptions{}.max_loads_in_flight;
};

struct PathSettings {
  std::uint64_t budget_mb = 256, small_budget_mb = 32;
  std::uint32_t loads_per_frame = 8;
};

// 1920x1080 at 60 degrees, as `octolod walk`; near/far relative to the model's radius.
Camera look(glm::vec3 eye, glm::vec3 target, float radius) {
  return make_perspective_camera(eye, target, glm::vec3(0, 1, 0), 1.0471976f, 16.0f / 9.0f, 1e-3f * radius,
                                 100.0f * radius, 1080.0f);
}

std::vector<glm::vec3> directions() {
  return {glm::normalize(glm::vec3(0.6f, 0.35f, 1.0f)), glm::normalize(glm::vec3(-1.0f, 0.2f, 0.3f)),
          glm::normalize(glm::vec3(-0.4f, -0.3f, -1.0f)), glm::normalize(glm::vec3(1.0f, 0.1f, -0.5f))};
}

std::vector<Path> make_paths(const Bounds& bounds, const PathSettings& settings) {
  glm::vec3 c, half;
  for (int a = 0; a < 3; ++a) {
    c[a] = static_cast<float>(0.5 * (bounds.min[a] + bounds.max[a]));
    half[a] = static_cast<float>(0.5 * (bounds.max[a] - bounds.min[a]));
  }
  const float r = std::max(glm::length(half), 1e-6f);
  // from `from` to `to` radii along `dir` in `frames` steps, geometric, looking at the centre
  auto move = [&](std::vector<Camera>& out, glm::vec3 dir, float from, float to, std::uint32_t frames) {
    for (std::uint32_t i = 0; i < frames; ++i) {
      const float t = frames > 1 ? static_cast<float>(i) / static_cast<float>(frames - 1) : 1.0f;
      out.push_back(look(c + dir * (r * from * std::pow(to / from, t)), c, r));
    }
  };
  const std::uint32_t lpf = settings.loads_per_frame;
  Path dive{"dive", settings.budget_mb, {{}}, true, lpf};
  Path teleport{"teleport", settings.budget_mb, {{}}, true, lpf};
  for (const glm::vec3 dir : directions()) {
    move(dive.runs[0], dir, 6.0f, 0.7f, 60);
    move(dive.runs[0], dir, 0.7f, 0.7f, 60);
    move(dive.runs[0], dir, 0.7f, 6.0f, 30);
    move(dive.runs[0], dir, 6.0f, 6.0f, 30);
    move(teleport.runs[0], dir, 0.7f, 0.7f, 90);
    move(teleport.runs[0], dir, 3.0f, 3.0f, 60);
  }
  Path dive_small{"dive-small", settings.small_budget_mb, dive.runs, true, lpf};
  // two turns along the surface at 0.75 r, each followed by a pull-back to 4 r in 15 frames
  Path skim{"skim-small", settings.small_budget_mb, {{}}, true, lpf};
  const glm::vec3 out = glm::normalize(glm::vec3(1.0f, 0.2f, 0.0f));
  for (std::uint32_t turn = 0; turn < 2; ++turn) {
    for (std::uint32_t i = 0; i < 360; ++i) {
      const float a = 6.2831853f * static_cast<float>(i) / 360.0f;
      skim.runs[0].push_back(look(c + 0.75f * r * glm::vec3(std::cos(a), 0.2f, std::sin(a)), c, r));
    }
    move(skim.runs[0], out, 0.75f, 4.0f, 15);
    move(skim.runs[0], out, 4.0f, 4.0f, 45);
  }
  // The worst case the cap is for (runtime_test's CoveringByDescendantsChecksAtMostTheFramesNodes
  // on a real tree): a cold start at 1.2 r whose whole cut loads in one go (no limit on loads in
  // flight or per frame) and no prefetch, so no LOD above the cut is ever asked for; then a jump
  // to 6 r, where every wanted LOD is missing and the fine cut below them is resident.
  Path cold{"cold-jump", settings.budget_mb, {}, false, 0, 1u << 20};
  for (const glm::vec3 dir : directions()) {
    cold.runs.emplace_back();
    move(cold.runs.back(), dir, 1.2f, 1.2f, 30);
    move(cold.runs.back(), dir, 6.0f, 6.0f, 30);
  }
  return {dive, dive_small, teleport, skim, cold};
}

std::string cap_name(std::uint32_t cap) { return cap == kUnlimited ? "unlimited" : std::to_string(cap); }

bool parse_caps(const char* text, std::vector<std::uint32_t>& caps) {
  caps.clear();
  std::string list(text);
  for (std::size_t begin = 0; begin <= list.size();) {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    const std::string item = list.substr(begin, end - begin);
    if (item == "unlimited") {
      caps.push_back(kUnlimited);
    } else {
      char* rest = nullptr;
      const unsigned long value = std::strtoul(item.c_str(), &rest, 10);
      if (item.empty() || *rest != '\0' || value >= kUnlimited) return false;
      caps.push_back(static_cast<std::uint32_t>(value));
    }
    begin = end + 1;
  }
  return !caps.empty();
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: cover_bench TREE [--budget-mb 256] [--small-budget-mb 32] [--loads-per-frame 8] "
                      "[--sse 2] [--caps 0,64,512,4096,32768,unlimited] [--paths dive,...]\n";
  if (argc < 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "%s", usage);
    return 1;
  }
  const std::string root = argv[1];
  PathSettings settings;
  double sse = 2.0;
  std::vector<std::uint32_t> caps = {0, 64, 512, 4096, 32768, kUnlimited};
  std::string only;  // comma-separated path names, empty: all
  for (int i = 2; i < argc; i += 2) {
    const bool has_value = i + 1 < argc;
    if (has_value && !std::strcmp(argv[i], "--budget-mb")) settings.budget_mb = std::stoull(argv[i + 1]);
    else if (has_value && !std::strcmp(argv[i], "--small-budget-mb")) settings.small_budget_mb = std::stoull(argv[i + 1]);
    else if (has_value && !std::strcmp(argv[i], "--loads-per-frame"))
      settings.loads_per_frame = static_cast<std::uint32_t>(std::stoul(argv[i + 1]));
    else if (has_value && !std::strcmp(argv[i], "--sse")) sse = std::stod(argv[i + 1]);
    else if (has_value && !std::strcmp(argv[i], "--paths")) only = std::string(",") + argv[i + 1] + ",";
    else if (!(has_value && !std::strcmp(argv[i], "--caps") && parse_caps(argv[i + 1], caps))) {
      std::fprintf(stderr, "error: bad option %s\n%s", argv[i], usage);
      return 1;
    }
  }
  // the unlimited run first: the others' frames are compared with its frames
  caps.erase(std::remove(caps.begin(), caps.end(), kUnlimited), caps.end());
  caps.insert(caps.begin(), kUnlimited);

  Result<Manifest> manifest = read_tree_manifest(root);
  if (!manifest.ok()) {
    std::fprintf(stderr, "error: %s\n", manifest.status().message().c_str());
    return 2;
  }
  std::printf("%s: %zu nodes; target %.2f px; budget %llu MiB, small %llu MiB; %u loads per frame "
              "(cold-jump: all, no prefetch)\n",
              root.c_str(), manifest->nodes.size(), sse, static_cast<unsigned long long>(settings.budget_mb),
              static_cast<unsigned long long>(settings.small_budget_mb), settings.loads_per_frame);
  std::printf("%-10s %9s %6s %6s %7s %8s %8s %8s %8s %7s %7s %8s %8s %8s %6s %6s %9s\n", "path", "cap", "frames",
              "miss_f", "cover_f", "cpu_p50", "cpu_p99", "cpu_max", "wall_max", "chk_p99", "chk_max", "jump_chk",
              "jump_cpu", "gaveup_f", "gaveup", "diff_f", "tri_ratio");
  for (const Path& path : make_paths(manifest->bounds, settings)) {
    if (!only.empty() && only.find("," + std::string(path.name) + ",") == std::string::npos) continue;
    // of the unlimited run: each run's drawn triangles per frame, and its frame with the most
    // cover checks (the jump), whose cost every cap is compared at
    std::vector<std::vector<std::uint64_t>> reference(path.runs.size());
    std::vector<std::size_t> jump(path.runs.size(), 0);
    for (const std::uint32_t cap : caps) {
      std::vector<double> cpu_ms, wall_ms, checks;
      std::uint32_t frames = 0, miss_frames = 0, cover_frames = 0, gave_up_frames = 0, gave_up = 0, differ = 0;
      std::uint32_t jump_checks = 0;
      double jump_cpu_ms = 0;
      double capped = 0, unlimited = 0;  // drawn triangles of the frames that gave up covers
      for (std::size_t run = 0; run < path.runs.size(); ++run) {
        StreamingOptions options;
        options.max_resident_bytes = path.budget_mb << 20;
        options.target_sse_pixels = sse;
        options.prefetch = path.prefetch;
        options.max_loads_in_flight = path.loads_in_flight;
        options.max_cover_checks_per_frame = cap;
        auto executor = std::make_shared<SteppedExecutor>();
        auto opened = StreamingTree::open_directory(root, executor, options);
        if (!opened.ok()) {
          std::fprintf(stderr, "error: %s\n", opened.status().message().c_str());
          return 2;
        }
        StreamingTree& tree = *opened.value();
        const std::size_t first = cpu_ms.size();
        for (std::size_t f = 0; f < path.runs[run].size(); ++f) {
          const FrameStats& s = tree.update(path.runs[run][f]).stats;
          executor->run(path.loads_per_frame);  // between frames, not timed
          ++frames;
          cpu_ms.push_back(s.selection_cpu_ms);
          wall_ms.push_back(s.selection_ms);
          checks.push_back(s.cover_checks);
          miss_frames += s.cache_misses > 0 ? 1u : 0u;
          cover_frames += s.cover_checks > 0 ? 1u : 0u;
          if (cap == kUnlimited) {
            reference[run].push_back(s.drawn_triangles);
            continue;
          }
          differ += s.drawn_triangles != reference[run][f] ? 1u : 0u;
          if (s.covers_out_of_checks > 0) {
            ++gave_up_frames;
            gave_up += s.covers_out_of_checks;
            capped += static_cast<double>(s.drawn_triangles);
            unlimited += static_cast<double>(reference[run][f]);
          }
        }
        if (cap == kUnlimited)
          for (std::size_t f = 1; f < path.runs[run].size(); ++f)
            if (checks[first + f] > checks[first + jump[run]]) jump[run] = f;
        jump_checks = std::max(jump_checks, static_cast<std::uint32_t>(checks[first + jump[run]]));
        jump_cpu_ms += cpu_ms[first + jump[run]] / static_cast<double>(path.runs.size());
      }
      char ratio[32] = "-";
      if (unlimited > 0) std::snprintf(ratio, sizeof ratio, "%.3f", capped / unlimited);
      std::printf("%-10s %9s %6u %6u %7u %8.4f %8.4f %8.4f %8.4f %7.0f %7.0f %8u %8.4f %8u %6u %6u %9s\n", path.name,
                  cap_name(cap).c_str(), frames, miss_frames, cover_frames, percentile(cpu_ms, 0.5),
                  percentile(cpu_ms, 0.99), *std::max_element(cpu_ms.begin(), cpu_ms.end()),
                  *std::max_element(wall_ms.begin(), wall_ms.end()), percentile(checks, 0.99),
                  *std::max_element(checks.begin(), checks.end()), jump_checks, jump_cpu_ms, gave_up_frames, gave_up,
                  differ, ratio);
    }
  }
  return 0;
}
