#pragma once
// The per-thread state of queries on block sources (private header): the calling thread's
// last block and its hazard record, and the lock-free fast path that reads through them. It
// lives in the store, beside the block tables it reads (BlockIndex.hpp, BlockTable.hpp);
// topo's queries reach it through topo::PagedQueries (BlockSource.cpp).

#include <regolith/store/BlockIndex.hpp>
#include <regolith/topo/Bilinear.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace regolith::store::detail {

using topo::kernel::CellValue;
using topo::kernel::ResidentBilinear;

/// The block of a block source that the calling thread read last: runs of queries inside
/// one block cost no call into the source. Keyed by the source's unique id
/// (BlockSource::id()), never its address. Trivially destructible on purpose, so that
/// reading it needs no thread-local initialisation guard; the block's memory is kept alive
/// by the thread's hazard record (a block entered through a table) or by tlBlockOwner (a
/// block the source handed out).
struct ThreadBlock {
  std::uint64_t source = 0;
  topo::kernel::BlockView view;
};
// Initial-exec TLS (one %fs-relative access; the linker makes it local-exec in an
// executable). The library is compiled position-independent, whose default model calls
// __tls_get_addr: the compiler then saved registers and spilled the query's arguments
// around every access, even where the linker had removed the call, and a point query on
// resident patches ran 40 % slower than when this state was topo's, inlined into the caller.
// The cost: the Python module, loaded with dlopen(), takes these 112 bytes from glibc's
// static TLS reserve (rtld.optional_static_tls, 512 bytes by default).
[[gnu::tls_model("initial-exec")]] inline thread_local ThreadBlock
    tlBlock;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)
// Keeps the memory of the calling thread's block alive when the source handed it out.
inline thread_local std::shared_ptr<const void> tlBlockOwner;  // NOLINT

/// The calling thread's hazard record for one domain (the last it joined), kept beside the
/// thread's block so that entering a block costs no call: a reader uses rec only for tables
/// of that domain (hazardFor() switches it). domain 0 (no domain) when the thread has none,
/// or its domain gave no record for the lock-free path. Trivially destructible, like the
/// thread's block. BlockTable.cpp clears it when the thread's records are given back at
/// thread exit (forgetThreadHazard()).
struct ThreadHazard {
  std::uint64_t domain = 0;
  HazardRecord* rec = nullptr;
};
[[gnu::tls_model("initial-exec")]] inline thread_local ThreadHazard  // as tlBlock
    tlHazard;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

/// Forgets the calling thread's hazard record (its domain gave the records back).
inline void forgetThreadHazard() noexcept { tlHazard = {}; }

/// The calling thread's hazard record for the domain of `table` (tlHazard), joining the
/// domain if the thread's record is of another one; null where the domain has no lock-free
/// path. A switch of domain gives up the thread's block (the domain joined clears the
/// thread's records in other domains). Out of line (BlockSource.cpp); may throw.
HazardRecord* hazardFor(const BlockIndex& table);

/// The block view of a published block.
[[nodiscard]] inline topo::kernel::BlockView viewOf(const PublishedBlock& b) noexcept {
  return {b.data, b.row0, b.col0, b.rows, b.cols, b.stride, b.uLo, b.uHi, b.vLo, b.vHi, b.origin};
}

/// Enters the block of `table` holding sample (r, c), if the table has one: protects it with
/// the thread's hazard record of the table's domain (BlockIndex.hpp: no lock, no fence) and
/// counts a hit on it. Returns it, or null (the caller then takes the slow path, which also
/// joins the table's domain: hazardFor()). Requires r < rows and c < cols of the table.
///
/// A random query only announces the block (the hazard moves, so the thread's block is
/// invalidated); the thread's block is set to it only when a second query in a row enters
/// it, the start of a run. Writing the whole ThreadBlock on every switch made random
/// queries three times slower: stores cannot leave the store buffer before the memory
/// misses of earlier queries are served, so the buffer filled and stalled the processor.
/// `promote` sets the thread's block at once (callers that read it next).
inline const PublishedBlock* enterBlock(const BlockIndex& table, std::uint64_t source,
                                        std::size_t r, std::size_t c, bool promote) noexcept {
  // tlHazard.domain is 0 (never a table's) unless rec is set.
  if (tlHazard.domain != table.domain()) return nullptr;
  HazardRecord* rec = tlHazard.rec;
  const BlockIndex::Slot slot = table.slot(r, c);
  const PublishedBlock* b = slot.load(std::memory_order_acquire);
  if (b == nullptr) return nullptr;
  constexpr auto relaxed = std::memory_order_relaxed;
  // Protected since the previous switch (so still alive, even if retracted meanwhile): a
  // run of queries in b has begun, and it was counted when it was entered.
  if (rec->ptr.load(relaxed) != b) {
    tlBlock.source = 0;  // the hazard leaves the thread's block
    protect(*rec, b);
    // seq_cst: the reclaimer's retract() is a seq_cst store (on x86 this is a plain load).
    if (slot.load(std::memory_order_seq_cst) != b) return nullptr;  // retracted meanwhile
    b->fastHits.store(b->fastHits.load(relaxed) + 1, relaxed);
    b->lastUse.store(table.now(), relaxed);
    if (!promote) return b;
  }
  tlBlock = {source, viewOf(*b)};
  return b;
}

