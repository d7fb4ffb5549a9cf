#pragma once
/// \file
/// Lock-free lookup of a paged source's resident blocks, for queries that jump between
/// blocks (random access) without taking the cache's lock.
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
/// its thread's hazard record with a plain store, re-reads the slot and uses the block only
/// if it is unchanged. The reclaimer retracts, runs a process-wide memory barrier
/// (Linux membarrier(2), which makes every running thread execute a full fence), then frees
/// a retracted block only if no thread's hazard record names it. The reader therefore needs
/// no fence. Where membarrier is unavailable, queries do not use the table (tlFastRecord
/// stays null) and enter new blocks through the cache's lock. Under ThreadSanitizer, which does not
/// model membarrier, the reader uses a sequentially consistent store instead.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace regolith::topo {

/// The address sample (0, 0) of the grid would have if a block's rows extended back to it,
/// in integer arithmetic (as a pointer it could lie outside any object): a query then finds
/// sample (r, c) at origin + (r·stride + c)·sizeof(float) with no subtraction of the
/// block's first row and column (fewer instructions on the random-access path).
[[nodiscard]] inline std::uintptr_t originOf(const float* data, std::size_t row0, std::size_t col0,
                                             std::size_t stride) noexcept {
  return reinterpret_cast<std::uintptr_t>(data) - (row0 * stride + col0) * sizeof(float);
}

/// A block as published in a BlockTable. Its samples and geometry are immutable while it is
/// published and until its reclaimer frees it. The counters are the cache's per-block hit
/// bookkeeping, written by readers with relaxed loads and stores (no read-modify-write, so
/// two threads entering the same block at the same instant may count once).
struct PublishedBlock {
  const float* data = nullptr;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0, stride = 0;
  /// Fractional (u, v) whose whole bilinear cell lies in the block (as in a ThreadBlock).
  double uLo = 0.0, uHi = 0.0, vLo = 0.0, vHi = 0.0;
  /// originOf(data, row0, col0, stride): sample (r, c) is at origin + (r·stride + c)·4.
  std::uintptr_t origin = 0;
  mutable std::atomic<std::uint64_t> fastHits{0};  // hits taken through the table
  mutable std::atomic<std::uint64_t> lastUse{0};   // tick of the last hit
};

/// The resident blocks of one source, one slot per aligned blockRows × blockCols block.
/// Readers: find(). Writers (the cache, under its own lock): publish() and retract().
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
class BlockTable {
 public:
  /// The most bytes of address space one table may reserve (2^40, 1 TiB; the table of a
  /// 2^31 × 2^31 grid in 64 × 64 patches takes 24 GiB).
  static constexpr std::size_t kMaxReservedBytes = std::size_t{1} << 40;
  /// The most blocks a table may hold (24 bytes of address space each).
  static constexpr std::size_t kMaxBlocks = kMaxReservedBytes / 24;

  /// Throws InvalidArgument for zero sizes or a table that would reserve more than
  /// kMaxReservedBytes, and Error if the address space cannot be reserved.
  BlockTable(std::size_t rows, std::size_t cols, std::size_t blockRows, std::size_t blockCols);
  ~BlockTable();
  BlockTable(const BlockTable&) = delete;
  BlockTable& operator=(const BlockTable&) = delete;

  [[nodiscard]] std::size_t rows() const noexcept { return rows_; }
  [[nodiscard]] std::size_t cols() const noexcept { return cols_; }
  [[nodiscard]] std::size_t blockRows() const noexcept { return blockRows_; }
  [[nodiscard]] std::size_t blockCols() const noexcept { return blockCols_; }

  /// An atomic view of one slot (the slots are plain pointers in zero-filled pages, so they
  /// are accessed through std::atomic_ref).
  using Slot = std::atomic_ref<const PublishedBlock*>;
  /// The slot of the block holding sample (r, c); load it with acquire. Requires
  /// r < rows(), c < cols().
  [[nodiscard]] Slot slot(std::size_t r, std::size_t c) const noexcept {
    return Slot(entries_[index(r, c)].block);
  }
  /// The published block holding sample (r, c), or null. Requires r < rows(), c < cols().
  [[nodiscard]] const PublishedBlock* find(std::size_t r, std::size_t c) const noexcept {
    return slot(r, c).load(std::memory_order_acquire);
  }
  /// Whether (blockRow, blockCol) names a block of the table.
  [[nodiscard]] bool hasBlock(std::size_t blockRow, std::size_t blockCol) const noexcept {
    return blockRow < blocksPerCol_ && blockCol < blocksPerRow_;
  }
  /// Publishes block (blockRow, blockCol), which must be complete (data and geometry).
  /// Writers only (under the owner's lock).
  void publish(std::size_t blockRow, std::size_t blockCol, const PublishedBlock* block) noexcept;
  /// Removes block (blockRow, blockCol); readers may still use it until it is reclaimed.
  /// Gives the slot's page back to the kernel when no block of it is published any more.
  /// Writers only (under the owner's lock).
  void retract(std::size_t blockRow, std::size_t blockCol) noexcept;

