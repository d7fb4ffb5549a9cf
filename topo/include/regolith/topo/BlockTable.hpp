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
/// no fence; where membarrier is unavailable (and under ThreadSanitizer, which does not model
/// it) the reader uses a sequentially consistent store instead.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace regolith::topo {

/// A block as published in a BlockTable. Its samples and geometry are immutable while it is
/// published and until its reclaimer frees it. The counters are the cache's per-block hit
/// bookkeeping, written by readers with relaxed loads and stores (no read-modify-write, so
/// two threads entering the same block at the same instant may count once).
struct PublishedBlock {
  const float* data = nullptr;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0, stride = 0;
  /// Fractional (u, v) whose whole bilinear cell lies in the block (as in a ThreadBlock).
  double uLo = 0.0, uHi = 0.0, vLo = 0.0, vHi = 0.0;
  mutable std::atomic<std::uint64_t> fastHits{0};  // hits taken through the table
  mutable std::atomic<std::uint64_t> lastUse{0};   // tick of the last hit
};

/// The resident blocks of one source, one slot per aligned blockRows × blockCols block.
/// Readers: find(). Writers (the cache, under its own lock): publish() and retract().
class BlockTable {
 public:
  /// Throws InvalidArgument for zero sizes.
  BlockTable(std::size_t rows, std::size_t cols, std::size_t blockRows, std::size_t blockCols);

  [[nodiscard]] std::size_t rows() const noexcept { return rows_; }
  [[nodiscard]] std::size_t cols() const noexcept { return cols_; }
  [[nodiscard]] std::size_t blockRows() const noexcept { return blockRows_; }
  [[nodiscard]] std::size_t blockCols() const noexcept { return blockCols_; }

  using Slot = std::atomic<const PublishedBlock*>;
  /// The slot of the block holding sample (r, c); load it with acquire. Requires
  /// r < rows(), c < cols().
  [[nodiscard]] const Slot& slot(std::size_t r, std::size_t c) const noexcept {
    // Shifts for power-of-two blocks (the default 256): a 64-bit division is some 40
    // micro-operations, and four of them per block switch kept the processor from
    // overlapping the memory misses of consecutive random queries.
    const std::size_t br = rowShift_ >= 0 ? r >> rowShift_ : r / blockRows_;
    const std::size_t bc = colShift_ >= 0 ? c >> colShift_ : c / blockCols_;
    return slots_[br * blocksPerRow_ + bc];
  }
  /// The published block holding sample (r, c), or null. Requires r < rows(), c < cols().
  [[nodiscard]] const PublishedBlock* find(std::size_t r, std::size_t c) const noexcept {
    return slot(r, c).load(std::memory_order_acquire);
  }
  /// Whether (blockRow, blockCol) names a block of the table.
  [[nodiscard]] bool hasBlock(std::size_t blockRow, std::size_t blockCol) const noexcept {
    return blockRow * blockRows_ < rows_ && blockCol < blocksPerRow_;
  }
  /// Publishes block (blockRow, blockCol), which must be complete (data and geometry).
  void publish(std::size_t blockRow, std::size_t blockCol, const PublishedBlock* block) noexcept {
    const std::size_t i = blockRow * blocksPerRow_ + blockCol;
    hints_[i].stride.store(block->stride, std::memory_order_relaxed);
    hints_[i].data.store(block->data, std::memory_order_relaxed);
    slots_[i].store(block, std::memory_order_release);
  }
  /// Removes block (blockRow, blockCol); readers may still use it until it is reclaimed.
  void retract(std::size_t blockRow, std::size_t blockCol) noexcept {
    const std::size_t i = blockRow * blocksPerRow_ + blockCol;
    hints_[i].data.store(nullptr, std::memory_order_relaxed);
    slots_[i].store(nullptr, std::memory_order_seq_cst);
  }

