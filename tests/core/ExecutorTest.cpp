#include <regolith/core/Executor.hpp>

#include <gtest/gtest.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

using regolith::core::parallelFor;
using regolith::core::ThreadPool;

TEST(Executor, ParallelForRunsEveryIndexExactlyOnce) {
  ThreadPool pool(3);
  EXPECT_EQ(pool.concurrency(), 3U);
  for (const std::size_t n : {0UL, 1UL, 2UL, 7UL, 1000UL}) {
    std::vector<std::atomic<int>> hits(n);
    parallelFor(pool, n, [&](std::size_t i) { hits[i].fetch_add(1); });
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(hits[i].load(), 1) << i << " of " << n;
  }
}

TEST(Executor, ParallelForUsesSeveralThreadsAndTheCaller) {
  ThreadPool pool(2);
  std::mutex m;
  std::set<std::thread::id> ids;
  std::atomic<int> inside{0};
  std::atomic<int> most{0};
  parallelFor(pool, 64, [&](std::size_t) {
    const int now = inside.fetch_add(1) + 1;
    int seen = most.load();
    while (now > seen && !most.compare_exchange_weak(seen, now)) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    inside.fetch_sub(1);
    const std::lock_guard lock(m);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_GE(ids.size(), 2U);
  EXPECT_LE(most.load(), 3);  // two workers and the caller
}

TEST(Executor, ParallelForFromInsideATaskOfTheSamePoolDoesNotDeadlock) {
  ThreadPool pool(1);  // the only worker is busy with the outer loop
  std::atomic<int> inner{0};
  parallelFor(pool, 4,
              [&](std::size_t) { parallelFor(pool, 8, [&](std::size_t) { inner.fetch_add(1); }); });
  EXPECT_EQ(inner.load(), 32);
}

TEST(Executor, TheFirstExceptionIsRethrownAfterStartedIndicesFinish) {
  ThreadPool pool(2);
  std::atomic<int> running{0};
  std::atomic<int> ran{0};
  EXPECT_THROW(parallelFor(pool, 200,
                           [&](std::size_t i) {
                             running.fetch_add(1);
                             std::this_thread::sleep_for(std::chrono::microseconds(200));
                             ran.fetch_add(1);
                             running.fetch_sub(1);
                             if (i == 3) throw std::runtime_error("index 3");
                           }),
               std::runtime_error);
  EXPECT_EQ(running.load(), 0);  // nothing still running when the call returned
  EXPECT_LT(ran.load(), 200);    // no new index started after the failure
}

TEST(Executor, ThreadPoolRunsQueuedTasksBeforeItIsDestroyed) {
  std::atomic<int> done{0};
  {
    ThreadPool pool(2);
    for (int i = 0; i < 100; ++i) pool.submit([&] { done.fetch_add(1); });
  }
  EXPECT_EQ(done.load(), 100);
}

TEST(Executor, WithoutAnExecutorParallelForRunsOnAPoolMadeForTheCall) {
  std::mutex m;
  std::set<std::thread::id> ids;
  std::vector<std::atomic<int>> hits(64);
  parallelFor(
      nullptr, hits.size(),
      [&](std::size_t i) {
        hits[i].fetch_add(1);
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        const std::lock_guard lock(m);
        ids.insert(std::this_thread::get_id());
      },
      3);
  for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
  EXPECT_GE(ids.size(), 2U);  // the caller and the pool's workers
  // One thread: the caller runs every index itself.
  ids.clear();
  parallelFor(
      nullptr, 5, [&](std::size_t) { ids.insert(std::this_thread::get_id()); }, 1);
  EXPECT_EQ(ids, std::set<std::thread::id>{std::this_thread::get_id()});
  EXPECT_THROW(parallelFor(
                   nullptr, 8,
                   [](std::size_t i) {
                     if (i == 5) throw std::runtime_error("index 5");
                   },
                   2),
               std::runtime_error);
}

TEST(Executor, AvailableCoresIsTheAffinitySetAndSizesADefaultPool) {
  cpu_set_t all;
  CPU_ZERO(&all);
  ASSERT_EQ(sched_getaffinity(0, sizeof all, &all), 0);
  EXPECT_EQ(regolith::core::availableCores(), static_cast<unsigned>(CPU_COUNT(&all)));
  EXPECT_GE(regolith::core::availableCores(), 1U);
  // A thread bound to one processor (as taskset -c N, or mpirun's binding of a rank) has one
  // core: a default pool made there gets one worker, not hardware_concurrency().
  std::size_t first = 0;
  while (first < std::size_t{CPU_SETSIZE} && !CPU_ISSET(first, &all)) ++first;
  unsigned cores = 0, workers = 0;
  std::thread bound([&] {
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    if (sched_setaffinity(0, sizeof one, &one) != 0) return;
    cores = regolith::core::availableCores();
    ThreadPool pool;
    workers = pool.concurrency();
  });
  bound.join();
  EXPECT_EQ(cores, 1U);
  EXPECT_EQ(workers, 1U);
}
