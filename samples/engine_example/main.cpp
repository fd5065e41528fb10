// engine_example: what a game does with octolod's streaming runtime, without the game.
//
//   engine_example TREE_DIR [FRAMES=300] [BUDGET_MIB=64]
//
// Opens a baked tree (manifest only), then runs a 60 Hz frame loop: move the camera along a path
// that approaches the model while circling it, call StreamingTree::update() (never blocks; two
// loader threads page node LODs in the background), "upload" every mesh of the draw list the first
// time it appears, release uploads no longer drawn, and print one line of statistics per frame.
// Replace GpuMeshCache's bodies with your graphics API's buffer calls.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <unordered_map>

#include <glm/glm.hpp>

#include "octolod/runtime/camera.h"
#include "octolod/runtime/executor.h"
#include "octolod/runtime/streaming_tree.h"

namespace {

// Vertex/index buffers on the GPU, keyed by the runtime's mesh pointer. A DrawItem's mesh is
// immutable and shared: holding the shared_ptr keeps the address from being reused, so the pointer
// is a safe key for as long as the upload lives.
class GpuMeshCache {
 public:
  // Makes sure `mesh` is on the GPU; returns the bytes uploaded now (0 when already there).
  std::uint64_t draw(const std::shared_ptr<const octolod::NodeMesh>& mesh, std::uint64_t frame) {
    auto [it, inserted] = uploads_.try_emplace(mesh.get());
    it->second.last_drawn = frame;
    if (!inserted) return 0;
    it->second.mesh = mesh;
    // glBufferData(GL_ARRAY_BUFFER, mesh->vertices...) / glBufferData(GL_ELEMENT_ARRAY_BUFFER, ...)
    it->second.bytes = (mesh->vertices.size() + mesh->indices.size()) * 4;
    gpu_bytes_ += it->second.bytes;
    return it->second.bytes;
  }
  // Frees uploads not drawn this frame (a real engine might keep them a few frames longer).
  void release_unused(std::uint64_t frame) {
    for (auto it = uploads_.begin(); it != uploads_.end();) {
      if (it->second.last_drawn == frame) {
        ++it;
        continue;
      }
      gpu_bytes_ -= it->second.bytes;  // glDeleteBuffers(...)
      it = uploads_.erase(it);
    }
  }
  std::uint64_t gpu_bytes() const { return gpu_bytes_; }

 private:
  struct Upload {
    std::shared_ptr<const octolod::NodeMesh> mesh;
    std::uint64_t bytes = 0;
    std::uint64_t last_drawn = 0;
  };
  std::unordered_map<const octolod::NodeMesh*, Upload> uploads_;
  std::uint64_t gpu_bytes_ = 0;
};

// Frame `i` of `frames`: half a turn around the model while closing in from 6 to 1.2 radii.
octolod::runtime::Camera camera_at(const octolod::Bounds& bounds, int i, int frames) {
  const glm::vec3 lo(bounds.min[0], bounds.min[1], bounds.min[2]);
  const glm::vec3 hi(bounds.max[0], bounds.max[1], bounds.max[2]);
  const glm::vec3 center = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-6f);
  const float t = frames > 1 ? static_cast<float>(i) / static_cast<float>(frames - 1) : 0.0f;
  const float angle = 3.14159265f * t;
  const float distance = radius * (6.0f - 4.8f * t);
  const glm::vec3 eye = center + distance * glm::normalize(glm::vec3(std::cos(angle), 0.4f, std::sin(angle)));
  const float fovy = 1.0471976f;  // 60 degrees
  return octolod::runtime::make_perspective_camera(eye, center, glm::vec3(0, 1, 0), fovy, 16.0f / 9.0f,
                                                   0.01f * radius, 20.0f * radius, 1080.0f);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: %s TREE_DIR [FRAMES=300] [BUDGET_MIB=64]\n", argv[0]);
    return 1;
  }
  const int frames = argc > 2 ? std::atoi(argv[2]) : 300;
  const long budget_mib = argc > 3 ? std::atol(argv[3]) : 64;
  if (frames < 1 || budget_mib < 1) {
    std::fprintf(stderr, "error: FRAMES and BUDGET_MIB must be positive\n");
    return 1;
  }

  // Two loader threads; the runtime never creates threads itself.
  auto loaders = std::make_shared<octolod::runtime::ThreadPoolExecutor>(2);
  octolod::runtime::StreamingOptions options;
  options.max_resident_bytes = static_cast<std::uint64_t>(budget_mib) << 20;
  options.target_sse_pixels = 2.0;
  options.log = [](std::string_view message) {
    std::fprintf(stderr, "warning: %.*s\n", static_cast<int>(message.size()), message.data());
  };
  auto opened = octolod::runtime::StreamingTree::open_directory(argv[1], loaders, options);
  if (!opened.ok()) {
    std::fprintf(stderr, "error: %s\n", opened.status().message().c_str());
    return 1;
  }
  octolod::runtime::StreamingTree& tree = *opened.value();
  std::printf("%s: %zu nodes, %llu triangles baked\n", argv[1], tree.manifest().nodes.size(),
              static_cast<unsigned long long>(tree.manifest().input_triangles));
  // The material's image, if the input was a textured mesh: load it as the engine loads images
  // (its v runs up from the image's bottom row).
  if (!tree.manifest().texture.empty())
    std::printf("texture: %s/%s\n", argv[1], tree.manifest().texture.c_str());

  GpuMeshCache gpu;
  const auto frame_time = std::chrono::microseconds(16667);
  auto next_frame = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) {
    const auto frame_number = static_cast<std::uint64_t>(i) + 1;
    const octolod::runtime::FrameResult& frame = tree.update(camera_at(tree.manifest().bounds, i, frames));

    // "draw": upload what is new, then one draw call per item (glDrawElements(...)).
    std::uint64_t uploaded = 0;
    for (const octolod::runtime::DrawItem& item : frame.draws) uploaded += gpu.draw(item.mesh, frame_number);
    gpu.release_unused(frame_number);

    const octolod::runtime::FrameStats& s = frame.stats;
    std::printf("frame %3d: %4u nodes %8llu tris (%u fallback) | upload %7.1f KiB, gpu %6.1f MiB | "
                "resident %6.1f MiB, loads +%u done %u | hits %u misses %u | select %.3f ms\n",
                i, s.drawn_nodes, static_cast<unsigned long long>(s.drawn_triangles), s.fallbacks,
                static_cast<double>(uploaded) / 1024.0, static_cast<double>(gpu.gpu_bytes()) / 1048576.0,
                static_cast<double>(s.resident_bytes) / 1048576.0, s.loads_issued, s.loads_completed,
                s.cache_hits, s.cache_misses, s.selection_ms);

    // vsync stand-in: the loaders work while the frame waits
    next_frame += frame_time;
    std::this_thread::sleep_until(next_frame);
  }
  return 0;
}
