// BlockTable (lock-free lookup of published blocks) and the hazard domains whose records let
// a reclaimer know which retracted blocks a thread may still be reading.
#include <regolith/core/Error.hpp>
#include <regolith/store/BlockTable.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::store;

namespace {
// Every sample finds the block of its own (row / blockRows, col / blockCols).
void expectLookupCoversTheGrid(std::size_t rows, std::size_t cols, std::size_t br, std::size_t bc) {
  BlockTable t(rows, cols, br, bc);
  const std::size_t nbr = (rows + br - 1) / br, nbc = (cols + bc - 1) / bc;
  std::vector<PublishedBlock> blocks(nbr * nbc);
  for (std::size_t i = 0; i < nbr; ++i) {
    for (std::size_t j = 0; j < nbc; ++j) {
      ASSERT_TRUE(t.hasBlock(i, j));
      t.publish(i, j, &blocks[i * nbc + j]);
    }
  }
  EXPECT_FALSE(t.hasBlock(nbr, 0));
  EXPECT_FALSE(t.hasBlock(0, nbc));
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      ASSERT_EQ(t.find(r, c), &blocks[(r / br) * nbc + c / bc]) << r << ", " << c;
    }
  }
}
}  // namespace

TEST(BlockTable, FindsTheBlockOfEverySampleWithPowerOfTwoBlocks) {
  expectLookupCoversTheGrid(70, 90, 16, 32);  // partial blocks at both far edges
}

TEST(BlockTable, FindsTheBlockOfEverySampleWithOtherBlockSizes) {
  expectLookupCoversTheGrid(70, 90, 12, 25);
}

TEST(BlockTable, RetractedBlocksAreNoLongerFound) {
  BlockTable t(10, 10, 4, 4);
  PublishedBlock a;
  EXPECT_EQ(t.find(5, 5), nullptr);
  t.publish(1, 1, &a);
  EXPECT_EQ(t.find(5, 5), &a);
  EXPECT_EQ(t.find(4, 7), &a);
  EXPECT_EQ(t.find(3, 7), nullptr);
  t.retract(1, 1);
  EXPECT_EQ(t.find(5, 5), nullptr);
}

namespace {
/// Resident bytes of the one mapping of this process whose size lies in [lo, hi]
/// (/proc/self/smaps, its "Rss:" line): the table's own reservation, so the count is the
/// kernel's for the table alone, not the whole process (whose allocator, and ASan's
/// quarantine and shadow, hold memory of their own).
std::size_t residentBytesOfMapping(std::size_t lo, std::size_t hi) {
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  std::size_t found = 0;
  int matches = 0;
  while (std::getline(smaps, line)) {
    const auto dash = line.find('-');
    const auto space = line.find(' ');
    if (dash != std::string::npos && space != std::string::npos && dash < space &&
        line.find_first_not_of("0123456789abcdef") == dash) {
      const std::size_t start = std::stoull(line.substr(0, dash), nullptr, 16);
      const std::size_t end = std::stoull(line.substr(dash + 1, space - dash - 1), nullptr, 16);
      inside = end - start >= lo && end - start <= hi;
      matches += inside ? 1 : 0;
    } else if (inside && line.rfind("Rss:", 0) == 0) {
      found = std::stoull(line.substr(4)) * 1024;  // "Rss:   123 kB"
    }
  }
  EXPECT_EQ(matches, 1) << "mappings of " << lo << ".." << hi << " bytes";
  return found;
}
}  // namespace

