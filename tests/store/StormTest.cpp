// Storm (issue 17): 16 threads query a paged DEM and a paged planet (single heights and
// surfaces, batches of heights and surfaces) while a Prefetcher moves its focus at random,
// all through one PatchCache whose budget holds only a few patches, so patches are loaded,
// evicted and reloaded all the time. Every answer must be bit-identical to the one computed
// single-threaded before the storm, and a watcher thread samples the cache continuously:
// its resident bytes never exceed the budget.
//
// The test runs for REGOLITH_STORM_SECONDS seconds (2 by default; scripts/storm.sh runs 60)
// and prints the counts (docs/reliability.md, "Storm").
#include <regolith/store/Prefetcher.hpp>

#include "store/PagerFixture.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace regolith::test;

namespace {

enum Kind : std::size_t {
  DemHeight,
  DemSurface,
  DemHeightsBatch,
  DemSurfacesBatch,
  PlanetSurface,
  PlanetHeightsBatch,
  KindCount
};
constexpr std::array<const char*, KindCount> kKindNames{
    "DEM height",         "DEM surface (normal)", "DEM heights batch",
    "DEM surfaces batch", "planet surface",       "planet heights batch"};

constexpr std::size_t kChunk = 64;    // points per job
constexpr std::size_t kChunks = 96;   // jobs per kind
constexpr std::size_t kThreads = 16;  // query threads

/// Points of one job: DEM grid coordinates (x, y) or planet (lat, lon), some outside.
struct Chunk {
  std::vector<double> a, b;
};

std::vector<Chunk> makeChunks(bool planet, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ua(planet ? -90.0 : -520.0, planet ? 90.0 : 420.0);
  std::uniform_real_distribution<double> ub(planet ? -180.0 : -320.0, planet ? 180.0 : 420.0);
  std::vector<Chunk> chunks(kChunks);
  for (Chunk& c : chunks) {
    for (std::size_t i = 0; i < kChunk; ++i) {
      c.a.push_back(ua(rng));
      c.b.push_back(ub(rng));
    }
  }
  return chunks;
}

struct Grids {
  TopoDem dem;
  TopoPlanet planet;
};

void put(std::vector<double>& out, const SurfaceSample& s) {
  out.insert(out.end(), {s.height, s.normal.x, s.normal.y, s.normal.z,
                         static_cast<double>(s.status), static_cast<double>(s.normalStatus)});
}

std::vector<double> demBatch(const TopoDem& dem, const Chunk& c, bool withNormals) {
  std::vector<double> h(kChunk);
  std::vector<glm::dvec3> n(kChunk);
  std::vector<QueryStatus> st(kChunk), nst(kChunk);
  if (withNormals)
    dem.surfaces(c.a, c.b, h, n, st, Interpolation::Bilinear, NormalFrame::BodyFixed, nst);
  else
    dem.heights(c.a, c.b, h, st, Interpolation::Bicubic);
  std::vector<double> out = h;
  for (std::size_t i = 0; i < kChunk; ++i)
    out.insert(out.end(),
               {n[i].x, n[i].y, n[i].z, static_cast<double>(st[i]), static_cast<double>(nst[i])});
  return out;
}

std::vector<double> planetBatch(const TopoPlanet& planet, const Chunk& c) {
  std::vector<double> h(kChunk);
  std::vector<QueryStatus> st(kChunk);
  planet.heights(c.a, c.b, h, st);
  for (const QueryStatus s : st) h.push_back(static_cast<double>(s));
  return h;
}

/// The answer of one job, flattened: heights, normals and statuses.
std::vector<double> run(const Grids& g, Kind kind, const Chunk& c) {
  std::vector<double> out;
  switch (kind) {
    case DemHeight:
      for (std::size_t i = 0; i < kChunk; ++i) {
        const HeightSample s = g.dem.height(c.a[i], c.b[i]);
        out.insert(out.end(), {s.height, static_cast<double>(s.status)});
      }
      return out;
    case DemSurface:
      for (std::size_t i = 0; i < kChunk; ++i)
        put(out, g.dem.surface(c.a[i], c.b[i], Interpolation::Bicubic, NormalFrame::BodyFixed));
      return out;
    case DemHeightsBatch: return demBatch(g.dem, c, false);
    case DemSurfacesBatch: return demBatch(g.dem, c, true);
    case PlanetSurface:
      for (std::size_t i = 0; i < kChunk; ++i) put(out, g.planet.surface({c.a[i], c.b[i]}));
      return out;
    default: return planetBatch(g.planet, c);
  }
}

bool bitIdentical(const std::vector<double>& x, const std::vector<double>& y) {
  return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0;
}

double stormSeconds() {
  const char* s = std::getenv("REGOLITH_STORM_SECONDS");
  const double v = s != nullptr ? std::atof(s) : 0.0;
  return v > 0.0 ? v : 2.0;
}

struct Counts {
  std::array<std::atomic<std::uint64_t>, KindCount> done{};
  std::atomic<std::uint64_t> mismatches{0}, errors{0};
};

/// Samples the cache without pause until `stop`: the most resident bytes seen, and how
/// often they exceeded the budget.
struct Watcher {
  std::size_t maxResident = 0, overBudget = 0, samples = 0;
  void watch(const PatchCache& cache, const std::atomic<bool>& stop) {
    while (!stop.load()) {
      const CacheStats s = cache.stats();
      maxResident = std::max(maxResident, s.residentBytes);
      overBudget += s.residentBytes > s.capacityBytes ? 1 : 0;
      ++samples;
    }
  }
};

/// Moves the prefetcher's focus at random over the DEM and the planet, cancelling the
/// previous focus each time (a moving rover), until `stop`.
std::uint64_t moveFocus(Prefetcher& pf, const std::atomic<bool>& stop) {
  std::mt19937_64 rng(7);
  std::uint64_t requests = 0;
  Prefetcher::Ticket previous = 0;
  while (!stop.load()) {
    const bool planet = rng() % 3 == 0;
    const std::size_t row = rng() % (planet ? 180 : 700), col = rng() % (planet ? 360 : 900);
    const char* grid = planet ? "planet" : "dem";
    const Prefetcher::Ticket t =
        pf.request(grid, pf.focusWindows(grid, row, col, 150), static_cast<int>(rng() % 4));
    if (previous != 0) pf.cancel(previous);
    previous = t;
    ++requests;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return requests;
}

/// The counts, for docs/reliability.md.
void printStorm(const Counts& counts, const Watcher& watcher, const CacheStats& s,
                const PrefetchStats& p, std::size_t budget, std::uint64_t focusMoves) {
  using ull = unsigned long long;
  ull total = 0;
  for (std::size_t k = 0; k < KindCount; ++k) {
    std::printf("storm: %-22s %10llu jobs of %zu points\n", kKindNames[k],
                static_cast<ull>(counts.done[k].load()), kChunk);
    total += counts.done[k].load();
  }
  std::printf("storm: %.0f s, %zu query threads, %llu jobs, %llu mismatches, %llu errors\n",
              stormSeconds(), kThreads, total, static_cast<ull>(counts.mismatches.load()),
              static_cast<ull>(counts.errors.load()));
  std::printf(
      "storm: budget %zu B, max resident seen %zu B (%zu samples, %zu over budget), "
      "peak %zu B\n",
      budget, watcher.maxResident, watcher.samples, watcher.overBudget, s.peakResidentBytes);
  std::printf(
      "storm: cache loads %llu, evictions %llu; prefetch focus moves %llu, loaded %llu, "
      "failed %llu\n",
      static_cast<ull>(s.loads), static_cast<ull>(s.evictions), static_cast<ull>(focusMoves),
      static_cast<ull>(p.loaded), static_cast<ull>(p.failed));
}

}  // namespace

TEST(Storm, SixteenThreadsUnderEvictionGetTheSingleThreadedAnswersWithinTheBudget) {
  const std::array<std::vector<Chunk>, 2> chunks{makeChunks(false, 17), makeChunks(true, 71)};
  const auto chunkOf = [&](std::size_t kind, std::size_t j) -> const Chunk& {
    return chunks[kind >= PlanetSurface ? 1 : 0][j];
  };
  // The reference: one thread, a cache large enough never to evict.
  std::vector<std::vector<double>> expected(KindCount * kChunks);
  {
    Opened big = openFixture();
    const Grids g{big.pager.dem("dem"), big.pager.planet("planet")};
    for (std::size_t k = 0; k < KindCount; ++k)
      for (std::size_t j = 0; j < kChunks; ++j)
        expected[k * kChunks + j] = run(g, static_cast<Kind>(k), chunkOf(k, j));
    ASSERT_EQ(big.cache->stats().evictions, 0U);
  }
  // The storm: a budget of 4 patches of 128 x 128 floats.
  const std::size_t budget = 4 * 128 * 128 * sizeof(float);
  Opened small = openFixture(budget);
  auto pager = std::make_shared<const Pager>(small.store, small.cache);
  const Grids g{pager->dem("dem"), pager->planet("planet")};
  Prefetcher pf(pager, 2);
  Counts counts;
  Watcher watcher;
  std::atomic<bool> stop{false};
  std::uint64_t focusMoves = 0;
  std::thread watch([&] { watcher.watch(*small.cache, stop); });
  std::thread focus([&] { focusMoves = moveFocus(pf, stop); });
  std::vector<std::thread> queries;
  for (std::size_t t = 0; t < kThreads; ++t) {
    queries.emplace_back([&, t] {
      // Each thread starts with its own kind and cycles through all, doing at least one job:
      // with 16 threads every kind runs even when a slow (TSan) storm does few jobs.
      std::mt19937_64 rng(1000 + t);
      std::size_t k = t % KindCount;
      do {
        k = (k + 1) % KindCount;
        const std::size_t j = rng() % kChunks;
        try {
          if (!bitIdentical(run(g, static_cast<Kind>(k), chunkOf(k, j)), expected[k * kChunks + j]))
            ++counts.mismatches;
        } catch (const std::exception&) {
          ++counts.errors;
        }
        ++counts.done[k];
      } while (!stop.load());
    });
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(stormSeconds()));
  stop = true;
  for (std::thread& q : queries) q.join();
  focus.join();
  watch.join();
  pf.waitIdle();

  const CacheStats s = small.cache->stats();
  printStorm(counts, watcher, s, pf.stats(), budget, focusMoves);
  for (std::size_t k = 0; k < KindCount; ++k) EXPECT_GT(counts.done[k].load(), 0U) << kKindNames[k];
  EXPECT_EQ(counts.mismatches.load(), 0U);
  EXPECT_EQ(counts.errors.load(), 0U);
  EXPECT_EQ(watcher.overBudget, 0U);
  EXPECT_LE(watcher.maxResident, budget);
  EXPECT_LE(s.peakResidentBytes, budget);
  EXPECT_GT(watcher.samples, 0U);
  // The storm really evicted, and the prefetcher really worked.
  EXPECT_GT(s.evictions, 100U);
  EXPECT_GT(pf.stats().loaded, 0U);
  EXPECT_EQ(pf.stats().failed, 0U) << pf.lastError();
}
