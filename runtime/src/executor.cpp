// The two Executors the runtime ships with: loader threads for games, a manual queue for tests.
#include "octolod/runtime/executor.h"

#include <algorithm>
#include <utility>

namespace octolod::runtime {

ThreadPoolExecutor::ThreadPoolExecutor(unsigned threads) {
  // 0 would never run a posted task, and every StreamingTree on it would stop loading
  const unsigned count = std::max(threads, 1u);
  threads_.reserve(count);
  for (unsigned i = 0; i < count; ++i) threads_.emplace_back([this] { run(); });
}

ThreadPoolExecutor::~ThreadPoolExecutor() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void ThreadPoolExecutor::post(std::function<void()> task) {
  {
    std::lock_guard lock(mutex_);
    tasks_.push_back(std::move(task));
  }
  wake_.notify_one();
}

void ThreadPoolExecutor::run() {
  for (;;) {
    std::function<void()> task;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
      if (tasks_.empty()) return;  // stopping and drained
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    task();
  }
}

void SynchronousExecutor::post(std::function<void()> task) {
  std::lock_guard lock(mutex_);
  tasks_.push_back(std::move(task));
}

std::size_t SynchronousExecutor::run_pending() {
  std::size_t ran = 0;
  for (;;) {
    std::function<void()> task;
    {
      std::lock_guard lock(mutex_);
      if (tasks_.empty()) return ran;
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    task();
    ++ran;
  }
}

std::size_t SynchronousExecutor::pending() const {
  std::lock_guard lock(mutex_);
  return tasks_.size();
}

}  // namespace octolod::runtime