// The kernel is the oracle: a table of 2^20 × 2^21 samples in 64 × 64 blocks reserves 12 GiB
// and costs nothing until blocks are published; publishing blocks far apart backs one page
// each; retracting them gives the pages back, and the slots read empty again.
TEST(BlockTable, MemoryFollowsThePublishedBlocksNotTheGrid) {
  BlockTable t(std::size_t{1} << 20, std::size_t{1} << 21, 64, 64);
  // 2^14 × 2^15 blocks of 24-byte entries: a 12 GiB reservation, and beside it the per-page
  // counts (12 MiB), which the kernel may merge into one mapping with it.
  const std::size_t reserved = (std::size_t{1} << 29) * 24;
  const auto residentBytes = [&] {
    return residentBytesOfMapping(reserved, reserved + reserved / 512);
  };
  const std::size_t opened = residentBytes();
  EXPECT_LT(opened, std::size_t{1} << 20);
  constexpr std::size_t kBlocks = 2048;  // one per page: block rows 8 apart, 2^15 slots a row
  PublishedBlock b;
  for (std::size_t i = 0; i < kBlocks; ++i) t.publish(i * 8, i % 7, &b);
  const std::size_t published = residentBytes();
  const std::size_t pages = kBlocks * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  EXPECT_GT(published, opened + pages / 2);  // the slots' pages are backed
  for (std::size_t i = 0; i < kBlocks; ++i) {
    ASSERT_EQ(t.find(i * 8 * 64, (i % 7) * 64 + 5), &b);
    t.retract(i * 8, i % 7);
  }
  const std::size_t retracted = residentBytes();
  EXPECT_LT(retracted, opened + pages / 8);  // and given back
  for (std::size_t i = 0; i < kBlocks; ++i) ASSERT_EQ(t.find(i * 8 * 64, (i % 7) * 64), nullptr);
  // A page holding two published slots stays until both are retracted.
  PublishedBlock c;
  t.publish(5, 0, &b);
  t.publish(5, 1, &c);
  t.retract(5, 0);
  EXPECT_EQ(t.find(std::size_t{5} * 64, 64), &c);
  t.retract(5, 1);
  EXPECT_EQ(t.find(std::size_t{5} * 64, 64), nullptr);
}

TEST(BlockTable, PrefetchHintsNeverReadABlock) {
  // prefetchCell() takes its address from the table's copy of the data pointer, never from
  // the block: after a block is retracted and freed, prefetching its cells is a no-op (an
  // AddressSanitizer build would report a read of the freed block).
  BlockTable t(64, 64, 16, 16);
  std::vector<float> samples(std::size_t{16} * 16, 1.0F);
  auto* b = new PublishedBlock{samples.data(), 16, 32, 16, 16, 16, 32.0, 47.0, 16.0, 31.0};
  for (std::size_t r = 0; r < 64; r += 5)
    for (std::size_t c = 0; c < 64; c += 3) t.prefetchCell(r, c);  // nothing published
  t.publish(1, 2, b);
  for (std::size_t r = 16; r < 32; ++r)
    for (std::size_t c = 32; c < 48; ++c) t.prefetchCell(r, c);
  t.retract(1, 2);
  delete b;  // NOLINT(cppcoreguidelines-owning-memory): the cache frees blocks like this
  for (std::size_t r = 16; r < 32; ++r)
    for (std::size_t c = 32; c < 48; ++c) t.prefetchCell(r, c);
  EXPECT_EQ(t.find(20, 40), nullptr);
}

TEST(BlockTable, ZeroSizesAreRefusedClearly) {
  EXPECT_THROW(BlockTable(0, 10, 4, 4), InvalidArgument);
  EXPECT_THROW(BlockTable(10, 10, 4, 0), InvalidArgument);
  try {
    const BlockTable t(10, 10, 0, 4);
    FAIL() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("blocks of 0 x 4"), std::string::npos) << e.what();
  }
}

TEST(Hazard, AThreadProtectsOneBlockUntilItMovesOnOrEnds) {
  const auto domain = std::make_shared<HazardDomain>();
  PublishedBlock a, b;
  std::atomic<int> step{0};
  std::thread reader([&] {
    HazardRecord& rec = domain->threadRecord();
    EXPECT_EQ(&rec, &domain->threadRecord());  // one record per thread and domain
    protect(rec, &a);
    step = 1;
    while (step != 2) std::this_thread::yield();
    protect(rec, &b);  // moves on: a is free to go
    step = 3;
    while (step != 4) std::this_thread::yield();
  });
  while (step != 1) std::this_thread::yield();
  ASSERT_TRUE(HazardDomain::barrier());
  EXPECT_TRUE(domain->isProtected(&a));
  EXPECT_FALSE(domain->isProtected(&b));
  step = 2;
  while (step != 3) std::this_thread::yield();
  ASSERT_TRUE(HazardDomain::barrier());
  EXPECT_FALSE(domain->isProtected(&a));
  EXPECT_TRUE(domain->isProtected(&b));
  step = 4;
  reader.join();  // the ended thread's record protects nothing
  ASSERT_TRUE(HazardDomain::barrier());
  EXPECT_FALSE(domain->isProtected(&b));
}

