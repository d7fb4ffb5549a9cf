#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/TopoDem.hpp>

#include "Kernels.hpp"

#include <glm/geometric.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>

namespace regolith::topo {
namespace {

using detail::ClampAcc;
using detail::KernelResult;

// Locates (x, y) in the grid; false if outside the pixel extent.
struct Where {
  double u, v;  // snapped onto a sample line within the slack, clamped to the centres
  bool inside;
  double rawU, rawV;  // as the point gives them
};

bool isPowerOfTwo(double d) noexcept {
  int e = 0;
  return std::frexp(d, &e) == 0.5;
}

// cmax, rmax: cols − 1 and rows − 1 (precomputed: size_t → double is not free); slack:
// TopoGrid::edgeSlack(), so that points on a reported edge are inside.
inline Where locate(const detail::DemIndexer& m, double x, double y, double cmax, double rmax,
                    const glm::dvec2& slack) noexcept {
  const double rawU = m.u(x), rawV = m.v(y);
  // On a sample line to a few ulps (a sample centre given as grid indices, or computed
  // another way) is on it: a hole next to it then has zero weight, as it has exactly there.
  const double u = detail::snapToLine(rawU, slack.x);
  const double v = detail::snapToLine(rawV, slack.y);
  const bool inside = u >= -0.5 - slack.x && u <= cmax + 0.5 + slack.x && v >= -0.5 - slack.y &&
                      v <= rmax + 0.5 + slack.y;
  // Within the half-pixel border the stencil sits on the outermost samples.
  return {std::clamp(u, 0.0, cmax), std::clamp(v, 0.0, rmax), inside, rawU, rawV};
}

// A bilinear height() is the interpolation at the point itself wherever the kernel has a
// value there (the cell (⌊u⌋, ⌊v⌋) inside the sample centres, no missing sample of non-zero
// weight): what the fast paths answer (ResidentBilinear::evalResident, pagedBilinear), with
// the same arithmetic, so that a height never depends on the path that answered it, nor a
// paged one on what is resident (stop 31: up to 12 ulps between a cold and a warm cache).
// Snapping onto a line decides only the rest: a sample whose weight vanishes on the line
// (a hole beside a sample centre), and the border. The fast paths cannot snap instead: the
// test for a point near a line made bilinear heights 2–33 % slower (docs/paging.md).
// The unsnapped point, when snapping moved it and its cell is inside the centres.
inline std::optional<Where> unsnapped(const Where& w, double cmax, double rmax) noexcept {
  if (w.rawU == w.u && w.rawV == w.v) return std::nullopt;
  if (!(w.rawU >= 0.0 && w.rawU < cmax && w.rawV >= 0.0 && w.rawV < rmax)) return std::nullopt;
  return Where{w.rawU, w.rawV, true, w.rawU, w.rawV};
}

// The calling thread's block, moved to the one holding the cell of `w` if needed.
inline const detail::ThreadBlock& threadBlock(const SampleSource& src, const Where& w) {
  return detail::acquireBlock(src, static_cast<std::size_t>(w.v), static_cast<std::size_t>(w.u));
}

// Calls fn with the accessor that fits the source: plain array loads when the samples are
// resident; otherwise loads from the block holding the point's cell (fetched through
// SampleSource::block() when the thread's last block does not hold it), falling back to
// SampleSource::sample() for stencil samples outside the block.
template <class Fn>
KernelResult withAccessor(const TopoGrid& g, const SampleSource& src, const float* resident,
                          const Where& w, Fn&& fn) {
  const long rows = static_cast<long>(g.rows()), cols = static_cast<long>(g.cols());
  if (resident != nullptr) return fn(ClampAcc<detail::MemFetch>{{resident, cols}, rows, cols});
  const detail::ThreadBlock& tb = threadBlock(src, w);
  return fn(ClampAcc<detail::BlockFetch>{{&src, &tb}, rows, cols});
}

// The bilinear height at w (a cell inside the sample centres), or nothing where the kernel
// has no value there (a missing sample of non-zero weight). On a paged source, the block
// path first: a fast path's arithmetic either way (detail::bilinearPatch, bilinear()).
std::optional<double> bilinearHeightAt(const TopoGrid& g, const SampleSource& src,
                                       const float* resident, const detail::ResidentBilinear& f,
                                       const Where& w) {
  detail::CellValue cv;
  if (resident == nullptr && detail::blockBilinear<false>(threadBlock(src, w), f, w.u, w.v, cv))
      [[likely]] {
    return cv.h;
  }
  const KernelResult k = withAccessor(g, src, resident, w, [&](const auto& acc) {
    return detail::evaluate<false>(Interpolation::Bilinear, acc, w.u, w.v, f.nodata);
  });
  if (k.status != QueryStatus::Ok) return std::nullopt;
  return k.h;
}

// The check is inline and the throwing part out of line, so that the hot path stays small.
[[noreturn]] void throwNonFinite(double x, double y, const char* op) {
  requireFinite(x, op, "x");
  requireFinite(y, op, "y");
  std::abort();  // unreachable: one of the two threw
}

inline void requirePoint(double x, double y, const char* op) {
  if (!std::isfinite(x) || !std::isfinite(y)) [[unlikely]]
    throwNonFinite(x, y, op);
}

void requireSameLength(std::size_t n, std::size_t m, const char* op, const char* field) {
  if (n != m) {
    throw InvalidArgument(std::string(op) + ": " + field + " has " + core::number(m) +
                          " elements, expected " + core::number(n));
  }
}

void requireFiniteArray(std::span<const double> a, const char* op, const char* field) {
  // Branch-free scan that vectorises: the exponent field is all ones exactly for NaN/±inf,
  // and adding one to it then carries into the sign bit. The loop below names the culprit.
  std::uint64_t bad = 0;
  for (const double v : a) {
    bad |= (std::bit_cast<std::uint64_t>(v) & 0x7ff0000000000000ULL) + 0x0010000000000000ULL;
  }
  if ((bad >> 63U) == 0) return;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i])) {
      throw InvalidArgument(std::string(op) + ": " + field + "[" + core::number(i) + "] is " +
                            core::number(a[i]) + ", expected a finite number");
    }
  }
}

}  // namespace

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
  return grad ? bilinearPatch<true>(s[0], s[1], s[2], s[3], tu, tv, f.nodata, f.hasNodata, out)
              : bilinearPatch<false>(s[0], s[1], s[2], s[3], tu, tv, f.nodata, f.hasNodata, out);
}

}  // namespace detail

