// Pager: paged grids answer exactly like in-memory ones, load only the patches they touch,
// stay within the cache budget, and give the same answers from many threads.
#include <regolith/core/Error.hpp>
#include <regolith/store/Pager.hpp>

#include "store/PagerFixture.hpp"
#include "support/WorkScale.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <span>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace regolith::topo;

namespace {
using namespace regolith::test;
constexpr Interpolation kAll[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                  Interpolation::Bicubic};
}  // namespace

TEST(Pager, PagedDemAnswersExactlyLikeTheInMemoryDem) {
  Opened o = openFixture();
  const TopoDem paged = o.pager.dem("dem");
  GridInfo info = demInfo(700, 900);
  const TopoDem mem(topoGridOf(info), placementOf(info), fixture().demSamples);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> x(-501.0, 400.0), y(-300.0, 401.0);
  for (int i = 0; i < 3000; ++i) {
    const double px = x(rng), py = y(rng);
    for (Interpolation k : kAll) {
      const SurfaceSample a = mem.surface(px, py, k, NormalFrame::BodyFixed);
      const SurfaceSample b = paged.surface(px, py, k, NormalFrame::BodyFixed);
      ASSERT_EQ(a.status, b.status) << px << "," << py;
      if (a.valid()) {
        ASSERT_EQ(a.height, b.height);
        ASSERT_EQ(a.normal, b.normal);
      }
    }
  }
}

TEST(Pager, ReadingOnePointLoadsOnlyThePatchThatHoldsIt) {
  Opened o = openFixture();
  const TopoDem dem = o.pager.dem("dem");
  // Sample (200, 200) is inside patch (1, 1) of 128×128; its bilinear cell too.
  (void)dem.height(-500.0 + 200.25, 400.0 - 200.25);
  CacheStats s = o.cache->stats();
  EXPECT_EQ(s.loads, 1u);
  EXPECT_EQ(o.store->counters().reads, 1u);
  EXPECT_EQ(o.store->counters().bytesRead, 128u * 128u * sizeof(float));
  EXPECT_TRUE(o.cache->contains(o.pager.keyOf("dem", 0, 200, 200)));
  // At a patch corner the bicubic stencil needs all four patches around it.
  (void)dem.height(-500.0 + 383.5, 400.0 - 383.5, Interpolation::Bicubic);
  s = o.cache->stats();
  EXPECT_EQ(s.loads, 1u + 4u);
}

TEST(Pager, RunsOfQueriesInOnePatchAskTheCacheOnce) {
  Opened o = openFixture();
  const TopoDem dem = o.pager.dem("dem");
  for (int i = 0; i < 10000; ++i) (void)dem.height(-500.0 + 140.0 + 0.01 * i, 400.0 - 140.0);
  const CacheStats s = o.cache->stats();
  EXPECT_EQ(s.loads, 1u);
  EXPECT_LE(s.hits + s.misses, 2u);
}

TEST(Pager, ResidentBytesStayWithinTheBudgetOnAGridEightTimesLarger) {
  // 700×900 floats = 2.5 MB; a budget of 4 patches of 128×128 (~260 KB) is ~10× smaller.
  const std::size_t patchBytes = 128 * 128 * sizeof(float) + 256;
  Opened o = openFixture(4 * patchBytes);
  const TopoDem dem = o.pager.dem("dem");
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> x(-500.0, 399.0), y(-299.0, 400.0);
  for (std::size_t i = 0, n = test::scaledWork(20000); i < n; ++i) {
    (void)dem.height(x(rng), y(rng), Interpolation::Bicubic);
    ASSERT_LE(o.cache->stats().residentBytes, o.cache->capacityBytes());
  }
  EXPECT_GT(o.cache->stats().evictions, 100u);
}

