// PatchCache: counting, the three eviction policies, the byte budget (also under threads),
// single loads per key, loader errors, clear().
#include <regolith/core/Error.hpp>
#include <regolith/store/PatchCache.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace std::chrono_literals;

namespace {

constexpr std::array<CachePolicy, 3> kPolicies{CachePolicy::HitCount, CachePolicy::Lru,
                                               CachePolicy::DecayingHitCount};

PatchKey key(std::uint32_t col, std::uint32_t row = 0, std::uint32_t level = 0) {
  return PatchKey{7, level, row, col};
}

std::shared_ptr<const Patch> makePatch(const PatchKey& k, std::size_t samples = 16) {
  auto p = std::make_shared<Patch>();
  p->key = k;
  p->rows = 1;
  p->cols = samples;
  p->samples.assign(samples, static_cast<float>(k.col));
  return p;
}

/// Budget charged for a patch of `samples` floats.
std::size_t bytesOf(std::size_t samples = 16) { return makePatch({}, samples)->bytes(); }

/// A loader that counts its calls and makes patches of a fixed size.
struct CountingLoader {
  std::atomic<int> calls{0};
  std::size_t samples = 16;
  PatchCache::Loader fn() {
    return [this](const PatchKey& k) {
      calls.fetch_add(1);
      return makePatch(k, samples);
    };
  }
};

/// Waits (outside the cache's lock) until `n` requests have missed, or 10 s pass.
void waitForMisses(const PatchCache& cache, std::uint64_t n) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (cache.stats().misses < n && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(100us);
  }
}

}  // namespace

TEST(PatchCache, PatchBytesAreTheSamplesPlusAFixedOverhead) {
  const std::size_t overhead = bytesOf(0);
  EXPECT_GT(overhead, 0U);
  EXPECT_EQ(bytesOf(65536), 65536 * sizeof(float) + overhead);
  EXPECT_EQ(bytesOf(1), sizeof(float) + overhead);
}

TEST(PatchCache, NamesPoliciesAndRejectsAZeroDecayPeriod) {
  EXPECT_EQ(toString(CachePolicy::HitCount), "HitCount");
  EXPECT_EQ(toString(CachePolicy::Lru), "Lru");
  EXPECT_EQ(toString(CachePolicy::DecayingHitCount), "DecayingHitCount");
  EXPECT_THROW(PatchCache(1000, CachePolicy::DecayingHitCount, 0), InvalidArgument);
  const PatchCache cache(1000, CachePolicy::Lru);
  EXPECT_EQ(cache.policy(), CachePolicy::Lru);
  EXPECT_EQ(cache.capacityBytes(), 1000U);
}

TEST(PatchCache, CountsHitsMissesLoadsAndBytes) {
  PatchCache cache(10 * bytesOf());
  CountingLoader loader;

  const auto a = cache.get(key(1), loader.fn());  // miss, load
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->key, key(1));
  EXPECT_EQ(cache.get(key(1), loader.fn()), a);  // hit, same object
  EXPECT_EQ(cache.find(key(2)), nullptr);        // miss, no load
  EXPECT_EQ(cache.find(key(1)), a);              // hit
  EXPECT_TRUE(cache.contains(key(1)));           // not counted
  EXPECT_FALSE(cache.contains(key(2)));
  cache.insert(makePatch(key(3), 32));  // a load, neither hit nor miss

  CacheStats s = cache.stats();
  EXPECT_EQ(loader.calls.load(), 1);
  EXPECT_EQ(s.hits, 2U);
  EXPECT_EQ(s.misses, 2U);
  EXPECT_EQ(s.loads, 2U);
  EXPECT_EQ(s.evictions, 0U);
  EXPECT_EQ(s.bytesLoaded, bytesOf(16) + bytesOf(32));
  EXPECT_EQ(s.residentBytes, bytesOf(16) + bytesOf(32));
  EXPECT_EQ(s.residentPatches, 2U);
  EXPECT_EQ(s.capacityBytes, 10 * bytesOf());

  // Inserting a key that is resident keeps the resident patch; the load still counts.
  cache.insert(makePatch(key(1), 64));
  EXPECT_EQ(cache.find(key(1)), a);
  s = cache.stats();
  EXPECT_EQ(s.loads, 3U);
  EXPECT_EQ(s.residentBytes, bytesOf(16) + bytesOf(32));

  cache.resetStats();
  s = cache.stats();
  EXPECT_EQ(s.hits + s.misses + s.loads + s.evictions + s.bytesLoaded, 0U);
  EXPECT_EQ(s.residentPatches, 2U);  // resetting counters evicts nothing
  EXPECT_EQ(s.residentBytes, bytesOf(16) + bytesOf(32));
}

