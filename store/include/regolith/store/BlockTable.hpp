#pragma once
/// \file
/// Lock-free lookup of a paged source's resident blocks, for queries that jump between
/// blocks (random access) without taking the cache's lock: the tables, the hazard domains
/// that keep a block alive while a thread reads it, and the recency clock. Queries see a
/// table through its read side, BlockIndex (BlockIndex.hpp); only the cache (PatchCache) writes
/// one.
///
/// Why hand-written: a query that enters a new block used to go through the cache (mutex,
/// hash map, policy bookkeeping, shared_ptr reference counts): some 300 instructions and
/// several full fences. That made the processor run one query at a time, so every
/// DRAM/TLB miss was paid in full (200 ns on the benchmark machine) where an in-memory grid
/// overlaps the misses of several queries (20–30 ns). No Debian library offers safe memory
/// reclamation for this; the scheme is the standard one (hazard pointers with an asymmetric
/// fence, as in folly and liburcu), kept to the few operations needed here.
///
/// Protocol. The cache publishes each resident block in the table of its source (a release
/// store) and retracts it before eviction. A reader loads the slot, announces the block in
/// its thread's hazard record of the table's domain with a plain store (protect()),
/// re-reads the slot and uses the block only if it is unchanged. The reclaimer retracts, runs
/// a process-wide memory barrier (Linux membarrier(2), which makes every running thread
/// execute a full fence), then frees a retracted block only if no record of its domain names
/// it. The reader therefore needs no fence. Where membarrier is unavailable, a domain hands
/// out no record for the lock-free path (joinDomain() gives null) and queries enter new
/// blocks through the cache's lock. ThreadSanitizer builds run this same protocol (TSan
/// does not model membarrier, but it needs no more than the release stores of the records
/// and the reclaimer's acquire loads to order a reader's last reads of a block before its
/// free), so the TSan tests check the code that ships.
///
/// Domains. Each cache has its own HazardDomain: its records (one per thread that has read
/// its tables) and its recency clock. Two caches share nothing, so one cache's reclaimer
/// scans only its own readers, and its recency ticks are its own.

#include <regolith/store/BlockIndex.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace regolith::store {

/// The hazard records of the threads that read one cache's block tables, and the cache's
/// recency clock. Made with std::make_shared (threads keep weak references to their records'
/// domain, to give the records back when they end). Thread-safety: every member may be
/// called from any thread.
class HazardDomain : public std::enable_shared_from_this<HazardDomain> {
 public:
  HazardDomain();
  ~HazardDomain();
  HazardDomain(const HazardDomain&) = delete;
  HazardDomain& operator=(const HazardDomain&) = delete;

  /// An id unique in the process and never reused (never 0).
  [[nodiscard]] std::uint64_t id() const noexcept { return id_; }

  /// The calling thread's record in this domain, registering the thread on first use (a
  /// record of an ended thread is reused). The record is given back when the thread ends.
  /// Requires that the domain is owned by a shared_ptr. Throws std::bad_alloc.
  [[nodiscard]] HazardRecord& threadRecord();
  /// threadRecord() where readers may skip the fence (membarrier(2) is registered), else
  /// null: queries then do not use the tables. Clears the thread's
  /// records in other domains (BlockIndex::joinDomain()).
  [[nodiscard]] HazardRecord* lockFreeRecord();
  /// Whether readers may use the lock-free path in this process (membarrier(2) registered).
  [[nodiscard]] static bool lockFree() noexcept;

  /// Reclaimer side, after retracting: a full memory barrier on every thread of the process
  /// (membarrier), or nothing when membarrier is unavailable (then no query announces
  /// hazards: they do not use the tables). False if the barrier could not be made;
  /// then nothing retracted may be freed yet.
  [[nodiscard]] static bool barrier() noexcept;
  /// True if some thread's record of this domain names p. Call after barrier().
  [[nodiscard]] bool isProtected(const void* p) const noexcept;
  /// Clears every record of this domain that names p. For an owner freeing blocks that no
  /// thread can be reading any more (their sources are gone): a record left naming a freed
  /// address would take a new block allocated there for one it has protected all along.
  void forget(const void* p) noexcept;

  /// A recency tick for an event under the cache's lock (a miss, a locked hit): unique and
  /// increasing across all threads.
  std::uint64_t tick() noexcept { return clock_.fetch_add(1, std::memory_order_relaxed); }
  /// The stamp of a lock-free hit (BlockIndex::now()): the clock as it is, newer than
  /// every tick handed out before it.
  [[nodiscard]] std::uint64_t now() const noexcept {
    return clock_.load(std::memory_order_relaxed);
  }
  /// The clock itself, for the tables' readers.
  [[nodiscard]] const std::atomic<std::uint64_t>* clock() const noexcept { return &clock_; }

