#pragma once
// An executor for tests that checks where work is sent: a real one-worker core::ThreadPool
// that counts the tasks it is given.

#include <regolith/core/Executor.hpp>

#include <atomic>
#include <functional>
#include <utility>

namespace regolith::test {

class CountingExecutor final : public core::Executor {
 public:
  void submit(std::function<void()> task) override {
    ++submitted;
    pool_.submit(std::move(task));
  }
  [[nodiscard]] unsigned concurrency() const noexcept override { return 1; }
  std::atomic<int> submitted{0};

 private:
  core::ThreadPool pool_{1};
};

}  // namespace regolith::test