TEST(PatchCache, HitCountEvictsTheLeastHitPatchWhereLruEvictsTheLeastRecent) {
  // A, B, C loaded; then B is hit 3 times, C twice and A once, A last. On loading D:
  //   HitCount (the paper) evicts A, the least hit, although it was used last;
  //   Lru evicts B, the least recently used, although it is the most hit.
  const auto victimOf = [](CachePolicy policy) {
    PatchCache cache(3 * bytesOf(), policy, 1'000'000);
    CountingLoader loader;
    for (std::uint32_t c : {0U, 1U, 2U}) (void)cache.get(key(c), loader.fn());
    for (std::uint32_t c : {1U, 1U, 1U, 2U, 2U, 0U}) EXPECT_NE(cache.find(key(c)), nullptr);
    (void)cache.get(key(3), loader.fn());
    EXPECT_EQ(cache.stats().evictions, 1U);
    EXPECT_TRUE(cache.contains(key(3)));
    std::vector<std::uint32_t> gone;
    for (std::uint32_t c : {0U, 1U, 2U}) {
      if (!cache.contains(key(c))) gone.push_back(c);
    }
    return gone;
  };
  EXPECT_EQ(victimOf(CachePolicy::HitCount), std::vector<std::uint32_t>{0});
  EXPECT_EQ(victimOf(CachePolicy::Lru), std::vector<std::uint32_t>{1});
  // Within a decay period the aging policy ranks like the paper's.
  EXPECT_EQ(victimOf(CachePolicy::DecayingHitCount), std::vector<std::uint32_t>{0});
}

TEST(PatchCache, HitCountBreaksTiesByLeastRecentUse) {
  PatchCache cache(3 * bytesOf(), CachePolicy::HitCount);
  CountingLoader loader;
  // No hits yet: the oldest load goes first.
  for (std::uint32_t c : {0U, 1U, 2U}) (void)cache.get(key(c), loader.fn());
  (void)cache.get(key(3), loader.fn());
  EXPECT_FALSE(cache.contains(key(0)));
  // 1, 2, 3 each hit once, in the order 2, 3, 1: 2 is the least recent of the tied.
  for (std::uint32_t c : {2U, 3U, 1U}) EXPECT_NE(cache.find(key(c)), nullptr);
  (void)cache.get(key(4), loader.fn());  // 4 has 0 hits, 1 and 3 have 1: 2 goes
  EXPECT_FALSE(cache.contains(key(2)));
  EXPECT_TRUE(cache.contains(key(1)));
  EXPECT_TRUE(cache.contains(key(3)));
  // The newcomer, with no hits, is the next victim (the paper's policy as written).
  (void)cache.get(key(5), loader.fn());
  EXPECT_FALSE(cache.contains(key(4)));
  EXPECT_TRUE(cache.contains(key(5)));
}

TEST(PatchCache, LruEvictsInOrderOfLastUse) {
  PatchCache cache(3 * bytesOf(), CachePolicy::Lru);
  CountingLoader loader;
  for (std::uint32_t c : {0U, 1U, 2U}) (void)cache.get(key(c), loader.fn());
  EXPECT_NE(cache.find(key(0)), nullptr);  // recency now 1, 2, 0
  EXPECT_TRUE(cache.contains(key(1)));     // contains() does not touch
  const std::vector<std::uint32_t> expectedVictims{1, 2, 0, 3};
  for (std::uint32_t i = 0; i < expectedVictims.size(); ++i) {
    (void)cache.get(key(10 + i), loader.fn());
    EXPECT_FALSE(cache.contains(key(expectedVictims[i]))) << "load " << i;
    EXPECT_EQ(cache.stats().residentPatches, 3U);
  }
}

