#pragma once
/// \file
/// The read side of a paged source's table of resident blocks: what a query needs to enter a
/// resident block without a lock (random access), and nothing more.
///
/// The tables themselves (their memory), the hazard domains that keep a block alive while a
/// thread reads it, the reclaimer's process-wide barrier and the recency clock are
/// BlockTable.hpp's, which describes the protocol and why it is hand-written. This header
/// makes no system call and holds no process-wide state: a reader loads a slot, announces
/// the block in its thread's hazard record of the table's domain with a plain store
/// (protect()), re-reads the slot, and uses the block only if it is unchanged. The readers
/// are the queries of a BlockSource (BlockSource.cpp).

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace regolith::store {

/// A block as published in a BlockIndex. Its samples and geometry are immutable while it is
/// published and until its reclaimer frees it. The counters are the cache's per-block hit
/// bookkeeping, written by readers with relaxed loads and stores (no read-modify-write, so
/// two threads entering the same block at the same instant may count once).
struct PublishedBlock {
  const float* data = nullptr;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0, stride = 0;
  /// Fractional (u, v) whose whole bilinear cell lies in the block (as in a
  /// topo::kernel::BlockView).
  double uLo = 0.0, uHi = 0.0, vLo = 0.0, vHi = 0.0;
  /// topo::kernel::originOf(data, row0, col0, stride): sample (r, c) is at
  /// origin + (r·stride + c)·4.
  std::uintptr_t origin = 0;
  mutable std::atomic<std::uint64_t> fastHits{0};  // hits taken through the table
  mutable std::atomic<std::uint64_t> lastUse{0};   // the domain's clock at the last hit
};

/// One reader thread's announcement in a hazard domain: the block it may be reading. The
/// domain (HazardDomain) owns the records and hands one to each thread that joins it.
struct HazardRecord {
  std::atomic<const void*> ptr{nullptr};
};

/// Announces that this thread is about to read `p` (then re-check that p is still
/// published before using it). No fence: the reclaimer's process-wide barrier
/// (HazardDomain::barrier(), membarrier(2)) pairs with it, which is why a domain hands
/// out records for the lock-free path only where that barrier exists. The same code runs
/// under ThreadSanitizer: the release store is what gives the reclaimer's acquire loads their
/// happens-before edge to the reads of the block that came before it, and membarrier(2)
/// (which TSan does not model) only decides which value those loads see.
inline void protect(HazardRecord& rec, const void* p) noexcept {
  rec.ptr.store(p, std::memory_order_release);
  std::atomic_signal_fence(std::memory_order_seq_cst);  // compiler-only; the barrier pairs
}

/// The resident blocks of one source as readers see them: one slot per aligned
/// blockRows × blockCols block, its hazard domain and that domain's recency clock. Made and
/// written only by BlockTable, which also documents the memory behind the slots. Thread-safety:
/// every const member may be called from any thread.
class BlockIndex {
 public:
  /// The sizes of a table: samples and blocks (all > 0; the store checks them).
  struct Geometry {
    std::size_t rows = 0, cols = 0, blockRows = 0, blockCols = 0;
  };

  virtual ~BlockIndex() = default;
  BlockIndex(const BlockIndex&) = delete;
  BlockIndex& operator=(const BlockIndex&) = delete;

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

  /// The table's hazard domain (its cache's): an id unique in the process and never reused,
  /// never 0.
  [[nodiscard]] std::uint64_t domain() const noexcept { return domain_; }
  /// The recency stamp of a lock-free hit: the domain's clock as it is, with no write to it
  /// (a read-modify-write per random query would be a locked instruction on a contended
  /// cache line). Lock-free hits between two ticks of the cache therefore tie.
  [[nodiscard]] std::uint64_t now() const noexcept {
    return clock_->load(std::memory_order_relaxed);
  }
  /// The calling thread's hazard record in the table's domain, the thread joining the domain
  /// on first use; or null where readers must not use the table (the domain's barrier would
  /// not pair with protect()): queries then enter new blocks through the source's block().
  /// Joining clears the thread's records in other domains (a thread reads through one domain
  /// at a time), so that their caches may free the blocks those named. Out of line and rare:
  /// queries keep the record per thread (BlockSource.cpp). May throw (allocation).
  [[nodiscard]] virtual HazardRecord* joinDomain() const = 0;

 protected:
  /// One block's slot, with copies of its data pointer and row stride for prefetchCell().
  /// Plain members (all zero = empty) accessed through std::atomic_ref, so that the zero
  /// pages of the store's mapping are valid entries without being written.
  struct Entry {
    const PublishedBlock* block;
    const float* hintData;
    std::size_t hintStride;
  };

  /// `g` must have every size > 0; `clock` must outlive the index. The owner sets entries_.
  BlockIndex(const Geometry& g, std::uint64_t domain,
             const std::atomic<std::uint64_t>* clock) noexcept
      : rows_(g.rows),
        cols_(g.cols),
        blockRows_(g.blockRows),
        blockCols_(g.blockCols),
        blocksPerRow_(g.cols / g.blockCols + (g.cols % g.blockCols != 0 ? 1 : 0)),
        blocksPerCol_(g.rows / g.blockRows + (g.rows % g.blockRows != 0 ? 1 : 0)),
        domain_(domain),
        clock_(clock) {
    pow2_ = isPow2(g.blockRows) && isPow2(g.blockCols);
    if (pow2_) {
      rowShift_ = static_cast<unsigned>(__builtin_ctzll(g.blockRows));
      colShift_ = static_cast<unsigned>(__builtin_ctzll(g.blockCols));
    }
  }

  /// The slot index of sample (r, c). Shifts for power-of-two blocks (the default 256): a
  /// 64-bit division is some 40 micro-operations, and four of them per block switch kept the
  /// processor from overlapping the memory misses of consecutive random queries.
  [[nodiscard]] std::size_t index(std::size_t r, std::size_t c) const noexcept {
    if (pow2_) [[likely]]
      return (r >> rowShift_) * blocksPerRow_ + (c >> colShift_);
    return (r / blockRows_) * blocksPerRow_ + c / blockCols_;
  }
  [[nodiscard]] std::size_t blocksPerRow() const noexcept { return blocksPerRow_; }
  [[nodiscard]] std::size_t blocksPerCol() const noexcept { return blocksPerCol_; }

  Entry* entries_ = nullptr;  // set by the owner (mutable through atomic_ref)

 private:
  static constexpr bool isPow2(std::size_t n) noexcept { return n != 0 && (n & (n - 1)) == 0; }

  std::size_t rows_, cols_, blockRows_, blockCols_, blocksPerRow_, blocksPerCol_;
  bool pow2_ = false;                     // both block sizes are powers of two
  unsigned rowShift_ = 0, colShift_ = 0;  // their log2 when pow2_
  std::uint64_t domain_;
  const std::atomic<std::uint64_t>* clock_;
};

}  // namespace regolith::store
