#include <regolith/store/BlockSource.hpp>

#include "ThreadQueries.hpp"

#include <array>
#include <atomic>
#include <limits>
#include <utility>

namespace regolith::store {

namespace detail {

HazardRecord* hazardFor(const BlockIndex& table) {
  if (tlHazard.domain == table.domain()) return tlHazard.rec;
  // Joining gives up the thread's hazards in other domains, one of which may protect the
  // thread's block.
  tlBlock.source = 0;
  tlHazard = {};  // before joining: joinDomain() may throw
  HazardRecord* rec = table.joinDomain();
  if (rec != nullptr) tlHazard = {table.domain(), rec};
  return rec;
}

bool straddlingBilinear(const ResidentBilinear& f, const BlockIndex& table, std::uint64_t source,
                        double u, double v, bool grad, CellValue& out) noexcept {
  // Without this, a rover crossing a block edge paid the generic kernel, whose samples
  // outside the thread's block come through the cache's lock: 2 % of a traverse's queries
  // took half of its time.
  // Entered from pagedBilinear() after enterBlock() succeeded, so the thread's record is of
  // the table's domain; checked anyway (it costs nothing here).
  if (tlHazard.domain != table.domain()) return false;
  HazardRecord* rec = tlHazard.rec;
  if (!(u >= 0.0 && v >= 0.0 && u < f.uMax && v < f.vMax)) return false;
  const auto c = static_cast<std::size_t>(u), r = static_cast<std::size_t>(v);
  const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(r);
  if (grad && !f.offLines(tu, tv)) return false;
  std::array<double, 4> s{};           // samples (r, c), (r, c + 1), (r + 1, c), (r + 1, c + 1)
  for (std::size_t k = 4; k-- > 0;) {  // (r, c) last: its block stays protected
    const std::size_t sr = r + k / 2, sc = c + k % 2;
    const BlockIndex::Slot slot = table.slot(sr, sc);
    const PublishedBlock* b = slot.load(std::memory_order_acquire);
    if (b == nullptr) return false;
    if (rec->ptr.load(std::memory_order_relaxed) != b) {
      tlBlock.source = 0;  // the hazard leaves the thread's block
      protect(*rec, b);
      if (slot.load(std::memory_order_seq_cst) != b) return false;  // retracted meanwhile
    }
    s[k] = static_cast<double>(b->data[(sr - b->row0) * b->stride + (sc - b->col0)]);
  }
  // The thread's block becomes the one of (r, c), already protected (no hit is counted: the
  // run in it goes on); a run of queries there continues without a switch.
  if (enterBlock(table, source, r, c, true) != nullptr) tlBlockOwner.reset();
  using topo::kernel::bilinearPatch;
  return grad ? bilinearPatch<true>(s[0], s[1], s[2], s[3], tu, tv, f.nodata, f.hasNodata, out)
              : bilinearPatch<false>(s[0], s[1], s[2], s[3], tu, tv, f.nodata, f.hasNodata, out);
}

}  // namespace detail

namespace {
std::uint64_t nextSourceId() noexcept {
  static std::atomic<std::uint64_t> next{1};  // ids only; no state is shared through it
  return next.fetch_add(1, std::memory_order_relaxed);
}

// One point's query (bilinearHeight(), bilinearSurface()): the thread's block inline, the
// table out of line, so that the common path saves no register. A point query that pushed
// registers and spilled its arguments on entry (GCC's frame for the whole inlined path)
// ran random queries 40 % slower: the stores queue behind the memory misses of earlier
// queries. Heights come back in a register (NaN: not answered).
constexpr double kNotAnswered = std::numeric_limits<double>::quiet_NaN();

[[gnu::noinline]] bool tableSurface(const BlockIndex* table, std::uint64_t source,
                                    const topo::kernel::ResidentBilinear& grid, double u, double v,
                                    topo::kernel::CellValue& out) noexcept {
  return detail::tableBilinear<true>(grid, table, source, u, v, out);
}

[[gnu::noinline]] double tableHeight(const BlockIndex* table, std::uint64_t source,
                                     const topo::kernel::ResidentBilinear& grid, double u,
                                     double v) noexcept {
  topo::kernel::CellValue cv;
  return detail::tableBilinear<false>(grid, table, source, u, v, cv) ? cv.h : kNotAnswered;
}
}  // namespace

BlockSource::BlockSource(std::shared_ptr<const BlockIndex> table)
    : table_(std::move(table)), id_(nextSourceId()) {}

double BlockSource::bilinearHeight(const topo::kernel::ResidentBilinear& grid, double u,
                                   double v) const noexcept {
  const detail::ThreadBlock& tb = detail::tlBlock;
  topo::kernel::CellValue cv;
  if (tb.source == id_ && topo::kernel::blockBilinear<false>(tb.view, grid, u, v, cv)) [[likely]]
    return cv.h;
  return tableHeight(table_.get(), id_, grid, u, v);
}

bool BlockSource::bilinearSurface(const topo::kernel::ResidentBilinear& grid, double u, double v,
                                  topo::kernel::CellValue& out) const noexcept {
  const detail::ThreadBlock& tb = detail::tlBlock;
  if (tb.source == id_ && topo::kernel::blockBilinear<true>(tb.view, grid, u, v, out)) [[likely]]
    return true;
  return tableSurface(table_.get(), id_, grid, u, v, out);
}

void BlockSource::bilinearHeights(const topo::kernel::DemIndexer& m,
                                  const topo::kernel::ResidentBilinear& grid,
                                  const topo::kernel::HeightBatch& b,
                                  topo::kernel::Fallback<topo::HeightSample> generic) const {
  topo::kernel::bilinearHeights(detail::PagedCells{grid, table_.get(), id_}, m, grid, b, generic);
}

void BlockSource::bilinearSurfaces(const topo::kernel::DemIndexer& m,
                                   const topo::kernel::ResidentBilinear& grid,
                                   const topo::kernel::SurfaceBatch& b,
                                   topo::kernel::Fallback<topo::SurfaceSample> generic) const {
  topo::kernel::bilinearSurfaces(detail::PagedCells{grid, table_.get(), id_}, m, grid, b, generic);
}

void BlockSource::prefetchCell(std::size_t r, std::size_t c) const noexcept {
  if (table_ != nullptr) table_->prefetchCell(r, c);
}

const topo::kernel::BlockView& BlockSource::threadBlock(std::size_t r, std::size_t c) const {
  detail::ThreadBlock& tb = detail::tlBlock;
  if (tb.source == id_ && tb.view.holds(r, c)) return tb.view;
  if (const BlockIndex* table = table_.get(); table != nullptr) {
    if (detail::hazardFor(*table) != nullptr &&
        detail::enterBlock(*table, id_, r, c, true) != nullptr) {
      detail::tlBlockOwner.reset();  // the hazard record protects the block now
      return tb.view;
    }
  }
  SampleBlock fresh = block(r, c);
  const auto d = [](std::size_t i) { return static_cast<double>(i); };
  tb = {id_,
        {fresh.data, fresh.row0, fresh.col0, fresh.rows, fresh.cols, fresh.stride, d(fresh.col0),
         d(fresh.col0 + fresh.cols) - 1.0, d(fresh.row0), d(fresh.row0 + fresh.rows) - 1.0,
         topo::kernel::originOf(fresh.data, fresh.row0, fresh.col0, fresh.stride)}};
  detail::tlBlockOwner = std::move(fresh.owner);
  return tb.view;
}

}  // namespace regolith::store
