// Prefetcher: background loading by priority, with cancellation.
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/store/Prefetcher.hpp>

#include "store/PagerFixture.hpp"
#include "support/CountingExecutor.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <future>
#include <mutex>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace regolith::test;

namespace {
std::shared_ptr<const Pager> sharedPager(Opened& o) {
  return std::make_shared<const Pager>(o.store, o.cache);
}
/// How many of the 4 × 4 patches of level 0 rows 100…399, cols 200…599 (patch rows 0…3,
/// cols 1…4 of 128) are resident.
std::size_t residentOfWindow(const PatchCache& cache, const Pager& pager) {
  std::size_t n = 0;
  for (std::size_t r = 0; r < 4; ++r) {
    for (std::size_t c = 1; c <= 4; ++c)
      n += cache.contains(pager.keyOf("dem", 0, r * 128, c * 128)) ? 1U : 0U;
  }
  return n;
}
}  // namespace

TEST(Prefetcher, LoadsEveryPatchOfTheRequestedWindows) {
  Opened o = openFixture();
  const auto pager = sharedPager(o);  // keys belong to the pager that made them
  Prefetcher pf(pager, 2);
  // Level 0 rows 100…399, cols 200…599 → patch rows 0…3, cols 1…4 of 128: 4 × 4 patches.
  const auto t = pf.request("dem", {{0, 100, 200, 300, 400}});
  pf.wait(t);
  for (std::size_t r = 0; r < 4; ++r) {
    for (std::size_t c = 1; c <= 4; ++c) {
      EXPECT_TRUE(o.cache->contains(pager->keyOf("dem", 0, r * 128, c * 128)));
    }
  }
  EXPECT_FALSE(o.cache->contains(pager->keyOf("dem", 0, 600, 0)));
  EXPECT_EQ(pf.stats().queued, 16u);
  EXPECT_EQ(pf.stats().loaded, 16u);
  // A query in the window is now a cache hit, not a load.
  const auto loads = o.cache->stats().loads;
  (void)pager->dem("dem").height(-500.0 + 300.0, 400.0 - 200.0);
  EXPECT_EQ(o.cache->stats().loads, loads);
}

TEST(Prefetcher, CoarseLevelsLoadBeforeFinerOnes) {
  Opened o = openFixture();
  Prefetcher pf(sharedPager(o), 1);
  std::mutex m;
  std::vector<std::uint32_t> order;
  pf.setOnLoaded([&](const PatchKey& k) {
    const std::lock_guard lock(m);
    order.push_back(k.level);
  });
  const auto windows = pf.focusWindows("dem", 350, 450, 200);
  ASSERT_EQ(windows.size(), o.store->grid("dem").levels);
  pf.wait(pf.request("dem", windows));
  ASSERT_FALSE(order.empty());
  EXPECT_TRUE(std::is_sorted(order.rbegin(), order.rend())) << "levels must not increase";
  EXPECT_EQ(order.front(), o.store->grid("dem").levels - 1);
  EXPECT_EQ(order.back(), 0u);
}

TEST(Prefetcher, HigherPriorityRequestsGoFirst) {
  Opened o = openFixture();
  Prefetcher pf(sharedPager(o), 1);
  std::mutex m;
  std::vector<std::uint32_t> rows;
  std::atomic<bool> gate{false};
  pf.setOnLoaded([&](const PatchKey& k) {
    while (!gate.load()) std::this_thread::yield();  // hold the single worker
    const std::lock_guard lock(m);
    rows.push_back(k.row);
  });
  const auto low = pf.request("dem", {{0, 0, 0, 128, 900}}, 0);     // patch row 0
  const auto high = pf.request("dem", {{0, 512, 0, 128, 900}}, 5);  // patch row 4
  gate = true;
  pf.wait(low);
  pf.wait(high);
  // The first patch may already have been taken from the low request before the high
  // one arrived; after it, every patch of the high request comes before the rest.
  ASSERT_EQ(rows.size(), 16u);
  std::size_t firstLow = rows[0] == 0 ? 1 : 0;
  for (std::size_t i = firstLow; i < firstLow + 8; ++i) EXPECT_EQ(rows[i], 4u) << i;
}