TEST(Pager, EightThreadsGetTheSameAnswersAsOne) {
  Opened o = openFixture(6 * (128 * 128 * sizeof(float) + 256));
  const TopoDem dem = o.pager.dem("dem");
  const std::size_t n = test::scaledWork(4000);
  std::vector<double> xs(n), ys(n), ref(n);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-500.0, 399.0), y(-299.0, 400.0);
  for (std::size_t i = 0; i < xs.size(); ++i) xs[i] = x(rng), ys[i] = y(rng);
  dem.heights(xs, ys, ref, {}, Interpolation::Bicubic);
  std::vector<std::vector<double>> got(8, std::vector<double>(xs.size()));
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t i = 0; i < xs.size(); ++i) {
        const std::size_t j = (i + 500 * t) % xs.size();  // different orders, same points
        got[t][j] = dem.height(xs[j], ys[j], Interpolation::Bicubic).height;
      }
    });
  }
  for (auto& th : threads) th.join();
  for (std::size_t t = 0; t < 8; ++t) {
    for (std::size_t i = 0; i < xs.size(); ++i) {
      if (std::isnan(ref[i])) {
        EXPECT_TRUE(std::isnan(got[t][i]));
      } else {
        ASSERT_EQ(got[t][i], ref[i]) << "thread " << t << " point " << i;
      }
    }
  }
}

TEST(Pager, PagedPlanetAnswersExactlyLikeTheInMemoryPlanet) {
  Opened o = openFixture();
  const TopoPlanet paged = o.pager.planet("planet");
  const TopoPlanet mem(topoGridOf(planetInfo()), bodyOf(planetInfo()), LatitudeType::Planetocentric,
                       fixture().planetSamples);
  for (double lat : {-90.0, -89.7, -10.3, 0.0, 45.5, 89.9, 90.0}) {
    for (double lon : {-180.0, -0.2, 0.0, 127.9, 179.99, 359.5}) {
      for (Interpolation k : kAll) {
        const SurfaceSample a = mem.surface({lat, lon}, k), b = paged.surface({lat, lon}, k);
        ASSERT_EQ(a.status, b.status);
        EXPECT_EQ(a.height, b.height) << lat << "," << lon;
        EXPECT_EQ(a.normal, b.normal);
      }
    }
  }
}

TEST(Pager, CoarseLevelsAreTwoByTwoMeansWithTheirOwnGeometry) {
  Opened o = openFixture();
  const TopoDem l1 = o.pager.dem("dem", 1);
  EXPECT_EQ(l1.grid().rows(), 350u);
  EXPECT_EQ(l1.grid().cols(), 450u);
  EXPECT_DOUBLE_EQ(l1.grid().spacingX(), 2.0);
  // Sample (10, 20) of level 1 = mean of level-0 samples (20…21, 40…41), centred between them.
  auto t = [](std::size_t r, std::size_t c) { return static_cast<double>(terrain(r, c)); };
  const double mean = (t(20, 40) + t(20, 41) + t(21, 40) + t(21, 41)) / 4.0;
  const glm::dvec2 c = l1.grid().sampleCentre(10, 20);
  EXPECT_DOUBLE_EQ(c.x, -500.0 + 40.5);
  EXPECT_DOUBLE_EQ(c.y, 400.0 - 20.5);
  EXPECT_NEAR(l1.height(c.x, c.y, Interpolation::Nearest).height, mean, 1e-4);
}

TEST(Pager, ReadWindowAcrossPatchesEqualsTheSource) {
  Opened o = openFixture();
  const auto src = o.pager.source("dem");
  std::vector<float> w(150 * 170);
  src->readWindow(100, 90, 150, 170, w);
  for (std::size_t r = 0; r < 150; r += 7) {
    for (std::size_t c = 0; c < 170; c += 5) {
      const float want = terrain(100 + r, 90 + c);
      if (std::isnan(want)) {
        EXPECT_TRUE(std::isnan(w[r * 170 + c]));
      } else {
        EXPECT_EQ(w[r * 170 + c], want);
      }
    }
  }
}

