// The hand-off between the render thread and the loader tasks (El-Sana & Chiang 2000: I/O runs
// separately from rendering). The render thread publishes a prioritized list of slots to load;
// loader tasks posted to the Executor pop the most important one, read it through the NodeSource
// (which refuses a file of another size than the manifest lists), decode and checksum it
// (decode_node_file), and push the result onto a completed list that the render thread drains at
// the start of its next frame. Both lists sit behind one mutex; the render thread never waits for
// a load, only for that mutex.
//
// Tasks share ownership of the queue, so a StreamingTree may be destroyed while tasks are still
// posted; shutdown() makes them finish without loading.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "octolod/formats/manifest.h"
#include "octolod/formats/node_file.h"
#include "octolod/formats/status.h"
#include "octolod/runtime/node_source.h"

namespace octolod::runtime {

struct LoadCompletion {
  std::uint32_t slot = 0;
  std::shared_ptr<const NodeMesh> mesh;  // null when status is not ok
  Status status;
};

class LoadQueue {
 public:
  // `*lods[slot]` is the LOD of each slot, held by `manifest` (which the queue keeps alive for
  // its tasks); a loaded node file must be what it says (check_node_lod) in `layout`.
  LoadQueue(std::shared_ptr<const NodeSource> source, std::shared_ptr<const Manifest> manifest,
            std::vector<const LodInfo*> lods, VertexLayout layout);

  // Render thread. take_pending() removes every request not yet started (into `out`, replacing
  // its content); set_pending() publishes `in` (most important last) and leaves `in` empty.
  void take_pending(std::vector<std::uint32_t>& out);
  void set_pending(std::vector<std::uint32_t>& in);
  // Moves every completed load into `out` (replacing its content).
  void take_completed(std::vector<LoadCompletion>& out);
  // How many more loader tasks to post so that every pending request has a task waiting for it,
  // with at most max_tasks posted and unfinished; counts them as posted.
  std::uint32_t claim_tasks(std::uint32_t max_tasks);
  // Drops pending requests; running tasks finish their current load and stop.
  void shutdown();

  // Loader task body: loads the most important pending request, if any. One request per task,
  // so that the tasks of several trees sharing an executor interleave in its queue (a task that
  // looped while its tree kept requesting held a pool thread for as long).
  void run_task();

 private:
  // A failed load (an exception included) is a completion with an error status.
  LoadCompletion load(std::uint32_t slot) const;
  void read_and_decode(const LodInfo& lod, LoadCompletion& done) const;

  const std::shared_ptr<const NodeSource> source_;
  const std::shared_ptr<const Manifest> manifest_;
  const std::vector<const LodInfo*> lods_;
  const VertexLayout layout_;

  std::mutex mutex_;
  std::vector<std::uint32_t> pending_;
  std::vector<LoadCompletion> completed_;
  std::uint32_t tasks_ = 0;    // posted and not finished
  std::uint32_t running_ = 0;  // of those, loading
  bool shutdown_ = false;
};

}  // namespace octolod::runtime