TEST(PatchCache, DecayingHitCountLetsAnOldPopularPatchBeEvicted) {
  // A is hit 63 times, then B 39 times (about 5 decay periods of 8 accesses later). On
  // loading C the paper's policy keeps A (63 > 39 hits); the aging policy has halved A's
  // count five times or more (63 -> < 2) while B's last period alone counts 8, so A goes.
  const auto survivors = [](CachePolicy policy) {
    PatchCache cache(2 * bytesOf(), policy, 8);
    CountingLoader loader;
    for (int i = 0; i < 64; ++i) (void)cache.get(key(0), loader.fn());
    for (int i = 0; i < 40; ++i) (void)cache.get(key(1), loader.fn());
    (void)cache.get(key(2), loader.fn());
    EXPECT_EQ(loader.calls.load(), 3);
    return std::array<bool, 2>{cache.contains(key(0)), cache.contains(key(1))};
  };
  EXPECT_EQ(survivors(CachePolicy::HitCount), (std::array<bool, 2>{true, false}));
  EXPECT_EQ(survivors(CachePolicy::DecayingHitCount), (std::array<bool, 2>{false, true}));
}

TEST(PatchCache, DecayingHitCountSurvivesManyRescales) {
  // A decay period of one access: thousands of periods pass, the scores are rescaled many
  // times and A's old hits underflow to nothing. Ties then fall back to recency.
  PatchCache cache(3 * bytesOf(), CachePolicy::DecayingHitCount, 1);
  CountingLoader loader;
  for (int i = 0; i < 11; ++i) (void)cache.get(key(0), loader.fn());
  for (int i = 0; i < 5000; ++i) (void)cache.get(key(1), loader.fn());
  (void)cache.get(key(2), loader.fn());
  (void)cache.get(key(3), loader.fn());  // A (old, decayed to 0) goes, not the newer C
  EXPECT_FALSE(cache.contains(key(0)));
  EXPECT_TRUE(cache.contains(key(1)));
  EXPECT_TRUE(cache.contains(key(2)));
  EXPECT_TRUE(cache.contains(key(3)));
}

TEST(PatchCache, EveryPolicyEvictsWhatAReferenceModelEvicts) {
  // A naive model: scores kept without rescaling, the victim found by a linear search for
  // the smallest (score, last use). Equal-size patches, random requests; the resident sets
  // must agree after every request.
  constexpr std::uint32_t kKeys = 16;
  constexpr std::size_t kCapacity = 5;
  constexpr std::uint64_t kPeriod = 7;  // 700 decay periods in 5000 requests: many rescales
  for (CachePolicy policy : kPolicies) {
    SCOPED_TRACE(std::string(toString(policy)));
    PatchCache cache(kCapacity * bytesOf(), policy, kPeriod);
    CountingLoader loader;
    struct Model {
      double score = 0.0;
      std::uint64_t lastUse = 0;
    };
    std::vector<std::optional<Model>> model(kKeys);
    std::uint64_t clock = 0;
    std::uint64_t accesses = 0;
    int epoch = 0;
    std::mt19937 rng(7);
    // Skewed requests, so that hit counts differ a lot between keys.
    std::geometric_distribution<std::uint32_t> anyKey(0.15);
    for (int i = 0; i < 5000; ++i) {
      const std::uint32_t c = anyKey(rng) % kKeys;
      if (++accesses % kPeriod == 0) ++epoch;
      (void)cache.get(key(c), loader.fn());
      if (auto& m = model[c]) {
        m->score += policy == CachePolicy::DecayingHitCount ? std::ldexp(1.0, epoch) : 1.0;
        m->lastUse = ++clock;
      } else {
        std::size_t resident = 0;
        for (const auto& r : model) resident += r ? 1U : 0U;
        if (resident == kCapacity) {
          std::size_t victim = kKeys;
          for (std::size_t k = 0; k < kKeys; ++k) {
            if (!model[k]) continue;
            const bool lower = victim == kKeys ||
                               (policy == CachePolicy::Lru
                                    ? model[k]->lastUse < model[victim]->lastUse
                                    : std::pair(model[k]->score, model[k]->lastUse) <
                                          std::pair(model[victim]->score, model[victim]->lastUse));
            if (lower) victim = k;
          }
          model[victim].reset();
        }
        model[c] = Model{0.0, ++clock};
      }
      for (std::uint32_t k = 0; k < kKeys; ++k) {
        ASSERT_EQ(cache.contains(key(k)), model[k].has_value()) << "request " << i << ", key " << k;
      }
    }
    EXPECT_GT(cache.stats().evictions, 100U);
  }
}