TopoDem::TopoDem(TopoGrid grid, Placement placement, std::shared_ptr<const SampleSource> samples)
    : grid_(std::move(grid)), placement_(std::move(placement)), samples_(std::move(samples)) {
  if (!samples_) throw InvalidArgument("TopoDem(): samples is null, expected a SampleSource");
  if (samples_->rows() != grid_.rows() || samples_->cols() != grid_.cols()) {
    throw InvalidArgument("TopoDem(): samples are " + core::number(samples_->rows()) + "x" +
                          core::number(samples_->cols()) + ", expected the grid's " +
                          core::number(grid_.rows()) + "x" + core::number(grid_.cols()));
  }
  resident_ = samples_->contiguous();
  sourceId_ = samples_->id();
  table_ = samples_->blockIndex();
  const double dx = grid_.spacingX(), dy = grid_.spacingY();
  index_ = {
      grid_.x0(), grid_.y0(), dx, dy, 1.0 / dx, 1.0 / dy, isPowerOfTwo(dx) && isPowerOfTwo(dy)};
  fast_.rows = static_cast<long>(grid_.rows());
  fast_.cols = static_cast<long>(grid_.cols());
  fast_.data = (fast_.rows >= 2 && fast_.cols >= 2) ? resident_ : nullptr;
  fast_.uMax = static_cast<double>(grid_.cols()) - 1.0;
  fast_.vMax = static_cast<double>(grid_.rows()) - 1.0;
  fast_.nodata = detail::nodataOrNan(grid_);
  fast_.hasNodata = grid_.nodata().has_value() && !std::isnan(*grid_.nodata());
  slack_ = grid_.edgeSlack();
  fast_.snapU = 2.0 * slack_.x;
  fast_.snapV = 2.0 * slack_.y;
}