  /// A thread's record: the reader's part, and the registry's.
  struct Record : HazardRecord {
    std::atomic<bool> inUse{false};  // owned by a live thread
    Record* next = nullptr;          // registry list (freed with the domain)
  };

 private:
  std::atomic<Record*> records_{nullptr};
  std::uint64_t id_;
  /// Source of recency ticks (0 means "never used"), alone on its cache line: lock-free hits
  /// read it, and only events under the cache's lock write it.
  alignas(64) std::atomic<std::uint64_t> clock_{1};
};

/// The resident blocks of one source, one slot per aligned blockRows × blockCols block, in
/// the hazard domain of the cache that publishes them. Readers: the BlockIndex side.
/// Writers (the cache, under its own lock): publish() and retract().
///
/// Memory: the slots are one anonymous mapping of the whole table, reserved without backing
/// (MAP_NORESERVE), so the operating system gives a page (170 slots) only when a block in it
/// is first published, and the table gives the page back (madvise MADV_DONTNEED, which
/// leaves it reading as zeros, all slots empty) when the last block published in it is
/// retracted. A table therefore costs nothing at construction, and at most one page per
/// published block afterwards: it follows the cache's resident patches, not the grid nor
/// the area ever paged (a 2^20 × 2^20 grid in 16 × 8 patches would otherwise take 192 GiB
/// up front, and a random walk over a 2^20 × 2^21 grid in 256 × 256 patches would keep up to
/// 768 MiB of pages it once touched). Counts of published slots per page, in a second such
/// mapping whose pages are given back in the same way, tell when a page empties. Why not a radix
/// tree: its extra dependent loads on every block switch would slow random queries, and the
/// kernel's lazy zero pages give the same sparseness with none.
class BlockTable final : public BlockIndex {
 public:
  /// The most bytes of address space one table may reserve (2^40, 1 TiB; the table of a
  /// 2^31 × 2^31 grid in 64 × 64 patches takes 24 GiB).
  static constexpr std::size_t kMaxReservedBytes = std::size_t{1} << 40;
  /// The most blocks a table may hold (24 bytes of address space each).
  static constexpr std::size_t kMaxBlocks = kMaxReservedBytes / 24;

  /// A table in `domain`, or in a domain of its own when it is null. Throws InvalidArgument
  /// for zero sizes or a table that would reserve more than kMaxReservedBytes, and Error if
  /// the address space cannot be reserved.
  BlockTable(std::size_t rows, std::size_t cols, std::size_t blockRows, std::size_t blockCols,
             std::shared_ptr<HazardDomain> domain = nullptr);
  ~BlockTable() override;
  BlockTable(const BlockTable&) = delete;
  BlockTable& operator=(const BlockTable&) = delete;

  /// The domain whose records protect this table's blocks.
  [[nodiscard]] HazardDomain& hazards() const noexcept { return *domain_; }
  [[nodiscard]] HazardRecord* joinDomain() const override { return domain_->lockFreeRecord(); }

  /// Publishes block (blockRow, blockCol), which must be complete (data and geometry).
  /// Writers only (under the owner's lock).
  void publish(std::size_t blockRow, std::size_t blockCol, const PublishedBlock* block) noexcept;
  /// Removes block (blockRow, blockCol); readers may still use it until it is reclaimed.
  /// Gives the slot's page back to the kernel when no block of it is published any more.
  /// Writers only (under the owner's lock).
  void retract(std::size_t blockRow, std::size_t blockCol) noexcept;

 private:
  BlockTable(const Geometry& g, std::shared_ptr<HazardDomain> domain);

  std::shared_ptr<HazardDomain> domain_;
  std::size_t mappedBytes_ = 0;
  /// Counts slot `index` in (published) or out of the pages it overlaps, giving back the
  /// pages that empty.
  void countSlot(std::size_t index, bool published) noexcept;

  /// Published slots overlapping each page of the mapping (a slot may straddle two pages
  /// and counts in both), then the non-zero counts of each page of those counts: a second
  /// lazily backed mapping, written by writers only, whose pages are given back as well.
  std::uint32_t* pageCounts_ = nullptr;
  std::uint32_t* countPageCounts_ = nullptr;
  std::size_t countBytes_ = 0;
  unsigned pageShift_ = 12;  // log2 of the system page size
};

}  // namespace regolith::store