TEST(PatchCache, PatchLargerThanTheBudgetIsReturnedButNotKept) {
  for (CachePolicy policy : kPolicies) {
    SCOPED_TRACE(std::string(toString(policy)));
    PatchCache cache(2 * bytesOf(), policy);
    CountingLoader small;
    (void)cache.get(key(0), small.fn());
    CountingLoader big;
    big.samples = 1000;
    const auto p = cache.get(key(1), big.fn());
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(p->samples.size(), 1000U);
    EXPECT_FALSE(cache.contains(key(1)));
    EXPECT_TRUE(cache.contains(key(0)));  // nothing was evicted for it
    cache.insert(makePatch(key(2), 1000));
    EXPECT_FALSE(cache.contains(key(2)));
    const CacheStats s = cache.stats();
    EXPECT_EQ(s.residentBytes, bytesOf());
    EXPECT_EQ(s.evictions, 0U);
    EXPECT_EQ(s.loads, 3U);
    (void)cache.get(key(1), big.fn());  // not kept, so loaded again
    EXPECT_EQ(big.calls.load(), 2);
  }
}

TEST(PatchCache, ShrinkingTheCapacityEvictsAtOnce) {
  for (CachePolicy policy : kPolicies) {
    SCOPED_TRACE(std::string(toString(policy)));
    PatchCache cache(4 * bytesOf(), policy);
    CountingLoader loader;
    for (std::uint32_t c : {0U, 1U, 2U, 3U}) (void)cache.get(key(c), loader.fn());
    for (std::uint32_t c : {2U, 3U}) EXPECT_NE(cache.find(key(c)), nullptr);
    cache.setCapacityBytes(2 * bytesOf() + 1);
    CacheStats s = cache.stats();
    EXPECT_EQ(s.capacityBytes, 2 * bytesOf() + 1);
    EXPECT_EQ(s.residentPatches, 2U);
    EXPECT_EQ(s.evictions, 2U);
    EXPECT_TRUE(cache.contains(key(2)));  // the hit and recent ones stay, in every policy
    EXPECT_TRUE(cache.contains(key(3)));
    cache.setCapacityBytes(0);
    s = cache.stats();
    EXPECT_EQ(s.residentPatches, 0U);
    EXPECT_EQ(s.residentBytes, 0U);
    cache.setCapacityBytes(8 * bytesOf());  // growing evicts nothing and allows loads again
    (void)cache.get(key(0), loader.fn());
    EXPECT_TRUE(cache.contains(key(0)));
  }
}

TEST(PatchCache, ClearEvictsEverything) {
  PatchCache cache(8 * bytesOf(), CachePolicy::HitCount);
  CountingLoader loader;
  for (std::uint32_t c : {0U, 1U, 2U}) (void)cache.get(key(c), loader.fn());
  (void)cache.get(key(1), loader.fn());
  cache.clear();
  CacheStats s = cache.stats();
  EXPECT_EQ(s.residentPatches, 0U);
  EXPECT_EQ(s.residentBytes, 0U);
  EXPECT_EQ(s.evictions, 3U);
  EXPECT_EQ(s.capacityBytes, 8 * bytesOf());
  for (std::uint32_t c : {0U, 1U, 2U}) EXPECT_FALSE(cache.contains(key(c)));
  (void)cache.get(key(1), loader.fn());
  EXPECT_EQ(loader.calls.load(), 4);
  EXPECT_TRUE(cache.contains(key(1)));
}

TEST(PatchCache, ResidentBytesNeverExceedTheCapacityUnderRandomOperations) {
  constexpr int kOps = 100'000;
  constexpr std::uint32_t kKeys = 64;
  for (CachePolicy policy : kPolicies) {
    SCOPED_TRACE(std::string(toString(policy)));
    std::mt19937 rng(20261122);
    std::uniform_int_distribution<std::uint32_t> anyKey(0, kKeys - 1);
    std::uniform_int_distribution<std::size_t> anySize(0, 256);
    std::uniform_int_distribution<int> anyOp(0, 99);
    PatchCache cache(16 * bytesOf(), policy, 3);  // short period: many decays and rescales
    std::uint64_t accesses = 0;
    std::size_t mostResident = 0;
    for (int i = 0; i < kOps; ++i) {
      const int op = anyOp(rng);
      const PatchKey k = key(anyKey(rng));
      // Now and then a patch bigger than any budget used below.
      const std::size_t samples = anyOp(rng) == 0 ? 5000 : anySize(rng);
      if (op < 60) {
        const auto p = cache.get(k, [&](const PatchKey& kk) { return makePatch(kk, samples); });
        ASSERT_EQ(p->key, k);
        ++accesses;
      } else if (op < 75) {
        const auto p = cache.find(k);
        ASSERT_TRUE(p == nullptr || p->key == k);
        ++accesses;
      } else if (op < 88) {
        cache.insert(makePatch(k, samples));
      } else if (op < 93) {
        cache.setCapacityBytes(std::uniform_int_distribution<std::size_t>(0, 40 * bytesOf())(rng));
      } else if (op < 94) {
        cache.clear();
      } else {
        (void)cache.contains(k);
      }
      const CacheStats s = cache.stats();
      ASSERT_LE(s.residentBytes, s.capacityBytes) << "after operation " << i;
      ASSERT_EQ(s.hits + s.misses, accesses);
      // The cache's own peak is the most it ever held: resident bytes grow only by one
      // insertion per operation, and every operation is sampled here.
      mostResident = std::max(mostResident, s.residentBytes);
      ASSERT_EQ(s.peakResidentBytes, mostResident) << "after operation " << i;
      if (i % 1000 == 0) {
        std::size_t resident = 0;
        for (std::uint32_t c = 0; c < kKeys; ++c) resident += cache.contains(key(c)) ? 1U : 0U;
        ASSERT_EQ(resident, s.residentPatches);
        ASSERT_LE(s.residentPatches * bytesOf(0), s.residentBytes);
      }
    }
    EXPECT_GT(cache.stats().evictions, 0U);
    // resetStats() starts the peak again from what is resident now.
    cache.resetStats();
    EXPECT_EQ(cache.stats().peakResidentBytes, cache.stats().residentBytes);
  }
}