HeightSample TopoDem::heightGeneric(double x, double y, Interpolation interp) const {
  requirePoint(x, y, "TopoDem::height()");
  const Where w = locate(index_, x, y, fast_.uMax, fast_.vMax, slack_);
  if (!w.inside) return {};
  if (interp == Interpolation::Bilinear) {
    if (const std::optional<Where> raw = unsnapped(w, fast_.uMax, fast_.vMax)) {
      const std::optional<double> h = bilinearHeightAt(grid_, *samples_, resident_, fast_, *raw);
      if (h) return {*h, QueryStatus::Ok};
    }
    detail::CellValue cv;
    if (resident_ == nullptr &&
        detail::blockBilinear<false>(threadBlock(*samples_, w), fast_, w.u, w.v, cv)) [[likely]] {
      return {cv.h, QueryStatus::Ok};
    }
  }
  const KernelResult k = withAccessor(grid_, *samples_, resident_, w, [&](const auto& acc) {
    return detail::evaluate<false>(interp, acc, w.u, w.v, fast_.nodata);
  });
  if (k.status != QueryStatus::Ok) return {std::numeric_limits<double>::quiet_NaN(), k.status};
  return {k.h, QueryStatus::Ok};
}

SurfaceSample TopoDem::surfaceGeneric(double x, double y, Interpolation interp,
                                      NormalFrame frame) const {
  requirePoint(x, y, "TopoDem::surface()");
  const Where w = locate(index_, x, y, fast_.uMax, fast_.vMax, slack_);
  if (!w.inside) return {};
  // Snapped, unlike a bilinear height() (see unsnapped()): the gradient must be the cell's
  // the snapped point lies in, and the height its own, so a sample centre given a few ulps
  // off its lines gives the sample (`regolith query`, docs/queries.md "Edges").
  if (resident_ == nullptr && interp == Interpolation::Bilinear) {
    // A point within the slack of a cell line is on it now (w is snapped): surface()'s paged
    // path (lock-free, also across block edges), else the thread's block fetched from the
    // source, takes it.
    detail::CellValue cv;
    if (detail::pagedBilinear<true>(fast_, table_, sourceId_, w.u, w.v, cv) ||
        detail::blockBilinear<true>(threadBlock(*samples_, w), fast_, w.u, w.v, cv)) [[likely]] {
      const SurfaceSample s{cv.h, detail::gridNormal(index_, cv.dhdu, cv.dhdv), QueryStatus::Ok,
                            QueryStatus::Ok};
      return frame == NormalFrame::Grid ? s : toBodyFixedNormal(s, x, y);
    }
  }
  const KernelResult k = withAccessor(grid_, *samples_, resident_, w, [&](const auto& acc) {
    return detail::evaluateSurface(interp, acc, w.u, w.v, fast_.nodata);
  });
  SurfaceSample s;
  s.status = k.status;
  s.normalStatus = k.gradStatus;
  if (k.status != QueryStatus::Ok) return s;
  s.height = k.h;
  if (k.gradStatus != QueryStatus::Ok) return s;
  s.normal = detail::gridNormal(index_, k.dhdu, k.dhdv);
  return frame == NormalFrame::Grid ? s : toBodyFixedNormal(s, x, y);
}

SurfaceSample TopoDem::toBodyFixedNormal(SurfaceSample s, double x, double y) const {
  try {
    s.normal = placement_.normalToBodyFixed(s.normal, x, y, s.height);
  } catch (const DomainError&) {
    // The point itself lies beyond the projection's domain (a grid reaching past a pole):
    // its height is the grid's, but it has no body-fixed normal.
    s.normal = glm::dvec3(std::numeric_limits<double>::quiet_NaN());
    s.normalStatus = QueryStatus::Unmappable;
  }
  return s;
}

