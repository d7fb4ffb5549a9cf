#pragma once
// Interpolation kernels shared by TopoDem and TopoPlanet (private header).
//
// Kernels are templates over an accessor so that the in-memory fast path compiles to plain
// array loads while paged sources go through their block (PagedQueries::threadBlock()) and
// SampleSource::sample(). An accessor provides
//   double operator()(long r, long c)  any integer index, mapped to a sample (wrap, pole,
//                                      or extrapolation one sample beyond an edge)
//   bool hasRow(long r), hasCol(long c)  whether the index names a distinct sample
//   long rMax(), cMax()  the largest base index of a cell (rows−2 on clamped axes)
// Coordinates u (column) and v (row) are fractional sample indices, already brought into
// the accessor's range by the caller.

#include <regolith/topo/Bilinear.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace regolith::topo::detail {

struct KernelResult {
  double h = 0.0;
  double dhdu = 0.0;                         // ∂h/∂(column index)
  double dhdv = 0.0;                         // ∂h/∂(row index)
  QueryStatus status = QueryStatus::Ok;      // of h
  QueryStatus gradStatus = QueryStatus::Ok;  // of dhdu, dhdv (when asked for)
  double dhduv = 0.0;  // ∂²h/∂u∂v (bilinear and bicubic; 0 for nearest and fallbacks)
};

// A sample is missing if NaN or equal to the nodata value (NaN itself when none is declared).
// floor() for the index range of grids; a libm call on baseline x86-64 (no SSE4.1), which
// would cost more than the whole bilinear kernel.
inline long floorToLong(double x) noexcept {
  const long i = static_cast<long>(x);
  return i - static_cast<long>(x < static_cast<double>(i));
}

// f, or the integer nearest to it when within `slack` (TopoGrid::edgeSlack()): a point on a
// sample line to a few ulps is on it. Casts, not nearbyint (a libm call on baseline
// x86-64); beyond 2^52 every double is an integer already.
inline double snapToLine(double f, double slack) noexcept {
  if (!(std::abs(f) < 4503599627370496.0)) return f;
  const double r = static_cast<double>(floorToLong(f + 0.5));
  return std::abs(f - r) <= slack ? r : f;
}

inline bool missing(double s, double nd) noexcept { return s != s || s == nd; }

// Raw fetchers: indices already valid.
struct MemFetch {
  const float* data;
  long cols;
  float operator()(long r, long c) const noexcept { return data[r * cols + c]; }
};

// Paged sources: loads from a resident block when it holds the sample (a paged source's
// PagedQueries::threadBlock(); an empty view for a source without blocks), else asks the
// source (a stencil straddling two blocks).
struct BlockFetch {
  const SampleSource* src;
  const kernel::BlockView* blk;
  float operator()(long r, long c) const {
    const auto ur = static_cast<std::size_t>(r), uc = static_cast<std::size_t>(c);
    const float* data = blk->data;  // null for a source without blocks (holds() is false)
    if (data != nullptr && blk->holds(ur, uc)) {
      return data[(ur - blk->row0) * blk->stride + (uc - blk->col0)];
    }
    return src->sample(ur, uc);
  }
};

// The block of `src` holding sample (r, c) for the calling thread, or an empty view when the
// source has no blocks.
inline const kernel::BlockView& blockOf(const SampleSource& src, std::size_t r, std::size_t c) {
  static constexpr kernel::BlockView kNone{};
  const PagedQueries* paged = src.paged();
  return paged != nullptr ? paged->threadBlock(r, c) : kNone;
}

// Samples beyond a non-periodic edge are extrapolated with Keys' own boundary condition,
// f(−1) = 3f(0) − 3f(1) + f(2), which keeps cubic convolution exact for quadratics right up
// to the border (edge replication would bend a plane there). With two samples the rule is
// linear, with one constant. Only one sample beyond an edge is ever requested.
template <class At>
double extrapolate(long n, long i, At&& at) {
  if (n == 1) return at(0);
  const bool low = i < 0;
  const long e0 = low ? 0 : n - 1, e1 = low ? 1 : n - 2, e2 = low ? 2 : n - 3;
  if (n == 2) return 2.0 * at(e0) - at(e1);
  return 3.0 * at(e0) - 3.0 * at(e1) + at(e2);
}

// TopoDem accessor (and regional TopoPlanet grids): both axes end at the grid's edges.
template <class Fetch>
struct ClampAcc {
  Fetch fetch;
  long rows, cols;
  double operator()(long r, long c) const {
    if (c < 0 || c >= cols) {
      return extrapolate(cols, c, [&](long cc) { return (*this)(r, cc); });
    }
    if (r < 0 || r >= rows) {
      return extrapolate(rows, r, [&](long rr) { return (*this)(rr, c); });
    }
    return static_cast<double>(fetch(r, c));
  }
  bool hasRow(long r) const noexcept { return r >= 0 && r < rows; }
  bool hasCol(long c) const noexcept { return c >= 0 && c < cols; }
  long rMax() const noexcept { return std::max(rows - 2, 0L); }
  long cMax() const noexcept { return std::max(cols - 2, 0L); }
};