TEST(PatchCache, ResidentBytesNeverExceedTheCapacityUnderEightThreads) {
  constexpr int kThreads = 8;
  constexpr int kGetsPerThread = 1000;
  constexpr std::uint32_t kKeys = 48;
  for (CachePolicy policy : kPolicies) {
    SCOPED_TRACE(std::string(toString(policy)));
    PatchCache cache(6 * bytesOf(64), policy, 64);
    std::atomic<int> loads{0};
    std::atomic<int> overBudget{0};
    std::atomic<int> wrongPatch{0};
    const PatchCache::Loader loader = [&](const PatchKey& k) {
      loads.fetch_add(1);
      std::this_thread::sleep_for(20us);
      return makePatch(k, 16 + 8 * (k.col % 8U));  // sizes differ per key
    };
    std::vector<std::thread> threads;
    threads.reserve(kThreads);
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&, t] {
        std::mt19937 rng(static_cast<std::uint32_t>(1000 + t));
        std::uniform_int_distribution<std::uint32_t> anyKey(0, kKeys - 1);
        for (int i = 0; i < kGetsPerThread; ++i) {
          const PatchKey k = key(anyKey(rng));
          const auto p = cache.get(k, loader);
          if (p == nullptr || p->key != k) wrongPatch.fetch_add(1);
          const CacheStats s = cache.stats();
          if (s.residentBytes > s.capacityBytes) overBudget.fetch_add(1);
          if (t == 0 && i % 100 == 50) {  // one thread also moves the budget
            cache.setCapacityBytes(((i / 100) % 2 == 0 ? 3 : 6) * bytesOf(64));
          }
        }
      });
    }
    for (auto& th : threads) th.join();
    const CacheStats s = cache.stats();
    EXPECT_EQ(overBudget.load(), 0);
    EXPECT_EQ(wrongPatch.load(), 0);
    EXPECT_LE(s.residentBytes, s.capacityBytes);
    EXPECT_EQ(s.hits + s.misses, static_cast<std::uint64_t>(kThreads) * kGetsPerThread);
    EXPECT_EQ(s.loads, static_cast<std::uint64_t>(loads.load()));
    EXPECT_LE(s.loads, s.misses);  // waiters on another thread's load miss without loading
  }
}

TEST(PatchCache, ConcurrentRequestsForOneKeyShareOneLoad) {
  constexpr int kThreads = 8;
  PatchCache cache(4 * bytesOf());
  std::atomic<int> calls{0};
  // The loader holds on until all eight requests have missed, so all of them are waiting
  // while it runs.
  const PatchCache::Loader loader = [&](const PatchKey& k) {
    calls.fetch_add(1);
    waitForMisses(cache, kThreads);
    return makePatch(k);
  };
  std::vector<std::shared_ptr<const Patch>> got(kThreads);
  std::vector<std::thread> threads;
  threads.reserve(kThreads);
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] { got[static_cast<std::size_t>(t)] = cache.get(key(5), loader); });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(calls.load(), 1);
  for (const auto& p : got) {
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(p, got[0]);  // one patch object, shared
  }
  const CacheStats s = cache.stats();
  EXPECT_EQ(s.misses, std::uint64_t{kThreads});
  EXPECT_EQ(s.hits, 0U);
  EXPECT_EQ(s.loads, 1U);
  EXPECT_EQ(s.residentPatches, 1U);
}