namespace {
/// Batch queries prefetch the cell of the point this many ahead (random points: the memory
/// misses of several points overlap instead of being paid one after another).
constexpr std::size_t kPrefetchAhead = 8;
/// Whether a batch jumps around the grid (random access, where prefetching pays), judged on
/// its first points: most of them more than a few cells from the one before. Along a path (a
/// rover's wheels) the cells are in cache already, and a loop that even checks for
/// prefetching ran a third slower (store_bench rover_batch), so such batches take a loop
/// without it. A batch no longer than the prefetch distance has nothing to prefetch (the
/// rover's six wheels of one step).
template <class ToU, class ToV>
bool scattered(std::span<const double> xs, std::span<const double> ys, ToU toU, ToV toV) {
  if (xs.size() <= kPrefetchAhead) return false;
  const std::size_t k = std::min<std::size_t>(xs.size(), 17);
  std::size_t jumps = 0;
  for (std::size_t i = 1; i < k; ++i) {
    const double du = toU(xs[i]) - toU(xs[i - 1]), dv = toV(ys[i]) - toV(ys[i - 1]);
    jumps += std::abs(du) + std::abs(dv) > 4.0 ? 1U : 0U;
  }
  return k > 1 && 2 * jumps > k - 1;
}

/// A batch's points and answers (status may be empty: not wanted).
struct Batch {
  std::span<const double> xs, ys;
  std::span<double> out;
  std::span<QueryStatus> status;
};

/// heights() on resident samples with the bilinear kernel: height()'s fast path on local
/// copies (stores to out[] could alias the TopoDem's own members, which would then be
/// reloaded for every point); `generic(x, y)` answers the points that path does not.
template <class Generic>
void residentBilinearBatch(const detail::DemIndexer m, const detail::ResidentBilinear f,
                           const Batch& b, Generic&& generic) {
  const std::size_t n = b.xs.size();
  const auto xs = b.xs, ys = b.ys;
  const auto out = b.out;
  const auto status = b.status;
  // Specialised on the spacing's reciprocal being exact and on whether status is wanted,
  // so the loop body has no branches but the bounds and missing-sample tests.
  auto loop = [&](auto recip, auto wantStatus, auto prefetch) {
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (prefetch) {
        if (i + kPrefetchAhead < n) {
          // Random access: fetch the cell of a point a few ahead, so its memory miss
          // overlaps this point's work.
          const std::size_t j = i + kPrefetchAhead;
          const double uj = recip ? (xs[j] - m.x0) * m.idx : (xs[j] - m.x0) / m.dx;
          const double vj = recip ? (m.y0 - ys[j]) * m.idy : (m.y0 - ys[j]) / m.dy;
          if (uj >= 0.0 && vj >= 0.0 && uj < f.uMax && vj < f.vMax) {
            const float* p = f.data + static_cast<long>(vj) * f.cols + static_cast<long>(uj);
            __builtin_prefetch(p);
            __builtin_prefetch(p + f.cols);
          }
        }
      }
      const double u = recip ? (xs[i] - m.x0) * m.idx : (xs[i] - m.x0) / m.dx;
      const double v = recip ? (m.y0 - ys[i]) * m.idy : (m.y0 - ys[i]) / m.dy;
      double h = 0.0;
      if (f.evalResident(u, v, h)) [[likely]] {
        out[i] = h;
        if constexpr (wantStatus) status[i] = QueryStatus::Ok;
        continue;
      }
      const HeightSample s = generic(xs[i], ys[i]);
      out[i] = s.height;
      if constexpr (wantStatus) status[i] = s.status;
    }
  };
  using Yes = std::true_type;
  using No = std::false_type;
  const auto run = [&](auto prefetch) {
    if (m.recip) {
      status.empty() ? loop(Yes{}, No{}, prefetch) : loop(Yes{}, Yes{}, prefetch);
    } else {
      status.empty() ? loop(No{}, No{}, prefetch) : loop(No{}, Yes{}, prefetch);
    }
  };
  if (scattered(
          xs, ys, [&](double x) { return m.u(x); }, [&](double y) { return m.v(y); })) {
    run(Yes{});
  } else {
    run(No{});
  }
}

