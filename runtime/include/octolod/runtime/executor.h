// Where the runtime's loads run (El-Sana & Chiang 2000: I/O separate from rendering). The runtime
// never spawns threads itself: it posts tasks to an injected Executor.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace octolod::runtime {

class Executor {
 public:
  virtual ~Executor() = default;
  // Runs `task` at some later point, possibly on another thread. Thread-safe. Every posted task
  // must run eventually: a StreamingTree posts a bounded number of loader tasks and posts more
  // only as they finish, so a dropped task stalls its loading. Tasks posted by the runtime own
  // what they use (shared state), so they may outlive the StreamingTree.
  virtual void post(std::function<void()> task) = 0;
};

// `threads` loader threads (at least one) draining a FIFO queue. The destructor runs every task
// already posted, then joins the threads.
class ThreadPoolExecutor final : public Executor {
 public:
  explicit ThreadPoolExecutor(unsigned threads);
  ~ThreadPoolExecutor() override;
  ThreadPoolExecutor(const ThreadPoolExecutor&) = delete;
  ThreadPoolExecutor& operator=(const ThreadPoolExecutor&) = delete;

  void post(std::function<void()> task) override;

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

// Queues tasks until the caller runs them with run_pending() on its own thread: deterministic
// tests step I/O exactly where they want it.
class SynchronousExecutor final : public Executor {
 public:
  void post(std::function<void()> task) override;
  // Runs queued tasks in FIFO order, including tasks they post, until none is left. Returns
  // how many ran.
  std::size_t run_pending();
  std::size_t pending() const;

 private:
  mutable std::mutex mutex_;
  std::deque<std::function<void()>> tasks_;
};

}  // namespace octolod::runtime
