// Pagers of one store file (Pager.hpp, "One store file, many pagers"): opened through the
// path, a symlink or a hard link, through one cache or two, they read each patch from the
// file once and hold it as one object; their answers are the in-memory grid's, bit for bit;
// every cache stays within its budget. Pagers of other files, or of a file written over the
// path since, share nothing.
#include <regolith/core/Error.hpp>
#include <regolith/store/Pager.hpp>

#include "store/PagerFixture.hpp"
#include "support/WorkScale.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <random>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::store;
using namespace regolith::topo;

namespace {
using namespace regolith::test;

// The DEM of the fixture is 700×900 samples in 128×128 patches: 6×8 patches at level 0.
constexpr std::size_t kPatchRows = 6, kPatchCols = 8;

// The fixture's file under another name: a symlink or a hard link to it, made once per process.
fs::path symlinkToFixture() {
  static const fs::path p = [] {
    fs::path link = scratch("pager-symlink.h5");
    fs::remove(link);
    fs::create_symlink(fixture().path, link);
    return link;
  }();
  return p;
}
fs::path hardLinkToFixture() {
  static const fs::path p = [] {
    fs::path link = scratch("pager-hardlink.h5");
    fs::remove(link);
    fs::create_hard_link(fixture().path, link);
    return link;
  }();
  return p;
}

Opened openPath(const fs::path& path, const std::shared_ptr<PatchCache>& cache) {
  auto store = std::make_shared<const Store>(Store::open(path));
  return {store, cache, Pager(store, cache)};
}

// Bilinear heights over a lattice that meets every sample cell of the DEM, so every patch of
// level 0: 7.3 m apart across x in [−500, 399], y in [−299, 400].
std::vector<double> sweep(const TopoDem& dem) {
  std::vector<double> out;
  for (double y = 400.0; y >= -299.0; y -= 7.3) {
    for (double x = -500.0; x <= 399.0; x += 7.3) {
      out.push_back(dem.height(x, y).height);
    }
  }
  return out;
}

TopoDem inMemoryDem() {
  const GridInfo info = demInfo(700, 900);
  return {topoGridOf(info), placementOf(info), fixture().demSamples};
}

// What the pagers must answer: the in-memory grid's heights.
const std::vector<double>& inMemory() {
  static const std::vector<double> want = sweep(inMemoryDem());
  return want;
}

// The same answers: bit for bit, NaN (the fixture's hole) included. (A cell across a patch
// edge is read from the block table when both its patches are resident and through the
// generic kernel when one is not; the two give the same bits, also within the snap slack of
// a cell line, which the lattice below meets: Pager.HeightsWithinTheSnapSlackOfACellLine*.)
void expectSameBits(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(std::bit_cast<std::uint64_t>(got[i]), std::bit_cast<std::uint64_t>(want[i]))
        << "point " << i << ": " << got[i] << " against " << want[i];
  }
}

// Every sample of a level, through its source (patch by patch, so every patch is loaded).
std::vector<float> samplesOf(const SampleSource& s) {
  std::vector<float> out(s.rows() * s.cols());
  s.readWindow(0, 0, s.rows(), s.cols(), out);
  return out;
}
void expectSameSamples(const std::vector<float>& got, const std::vector<float>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(std::bit_cast<std::uint32_t>(got[i]), std::bit_cast<std::uint32_t>(want[i]))
        << "sample " << i;
  }
}

PatchKey patchKey(const Pager& pager, std::size_t pr, std::size_t pc) {
  return pager.keyOf("dem", 0, pr * 128, pc * 128);
}

std::size_t patchBytes() {
  Patch p;
  p.samples.resize(std::size_t{128} * 128);
  return p.bytes();
}

std::uint64_t reads(const Opened& o) { return o.store->counters().reads; }

/// The heights at (xs, ys) from 8 threads, the even ones querying a and the odd ones b, each
/// in its own order (the same points): one vector of answers per thread.
std::vector<std::vector<double>> heightsFromEightThreads(const TopoDem& a, const TopoDem& b,
                                                         const std::vector<double>& xs,
                                                         const std::vector<double>& ys) {
  std::vector<std::vector<double>> got(8, std::vector<double>(xs.size()));
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      const TopoDem& dem = t % 2 == 0 ? a : b;
      for (std::size_t i = 0; i < xs.size(); ++i) {
        const std::size_t j = (i + 377 * t) % xs.size();
        got[t][j] = dem.height(xs[j], ys[j]).height;
      }
    });
  }
  for (auto& th : threads) th.join();
  return got;
}

}  // namespace