/// heights() on paged samples with the bilinear kernel: height()'s inline paths (the
/// thread's block, then the lock-free block table) on local copies, for the same reason. A
/// variant that protected 8 blocks at once to overlap their memory misses measured no
/// faster (docs/paging.md).
template <class Generic>
void pagedBilinearBatch(const detail::DemIndexer m, const detail::ResidentBilinear f,
                        const BlockIndex* table, std::uint64_t id, const Batch& b,
                        Generic&& generic) {
  const std::size_t n = b.xs.size();
  const auto xs = b.xs, ys = b.ys;
  const auto out = b.out;
  const auto status = b.status;
  auto loop = [&](auto prefetch) {
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (prefetch) {
        if (i + kPrefetchAhead < n) {
          // Random access: fetch the cell of a point a few ahead (its block's data through
          // the table's hints), so its memory miss overlaps this point's work.
          const std::size_t j = i + kPrefetchAhead;
          const double uj = m.u(xs[j]), vj = m.v(ys[j]);
          if (uj >= 0.0 && vj >= 0.0 && uj < f.uMax && vj < f.vMax)
            table->prefetchCell(static_cast<std::size_t>(vj), static_cast<std::size_t>(uj));
        }
      }
      double h = 0.0;
      if (detail::pagedBilinear(f, table, id, m.u(xs[i]), m.v(ys[i]), h)) [[likely]] {
        out[i] = h;
        if (!status.empty()) status[i] = QueryStatus::Ok;
        continue;
      }
      const HeightSample s = generic(xs[i], ys[i]);
      out[i] = s.height;
      if (!status.empty()) status[i] = s.status;
    }
  };
  if (table != nullptr &&
      scattered(
          xs, ys, [&](double x) { return m.u(x); }, [&](double y) { return m.v(y); })) {
    loop(std::true_type{});
  } else {
    loop(std::false_type{});
  }
}

/// heights() on resident samples with any kernel, chosen once for the whole batch.
void residentKernelBatch(const float* resident, long rows, long cols,
                         const detail::DemIndexer& index, const detail::ResidentBilinear& fast,
                         const glm::dvec2& slack, Interpolation interp, const Batch& b) {
  const double nd = fast.nodata;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  using Acc = ClampAcc<detail::MemFetch>;
  const Acc acc{{resident, cols}, rows, cols};
  auto run = [&](auto kernel) {
    for (std::size_t i = 0; i < b.xs.size(); ++i) {
      const Where w = locate(index, b.xs[i], b.ys[i], fast.uMax, fast.vMax, slack);
      QueryStatus st = QueryStatus::OutsideGrid;
      double h = nan;
      if (w.inside) {
        const KernelResult k = kernel(acc, w.u, w.v, nd);
        st = k.status;
        h = st == QueryStatus::Ok ? k.h : nan;
      }
      b.out[i] = h;
      if (!b.status.empty()) b.status[i] = st;
    }
  };
  switch (interp) {
    case Interpolation::Nearest: run(detail::nearest<false, Acc>); break;
    case Interpolation::Bicubic: run(detail::bicubic<false, Acc>); break;
    case Interpolation::Bilinear: run(detail::bilinear<false, Acc>); break;
  }
}
}  // namespace

void TopoDem::heights(std::span<const double> xs, std::span<const double> ys, std::span<double> out,
                      std::span<QueryStatus> status, Interpolation interp) const {
  constexpr const char* op = "TopoDem::heights()";
  const std::size_t n = xs.size();
  requireSameLength(n, ys.size(), op, "ys");
  requireSameLength(n, out.size(), op, "out");
  if (!status.empty()) requireSameLength(n, status.size(), op, "status");
  requireFiniteArray(xs, op, "xs");
  requireFiniteArray(ys, op, "ys");
  const Batch batch{xs, ys, out, status};
  const auto generic = [&](double x, double y) { return heightGeneric(x, y, interp); };
  if (fast_.data != nullptr && interp == Interpolation::Bilinear) {
    residentBilinearBatch(index_, fast_, batch, generic);
  } else if (resident_ == nullptr && interp == Interpolation::Bilinear) {
    pagedBilinearBatch(index_, fast_, table_, sourceId_, batch, generic);
  } else if (resident_ == nullptr) {  // paged, other kernels: per point, reusing the thread's block
    for (std::size_t i = 0; i < n; ++i) {
      const HeightSample s = generic(xs[i], ys[i]);
      out[i] = s.height;
      if (!status.empty()) status[i] = s.status;
    }
  } else {
    residentKernelBatch(resident_, static_cast<long>(grid_.rows()), static_cast<long>(grid_.cols()),
                        index_, fast_, slack_, interp, batch);
  }
}