/// Bilinear height (and gradient, when grad) for a cell across a block edge (its samples in
/// two or four published blocks), read lock-free: each sample from its block under the
/// thread's hazard record, the block of the cell's first sample last, which then becomes
/// the thread's block. Out of line (BlockSource.cpp). False leaves the point to the generic
/// path.
[[gnu::cold, gnu::noinline]] bool straddlingBilinear(const ResidentBilinear& f,
                                                     const BlockIndex& table, std::uint64_t source,
                                                     double u, double v, bool grad,
                                                     CellValue& out) noexcept;

/// Bilinear height (and gradient, when Grad) from the block table: a lock-free switch to
/// the block holding the cell (the random-access case), also for a cell across a block
/// edge. False leaves the point to the generic path (not resident, missing samples, outside
/// the sample centres; when Grad, near a cell line).
template <bool Grad>
[[gnu::always_inline]] inline bool tableBilinear(const ResidentBilinear& f, const BlockIndex* table,
                                                 std::uint64_t source, double u, double v,
                                                 CellValue& out) noexcept {
  if (table == nullptr) return false;
  // One unsigned test per axis keeps the table index inside the grid: NaN, infinities and
  // negative values give huge unsigned values. A u in (−1, 0) truncates to column 0; the
  // block's own bounds (uLo = 0) then reject it.
  const std::int64_t c = topo::kernel::truncIndex(u), r = topo::kernel::truncIndex(v);
  const auto uc = static_cast<std::uint64_t>(c), ur = static_cast<std::uint64_t>(r);
  if (uc >= table->cols() || ur >= table->rows()) return false;
  const PublishedBlock* b = enterBlock(*table, source, ur, uc, false);
  if (b == nullptr) return false;
  if (topo::kernel::cellBilinear<Grad>(*b, f, u, v, c, r, out)) [[likely]]
    return true;
  return straddlingBilinear(f, *table, source, u, v, Grad, out);
}

/// Bilinear height (and gradient, when Grad) on a block source: from the thread's last
/// block if it holds the cell, else from the block table (tableBilinear()). Always inlined:
/// in the batch loops GCC otherwise calls it out of line.
template <bool Grad>
[[gnu::always_inline]] inline bool pagedBilinear(const ResidentBilinear& f, const BlockIndex* table,
                                                 std::uint64_t source, double u, double v,
                                                 CellValue& out) noexcept {
  const ThreadBlock& tb = tlBlock;
  if (tb.source == source && topo::kernel::blockBilinear<Grad>(tb.view, f, u, v, out)) [[likely]] {
    return true;
  }
  return tableBilinear<Grad>(f, table, source, u, v, out);
}

/// The cells of a block source for topo::kernel's batch loops (Bilinear.hpp).
struct PagedCells {
  ResidentBilinear f;  // a copy: the loops' stores to double outputs could alias a reference
  const BlockIndex* table = nullptr;
  std::uint64_t source = 0;
  // Always inlined, as pagedBilinear(): called out of line, the batch loops ran 15 % slower.
  template <bool Grad>
  [[nodiscard, gnu::always_inline]] bool eval(double u, double v, CellValue& out) const noexcept {
    return pagedBilinear<Grad>(f, table, source, u, v, out);
  }
  [[nodiscard]] bool prefetches() const noexcept { return table != nullptr; }
  void prefetchCell(std::size_t r, std::size_t c) const noexcept { table->prefetchCell(r, c); }
};

}  // namespace regolith::store::detail