TEST(PagerSharing, StoreFileIdIsTheFilesThroughSymlinksAndHardLinks) {
  const FileId id = Store::open(fixture().path).fileId();
  EXPECT_NE(id.inode, 0u);
  EXPECT_EQ(Store::open(symlinkToFixture()).fileId(), id);
  EXPECT_EQ(Store::open(hardLinkToFixture()).fileId(), id);
  const fs::path copy = scratch("pager-copy-id.h5");
  fs::copy_file(fixture().path, copy, fs::copy_options::overwrite_existing);
  EXPECT_NE(Store::open(copy).fileId(), id);
}

TEST(PagerSharing, PagersOfOneFileThroughOneCacheLoadEachPatchOnce) {
  // Three spellings of one file, three Store opens, three pagers, one cache.
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Opened a = openPath(fixture().path, cache);
  const Opened b = openPath(symlinkToFixture(), cache);
  const Opened c = openPath(hardLinkToFixture(), cache);
  EXPECT_EQ(a.pager.keyOf("dem", 0, 200, 300), b.pager.keyOf("dem", 0, 200, 300));
  EXPECT_EQ(a.pager.keyOf("dem", 0, 200, 300), c.pager.keyOf("dem", 0, 200, 300));

  const std::vector<double>& want = inMemory();
  expectSameBits(sweep(a.pager.dem("dem")), want);
  expectSameBits(sweep(b.pager.dem("dem")), want);
  expectSameBits(sweep(c.pager.dem("dem")), want);

  const CacheStats s = cache->stats();
  EXPECT_EQ(s.loads, kPatchRows * kPatchCols);
  EXPECT_EQ(s.residentPatches, kPatchRows * kPatchCols);
  EXPECT_EQ(reads(a), kPatchRows * kPatchCols);  // the first sweep read them all
  EXPECT_EQ(reads(b), 0u);
  EXPECT_EQ(reads(c), 0u);
  EXPECT_LE(s.peakResidentBytes, s.capacityBytes);
}

TEST(PagerSharing, PagersOfOneFileThroughTwoCachesHoldEachPatchAsOneObject) {
  // Pager b's cache holds 4 patches: its budget is its own, and it evicts, but every patch it
  // loads is the one a's cache holds, not a second read.
  auto big = std::make_shared<PatchCache>(std::size_t{64} << 20);
  auto small = std::make_shared<PatchCache>(4 * patchBytes());
  const Opened a = openPath(fixture().path, big);
  const Opened b = openPath(hardLinkToFixture(), small);

  const std::vector<double>& want = inMemory();
  expectSameBits(sweep(a.pager.dem("dem")), want);
  expectSameSamples(samplesOf(*b.pager.source("dem")), samplesOf(*fixture().demSamples));
  expectSameBits(sweep(b.pager.dem("dem")), want);  // 4 patches resident at most
  EXPECT_EQ(reads(a), kPatchRows * kPatchCols);
  EXPECT_EQ(reads(b), 0u);
  for (std::size_t pr = 0; pr < kPatchRows; ++pr) {
    for (std::size_t pc = 0; pc < kPatchCols; ++pc) {
      EXPECT_EQ(a.pager.patch(patchKey(a.pager, pr, pc)).get(),
                b.pager.patch(patchKey(b.pager, pr, pc)).get())
          << pr << "," << pc;
    }
  }
  EXPECT_EQ(reads(b), 0u);

  const CacheStats sa = big->stats(), sb = small->stats();
  EXPECT_EQ(sa.evictions, 0u);
  EXPECT_GT(sb.evictions, 0u);
  EXPECT_LE(sb.peakResidentBytes, sb.capacityBytes);
  EXPECT_LE(sa.peakResidentBytes, sa.capacityBytes);
}

TEST(PagerSharing, AnEvictedPatchNoOneHoldsIsReadAgain) {
  // Sharing keeps no patch alive by itself: once no cache or reader holds it, it is read.
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Opened a = openPath(fixture().path, cache);
  const Opened b = openPath(symlinkToFixture(), std::make_shared<PatchCache>(patchBytes()));
  const PatchKey key = patchKey(a.pager, 2, 3);
  (void)a.pager.patch(key);
  EXPECT_EQ(reads(a), 1u);
  cache->clear();
  const auto again = b.pager.patch(key);  // held by b's cache from now on
  EXPECT_EQ(reads(b), 1u);
  EXPECT_EQ(a.pager.patch(key).get(), again.get());
  EXPECT_EQ(reads(a), 1u);
}

