#pragma once
/// \file
/// Where Regolith runs work off the caller's thread. Nothing in Regolith starts threads of
/// its own: a module that runs work in parallel or in the background accepts an Executor
/// (docs/architecture.md). ThreadPool is the one implementation the library ships.
///
/// Thread-safety: submit() and concurrency() may be called from any thread.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace regolith::core {

/// Runs submitted tasks, in any order, on threads it owns.
class Executor {
 public:
  Executor() = default;
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;
  Executor(Executor&&) = delete;
  Executor& operator=(Executor&&) = delete;
  virtual ~Executor() = default;

  /// Queues `task`. A task must not throw: an exception escaping it terminates the process,
  /// as it would on a bare std::thread (parallelFor() catches and forwards them).
  virtual void submit(std::function<void()> task) = 0;

  /// How many tasks can run at once.
  [[nodiscard]] virtual unsigned concurrency() const noexcept = 0;
};

/// The processors this process may run on: the size of its CPU affinity set
/// (sched_getaffinity(2): one under `taskset -c 0`, or in an MPI rank that mpirun bound to a
/// core), else std::thread::hardware_concurrency(); at least 1. What a default thread count
/// should use: more threads than this share the same cores and only add switching.
[[nodiscard]] unsigned availableCores() noexcept;

/// A fixed set of worker threads taking tasks from one queue. The destructor runs every task
/// already queued, then joins the workers.
class ThreadPool final : public Executor {
 public:
  /// `threads` workers; 0 means availableCores().
  explicit ThreadPool(unsigned threads = 0);
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;
  ThreadPool(ThreadPool&&) = delete;
  ThreadPool& operator=(ThreadPool&&) = delete;
  ~ThreadPool() override;

  void submit(std::function<void()> task) override;
  [[nodiscard]] unsigned concurrency() const noexcept override {
    return static_cast<unsigned>(workers_.size());
  }

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> queue_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

/// Runs `task` on `executor` and returns the future of its result; an exception it throws
/// reaches the future's get(). The future does not wait in its destructor (unlike
/// std::async's): whoever owns what the task uses must wait for it before destroying that.
template <typename F>
[[nodiscard]] std::future<std::invoke_result_t<std::decay_t<F>&>> submitTask(Executor& executor,
                                                                             F&& task) {
  using R = std::invoke_result_t<std::decay_t<F>&>;
  auto job = std::make_shared<std::packaged_task<R()>>(std::forward<F>(task));
  std::future<R> result = job->get_future();
  executor.submit([job] { (*job)(); });
  return result;
}

/// Runs body(0) … body(n − 1), each exactly once, on the calling thread and on up to
/// `maxTasks − 1` tasks of `executor` (0: the executor's concurrency). Returns when every
/// index has run. The calling thread takes indices too, so a call from inside a task of the
/// same executor cannot deadlock. After the first exception no new index starts; that
/// exception is rethrown once the indices already started have finished.
void parallelFor(Executor& executor, std::size_t n, const std::function<void(std::size_t)>& body,
                 unsigned maxTasks = 0);

/// As above, on `executor` if it is not null, else on a core::ThreadPool of up to
/// `threads` − 1 workers made for the call (none when `threads` or `n` is at most 1: the
/// caller then runs every index). `threads` counts the caller and must be ≥ 1.
void parallelFor(Executor* executor, std::size_t n, const std::function<void(std::size_t)>& body,
                 unsigned threads);

}  // namespace regolith::core