// One domain per cache: a thread's hazard in one domain protects nothing in another, each
// domain's clock is its own, and a table reads the clock of its domain.
TEST(Hazard, DomainsShareNeitherRecordsNorClocks) {
  const auto one = std::make_shared<HazardDomain>();
  const auto two = std::make_shared<HazardDomain>();
  EXPECT_NE(one->id(), two->id());
  EXPECT_NE(one->id(), 0U);
  PublishedBlock a;
  HazardRecord& r1 = one->threadRecord();
  HazardRecord& r2 = two->threadRecord();
  EXPECT_NE(&r1, &r2);
  protect(r1, &a);
  ASSERT_TRUE(HazardDomain::barrier());
  EXPECT_TRUE(one->isProtected(&a));
  EXPECT_FALSE(two->isProtected(&a));
  one->forget(&a);
  EXPECT_FALSE(one->isProtected(&a));

  const std::uint64_t before = two->now();
  for (int i = 0; i < 100; ++i) (void)one->tick();
  EXPECT_EQ(two->now(), before);
  const BlockTable t1(10, 10, 4, 4, one), t2(10, 10, 4, 4, two);
  EXPECT_EQ(t1.domain(), one->id());
  EXPECT_EQ(t2.domain(), two->id());
  EXPECT_EQ(t1.now(), one->now());
  EXPECT_EQ(t2.now(), before);
  EXPECT_EQ(&t1.hazards(), one.get());
  // Where membarrier(2) is registered (this test machine), the lock-free path is open and
  // joining gives the thread's record of the table's domain.
  if (HazardDomain::lockFree()) {
    EXPECT_EQ(t1.joinDomain(), &r1);
    protect(r1, &a);
    // Joining the second domain gives up the thread's hazard in the first, so the first
    // cache may free the block the thread read last there.
    EXPECT_EQ(t2.joinDomain(), &r2);
    ASSERT_TRUE(HazardDomain::barrier());
    EXPECT_FALSE(one->isProtected(&a));
  } else {
    EXPECT_EQ(t1.joinDomain(), nullptr);
  }
  // A table made without a domain has one of its own.
  const BlockTable own(10, 10, 4, 4);
  EXPECT_NE(own.domain(), one->id());
  EXPECT_NE(own.domain(), two->id());
}

// A record outlives neither its domain's use nor its thread: a thread's records are given
// back when it ends, even for a domain already gone.
TEST(Hazard, RecordsOfEndedThreadsAreReusedAndDomainsMayGoFirst) {
  const auto domain = std::make_shared<HazardDomain>();
  HazardRecord* first = nullptr;
  std::thread([&] { first = &domain->threadRecord(); }).join();
  HazardRecord* second = nullptr;
  std::thread([&] { second = &domain->threadRecord(); }).join();
  EXPECT_EQ(first, second);  // the ended thread's record, reused
  std::thread([] {
    auto gone = std::make_shared<HazardDomain>();
    protect(gone->threadRecord(), &gone);
    gone.reset();  // the thread ends after its domain: nothing to give back, no crash
  }).join();
}

TEST(Hazard, RecencyTicksAreUniqueAndIncreasingAcrossThreadsAndStampsAreNewer) {
  HazardDomain clock;
  std::uint64_t last = clock.tick();
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t t = clock.tick();
    ASSERT_GT(t, last);
    last = t;
  }
  // A lock-free hit's stamp is newer than every tick handed out before it, and does not
  // advance the clock.
  EXPECT_GT(clock.now(), last);
  EXPECT_EQ(clock.now(), clock.now());
  // Ticks of several threads at once: all distinct.
  std::vector<std::uint64_t> ticks[4];
  {
    std::vector<std::thread> threads;
    for (auto& v : ticks) {
      threads.emplace_back([&v, &clock] {
        for (int i = 0; i < 2000; ++i) v.push_back(clock.tick());
      });
    }
    for (std::thread& t : threads) t.join();
  }
  std::vector<std::uint64_t> all;
  for (const auto& v : ticks) {
    ASSERT_TRUE(std::is_sorted(v.begin(), v.end()));
    all.insert(all.end(), v.begin(), v.end());
  }
  std::sort(all.begin(), all.end());
  EXPECT_EQ(std::adjacent_find(all.begin(), all.end()), all.end());
  EXPECT_GT(all.front(), last);
  EXPECT_GT(clock.now(), all.back());
}