TEST(Pager, ClearErrorsForUnknownGridsLevelsAndKinds) {
  Opened o = openFixture();
  try {
    (void)o.pager.dem("nope");
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("store::Pager::dem(): "), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("no grid 'nope'"), std::string::npos);
  }
  EXPECT_THROW((void)o.pager.dem("dem", 99), StoreError);
  EXPECT_THROW((void)o.pager.dem("planet"), StoreError);
  EXPECT_THROW((void)o.pager.planet("dem"), StoreError);
  EXPECT_THROW((void)o.pager.patch({9999, 0, 0, 0}), InvalidArgument);
}

TEST(Pager, GridsOutliveThePagerThatMadeThem) {
  std::optional<TopoDem> dem;
  {
    Opened o = openFixture();
    dem.emplace(o.pager.dem("dem"));
  }
  EXPECT_TRUE(dem->height(0.0, 0.0).valid());
}

// ---- Lock-free hits on resident patches (store/BlockTable.hpp, PatchCache.cpp) ----------

namespace {
// A point inside patch (pr, pc) of the DEM (128×128 patches, sample (r, c) at x = −500 + c,
// y = 400 − r), shifted by `d` samples so that successive points differ.
std::pair<double, double> inPatch(int pr, int pc, double d = 0.0) {
  return {-500.0 + pc * 128 + 40.0 + d, 400.0 - (pr * 128 + 40.0) - d};
}
double heightIn(const TopoDem& dem, int pr, int pc, double d = 0.0) {
  const auto [x, y] = inPatch(pr, pc, d);
  return dem.height(x, y).height;
}
PatchKey keyIn(const Pager& pager, int pr, int pc) {
  return pager.keyOf("dem", 0, static_cast<std::size_t>(pr) * 128 + 40,
                     static_cast<std::size_t>(pc) * 128 + 40);
}
std::size_t patchBytes() {
  Patch p;
  p.samples.resize(128 * 128);
  return p.bytes();
}
TopoDem inMemoryDem() {
  const GridInfo info = demInfo(700, 900);
  return {topoGridOf(info), placementOf(info), fixture().demSamples};
}
}  // namespace

TEST(Pager, QueriesJumpingBetweenResidentPatchesCountOneHitPerPatchEntered) {
  Opened o = openFixture();
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  for (int pr = 0; pr < 2; ++pr) {
    for (int pc = 0; pc < 2; ++pc) (void)heightIn(dem, pr, pc);  // make them resident
  }
  (void)heightIn(dem, 1, 1, 1.0);  // the thread's block: patch (1, 1)
  (void)heightIn(dem, 1, 1, 2.0);
  o.cache->resetStats();
  // Runs: A A | B B B | A | C | A  ->  5 patches entered.
  const int seq[][2] = {{0, 0}, {0, 0}, {0, 1}, {0, 1}, {0, 1}, {0, 0}, {1, 0}, {0, 0}};
  double d = 0.0;
  for (const auto& p : seq) {
    d += 0.37;
    ASSERT_EQ(heightIn(dem, p[0], p[1], d), heightIn(mem, p[0], p[1], d));
  }
  const CacheStats s = o.cache->stats();
  EXPECT_EQ(s.hits, 5u);
  EXPECT_EQ(s.misses, 0u);
  EXPECT_EQ(s.loads, 0u);
}