TEST(Prefetcher, CancelDropsQueuedWorkAndWaitReturns) {
  Opened o = openFixture();
  Prefetcher pf(sharedPager(o), 1);
  std::atomic<bool> gate{false};
  pf.setOnLoaded([&](const PatchKey&) {
    while (!gate.load()) std::this_thread::yield();
  });
  const auto t = pf.request("dem", {{0, 0, 0, 700, 900}});  // 6 × 8 = 48 patches
  pf.cancel(t);
  gate = true;
  pf.wait(t);
  pf.waitIdle();
  const PrefetchStats s = pf.stats();
  EXPECT_EQ(s.queued, 48u);
  EXPECT_GE(s.cancelled, 46u);
  EXPECT_EQ(s.loaded + s.cancelled, 48u);
}

TEST(Prefetcher, UnknownGridsAndLevelsThrowAtOnce) {
  Opened o = openFixture();
  Prefetcher pf(sharedPager(o), 1);
  EXPECT_THROW((void)pf.request("nope", {{0, 0, 0, 1, 1}}), StoreError);
  EXPECT_THROW((void)pf.request("dem", {{42, 0, 0, 1, 1}}), StoreError);
  EXPECT_THROW(Prefetcher(nullptr), InvalidArgument);
}

TEST(Prefetcher, DestructionWhileBusyJoinsCleanly) {
  Opened o = openFixture();
  {
    Prefetcher pf(sharedPager(o), 2);
    (void)pf.request("dem", {{0, 0, 0, 700, 900}});
  }  // the destructor cancels the queue and joins; no load is left running
  const auto loads = o.cache->stats().loads;
  EXPECT_LE(loads, 48u);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(o.cache->stats().loads, loads);
}

TEST(Prefetcher, PrefetchersShareTheExecutorTheyAreGivenAndStartNoThreads) {
  Opened o = openFixture();
  const auto pager = sharedPager(o);
  // One thread for two prefetchers: each loads as tasks that return when its queue is empty,
  // so neither holds the thread while the other has work.
  auto pool = std::make_shared<core::ThreadPool>(1);
  Prefetcher a(pager, pool), b(pager, pool);
  const auto ta = a.request("dem", {{0, 0, 0, 256, 256}});
  const auto tb = b.request("dem", {{0, 256, 256, 256, 256}});
  a.wait(ta);
  b.wait(tb);
  EXPECT_EQ(a.stats().loaded, 4u);
  EXPECT_EQ(b.stats().loaded, 4u);
  // The pool still runs other work: nothing of the prefetchers is parked on it.
  std::atomic<int> ran{0};
  core::parallelFor(*pool, 8, [&](std::size_t) { ran.fetch_add(1); });
  EXPECT_EQ(ran.load(), 8);
  // A second request after the queue drained starts a new task.
  const auto again = a.request("dem", {{1, 0, 0, 128, 128}});
  a.wait(again);
  EXPECT_EQ(a.stats().loaded, 5u);
  EXPECT_THROW(Prefetcher(pager, std::shared_ptr<core::Executor>()), InvalidArgument);
  try {
    Prefetcher(pager, std::size_t{0});
    ADD_FAILURE() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "store::Prefetcher(): threads is 0, expected >= 1");
  }
}