TEST(PagerSharing, EightThreadsOnTwoPagersOfOneFileReadEachPatchOnceWithinBudgets) {
  // Four threads on each pager of one file through two caches, at random points: the
  // answers are the in-memory grid's, each cache keeps its budget at every moment, and
  // every patch either cache ever loaded was read once between the two stores (no eviction
  // here: both budgets hold the grid).
  const std::size_t budget = kPatchRows * kPatchCols * patchBytes();
  const Opened a = openPath(fixture().path, std::make_shared<PatchCache>(budget));
  const Opened b = openPath(symlinkToFixture(), std::make_shared<PatchCache>(budget));
  const TopoDem da = a.pager.dem("dem"), db = b.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  std::vector<double> xs(3000), ys(3000), want(3000);
  std::mt19937 rng(30);
  std::uniform_real_distribution<double> x(-500.0, 399.0), y(-299.0, 400.0);
  for (std::size_t i = 0; i < xs.size(); ++i) xs[i] = x(rng), ys[i] = y(rng);
  for (std::size_t i = 0; i < xs.size(); ++i) want[i] = mem.height(xs[i], ys[i]).height;
  for (const std::vector<double>& got : heightsFromEightThreads(da, db, xs, ys)) {
    expectSameBits(got, want);
  }

  std::uint64_t held = 0;  // patches resident in either cache
  for (std::size_t pr = 0; pr < kPatchRows; ++pr) {
    for (std::size_t pc = 0; pc < kPatchCols; ++pc) {
      const PatchKey k = patchKey(a.pager, pr, pc);
      if (a.cache->contains(k) || b.cache->contains(k)) ++held;
    }
  }
  EXPECT_EQ(reads(a) + reads(b), held);
  EXPECT_GT(held, 40u);
  for (const Opened* o : {&a, &b}) {
    const CacheStats s = o->cache->stats();
    EXPECT_EQ(s.evictions, 0u);
    EXPECT_LE(s.peakResidentBytes, s.capacityBytes);
  }
}

TEST(PagerSharing, EightThreadsOnTwoPagersOfOneFileUnderEvictionGetTheInMemoryAnswers) {
  // The same, with 6 patches of budget each: patches are evicted from one cache while the
  // other, or a thread inside them, still holds them; reads of patches no one holds any more
  // race with requests from the other pager. Answers and budgets must not notice (and TSan
  // runs this).
  const std::size_t budget = 6 * patchBytes();
  const Opened a = openPath(fixture().path, std::make_shared<PatchCache>(budget));
  const Opened b = openPath(hardLinkToFixture(), std::make_shared<PatchCache>(budget));
  const TopoDem da = a.pager.dem("dem"), db = b.pager.dem("dem");
  const TopoDem mem = inMemoryDem();
  const std::size_t n = test::scaledWork(3000);
  std::vector<double> xs(n), ys(n), want(n);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> x(-499.0, 398.0), y(-298.0, 399.0);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    xs[i] = x(rng), ys[i] = y(rng);
    want[i] = mem.height(xs[i], ys[i]).height;
  }
  for (const std::vector<double>& got : heightsFromEightThreads(da, db, xs, ys)) {
    expectSameBits(got, want);
  }
  for (const Opened* o : {&a, &b}) {
    const CacheStats s = o->cache->stats();
    EXPECT_GT(s.evictions, 0u);
    EXPECT_LE(s.peakResidentBytes, s.capacityBytes);
  }
  // Every read was of a patch some load asked for.
  EXPECT_LE(reads(a) + reads(b), a.cache->stats().loads + b.cache->stats().loads);
}