TEST(Pager, CellsAcrossPatchEdgesAreReadLockFreeAndExactly) {
  // A bilinear cell whose samples lie in two or four resident patches (a rover crossing a
  // patch edge) is read from the block table, not through the cache: a run of queries in it
  // counts no further hit (each sample outside the thread's patch used to be a locked
  // lookup), and the heights are the in-memory ones bit for bit.
  Opened o = openFixture();
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  for (int pr = 0; pr < 2; ++pr) {
    for (int pc = 0; pc < 2; ++pc) (void)heightIn(dem, pr, pc);  // make them resident
  }
  // Cells (row, col) = (127, 127): four patches; (40, 127): two side by side; (127, 40): two
  // one above the other.
  for (const auto& [r, c] :
       {std::pair{127.0, 127.0}, std::pair{40.0, 127.0}, std::pair{127.0, 40.0}}) {
    (void)dem.height(-500.0 + c + 0.5, 400.0 - r - 0.5);  // the run begins
    o.cache->resetStats();
    for (int i = 0; i < 1000; ++i) {
      const double x = -500.0 + c + 0.001 * i, y = 400.0 - r - 0.999 + 0.00093 * i;
      const HeightSample a = mem.height(x, y), b = dem.height(x, y);
      ASSERT_TRUE(b.valid()) << r << "," << c << " #" << i;
      ASSERT_EQ(a.height, b.height) << r << "," << c << " #" << i;
    }
    const CacheStats s = o.cache->stats();
    EXPECT_EQ(s.hits, 0u) << "cell " << r << "," << c;
    EXPECT_EQ(s.misses, 0u);
  }
  // Batches take the same path.
  std::vector<double> xs, ys, out(500);
  for (int i = 0; i < 500; ++i) {
    xs.push_back(-500.0 + 127.0 + 0.002 * i);
    ys.push_back(400.0 - 127.0 - 0.002 * i);
  }
  o.cache->resetStats();
  dem.heights(xs, ys, out, {});
  for (std::size_t i = 0; i < xs.size(); ++i) ASSERT_EQ(out[i], mem.height(xs[i], ys[i]).height);
  EXPECT_LE(o.cache->stats().hits, 1u);
}

namespace {
// Points a few ulps of x (or y) from the sample line of column `c` (or row `r`) through
// (x, y): inside the snap slack of the line (TopoGrid::edgeSlack(), which the generic kernel
// snaps onto it), just beyond it, and beyond twice it (which the fast paths answer). Their
// cells lie across a patch edge (c or r 127 or 128) or inside one patch (c or r 40).
std::vector<std::pair<double, double>> pointsByCellLines(const TopoGrid& g) {
  const glm::dvec2 slack = g.edgeSlack();
  // About 2.5 slacks of steps of one ulp of x on each side (the spacing is 1 m).
  const int steps = static_cast<int>(2.5 * slack.x / (std::nextafter(500.0, 1e3) - 500.0)) + 2;
  std::vector<std::pair<double, double>> out;
  for (const double line : {40.0, 127.0, 128.0}) {
    const double x = -500.0 + line, y = 400.0 - line;
    for (const double sign : {-1.0, 1.0}) {
      double px = x, py = y;
      for (int i = 0; i <= steps; ++i) {
        out.emplace_back(px, 400.0 - line - 0.37);   // near a column line
        out.emplace_back(-500.0 + line + 0.61, py);  // near a row line
        out.emplace_back(px, py);                    // near both
        px = std::nextafter(px, sign * 1e9);
        py = std::nextafter(py, sign * 1e9);
      }
    }
  }
  return out;
}
std::uint64_t bitsOf(double h) { return std::bit_cast<std::uint64_t>(h); }
}  // namespace