TEST(PatchCache, LoadsOfDifferentKeysRunInParallelOutsideTheLock) {
  // Each loader waits until the other one has started: that only finishes if both loads
  // run at once. Meanwhile the cache answers other calls.
  PatchCache cache(4 * bytesOf());
  cache.insert(makePatch(key(0)));
  std::atomic<int> inLoader{0};
  std::atomic<int> sawBoth{0};
  const PatchCache::Loader loader = [&](const PatchKey& k) {
    inLoader.fetch_add(1);
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (inLoader.load() < 2 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(100us);
    }
    if (inLoader.load() == 2) sawBoth.fetch_add(1);
    return makePatch(k);
  };
  std::thread a([&] { (void)cache.get(key(1), loader); });
  std::thread b([&] { (void)cache.get(key(2), loader); });
  while (inLoader.load() < 2) std::this_thread::sleep_for(100us);
  EXPECT_NE(cache.find(key(0)), nullptr);  // not blocked by the loads in flight
  a.join();
  b.join();
  EXPECT_EQ(sawBoth.load(), 2);
  EXPECT_TRUE(cache.contains(key(1)));
  EXPECT_TRUE(cache.contains(key(2)));
  EXPECT_EQ(cache.stats().loads, 3U);
}

TEST(PatchCache, LoaderExceptionsReachEveryWaiterAndNothingIsInserted) {
  constexpr int kThreads = 8;
  PatchCache cache(4 * bytesOf());
  std::atomic<int> calls{0};
  const PatchCache::Loader failing = [&](const PatchKey&) -> std::shared_ptr<const Patch> {
    calls.fetch_add(1);
    waitForMisses(cache, kThreads);
    throw std::runtime_error("read failed: disk on fire");
  };
  // Every thread catches the same exception object. Each keeps an exception_ptr to it until
  // after join(), so the object is freed on this thread: exception_ptr's reference count
  // lives in the uninstrumented libstdc++, and ThreadSanitizer would otherwise report the
  // free on the last thread out as a race with another thread's what().
  std::vector<std::string> messages(kThreads);
  std::vector<std::exception_ptr> keepAlive(kThreads);
  std::vector<std::thread> threads;
  threads.reserve(kThreads);
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      const auto i = static_cast<std::size_t>(t);
      try {
        (void)cache.get(key(9), failing);
      } catch (const std::runtime_error& e) {
        keepAlive[i] = std::current_exception();
        messages[i] = e.what();
      }
    });
  }
  for (auto& th : threads) th.join();
  keepAlive.clear();
  EXPECT_EQ(calls.load(), 1);
  for (const auto& m : messages) EXPECT_EQ(m, "read failed: disk on fire");
  EXPECT_FALSE(cache.contains(key(9)));
  CacheStats s = cache.stats();
  EXPECT_EQ(s.loads, 0U);
  EXPECT_EQ(s.residentBytes, 0U);

  // A loader that returns nothing is an error too.
  EXPECT_THROW((void)cache.get(key(9), [](const PatchKey&) { return nullptr; }), InvalidArgument);
  EXPECT_FALSE(cache.contains(key(9)));

  // The key is not poisoned: a later load succeeds.
  CountingLoader good;
  const auto p = cache.get(key(9), good.fn());
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(good.calls.load(), 1);
  EXPECT_TRUE(cache.contains(key(9)));
  s = cache.stats();
  EXPECT_EQ(s.loads, 1U);
  EXPECT_EQ(s.misses, std::uint64_t{kThreads} + 2);
}

TEST(PatchCache, BlockTablesAreOnePerGridLevelAndRefuseOtherSizes) {
  PatchCache cache(1 << 20);
  EXPECT_THROW((void)cache.blockTable(1, 0, 100, 100, 0, 16), InvalidArgument);
  const auto t = cache.blockTable(1, 0, 100, 100, 16, 16);  // the failed call left nothing
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(cache.blockTable(1, 0, 100, 100, 16, 16), t);
  EXPECT_NE(cache.blockTable(1, 1, 50, 50, 16, 16), t);
  try {
    (void)cache.blockTable(1, 0, 100, 100, 32, 32);
    FAIL() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("100x100 samples in 16x16 patches"), std::string::npos)
        << e.what();
  }
}
