#pragma once
// An executor for tests that checks where work runs: a real one-worker core::ThreadPool that
// counts the tasks it is given and records the threads that ran them.

#include <regolith/core/Executor.hpp>

#include <atomic>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace regolith::test {

class CountingExecutor final : public core::Executor {
 public:
  void submit(std::function<void()> task) override {
    ++submitted;
    pool_.submit([this, task = std::move(task)] {
      {
        const std::lock_guard lock(m);
        ran.push_back(std::this_thread::get_id());
      }
      task();
    });
  }
  [[nodiscard]] unsigned concurrency() const noexcept override { return 1; }
  std::atomic<int> submitted{0};
  std::mutex m;
  std::vector<std::thread::id> ran;  ///< the thread of each task run, in order (under m)

 private:
  core::ThreadPool pool_{1};
};

}  // namespace regolith::test
