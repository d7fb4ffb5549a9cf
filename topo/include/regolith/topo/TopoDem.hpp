#pragma once
/// \file
/// A local Cartesian DEM placed on a body.

#include <regolith/topo/BlockIndex.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#if defined(__x86_64__) || defined(_M_X64)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>

namespace regolith::topo {

namespace detail {
// Internal. These live in the header only so that TopoDem::height() inlines into the
// caller's loop: the rover's bilinear query costs a few nanoseconds, and an out-of-line call
// plus the generic kernel would double it (docs/accuracy-vs-time.md).

/// Grid coordinates → fractional sample indices (col u, row v). Division keeps sample
/// centres exact for any spacing; when 1/dx and 1/dy are exact (powers of two: 0.25, 1,
/// 2 m…) multiplying gives the same bits at a quarter of the cost.
struct DemIndexer {
  double x0 = 0.0, y0 = 0.0, dx = 1.0, dy = 1.0, idx = 1.0, idy = 1.0;
  bool recip = false;
  [[nodiscard]] double u(double x) const noexcept { return recip ? (x - x0) * idx : (x - x0) / dx; }
  [[nodiscard]] double v(double y) const noexcept { return recip ? (y0 - y) * idy : (y0 - y) / dy; }
};

/// A bilinear cell's height and, for surface queries, its gradient: ∂h/∂u per column and
/// ∂h/∂v per row index.
struct CellValue {
  double h = 0.0, dhdu = 0.0, dhdv = 0.0;
};

/// The bilinear patch through samples a (r, c), b (r, c + 1), cc (r + 1, c) and
/// d (r + 1, c + 1) at fractions (tu, tv): its height and, when Grad, its analytic gradient,
/// the two further differences of the same four samples. The operations are those of the
/// generic kernel (Kernels.hpp, bilinear), so the fast and generic paths give the same bits.
/// False when a sample is missing: a NaN sample makes h NaN (0·NaN is NaN), so one test
/// covers them all, plus the declared nodata value if there is one.
template <bool Grad>
inline bool bilinearPatch(double a, double b, double cc, double d, double tu, double tv,
                          double nodata, bool hasNodata, CellValue& out) noexcept {
  const double top = a + tu * (b - a), bottom = cc + tu * (d - cc);
  out.h = top + tv * (bottom - top);
  if constexpr (Grad) {
    out.dhdu = (1 - tv) * (b - a) + tv * (d - cc);
    out.dhdv = bottom - top;
  }
  return out.h == out.h &&
         (!hasNodata || ((a != nodata) & (b != nodata) & (cc != nodata) & (d != nodata)));
}

/// Bilinear queries over resident samples, for points whose cell lies inside the grid.
struct ResidentBilinear {
  const float* data = nullptr;  // null: no fast path (paged source, or under 2×2 samples)
  long rows = 0, cols = 0;
  double uMax = 0.0, vMax = 0.0;  // cols − 1, rows − 1
  double nodata = std::numeric_limits<double>::quiet_NaN();
  bool hasNodata = false;  // a nodata value other than NaN is declared
  /// Fractions within twice TopoGrid::edgeSlack() of a cell line (col, row): the generic
  /// path snaps such points onto the line, which can move them into the next cell, so a
  /// gradient there is left to it (a height is continuous across the line and is not).
  double snapU = 0.0, snapV = 0.0;

  /// Whether a surface query at fractions (tu, tv) of its cell takes the cell the generic
  /// path takes: each fraction 0 exactly, or farther than the snap slack from both lines.
  [[nodiscard]] bool offLines(double tu, double tv) const noexcept {
    return ((tu == 0.0) | (tu > snapU)) & (tu < 1.0 - snapU) & ((tv == 0.0) | (tv > snapV)) &
           (tv < 1.0 - snapV);
  }

