// LoadQueue, see load_queue.h.
#include "load_queue.h"

#include <algorithm>
#include <exception>
#include <utility>

namespace octolod::runtime {

LoadQueue::LoadQueue(std::shared_ptr<const NodeSource> source, std::shared_ptr<const Manifest> manifest,
                     std::vector<const LodInfo*> lods, VertexLayout layout)
    : source_(std::move(source)), manifest_(std::move(manifest)), lods_(std::move(lods)), layout_(layout) {}

void LoadQueue::take_pending(std::vector<std::uint32_t>& out) {
  out.clear();
  std::lock_guard lock(mutex_);
  out.swap(pending_);
}

void LoadQueue::set_pending(std::vector<std::uint32_t>& in) {
  {
    std::lock_guard lock(mutex_);
    pending_.swap(in);
  }
  in.clear();
}

void LoadQueue::take_completed(std::vector<LoadCompletion>& out) {
  out.clear();
  std::lock_guard lock(mutex_);
  out.swap(completed_);
}

std::uint32_t LoadQueue::claim_tasks(std::uint32_t max_tasks) {
  std::lock_guard lock(mutex_);
  // a task loads one request: one waiting task per pending request, at most max_tasks in all
  const std::uint32_t waiting = tasks_ - running_;
  const auto pending = static_cast<std::uint32_t>(pending_.size());
  const std::uint32_t room = max_tasks > tasks_ ? max_tasks - tasks_ : 0;
  const std::uint32_t more = pending > waiting ? std::min(room, pending - waiting) : 0;
  tasks_ += more;
  return more;
}

void LoadQueue::shutdown() {
  std::lock_guard lock(mutex_);
  shutdown_ = true;
  pending_.clear();
}

void LoadQueue::run_task() {
  std::uint32_t slot = 0;
  {
    std::lock_guard lock(mutex_);
    if (shutdown_ || pending_.empty()) {
      --tasks_;
      return;
    }
    slot = pending_.back();
    pending_.pop_back();
    ++running_;
  }
  LoadCompletion done = load(slot);
  std::lock_guard lock(mutex_);
  --running_;
  --tasks_;
  if (!shutdown_) completed_.push_back(std::move(done));
}

LoadCompletion LoadQueue::load(std::uint32_t slot) const {
  LoadCompletion done;
  done.slot = slot;
  const LodInfo& lod = *lods_[slot];
  const std::string& file = lod.file;
  // a NodeSource that throws, or memory running out, fails this load instead of the loader
  // thread (ThreadPoolExecutor would terminate) or the render thread (SynchronousExecutor)
  try {
    read_and_decode(lod, done);
  } catch (const std::exception& e) {
    done.mesh.reset();
    done.status = io_error(file + ": load failed: " + e.what());
  }
  return done;
}

void LoadQueue::read_and_decode(const LodInfo& lod, LoadCompletion& done) const {
  const std::string& file = lod.file;
  Result<std::vector<std::byte>> bytes = source_->read(file, lod.bytes);
  if (!bytes.ok()) {
    done.status = bytes.status();
    return;
  }
  Result<NodeMesh> mesh = decode_node_file(bytes.value(), file);
  if (!mesh.ok()) {
    done.status = mesh.status();
    return;
  }
  if (const Status checked = check_node_lod(mesh.value(), lod, layout_, file); !checked.ok()) {
    done.status = checked;
    return;
  }
  done.mesh = std::make_shared<const NodeMesh>(std::move(mesh).value());
}

}  // namespace octolod::runtime
