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
inline Where locate(const kernel::DemIndexer& m, double x, double y, double cmax, double rmax,
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
// weight): what the fast paths answer (ResidentBilinear::evalResident,
// PagedQueries::bilinearHeight), with the same arithmetic, so that a height never depends on the
// path that answered it, nor a paged one on what is resident (stop 31: up to 12 ulps between a cold
// and a warm cache). Snapping onto a line decides only the rest: a sample whose weight vanishes on
// the line (a hole beside a sample centre), and the border. The fast paths cannot snap instead: the
// test for a point near a line made bilinear heights 2–33 % slower (docs/paging.md).
// The unsnapped point, when snapping moved it and its cell is inside the centres.
inline std::optional<Where> unsnapped(const Where& w, double cmax, double rmax) noexcept {
  if (w.rawU == w.u && w.rawV == w.v) return std::nullopt;
  if (!(w.rawU >= 0.0 && w.rawU < cmax && w.rawV >= 0.0 && w.rawV < rmax)) return std::nullopt;
  return Where{w.rawU, w.rawV, true, w.rawU, w.rawV};
}

// The calling thread's block of a paged source holding the cell of `w` (an empty view for a
// source without blocks).
inline const kernel::BlockView& threadBlock(const SampleSource& src, const Where& w) {
  return detail::blockOf(src, static_cast<std::size_t>(w.v), static_cast<std::size_t>(w.u));
}

// Calls fn with the accessor that fits the source: plain array loads when the samples are
// resident; otherwise loads from the block holding the point's cell (the paged source's
// thread block), falling back to SampleSource::sample() for stencil samples outside it.
template <class Fn>
KernelResult withAccessor(const TopoGrid& g, const SampleSource& src, const float* resident,
                          const Where& w, Fn&& fn) {
  const long rows = static_cast<long>(g.rows()), cols = static_cast<long>(g.cols());
  if (resident != nullptr) return fn(ClampAcc<detail::MemFetch>{{resident, cols}, rows, cols});
  const kernel::BlockView& tb = threadBlock(src, w);
  return fn(ClampAcc<detail::BlockFetch>{{&src, &tb}, rows, cols});
}

// The bilinear height at w (a cell inside the sample centres), or nothing where the kernel
// has no value there (a missing sample of non-zero weight). On a paged source, the block
// path first: a fast path's arithmetic either way (kernel::bilinearPatch, bilinear()).
std::optional<double> bilinearHeightAt(const TopoGrid& g, const SampleSource& src,
                                       const float* resident, const kernel::ResidentBilinear& f,
                                       const Where& w) {
  kernel::CellValue cv;
  if (resident == nullptr && kernel::blockBilinear<false>(threadBlock(src, w), f, w.u, w.v, cv))
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

TopoDem::TopoDem(TopoGrid grid, Placement placement, std::shared_ptr<const SampleSource> samples)
    : grid_(std::move(grid)), placement_(std::move(placement)), samples_(std::move(samples)) {
  if (!samples_) throw InvalidArgument("TopoDem(): samples is null, expected a SampleSource");
  if (samples_->rows() != grid_.rows() || samples_->cols() != grid_.cols()) {
    throw InvalidArgument("TopoDem(): samples are " + core::number(samples_->rows()) + "x" +
                          core::number(samples_->cols()) + ", expected the grid's " +
                          core::number(grid_.rows()) + "x" + core::number(grid_.cols()));
  }
  resident_ = samples_->contiguous();
  paged_ = samples_->paged();
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
    kernel::CellValue cv;
    if (resident_ == nullptr &&
        kernel::blockBilinear<false>(threadBlock(*samples_, w), fast_, w.u, w.v, cv)) [[likely]] {
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
    kernel::CellValue cv;
    if ((paged_ != nullptr && paged_->bilinearSurface(fast_, w.u, w.v, cv)) ||
        kernel::blockBilinear<true>(threadBlock(*samples_, w), fast_, w.u, w.v, cv)) [[likely]] {
      const SurfaceSample s{cv.h, kernel::gridNormal(index_, cv.dhdu, cv.dhdv), QueryStatus::Ok,
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
  s.normal = kernel::gridNormal(index_, k.dhdu, k.dhdv);
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
/// heights() on resident samples with any kernel, chosen once for the whole batch.
void residentKernelBatch(const float* resident, long rows, long cols,
                         const kernel::DemIndexer& index, const kernel::ResidentBilinear& fast,
                         const glm::dvec2& slack, Interpolation interp,
                         const kernel::HeightBatch& b) {
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
  const kernel::HeightBatch batch{xs, ys, out, status};
  const auto generic = [&](double x, double y) { return heightGeneric(x, y, interp); };
  if (fast_.data != nullptr && interp == Interpolation::Bilinear) {
    kernel::bilinearHeights(kernel::ResidentCells{fast_}, index_, fast_, batch, generic);
  } else if (paged_ != nullptr && interp == Interpolation::Bilinear) {
    // The source's own loop (its cells keep per-thread state); one call for the batch.
    struct Context {
      const TopoDem* dem;
      Interpolation interp;
    } const context{this, interp};
    const kernel::Fallback<HeightSample> fallback{[](const void* c, double x, double y) {
                                                    const auto* k = static_cast<const Context*>(c);
                                                    return k->dem->heightGeneric(x, y, k->interp);
                                                  },
                                                  &context};
    paged_->bilinearHeights(index_, fast_, batch, fallback);
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
  if (interp == Interpolation::Bilinear && frame == NormalFrame::Grid &&
      (fast_.data != nullptr || paged_ != nullptr)) {
    // surface()'s fast paths, with heights()'s prefetching for batches that jump around.
    const kernel::SurfaceBatch batch{xs, ys, outHeights, outNormals, status, normalStatus};
    if (fast_.data != nullptr) {
      kernel::bilinearSurfaces(
          kernel::ResidentCells{fast_}, index_, fast_, batch,
          [&](double x, double y) { return surfaceGeneric(x, y, interp, frame); });
      return;
    }
    const kernel::Fallback<SurfaceSample> fallback{
        [](const void* c, double x, double y) {
          return static_cast<const TopoDem*>(c)->surfaceGeneric(x, y, Interpolation::Bilinear,
                                                                NormalFrame::Grid);
        },
        this};
    paged_->bilinearSurfaces(index_, fast_, batch, fallback);
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