  /// Fills out (the gradient too when Grad) and returns true, or returns false when the
  /// point is not inside the sample centres (NaN coordinates included), a sample is
  /// missing, or (Grad) the point is within the snap slack of a cell line; the generic path
  /// decides those. Requires data != nullptr.
  template <bool Grad>
  [[nodiscard]] bool evalResident(double u, double v, CellValue& out) const noexcept {
    // Strict upper bounds: the cell (c, r) = (⌊u⌋, ⌊v⌋) then needs no clamping; the last
    // row and column of centres go through the generic path.
    if (!(u >= 0.0 && v >= 0.0 && u < uMax && v < vMax)) return false;
    const auto c = static_cast<long>(u), r = static_cast<long>(v);
    const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(r);
    if constexpr (Grad) {
      if (!offLines(tu, tv)) [[unlikely]]
        return false;
    }
    const float* p = data + r * cols + c;
    return bilinearPatch<Grad>(static_cast<double>(p[0]), static_cast<double>(p[1]),
                               static_cast<double>(p[cols]), static_cast<double>(p[cols + 1]), tu,
                               tv, nodata, hasNodata, out);
  }
  /// Height only (evalResident<false>).
  [[nodiscard]] bool evalResident(double u, double v, double& h) const noexcept {
    CellValue cv;
    const bool ok = evalResident<false>(u, v, cv);
    h = cv.h;
    return ok;
  }
};

/// The unit normal in the grid frame, (x, y, h) with row 0 north, of a surface with
/// gradient (∂h/∂u, ∂h/∂v) per index: ∂h/∂x = ∂h/∂u / dx and ∂h/∂y = −∂h/∂v / dy. One
/// definition for the fast and generic paths, so that both give the same bits; the
/// reciprocal is used only where it is exact (powers of two: the same bits as dividing).
[[nodiscard]] inline glm::dvec3 gridNormal(const DemIndexer& m, double dhdu, double dhdv) noexcept {
  const double hx = m.recip ? dhdu * m.idx : dhdu / m.dx;
  const double hy = -(m.recip ? dhdv * m.idy : dhdv / m.dy);
  return glm::normalize(glm::dvec3(-hx, -hy, 1.0));
}

/// The block of a paged source that the calling thread read last (see SampleSource::block):
/// runs of queries inside one block cost no call into the source. Keyed by the source's
/// unique id, never its address. Trivially destructible on purpose, so that reading it
/// needs no thread-local initialisation guard; the block's memory is kept alive by a
/// companion thread-local owner in TopoDem.cpp.
struct ThreadBlock {
  std::uint64_t source = 0;
  const float* data = nullptr;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0, stride = 0;
  /// Fractional (u, v) whose whole bilinear cell lies in the block:
  /// uLo ≤ u < uHi and vLo ≤ v < vHi (empty when there is no block).
  double uLo = 0.0, uHi = 0.0, vLo = 0.0, vHi = 0.0;
  std::uintptr_t origin = 0;  // originOf(data, row0, col0, stride) (BlockIndex.hpp)