// TopoPlanet accessor: longitude wraps on a global grid; rows beyond a pole reflect to the
// row on the opposite meridian when the grid is global with an even column count.
template <class Fetch>
struct PlanetAcc {
  Fetch fetch;
  long rows, cols;
  bool global, reflectNorth, reflectSouth;
  double operator()(long r, long c) const {
    if (r < 0 && reflectNorth) {
      r = -1 - r;
      c += cols / 2;
    } else if (r >= rows && reflectSouth) {
      r = 2 * rows - 1 - r;
      c += cols / 2;
    }
    if (global) {
      // Stencils reach at most 2 columns beyond the grid, plus half a turn across a pole,
      // so one add or subtract wraps (cheaper than an integer division per sample).
      if (c < 0) {
        c += cols;
      } else if (c >= cols) {
        c -= cols;
      }
    } else if (c < 0 || c >= cols) {
      return extrapolate(cols, c, [&](long cc) { return (*this)(r, cc); });
    }
    if (r < 0 || r >= rows) {
      return extrapolate(rows, r, [&](long rr) { return (*this)(rr, c); });
    }
    return static_cast<double>(fetch(r, c));
  }
  bool hasRow(long r) const noexcept {
    return (r >= 0 && r < rows) || (r < 0 && reflectNorth) || (r >= rows && reflectSouth);
  }
  bool hasCol(long c) const noexcept { return global || (c >= 0 && c < cols); }
  long rMax() const noexcept { return std::max(rows - 2, 0L); }
  long cMax() const noexcept { return global ? LONG_MAX : std::max(cols - 2, 0L); }
};

// Keys (1981) cubic convolution, a = −0.5: weights of samples −1, 0, 1, 2 at fraction t,
// and their derivatives.
inline void keysWeights(double t, double w[4], double dw[4]) noexcept {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
  w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
  w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  dw[0] = 0.5 * (-3.0 * t2 + 4.0 * t - 1.0);
  dw[1] = 0.5 * (9.0 * t2 - 10.0 * t);
  dw[2] = 0.5 * (-9.0 * t2 + 8.0 * t + 1.0);
  dw[3] = 0.5 * (3.0 * t2 - 2.0 * t);
}

template <bool Grad, class Acc>
KernelResult nearest(const Acc& acc, double u, double v, double nd) {
  const long c = floorToLong(u + 0.5);
  const long r = floorToLong(v + 0.5);
  KernelResult k;
  const double s = acc(r, c);
  if (missing(s, nd)) return {0.0, 0.0, 0.0, QueryStatus::Nodata, QueryStatus::Nodata};
  k.h = s;
  if constexpr (Grad) {
    // Central differences of the neighbouring samples; one-sided where a neighbour is beyond
    // an edge or missing. An axis with neighbours that are all missing has no slope: the
    // height stays valid and the gradient is Nodata. An axis of one sample is flat.
    auto diff = [&](bool hasLo, bool hasHi, double lo, double hi, double& out) {
      const bool okLo = hasLo && !missing(lo, nd), okHi = hasHi && !missing(hi, nd);
      if (!okLo && !okHi) {
        out = 0.0;
        return !hasLo && !hasHi;
      }
      out = ((okHi ? hi : k.h) - (okLo ? lo : k.h)) / (int(okLo) + int(okHi));
      return true;
    };
    if (!diff(acc.hasCol(c - 1), acc.hasCol(c + 1), acc(r, c - 1), acc(r, c + 1), k.dhdu) ||
        !diff(acc.hasRow(r - 1), acc.hasRow(r + 1), acc(r - 1, c), acc(r + 1, c), k.dhdv)) {
      k.dhdu = k.dhdv = 0.0;
      k.gradStatus = QueryStatus::Nodata;
    }
  }
  return k;
}

template <bool Grad, class Acc>
KernelResult bilinear(const Acc& acc, double u, double v, double nd) {
  const long c = std::min(floorToLong(u), acc.cMax());
  const long r = std::min(floorToLong(v), acc.rMax());
  const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(r);
  double s00 = acc(r, c), s01 = acc(r, c + 1), s10 = acc(r + 1, c), s11 = acc(r + 1, c + 1);
  if (missing(s00, nd) || missing(s01, nd) || missing(s10, nd) || missing(s11, nd)) {
    if constexpr (Grad) return {0.0, 0.0, 0.0, QueryStatus::Nodata, QueryStatus::Nodata};
    // Height only: a missing sample is harmless exactly when its weight is zero.
    const double w[4] = {(1 - tu) * (1 - tv), tu * (1 - tv), (1 - tu) * tv, tu * tv};
    double* s[4] = {&s00, &s01, &s10, &s11};
    for (int i = 0; i < 4; ++i) {
      if (missing(*s[i], nd)) {
        if (w[i] != 0.0) return {0.0, 0.0, 0.0, QueryStatus::Nodata, QueryStatus::Nodata};
        *s[i] = 0.0;
      }
    }
  }
  const double a = s00, b = s01, cc = s10, d = s11;  // NOLINT(readability-identifier-length)
  KernelResult k;
  const double top = a + tu * (b - a), bottom = cc + tu * (d - cc);
  k.h = top + tv * (bottom - top);
  if constexpr (Grad) {
    k.dhdu = (1 - tv) * (b - a) + tv * (d - cc);
    k.dhdv = bottom - top;
    k.dhduv = (d - cc) - (b - a);
  }
  return k;
}