TEST(Prefetcher, APyramidsLevelsLoadTheWindowsTheyAreHintedInTheBackground) {
  Opened o = openFixture();
  const topo::GridPyramid pyramid = o.pager.pyramid("dem");
  EXPECT_EQ(o.cache->stats().loads, 0U) << "exporting reads nothing";
  // Level 0 rows 100…399, cols 200…599 → patch rows 0…3, cols 1…4 of 128: 4 × 4 patches,
  // and a window off the grid's edge, clipped.
  const topo::SampleSource::Window hint[] = {{100, 200, 300, 400}, {650, 850, 500, 500}};
  pyramid.levels[0].source->prefetch(hint);
  const auto resident = [&] {
    return residentOfWindow(*o.cache, o.pager) +
           (o.cache->contains(o.pager.keyOf("dem", 0, 699, 899)) ? 1U : 0U);
  };
  // The loads happen on the pyramid's own loader thread: wait for them (bounded).
  for (int i = 0; i < 6000 && resident() < 17; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(resident(), 17U);
  EXPECT_FALSE(o.cache->contains(o.pager.keyOf("dem", 0, 600, 0)));
  // Reading the hinted window is then all hits.
  const auto loads = o.cache->stats().loads;
  std::vector<float> out(300 * 400);
  pyramid.levels[0].source->readWindow(100, 200, 300, 400, out);
  EXPECT_EQ(o.cache->stats().loads, loads);
  // A source from Pager::source() takes the hint and loads nothing; nor does an empty hint.
  o.cache->clear();
  o.pager.source("dem", 1)->prefetch(hint);
  pyramid.levels[1].source->prefetch({});
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(o.cache->stats().residentBytes, 0U);
}

TEST(Prefetcher, APyramidGivenAnExecutorLoadsItsHintsThereAndMakesNoThread) {
  Opened o = openFixture();
  const auto executor = std::make_shared<CountingExecutor>();
  const topo::GridPyramid pyramid = o.pager.pyramid("dem", executor);
  EXPECT_EQ(executor->submitted, 0) << "exporting submits nothing";
  const topo::SampleSource::Window hint[] = {{100, 200, 300, 400}};  // 4 × 4 patches
  pyramid.levels[0].source->prefetch(hint);
  const auto resident = [&] { return residentOfWindow(*o.cache, o.pager); };
  for (int i = 0; i < 6000 && resident() < 16; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(resident(), 16U);
  // Loaded by the executor's tasks (a pyramid that made a thread of its own would submit
  // nothing): one task drains the queue, more only if it emptied meanwhile.
  EXPECT_GE(executor->submitted, 1);
}

TEST(Prefetcher, MayBeDestroyedOnItsExecutorsOnlyWorkerWithItsTaskQueuedBehind) {
  // A prefetcher on a shared one-worker executor, destroyed by a task on that worker while
  // its loading task waits in the queue behind: the destructor must not wait for that task
  // (it could never start), and the task, run later, must load nothing.
  Opened o = openFixture();
  std::promise<void> destroyed;
  auto done = destroyed.get_future();
  {
    const auto pool = std::make_shared<core::ThreadPool>(1);
    auto pf = std::make_unique<Prefetcher>(sharedPager(o), pool, 1);
    std::promise<void> gate;
    std::shared_future<void> open = gate.get_future().share();
    pool->submit([&pf, open, &destroyed] {
      open.wait();
      pf.reset();
      destroyed.set_value();
    });
    (void)pf->request("dem", {{0, 100, 200, 300, 400}});  // queued behind the task above
    gate.set_value();
    EXPECT_EQ(done.wait_for(std::chrono::seconds(60)), std::future_status::ready)
        << "the destructor waited for a task queued behind it";
  }  // the pool runs the queued loading task, which returns without loading, and joins
  EXPECT_EQ(o.cache->stats().loads, 0U);
}

TEST(Prefetcher, LoadIsAheadOfQueuedRequestsAndTheCallerLoadsWhileTheExecutorIsBusy) {
  Opened o = openFixture();
  const auto pager = sharedPager(o);
  const auto pool = std::make_shared<core::ThreadPool>(1);
  std::promise<void> gate;
  std::shared_future<void> open = gate.get_future().share();
  pool->submit([open] { open.wait(); });  // the executor's only worker is busy
  Prefetcher pf(pager, pool, 1);
  // A request queued first (patch rows 4…5, cols 0…1 of level 0), then a load of 4 × 4
  // other patches: the load returns with its patches resident though no task could run.
  const auto queued = pf.request("dem", {{0, 512, 0, 256, 256}});
  pf.load("dem", {{0, 100, 200, 300, 400}, {0, 150, 250, 10, 10}});  // the second inside the first
  EXPECT_EQ(residentOfWindow(*o.cache, *pager), 16U);
  EXPECT_FALSE(o.cache->contains(pager->keyOf("dem", 0, 512, 0))) << "the request waits";
  EXPECT_EQ(pf.stats().loaded, 16U) << "each patch once, though the windows overlap";
  gate.set_value();
  pf.wait(queued);
  EXPECT_TRUE(o.cache->contains(pager->keyOf("dem", 0, 512, 0)));
  EXPECT_EQ(pf.stats().loaded, 20U);
  EXPECT_THROW(pf.load("nosuch", {{0, 0, 0, 1, 1}}), StoreError);
  pf.load("dem", {});  // nothing to load: returns at once
}

TEST(Prefetcher, APyramidsLevelLoadsAWindowBeforeReturningAndAPagerSourceLoadsNothing) {
  Opened o = openFixture();
  const topo::GridPyramid pyramid = o.pager.pyramid("dem");
  const topo::SampleSource::Window window[] = {{100, 200, 300, 400}};
  pyramid.levels[0].source->load(window);
  EXPECT_EQ(residentOfWindow(*o.cache, o.pager), 16U);
  const auto loads = o.cache->stats().loads;
  std::vector<float> out(300 * 400);
  pyramid.levels[0].source->readWindow(100, 200, 300, 400, out);
  EXPECT_EQ(o.cache->stats().loads, loads) << "the read is all hits";
  o.cache->clear();
  o.pager.source("dem", 0)->load(window);
  EXPECT_EQ(o.cache->stats().residentBytes, 0U);
}

TEST(Prefetcher, ALevelLeavesWindowsOfOverHalfItsCacheToTheReads) {
  Opened o = openFixture();
  // Room for three 128² patches: a window of 16 would evict its first patches before they
  // were read, so load() leaves it to the reads; one patch is loaded.
  const auto small = std::make_shared<PatchCache>(3 * (128 * 128 * sizeof(float) + 4096));
  const Pager pager(o.store, small);
  const topo::GridPyramid pyramid = pager.pyramid("dem");
  const topo::SampleSource::Window big[] = {{100, 200, 300, 400}}, one[] = {{0, 0, 10, 10}};
  pyramid.levels[0].source->load(big);
  EXPECT_EQ(small->stats().loads, 0U);
  pyramid.levels[0].source->load(one);
  EXPECT_EQ(small->stats().loads, 1U);
  EXPECT_TRUE(small->contains(pager.keyOf("dem", 0, 0, 0)));
}

TEST(Prefetcher, LoadsPatchesALoadAsksForOnTheCallersThreadOnly) {
  // The executor's tasks leave a load()'s patches to its caller (they keep to the
  // requests), so the loads a renderer waits for run where they ran before the Prefetcher
  // took them: every patch of the window is loaded on this thread.
  Opened o = openFixture();
  Prefetcher pf(sharedPager(o), 2);
  std::mutex m;
  std::vector<std::thread::id> threads;
  pf.setOnLoaded([&](const PatchKey&) {
    const std::lock_guard lock(m);
    threads.push_back(std::this_thread::get_id());
  });
  pf.load("dem", {{0, 100, 200, 300, 400}});
  const std::lock_guard lock(m);
  ASSERT_EQ(threads.size(), 16U);
  for (const std::thread::id id : threads) EXPECT_EQ(id, std::this_thread::get_id());
}