  [[nodiscard]] bool holds(std::size_t r, std::size_t c) const noexcept {
    return data != nullptr && r >= row0 && c >= col0 && r - row0 < rows && c - col0 < cols;
  }
};
inline thread_local ThreadBlock
    tlBlock;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

/// The calling thread's hazard record for the domain of `table` (tlHazard), joining the
/// domain if the thread's record is of another one; null where the domain has no lock-free
/// path. A switch of domain gives up the thread's block (the domain joined clears the
/// thread's records in other domains). Out of line (TopoDem.cpp); may throw.
HazardRecord* hazardFor(const BlockIndex& table);

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
  tlBlock = {source,    b->data, b->row0, b->col0, b->rows, b->cols,
             b->stride, b->uLo,  b->uHi,  b->vLo,  b->vHi,  b->origin};
  return b;
}

/// ⌊x⌋ toward zero as a signed integer, or INT64_MIN for NaN and values beyond ±2^63, with
/// no undefined behaviour and, on x86-64, in one instruction (the processor's own answer for
/// those inputs). Random queries test the result as an unsigned index instead of four
/// floating-point comparisons: every instruction on that path keeps the processor from
/// overlapping the memory misses of consecutive queries (docs/paging.md).
[[nodiscard]] inline std::int64_t truncIndex(double x) noexcept {
#if defined(__x86_64__) || defined(_M_X64)
  return _mm_cvttsd_si64(_mm_set_sd(x));
#else
  constexpr double lim = 9223372036854775808.0;  // 2^63
  return x > -lim && x < lim ? static_cast<std::int64_t>(x)
                             : std::numeric_limits<std::int64_t>::min();
#endif
}

/// Bilinear height (and gradient, when Grad) from a block whose whole cell
/// (c, r) = (⌊u⌋, ⌊v⌋) holds (u, v), given c and r. False leaves the point to the generic
/// kernel (also for NaN: it fails the bounds; and, when Grad, near a cell line: see
/// ResidentBilinear::offLines).
template <bool Grad, class Block>
inline bool cellBilinear(const Block& b, const ResidentBilinear& f, double u, double v,
                         std::int64_t c, std::int64_t r, CellValue& out) noexcept {
  if (!(u >= b.uLo && u < b.uHi && v >= b.vLo && v < b.vHi)) return false;
  const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(r);
  if constexpr (Grad) {
    if (!f.offLines(tu, tv)) [[unlikely]]
      return false;
  }
  // The bounds above make c, r non-negative and inside the block. c and r arrive signed:
  // unsigned conversions from double cost a branch each on x86-64.
  const std::size_t stride = b.stride;
  const auto* p = reinterpret_cast<const float*>(  // NOLINT(performance-no-int-to-ptr)
      b.origin +
      (static_cast<std::size_t>(r) * stride + static_cast<std::size_t>(c)) * sizeof(float));
  return bilinearPatch<Grad>(static_cast<double>(p[0]), static_cast<double>(p[1]),
                             static_cast<double>(p[stride]), static_cast<double>(p[stride + 1]), tu,
                             tv, f.nodata, f.hasNodata, out);
}
/// Bilinear height (and gradient) from a block when the whole cell of (u, v) lies in it
/// (false for NaN). False leaves the point to the generic kernel.
template <bool Grad, class Block>
inline bool blockBilinear(const Block& b, const ResidentBilinear& f, double u, double v,
                          CellValue& out) noexcept {
  if (!(u >= b.uLo && u < b.uHi && v >= b.vLo && v < b.vHi)) return false;
  return cellBilinear<Grad>(b, f, u, v, static_cast<std::int64_t>(u), static_cast<std::int64_t>(v),
                            out);
}
/// Bilinear height (and gradient, when grad) for a cell across a block edge (its samples in
/// two or four published blocks), read lock-free: each sample from its block under the
/// thread's hazard record, the block of the cell's first sample last, which then becomes
/// the thread's block. Out of line (TopoDem.cpp). False leaves the point to the generic path.
[[gnu::cold]] bool straddlingBilinear(const ResidentBilinear& f, const BlockIndex& table,
                                      std::uint64_t source, double u, double v, bool grad,
                                      CellValue& out) noexcept;

/// Bilinear height (and gradient, when Grad) on a paged source: from the thread's last
/// block if it holds the cell, else from the block table (a lock-free switch, the
/// random-access case), also for a cell across a block edge. False leaves the point to the
/// generic path (not resident, missing samples, outside the sample centres; when Grad, near
/// a cell line). Always inlined: in the batch loops GCC otherwise calls it out of line.
template <bool Grad>
[[gnu::always_inline]] inline bool pagedBilinear(const ResidentBilinear& f, const BlockIndex* table,
                                                 std::uint64_t source, double u, double v,
                                                 CellValue& out) noexcept {
  const ThreadBlock& tb = tlBlock;
  if (tb.source == source && blockBilinear<Grad>(tb, f, u, v, out)) [[likely]] {
    return true;
  }
  if (table == nullptr) return false;
  // One unsigned test per axis keeps the table index inside the grid: NaN, infinities and
  // negative values give huge unsigned values. A u in (−1, 0) truncates to column 0; the
  // block's own bounds (uLo = 0) then reject it.
  const std::int64_t c = truncIndex(u), r = truncIndex(v);
  const auto uc = static_cast<std::uint64_t>(c), ur = static_cast<std::uint64_t>(r);
  if (uc >= table->cols() || ur >= table->rows()) return false;
  const PublishedBlock* b = enterBlock(*table, source, ur, uc, false);
  if (b == nullptr) return false;
  if (cellBilinear<Grad>(*b, f, u, v, c, r, out)) [[likely]]
    return true;
  return straddlingBilinear(f, *table, source, u, v, Grad, out);
}
/// Height only (pagedBilinear<false>).
inline bool pagedBilinear(const ResidentBilinear& f, const BlockIndex* table, std::uint64_t source,
                          double u, double v, double& h) noexcept {
  CellValue cv;
  const bool ok = pagedBilinear<false>(f, table, source, u, v, cv);
  h = cv.h;
  return ok;
}
}  // namespace detail

/// A planar grid of heights in metres (grid x, y in metres, row 0 north/top), placed on a
/// body by a Placement.
///
/// Queries take grid coordinates (x, y) in metres. Points inside the pixel extent but
/// beyond the outermost sample centres use the edge samples (the kernel's stencil is
/// clamped to the grid); points outside the pixel extent return OutsideGrid and NaN. NaN
/// or infinite coordinates throw InvalidArgument. Samples that are NaN or equal the grid's
/// nodata value give Nodata and NaN (docs/queries.md lists the exact rules).
///
/// Thread-safety: all queries are const and may run concurrently if the SampleSource
/// allows it (InMemorySamples does).
class TopoDem {
 public:
  /// Throws InvalidArgument if samples is null or its size differs from the grid's.
  TopoDem(TopoGrid grid, Placement placement, std::shared_ptr<const SampleSource> samples);