TEST(Pager, HeightsWithinTheSnapSlackOfACellLineDoNotDependOnWhatIsResident) {
  // The generic kernel snaps a point within the slack of a sample line onto it; the fast
  // paths (resident samples, the thread's patch, the block table, a cell across patches)
  // do not. A bilinear height() is the interpolation at the point itself wherever it has a
  // value (TopoDem.cpp, unsnapped()), on every path, so a paged height near a patch edge is
  // the same bits whether the patches around it are resident (fast paths) or not (generic
  // kernel), and the same as in memory; so is a surface (snapped on every path). Stop 30
  // found up to 12 ulps between cold and warm heights here.
  const TopoDem mem = inMemoryDem();
  const std::vector<std::pair<double, double>> pts = pointsByCellLines(mem.grid());
  std::vector<double> want, xs, ys;
  std::vector<SurfaceSample> wantSurface;
  for (const auto& [x, y] : pts) {
    want.push_back(mem.height(x, y).height);
    wantSurface.push_back(mem.surface(x, y));
    xs.push_back(x);
    ys.push_back(y);
  }
  const auto expectSurface = [&](const TopoDem& dem, std::size_t i, const char* what) {
    const SurfaceSample s = dem.surface(pts[i].first, pts[i].second);
    ASSERT_EQ(s.status, QueryStatus::Ok) << what << ", point " << i;
    ASSERT_EQ(bitsOf(s.height), bitsOf(wantSurface[i].height)) << what << ", point " << i;
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(bitsOf(s.normal[a]), bitsOf(wantSurface[i].normal[a])) << what << ", point " << i;
    }
  };
  // In memory, one at a time and as a batch (the resident batch loop).
  std::vector<double> batch(pts.size());
  mem.heights(xs, ys, batch, {});
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(bitsOf(batch[i]), bitsOf(want[i])) << "in-memory batch, point " << i;
  }
  // Cold: a cache of one patch, new for each point, so a cell across patches is never
  // wholly resident and goes through the generic kernel (every point, or every k-th under
  // test::scaledWork()).
  ASSERT_FALSE(pts.empty());
  const std::size_t coldStride = pts.size() / test::scaledWork(pts.size());
  for (std::size_t i = 0; i < pts.size(); i += coldStride) {
    Opened cold = openFixture(patchBytes());
    const TopoDem dem = cold.pager.dem("dem");
    const double h = dem.height(pts[i].first, pts[i].second).height;
    ASSERT_EQ(bitsOf(h), bitsOf(want[i])) << "cold, point " << i << " (" << pts[i].first << ", "
                                          << pts[i].second << "): " << h << " against " << want[i];
    expectSurface(openFixture(patchBytes()).pager.dem("dem"), i, "cold surface");
  }
  // Warm: every patch around resident (the thread's patch, the block table, cells across
  // patches), one at a time and as a batch.
  Opened warm = openFixture();
  const TopoDem dem = warm.pager.dem("dem");
  for (int pr = 0; pr < 2; ++pr) {
    for (int pc = 0; pc < 2; ++pc) (void)heightIn(dem, pr, pc);
  }
  warm.cache->resetStats();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double h = dem.height(pts[i].first, pts[i].second).height;
    ASSERT_EQ(bitsOf(h), bitsOf(want[i]))
        << "warm, point " << i << ": " << h << " against " << want[i];
    expectSurface(dem, i, "warm surface");
  }
  EXPECT_EQ(warm.cache->stats().loads, 0u);
  dem.heights(xs, ys, batch, {});
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(bitsOf(batch[i]), bitsOf(want[i])) << "warm batch, point " << i;
  }
}

TEST(Pager, LruEvictsTheLeastRecentPatchWhenHitsTookTheLockFreePath) {
  Opened o = openFixture(3 * patchBytes());
  ASSERT_EQ(o.cache->policy(), CachePolicy::Lru);
  const TopoDem dem = o.pager.dem("dem");
  (void)heightIn(dem, 0, 0);  // loads P1, P2, P3
  (void)heightIn(dem, 0, 1);
  (void)heightIn(dem, 0, 2);
  (void)heightIn(dem, 0, 0, 1.0);  // P1 is used again (a lock-free hit)
  ASSERT_EQ(o.cache->stats().loads, 3u);
  (void)heightIn(dem, 0, 3);  // P4: one patch must go, and P2 is the least recent
  EXPECT_TRUE(o.cache->contains(keyIn(o.pager, 0, 0)));
  EXPECT_FALSE(o.cache->contains(keyIn(o.pager, 0, 1)));
  EXPECT_TRUE(o.cache->contains(keyIn(o.pager, 0, 2)));
  EXPECT_TRUE(o.cache->contains(keyIn(o.pager, 0, 3)));
}

