#include <regolith/core/Executor.hpp>

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>

namespace regolith::core {

unsigned availableCores() noexcept {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return static_cast<unsigned>(n);
  }
  return std::max(1U, std::thread::hardware_concurrency());
}

ThreadPool::ThreadPool(unsigned threads) {
  if (threads == 0) threads = availableCores();
  workers_.reserve(threads);
  for (unsigned i = 0; i < threads; ++i) workers_.emplace_back([this] { run(); });
}

ThreadPool::~ThreadPool() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void ThreadPool::submit(std::function<void()> task) {
  {
    const std::lock_guard lock(mutex_);
    queue_.push_back(std::move(task));
  }
  wake_.notify_one();
}

void ThreadPool::run() {
  for (;;) {
    std::function<void()> task;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping, and nothing left to run
      task = std::move(queue_.front());
      queue_.pop_front();
    }
    task();
  }
}

namespace {

/// Shared by the caller and the helper tasks of one parallelFor(); helpers that start after
/// every index is taken find nothing to do, so the caller waits for indices, not for tasks.
struct Loop {
  explicit Loop(std::size_t count, const std::function<void(std::size_t)>& f) : n(count), body(f) {}
  const std::size_t n;
  const std::function<void(std::size_t)> body;
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex mutex;
  std::condition_variable finished;
  std::size_t done = 0;  // indices finished or skipped, under mutex
  std::exception_ptr error;

  void work() {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= n) return;
      std::exception_ptr e;
      if (!failed.load()) {
        try {
          body(i);
        } catch (...) {
          e = std::current_exception();
          failed = true;
        }
      }
      const std::lock_guard lock(mutex);
      if (e && !error) error = e;
      if (++done == n) finished.notify_all();
    }
  }
};

}  // namespace

void parallelFor(Executor& executor, std::size_t n, const std::function<void(std::size_t)>& body,
                 unsigned maxTasks) {
  if (n == 0) return;
  const unsigned tasks = maxTasks != 0 ? maxTasks : executor.concurrency();
  const std::size_t helpers = std::min<std::size_t>(n, std::max(1U, tasks)) - 1;
  if (helpers == 0) {
    for (std::size_t i = 0; i < n; ++i) body(i);
    return;
  }
  const auto loop = std::make_shared<Loop>(n, body);
  for (std::size_t t = 0; t < helpers; ++t) executor.submit([loop] { loop->work(); });
  loop->work();
  std::unique_lock lock(loop->mutex);
  loop->finished.wait(lock, [&] { return loop->done == n; });
  if (loop->error) std::rethrow_exception(loop->error);
}

void parallelFor(Executor* executor, std::size_t n, const std::function<void(std::size_t)>& body,
                 unsigned threads) {
  if (executor != nullptr) {
    parallelFor(*executor, n, body, threads);
    return;
  }
  const std::size_t workers = std::min<std::size_t>(threads, n);
  if (workers <= 1) {
    for (std::size_t i = 0; i < n; ++i) body(i);
    return;
  }
  ThreadPool pool(static_cast<unsigned>(workers - 1));
  parallelFor(pool, n, body, threads);
}

}  // namespace regolith::core