void TopoDem::surfaces(std::span<const double> xs, std::span<const double> ys,
                       std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                       std::span<QueryStatus> status, Interpolation interp, NormalFrame frame,
                       std::span<QueryStatus> normalStatus) const {
  constexpr const char* op = "TopoDem::surfaces()";
  const std::size_t n = xs.size();
  requireSameLength(n, ys.size(), op, "ys");
  requireSameLength(n, outHeights.size(), op, "outHeights");
  requireSameLength(n, outNormals.size(), op, "outNormals");
  if (!status.empty()) requireSameLength(n, status.size(), op, "status");
  if (!normalStatus.empty()) requireSameLength(n, normalStatus.size(), op, "normalStatus");
  requireFiniteArray(xs, op, "xs");
  requireFiniteArray(ys, op, "ys");
  const bool resident = fast_.data != nullptr;
  if (interp == Interpolation::Bilinear && frame == NormalFrame::Grid &&
      (resident || resident_ == nullptr)) {
    // surface()'s fast paths on local copies (stores to the outputs could alias the members,
    // which would then be reloaded for every point), with heights()'s prefetching for
    // batches that jump around the grid.
    const detail::DemIndexer m = index_;
    const detail::ResidentBilinear f = fast_;
    const BlockIndex* table = table_;
    const std::uint64_t id = sourceId_;
    auto loop = [&](auto inMemory, auto prefetch) {
      for (std::size_t i = 0; i < n; ++i) {
        if constexpr (prefetch) {
          if (i + kPrefetchAhead < n) {
            const std::size_t j = i + kPrefetchAhead;
            const double uj = m.u(xs[j]), vj = m.v(ys[j]);
            if (uj >= 0.0 && vj >= 0.0 && uj < f.uMax && vj < f.vMax) {
              const auto rj = static_cast<std::size_t>(vj), cj = static_cast<std::size_t>(uj);
              if constexpr (inMemory) {
                const float* p = f.data + rj * static_cast<std::size_t>(f.cols) + cj;
                __builtin_prefetch(p);
                __builtin_prefetch(p + f.cols);
              } else {
                table->prefetchCell(rj, cj);
              }
            }
          }
        }
        const double u = m.u(xs[i]), v = m.v(ys[i]);
        detail::CellValue cv;
        bool ok = false;
        if constexpr (inMemory) {
          ok = f.evalResident<true>(u, v, cv);
        } else {
          ok = detail::pagedBilinear<true>(f, table, id, u, v, cv);
        }
        if (ok) [[likely]] {
          outHeights[i] = cv.h;
          outNormals[i] = detail::gridNormal(m, cv.dhdu, cv.dhdv);
          if (!status.empty()) status[i] = QueryStatus::Ok;
          if (!normalStatus.empty()) normalStatus[i] = QueryStatus::Ok;
          continue;
        }
        const SurfaceSample s = surfaceGeneric(xs[i], ys[i], interp, frame);
        outHeights[i] = s.height;
        outNormals[i] = s.normal;
        if (!status.empty()) status[i] = s.status;
        if (!normalStatus.empty()) normalStatus[i] = s.normalStatus;
      }
    };
    using Yes = std::true_type;
    using No = std::false_type;
    const bool jumps =
        (resident || table != nullptr) &&
        scattered(
            xs, ys, [&](double x) { return m.u(x); }, [&](double y) { return m.v(y); });
    if (resident) {
      jumps ? loop(Yes{}, Yes{}) : loop(Yes{}, No{});
    } else {
      jumps ? loop(No{}, Yes{}) : loop(No{}, No{});
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const SurfaceSample s = surface(xs[i], ys[i], interp, frame);
    outHeights[i] = s.height;
    outNormals[i] = s.normal;
    if (!status.empty()) status[i] = s.status;
    if (!normalStatus.empty()) normalStatus[i] = s.normalStatus;
  }
}

glm::dvec3 TopoDem::samplePosition(std::size_t row, std::size_t col) const {
  if (row >= grid_.rows() || col >= grid_.cols()) {
    throw InvalidArgument("TopoDem::samplePosition(): sample (" + core::number(row) + ", " +
                          core::number(col) + ") is outside the " + core::number(grid_.rows()) +
                          "x" + core::number(grid_.cols()) + " grid");
  }
  const float s = samples_->sample(row, col);
  const glm::dvec2 xy = grid_.sampleCentre(static_cast<double>(row), static_cast<double>(col));
  const double h =
      grid_.isNodata(s) ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(s);
  if (std::isnan(h)) return glm::dvec3(std::numeric_limits<double>::quiet_NaN());
  return placement_.toBodyFixed(xy.x, xy.y, h);
}

}  // namespace regolith::topo