TEST(Pager, HitCountEvictsTheLeastHitPatchWhenHitsTookTheLockFreePath) {
  auto store = std::make_shared<const Store>(Store::open(fixture().path));
  auto cache = std::make_shared<PatchCache>(3 * patchBytes(), CachePolicy::HitCount);
  const Pager pager(store, cache);
  const TopoDem dem = pager.dem("dem");
  (void)heightIn(dem, 0, 0);  // P1, P2, P3 loaded, no hits yet
  (void)heightIn(dem, 0, 1);
  (void)heightIn(dem, 0, 2);
  double d = 0.0;
  for (const int pc : {0, 2, 0, 2, 0}) (void)heightIn(dem, 0, pc, d += 0.5);  // P1 3, P3 2
  EXPECT_EQ(cache->stats().hits, 5u);
  (void)heightIn(dem, 0, 3);  // P4 loaded: P2 has the fewest hits (0)
  EXPECT_FALSE(cache->contains(keyIn(pager, 0, 1)));
  (void)heightIn(dem, 0, 4);  // P5 loaded: now P4 has the fewest (0), not P1 (3) or P3 (2)
  EXPECT_TRUE(cache->contains(keyIn(pager, 0, 0)));
  EXPECT_TRUE(cache->contains(keyIn(pager, 0, 2)));
  EXPECT_FALSE(cache->contains(keyIn(pager, 0, 3)));
  EXPECT_TRUE(cache->contains(keyIn(pager, 0, 4)));
}

TEST(Pager, AnEvictedPatchStaysReadableWhileAThreadIsInsideIt) {
  Opened o = openFixture();
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  (void)heightIn(dem, 2, 2);  // resident, so the reader enters it through the table
  (void)heightIn(dem, 0, 0);  // this thread's own block is elsewhere
  std::atomic<int> step{0};
  std::size_t mismatches = 0;
  std::thread reader([&] {
    (void)heightIn(dem, 2, 2, 1.0);  // enters patch (2, 2) and holds it as its block
    (void)heightIn(dem, 2, 2, 2.0);
    step = 1;
    while (step != 2) std::this_thread::yield();
    for (int i = 0; i < 2000; ++i) {  // reads the evicted patch through its block
      const double d = 0.03 * i;
      const double a = heightIn(dem, 2, 2, d), b = heightIn(mem, 2, 2, d);
      if (!(a == b || (std::isnan(a) && std::isnan(b)))) ++mismatches;  // (300, 301) is NaN
    }
    step = 3;
    while (step != 4) std::this_thread::yield();
  });
  while (step != 1) std::this_thread::yield();
  std::weak_ptr<const Patch> patch = o.cache->find(keyIn(o.pager, 2, 2));
  ASSERT_FALSE(patch.expired());
  o.cache->clear();  // evicts it while the reader is inside
  EXPECT_EQ(o.cache->stats().residentPatches, 0u);
  EXPECT_FALSE(patch.expired()) << "freed while a thread may read it";
  step = 2;
  while (step != 3) std::this_thread::yield();
  EXPECT_EQ(mismatches, 0u);
  EXPECT_FALSE(patch.expired());
  step = 4;
  reader.join();
  o.cache->clear();  // the reader has ended: its patch is reclaimed now
  EXPECT_TRUE(patch.expired());
}

TEST(Pager, EightThreadsJumpingBetweenPatchesUnderEvictionGetTheInMemoryAnswers) {
  Opened o = openFixture(3 * patchBytes());
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  const std::size_t n = test::scaledWork(1500);
  std::vector<double> xs(n), ys(n), ref(n);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> x(-500.0, 399.0), y(-299.0, 400.0);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    xs[i] = x(rng);
    ys[i] = y(rng);
    ref[i] = mem.height(xs[i], ys[i]).height;
  }
  std::vector<std::size_t> wrong(8, 0);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t i = 0; i < xs.size(); ++i) {
        const std::size_t j = (i * (t + 1) + 97 * t) % xs.size();
        const double h = dem.height(xs[j], ys[j]).height;
        if (!(h == ref[j] || (std::isnan(h) && std::isnan(ref[j])))) ++wrong[t];
      }
    });
  }
  for (auto& th : threads) th.join();
  for (std::size_t t = 0; t < 8; ++t) EXPECT_EQ(wrong[t], 0u) << "thread " << t;
  const CacheStats s = o.cache->stats();
  EXPECT_LE(s.residentBytes, s.capacityBytes);
  EXPECT_GT(s.evictions, 100u);
}