  /// Asks the processor to fetch the bilinear cell of sample (r, c) (rows r and r + 1) and
  /// the block's header into the cache, if the block is published. A hint only: it reads
  /// no block (the address comes from a copy of the block's data pointer and stride kept in
  /// the table), so it needs no hazard protection, and a stale address is harmless (a
  /// prefetch never faults). Batch queries issue it a few points ahead, so the memory misses
  /// of several random points overlap. Requires r < rows(), c < cols().
  void prefetchCell(std::size_t r, std::size_t c) const noexcept {
    const std::size_t br = rowShift_ >= 0 ? r >> rowShift_ : r / blockRows_;
    const std::size_t bc = colShift_ >= 0 ? c >> colShift_ : c / blockCols_;
    const std::size_t i = br * blocksPerRow_ + bc;
    const float* data = hints_[i].data.load(std::memory_order_relaxed);
    if (data == nullptr) return;
    const std::size_t stride = hints_[i].stride.load(std::memory_order_relaxed);
    // Integer arithmetic: the pointer may be stale, so no pointer arithmetic on it.
    const std::uintptr_t p =
        reinterpret_cast<std::uintptr_t>(data) +
        ((r - br * blockRows_) * stride + (c - bc * blockCols_)) * sizeof(float);
    __builtin_prefetch(reinterpret_cast<const void*>(p));                           // NOLINT
    __builtin_prefetch(reinterpret_cast<const void*>(p + stride * sizeof(float)));  // NOLINT
    __builtin_prefetch(slots_[i].load(std::memory_order_relaxed));
  }

 private:
  /// Copies of a published block's data pointer and row stride, for prefetchCell().
  struct Hint {
    std::atomic<const float*> data{nullptr};
    std::atomic<std::size_t> stride{0};
  };

  std::size_t rows_, cols_, blockRows_, blockCols_, blocksPerRow_;
  int rowShift_ = -1, colShift_ = -1;  // log2 of the block size, or −1 if not a power of two
  std::unique_ptr<Slot[]> slots_;
  std::unique_ptr<Hint[]> hints_;
};

/// Hazard records: one per thread, process-wide (the hazard domain is per-process
/// infrastructure, like the thread-local block queries keep; it holds no terrain state).
namespace hazard {

struct Record {
  std::atomic<const void*> ptr{nullptr};    // the block this thread may be reading
  std::atomic<bool> inUse{false};           // owned by a live thread
  Record* next = nullptr;                   // registry list (records are never freed)
  std::uint64_t tickNext = 0, tickEnd = 0;  // this thread's reserved recency ticks
};

/// The calling thread's record, or null before acquire().
inline thread_local Record* tlRecord = nullptr;  // NOLINT

/// Set once, before the first record is handed out: membarrier(2) is registered, so readers
/// may skip the fence.
inline std::atomic<bool> gAsymmetric{false};  // NOLINT
/// Source of recency ticks (0 means "never used").
inline std::atomic<std::uint64_t> gClock{1};  // NOLINT

/// The calling thread's record, registering one on first use (out of line, once per thread).
Record& acquire();

/// Announces that this thread is about to read `p` (then re-check that p is still
/// published before using it).
inline void protect(Record& rec, const void* p) noexcept {
#if defined(__SANITIZE_THREAD__)
  rec.ptr.store(p, std::memory_order_seq_cst);
#else
  rec.ptr.store(p, std::memory_order_release);
  if (gAsymmetric.load(std::memory_order_relaxed)) {
    std::atomic_signal_fence(std::memory_order_seq_cst);  // compiler-only; membarrier pairs
  } else {
    std::atomic_thread_fence(std::memory_order_seq_cst);
  }
#endif
}

/// Reclaimer side, after retracting: a full memory barrier on every thread of the process
/// (membarrier), or a local full fence when readers fence themselves. False if the barrier
/// could not be made; then nothing retracted may be freed yet.
[[nodiscard]] bool barrier() noexcept;

/// True if some thread's record names p. Call after barrier().
[[nodiscard]] bool isProtected(const void* p) noexcept;

/// Clears every record that names p. For an owner freeing blocks that no thread can be
/// reading any more (their sources are gone): a record left naming a freed address would
/// take a new block allocated there for one it has protected all along.
void forget(const void* p) noexcept;

/// A recency tick for the calling thread: strictly increasing within a thread; across
/// threads, ticks are reserved in runs of 64, so their order is approximate.
inline std::uint64_t tick(Record& rec) noexcept {
  if (rec.tickNext == rec.tickEnd) {
    rec.tickNext = gClock.fetch_add(64, std::memory_order_relaxed);
    rec.tickEnd = rec.tickNext + 64;
  }
  return rec.tickNext++;
}

}  // namespace hazard
}  // namespace regolith::topo