  [[nodiscard]] const TopoGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const Placement& placement() const noexcept { return placement_; }
  [[nodiscard]] const Body& body() const noexcept { return placement_.body(); }
  [[nodiscard]] const SampleSource& samples() const noexcept { return *samples_; }
  [[nodiscard]] std::shared_ptr<const SampleSource> sharedSamples() const noexcept {
    return samples_;
  }

  /// Height at grid point (x, y).
  [[nodiscard]] HeightSample height(double x, double y,
                                    Interpolation interp = Interpolation::Bilinear) const;
  /// Height and unit normal at grid point (x, y).
  [[nodiscard]] SurfaceSample surface(double x, double y,
                                      Interpolation interp = Interpolation::Bilinear,
                                      NormalFrame frame = NormalFrame::Grid) const;

  /// Batch heights: arrays in, arrays out, all the same length (else InvalidArgument).
  /// status may be empty. All inputs are checked for NaN/inf before anything is written.
  void heights(std::span<const double> xs, std::span<const double> ys, std::span<double> out,
               std::span<QueryStatus> status, Interpolation interp = Interpolation::Bilinear) const;
  /// Batch heights and normals. status receives the heights' statuses and normalStatus
  /// the normals' (either may be empty; see SurfaceSample). A point whose normal the
  /// placement cannot map gets normalStatus Unmappable; it never fails the batch.
  void surfaces(std::span<const double> xs, std::span<const double> ys,
                std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                std::span<QueryStatus> status, Interpolation interp = Interpolation::Bilinear,
                NormalFrame frame = NormalFrame::Grid,
                std::span<QueryStatus> normalStatus = {}) const;

  /// Body-fixed position of grid point (x, y) at height h.
  [[nodiscard]] glm::dvec3 toBodyFixed(double x, double y, double h) const {
    return placement_.toBodyFixed(x, y, h);
  }
  /// Body-fixed position of sample (row, col) at its stored height (NaN if nodata).
  [[nodiscard]] glm::dvec3 samplePosition(std::size_t row, std::size_t col) const;

 private:
  TopoGrid grid_;
  Placement placement_;
  std::shared_ptr<const SampleSource> samples_;
  const float* resident_ = nullptr;  // samples_->contiguous(), cached
  detail::DemIndexer index_;
  detail::ResidentBilinear fast_;
  std::uint64_t sourceId_ = 0;         // samples_->id()
  const BlockIndex* table_ = nullptr;  // samples_->blockIndex(), cached
  glm::dvec2 slack_{0.0};              // grid_.edgeSlack()

  [[nodiscard]] HeightSample heightGeneric(double x, double y, Interpolation interp) const;
  [[nodiscard]] SurfaceSample surfaceGeneric(double x, double y, Interpolation interp,
                                             NormalFrame frame) const;
  /// s with its grid-frame normal taken to the body-fixed frame (normalStatus Unmappable
  /// where the placement cannot map the point). Requires s.normalValid().
  [[nodiscard]] SurfaceSample toBodyFixedNormal(SurfaceSample s, double x, double y) const;
};

inline HeightSample TopoDem::height(double x, double y, Interpolation interp) const {
  if (interp == Interpolation::Bilinear) {
    const double u = index_.u(x), v = index_.v(y);
    double h = 0.0;
    if (fast_.data != nullptr) {
      if (fast_.evalResident(u, v, h)) [[likely]]
        return {h, QueryStatus::Ok};
    } else {
      if (detail::pagedBilinear(fast_, table_, sourceId_, u, v, h)) [[likely]] {
        return {h, QueryStatus::Ok};
      }
    }
  }
  return heightGeneric(x, y, interp);
}

inline SurfaceSample TopoDem::surface(double x, double y, Interpolation interp,
                                      NormalFrame frame) const {
  if (interp == Interpolation::Bilinear) {
    // The normal comes from the height's four samples (their two further differences), on
    // height()'s fast paths.
    const double u = index_.u(x), v = index_.v(y);
    detail::CellValue cv;
    const bool ok = fast_.data != nullptr
                        ? fast_.evalResident<true>(u, v, cv)
                        : detail::pagedBilinear<true>(fast_, table_, sourceId_, u, v, cv);
    if (ok) [[likely]] {
      const SurfaceSample s{cv.h, detail::gridNormal(index_, cv.dhdu, cv.dhdv), QueryStatus::Ok,
                            QueryStatus::Ok};
      return frame == NormalFrame::Grid ? s : toBodyFixedNormal(s, x, y);
    }
  }
  return surfaceGeneric(x, y, interp, frame);
}

}  // namespace regolith::topo