template <bool Grad, class Acc>
KernelResult bicubic(const Acc& acc, double u, double v, double nd) {
  const long c = std::min(floorToLong(u), acc.cMax());
  const long r = std::min(floorToLong(v), acc.rMax());
  double wu[4], dwu[4], wv[4], dwv[4];
  keysWeights(u - static_cast<double>(c), wu, dwu);
  keysWeights(v - static_cast<double>(r), wv, dwv);
  KernelResult k;
  for (int i = 0; i < 4; ++i) {
    double row = 0.0, drow = 0.0;
    for (int j = 0; j < 4; ++j) {
      const double s = acc(r - 1 + i, c - 1 + j);
      if (missing(s, nd)) {
        if (Grad || (wv[i] * wu[j]) != 0.0)
          return {0.0, 0.0, 0.0, QueryStatus::Nodata, QueryStatus::Nodata};
        continue;
      }
      row += wu[j] * s;
      if constexpr (Grad) drow += dwu[j] * s;
    }
    k.h += wv[i] * row;
    if constexpr (Grad) {
      k.dhdu += wv[i] * drow;
      k.dhdv += dwv[i] * row;
      k.dhduv += dwv[i] * drow;
    }
  }
  return k;
}

template <bool Grad, class Acc>
KernelResult evaluate(Interpolation interp, const Acc& acc, double u, double v, double nd) {
  switch (interp) {
    case Interpolation::Nearest: return nearest<Grad>(acc, u, v, nd);
    case Interpolation::Bicubic: return bicubic<Grad>(acc, u, v, nd);
    case Interpolation::Bilinear: break;
  }
  return bilinear<Grad>(acc, u, v, nd);
}

// The gradient of the cell holding (u, v) from the samples it has: all four (the bilinear
// gradient) or three (the plane through them). False if it has fewer.
template <class Acc>
bool cellGradient(const Acc& acc, double u, double v, double nd, double& dhdu, double& dhdv) {
  const long c = std::min(floorToLong(u), acc.cMax());
  const long r = std::min(floorToLong(v), acc.rMax());
  const double s00 = acc(r, c), s01 = acc(r, c + 1), s10 = acc(r + 1, c), s11 = acc(r + 1, c + 1);
  const bool m00 = missing(s00, nd), m01 = missing(s01, nd), m10 = missing(s10, nd),
             m11 = missing(s11, nd);
  const int nMissing = int(m00) + int(m01) + int(m10) + int(m11);
  if (nMissing == 0) {
    const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(r);
    dhdu = (1 - tv) * (s01 - s00) + tv * (s11 - s10);
    dhdv = (1 - tu) * (s10 - s00) + tu * (s11 - s01);
    return true;
  }
  if (nMissing > 1) return false;
  // Three samples: each difference along an axis uses the row or column that has both ends.
  dhdu = m00 || m01 ? s11 - s10 : s01 - s00;
  dhdv = m00 || m10 ? s11 - s01 : s10 - s00;
  return true;
}

// Height and gradient at (u, v) for a surface query. The height is valid wherever the
// height kernel has its samples (as evaluate<false>). The gradient is the kernel's own when
// its whole stencil is there; where the stencil reaches a hole, it falls back to the cell's
// gradient (cellGradient), then to the nearest sample's one-sided differences; gradStatus
// is Nodata when none of them has its samples.
template <class Acc>
KernelResult evaluateSurface(Interpolation interp, const Acc& acc, double u, double v, double nd) {
  KernelResult k = evaluate<true>(interp, acc, u, v, nd);
  if (k.status == QueryStatus::Ok) return k;  // nearest sets gradStatus itself
  k = evaluate<false>(interp, acc, u, v, nd);
  if (k.status != QueryStatus::Ok) {
    k.gradStatus = k.status;
    return k;
  }
  if (cellGradient(acc, u, v, nd, k.dhdu, k.dhdv)) return k;
  const KernelResult n = nearest<true>(acc, u, v, nd);
  k.dhdu = n.dhdu;
  k.dhdv = n.dhdv;
  k.gradStatus = n.status == QueryStatus::Ok ? n.gradStatus : n.status;
  return k;
}

inline double nodataOrNan(const TopoGrid& g) noexcept {
  return g.nodata() ? static_cast<double>(*g.nodata()) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace regolith::topo::detail