  /// Asks the processor to fetch the bilinear cell of sample (r, c) (rows r and r + 1) and
  /// the block's header into the cache, if the block is published. A hint only: it reads
  /// no block (the address comes from a copy of the block's data pointer and stride kept in
  /// the table), so it needs no hazard protection, and a stale address is harmless (a
  /// prefetch never faults). Batch queries issue it a few points ahead, so the memory misses
  /// of several random points overlap. Requires r < rows(), c < cols().
  void prefetchCell(std::size_t r, std::size_t c) const noexcept {
    const std::size_t br = pow2_ ? r >> rowShift_ : r / blockRows_;
    const std::size_t bc = pow2_ ? c >> colShift_ : c / blockCols_;
    Entry& e = entries_[br * blocksPerRow_ + bc];
    const float* data = std::atomic_ref(e.hintData).load(std::memory_order_relaxed);
    if (data == nullptr) return;
    const std::size_t stride = std::atomic_ref(e.hintStride).load(std::memory_order_relaxed);
    // Integer arithmetic: the pointer may be stale, so no pointer arithmetic on it.
    const std::uintptr_t p =
        reinterpret_cast<std::uintptr_t>(data) +
        ((r - br * blockRows_) * stride + (c - bc * blockCols_)) * sizeof(float);
    __builtin_prefetch(reinterpret_cast<const void*>(p));                           // NOLINT
    __builtin_prefetch(reinterpret_cast<const void*>(p + stride * sizeof(float)));  // NOLINT
    __builtin_prefetch(Slot(e.block).load(std::memory_order_relaxed));
  }

 private:
  /// One block's slot, with copies of its data pointer and row stride for prefetchCell().
  /// Plain members (all zero = empty) accessed through std::atomic_ref, so that the zero
  /// pages of the mapping are valid entries without being written.
  struct Entry {
    const PublishedBlock* block;
    const float* hintData;
    std::size_t hintStride;
  };

  /// The slot index of sample (r, c). Shifts for power-of-two blocks (the default 256): a
  /// 64-bit division is some 40 micro-operations, and four of them per block switch kept the
  /// processor from overlapping the memory misses of consecutive random queries.
  [[nodiscard]] std::size_t index(std::size_t r, std::size_t c) const noexcept {
    if (pow2_) [[likely]]
      return (r >> rowShift_) * blocksPerRow_ + (c >> colShift_);
    return (r / blockRows_) * blocksPerRow_ + c / blockCols_;
  }

  std::size_t rows_, cols_, blockRows_, blockCols_, blocksPerRow_ = 0, blocksPerCol_ = 0;
  bool pow2_ = false;                     // both block sizes are powers of two
  unsigned rowShift_ = 0, colShift_ = 0;  // their log2 when pow2_
  Entry* entries_ = nullptr;              // the mapping (mutable through atomic_ref)
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

/// Hazard records: one per thread, process-wide (the hazard domain is per-process
/// infrastructure, like the thread-local block queries keep; it holds no terrain state).
namespace hazard {

struct Record {
  std::atomic<const void*> ptr{nullptr};  // the block this thread may be reading
  std::atomic<bool> inUse{false};         // owned by a live thread
  Record* next = nullptr;                 // registry list (records are never freed)
};

/// The calling thread's record, or null before acquire().
inline thread_local Record* tlRecord = nullptr;  // NOLINT
/// The same record for the lock-free query path (enterBlock), or null: acquire() sets it
/// only where readers need no fence (membarrier(2) registered; or under ThreadSanitizer,
/// where readers store their hazards sequentially consistently), so that path carries no
/// test of gAsymmetric. Elsewhere (an old kernel, a seccomp filter) queries entering a new
/// block go through the source's block() under the cache's lock instead.
inline thread_local Record* tlFastRecord = nullptr;  // NOLINT

/// Set once, before the first record is handed out: membarrier(2) is registered, so readers
/// may skip the fence.
inline std::atomic<bool> gAsymmetric{false};  // NOLINT
/// Source of recency ticks (0 means "never used"), alone on its cache line: lock-free hits
/// read it, and only events under a cache's lock write it.
alignas(64) inline std::atomic<std::uint64_t> gClock{1};  // NOLINT

/// The calling thread's record, registering one on first use (out of line, once per thread).
Record& acquire();

/// Announces that this thread is about to read `p` (then re-check that p is still
/// published before using it). No fence: membarrier(2) on the reclaimer's side pairs with it,
/// which is why queries use it only through tlFastRecord (set only where membarrier is
/// registered, or under TSan, where the store is sequentially consistent instead).
inline void protect(Record& rec, const void* p) noexcept {
#if defined(__SANITIZE_THREAD__)
  rec.ptr.store(p, std::memory_order_seq_cst);
#else
  rec.ptr.store(p, std::memory_order_release);
  std::atomic_signal_fence(std::memory_order_seq_cst);  // compiler-only; membarrier pairs
#endif
}

/// Reclaimer side, after retracting: a full memory barrier on every thread of the process
/// (membarrier), or a local full fence when membarrier is unavailable (then no query
/// announces hazards: they do not use the tables). False if the barrier could not be made;
/// then nothing retracted may be freed yet.
[[nodiscard]] bool barrier() noexcept;

/// True if some thread's record names p. Call after barrier().
[[nodiscard]] bool isProtected(const void* p) noexcept;

/// Clears every record that names p. For an owner freeing blocks that no thread can be
/// reading any more (their sources are gone): a record left naming a freed address would
/// take a new block allocated there for one it has protected all along.
void forget(const void* p) noexcept;

/// A recency tick for an event under a cache's lock (a miss, a locked hit): unique and
/// increasing across all threads.
inline std::uint64_t tick() noexcept { return gClock.fetch_add(1, std::memory_order_relaxed); }

/// The recency stamp of a lock-free hit: the clock's current value, newer than every tick
/// handed out before it, with no write to the shared clock (a read-modify-write per random
/// query would be a locked instruction and a contended cache line). Lock-free hits between
/// two ticks therefore tie with each other and with the next tick.
inline std::uint64_t now() noexcept { return gClock.load(std::memory_order_relaxed); }

}  // namespace hazard
}  // namespace regolith::topo