TEST(PagerSharing, PagersOfDifferentFilesShareNothing) {
  // A copy holds the same bytes under another inode: its pager reads its own patches.
  const fs::path copy = scratch("pager-copy.h5");
  fs::copy_file(fixture().path, copy, fs::copy_options::overwrite_existing);
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Opened a = openPath(fixture().path, cache);
  const Opened b = openPath(copy, cache);
  EXPECT_NE(a.pager.keyOf("dem", 0, 0, 0), b.pager.keyOf("dem", 0, 0, 0));
  const std::vector<double>& want = inMemory();
  expectSameBits(sweep(a.pager.dem("dem")), want);
  expectSameBits(sweep(b.pager.dem("dem")), want);
  EXPECT_EQ(reads(a), kPatchRows * kPatchCols);
  EXPECT_EQ(reads(b), kPatchRows * kPatchCols);
  EXPECT_EQ(cache->stats().residentPatches, 2 * kPatchRows * kPatchCols);
  EXPECT_NE(a.pager.patch(patchKey(a.pager, 1, 1)).get(),
            b.pager.patch(patchKey(b.pager, 1, 1)).get());
}

TEST(PagerSharing, DestroyingOnePagerLeavesTheOtherWorking) {
  const std::vector<double>& want = inMemory();
  std::optional<Opened> a = openPath(fixture().path, std::make_shared<PatchCache>(64u << 20));
  const Opened b = openPath(hardLinkToFixture(), std::make_shared<PatchCache>(64u << 20));
  std::optional<TopoDem> demA = a->pager.dem("dem");
  const TopoDem demB = b.pager.dem("dem");
  expectSameBits(sweep(*demA), want);
  expectSameBits(sweep(demB), want);
  EXPECT_EQ(reads(*a), kPatchRows * kPatchCols);
  EXPECT_EQ(reads(b), 0u);
  const PatchKey key = patchKey(a->pager, 3, 5);
  demA.reset();
  a.reset();  // its pager, store, cache and source: b's cache still holds every patch
  expectSameBits(sweep(demB), want);
  EXPECT_EQ(reads(b), 0u);
  EXPECT_EQ(b.pager.keyOf("dem", 0, std::size_t{3} * 128, std::size_t{5} * 128), key);

  // A new pager of the file while b lives shares b's patches.
  const Opened c = openPath(fixture().path, std::make_shared<PatchCache>(64u << 20));
  expectSameBits(sweep(c.pager.dem("dem")), want);
  EXPECT_EQ(reads(c), 0u);
}

TEST(PagerSharing, APagerMadeAfterAllOthersAreGoneReadsTheFile) {
  const std::vector<double>& want = inMemory();
  {
    const Opened a = openPath(fixture().path, std::make_shared<PatchCache>(64u << 20));
    expectSameBits(sweep(a.pager.dem("dem")), want);
    EXPECT_EQ(reads(a), kPatchRows * kPatchCols);
  }
  const Opened b = openPath(fixture().path, std::make_shared<PatchCache>(64u << 20));
  expectSameBits(sweep(b.pager.dem("dem")), want);
  EXPECT_EQ(reads(b), kPatchRows * kPatchCols);
}

TEST(PagerSharing, AStoreWrittenOverThePathIsANewFileForNewPagers) {
  // The store at `path` is replaced (writeStore renames a new file over it: a new inode)
  // while a pager of the old one lives: a new pager reads the new samples, the old pager the
  // old ones, and they share no patch, even through one cache.
  const fs::path path = scratch("pager-replaced.h5");
  WriteOptions o;
  o.patchRows = o.patchCols = 128;
  writeStore(path, std::vector<GridSource>{{demInfo(700, 900), fixture().demSamples}}, o);
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Opened old = openPath(path, cache);
  const auto oldSource = old.pager.source("dem");
  const auto raised = InMemorySamples::fromFunction(
      700, 900, [](std::size_t r, std::size_t c) { return terrain(r, c) + 1000.0f; });
  expectSameSamples(samplesOf(*oldSource), samplesOf(*fixture().demSamples));

  writeStore(path, std::vector<GridSource>{{demInfo(700, 900), raised}}, o);
  const Opened fresh = openPath(path, cache);
  EXPECT_NE(fresh.store->fileId(), old.store->fileId());
  EXPECT_NE(old.pager.keyOf("dem", 0, 0, 0), fresh.pager.keyOf("dem", 0, 0, 0));
  expectSameSamples(samplesOf(*fresh.pager.source("dem")), samplesOf(*raised));
  EXPECT_EQ(reads(fresh), kPatchRows * kPatchCols);
  expectSameSamples(samplesOf(*oldSource), samplesOf(*fixture().demSamples));  // still the old file
  EXPECT_EQ(reads(old), kPatchRows * kPatchCols);
}