TEST(Pager, BatchesThatPrefetchAheadUnderEvictionGetTheInMemoryAnswers) {
  // heights() prefetches the cells of points a few ahead from the block table's hints;
  // patches are evicted and freed meanwhile (a small budget, four threads), and every batch
  // still equals the in-memory answers, nodata and points outside the grid included.
  Opened o = openFixture(3 * patchBytes());
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  const std::size_t n = test::scaledWork(3000);
  std::vector<double> xs(n), ys(n), ref(n);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> x(-520.0, 420.0), y(-320.0, 420.0);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    xs[i] = x(rng);
    ys[i] = y(rng);
    ref[i] = mem.height(xs[i], ys[i]).height;
  }
  std::vector<std::size_t> wrong(4, 0);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::vector<double> got(xs.size());
      std::vector<QueryStatus> status(xs.size());
      for (int round = 0; round < 3; ++round) {
        dem.heights(xs, ys, got,
                    round == 1 ? std::span<QueryStatus>(status) : std::span<QueryStatus>());
        for (std::size_t i = 0; i < xs.size(); ++i) {
          if (!(got[i] == ref[i] || (std::isnan(got[i]) && std::isnan(ref[i])))) ++wrong[t];
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  for (std::size_t t = 0; t < 4; ++t) EXPECT_EQ(wrong[t], 0u) << "thread " << t;
  EXPECT_GT(o.cache->stats().evictions, 100u);
}

namespace {
// The fixture's DEM read sample by sample: every query takes the generic kernel.
class SampleBySample final : public SampleSource {
 public:
  explicit SampleBySample(std::shared_ptr<const InMemorySamples> s) : s_(std::move(s)) {}
  std::size_t rows() const noexcept override { return s_->rows(); }
  std::size_t cols() const noexcept override { return s_->cols(); }
  float sample(std::size_t r, std::size_t c) const override { return s_->sample(r, c); }

 private:
  std::shared_ptr<const InMemorySamples> s_;
};
TopoDem genericDem() {
  const GridInfo info = demInfo(700, 900);
  return {topoGridOf(info), placementOf(info),
          std::make_shared<SampleBySample>(fixture().demSamples)};
}
bool sameSurface(const SurfaceSample& a, const SurfaceSample& b) {
  const auto same = [](double p, double q) { return p == q || (std::isnan(p) && std::isnan(q)); };
  return a.status == b.status && a.normalStatus == b.normalStatus && same(a.height, b.height) &&
         same(a.normal.x, b.normal.x) && same(a.normal.y, b.normal.y) &&
         same(a.normal.z, b.normal.z);
}
}  // namespace

TEST(Pager, SurfacesAcrossPatchEdgesAreReadLockFreeAndEqualTheGenericPath) {
  // surface() takes its normal from the height's four samples on height()'s lock-free paths:
  // inside the thread's patch, and in cells whose samples lie in two or four patches. Its
  // answers are the generic kernel's bits (a source read sample by sample), also a few ulps
  // either side of a cell line, where the generic path snaps the point onto the line.
  Opened o = openFixture();
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  const TopoDem generic = genericDem();
  for (int pr = 0; pr < 2; ++pr) {
    for (int pc = 0; pc < 2; ++pc) (void)heightIn(dem, pr, pc);  // make them resident
  }
  const auto check = [&](double x, double y, const char* what) {
    const SurfaceSample g = generic.surface(x, y), b = dem.surface(x, y), a = mem.surface(x, y);
    EXPECT_TRUE(b.normalValid()) << what << " " << x << "," << y;
    EXPECT_TRUE(sameSurface(g, b)) << what << " " << x << "," << y;
    EXPECT_TRUE(sameSurface(g, a)) << what << " " << x << "," << y;
  };
  for (const auto& [r, c] :
       {std::pair{127.0, 127.0}, std::pair{40.0, 127.0}, std::pair{127.0, 40.0}}) {
    (void)dem.surface(-500.0 + c + 0.5, 400.0 - r - 0.5);  // the run begins
    o.cache->resetStats();
    for (int i = 0; i < 1000; ++i) {
      check(-500.0 + c + 0.001 * i, 400.0 - r - 0.999 + 0.00093 * i, "run");
    }
    EXPECT_EQ(o.cache->stats().hits, 0u) << "cell " << r << "," << c;
    EXPECT_EQ(o.cache->stats().misses, 0u);
    // A few ulps from the cell's far lines (which are patch edges for (127, 127)): the
    // generic path's cell, on the block table (a switch of the thread's patch is a hit).
    const double xLine = -500.0 + c + 1.0, yLine = 400.0 - r - 1.0;
    for (int i = 0; i < 100; ++i) {
      const double along = 0.01 * i;
      for (const double x : {std::nextafter(xLine, -1e9), std::nextafter(xLine, 1e9)}) {
        check(x, yLine + 0.5 + along * 0.4, "near a column line");
      }
      for (const double y : {std::nextafter(yLine, -1e9), std::nextafter(yLine, 1e9)}) {
        check(xLine - 0.5 - along * 0.4, y, "near a row line");
      }
    }
    EXPECT_EQ(o.cache->stats().misses, 0u);
  }
}

TEST(Pager, SurfaceBatchesUnderEvictionGetTheGenericAnswers) {
  // surfaces() along a path (the rover) and at random points (prefetching ahead), with a
  // budget of three patches, so that patches are evicted under the batch: every answer,
  // nodata, the hole's neighbours and points outside the grid included, is the generic
  // kernel's, in both frames.
  Opened o = openFixture(3 * patchBytes());
  const TopoDem dem = o.pager.dem("dem");
  const TopoDem generic = genericDem();
  std::vector<double> xs, ys;
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> x(-520.0, 420.0), y(-320.0, 420.0);
  const std::size_t n = test::scaledWork(3000);
  for (std::size_t i = 0; i < n; ++i) {
    xs.push_back(x(rng));
    ys.push_back(y(rng));
  }
  for (std::size_t i = 0; i < n; ++i) {  // across the hole at (300, 301) and patch edges
    const double step = 3000.0 / static_cast<double>(n) * static_cast<double>(i);
    xs.push_back(-500.0 + 250.0 + 0.02 * step);
    ys.push_back(400.0 - 299.3 - 0.0005 * step);
  }
  for (const NormalFrame frame : {NormalFrame::Grid, NormalFrame::BodyFixed}) {
    for (const std::size_t from : {std::size_t{0}, n}) {
      const auto px = std::span(xs).subspan(from, n), py = std::span(ys).subspan(from, n);
      std::vector<double> h(n);
      std::vector<glm::dvec3> nrm(n);
      std::vector<QueryStatus> st(n), nst(n);
      dem.surfaces(px, py, h, nrm, st, Interpolation::Bilinear, frame, nst);
      std::size_t wrong = 0, valid = 0, nodata = 0;
      for (std::size_t i = 0; i < px.size(); ++i) {
        const SurfaceSample g = generic.surface(px[i], py[i], Interpolation::Bilinear, frame);
        wrong += sameSurface(g, {h[i], nrm[i], st[i], nst[i]}) ? 0U : 1U;
        valid += g.normalValid() ? 1U : 0U;
        nodata += g.status == QueryStatus::Nodata ? 1U : 0U;
      }
      EXPECT_EQ(wrong, 0u) << "points from " << from;
      EXPECT_GT(valid, 2 * n / 3);
      if (from != 0) {
        EXPECT_GT(nodata, 0u);
      }
    }
  }
  EXPECT_GT(o.cache->stats().evictions, 10u);
}
