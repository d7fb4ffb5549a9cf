#pragma once
/// \file
/// The bilinear query kernel on resident samples, as templates shared by every grid whatever
/// holds its samples: one array in memory (TopoDem, TopoPlanet here) or resident blocks of a
/// paged source (the store's pager, through topo::PagedQueries). Pure functions and plain
/// structs: no threads, no system calls, no global state. A paged source keeps whatever
/// per-thread state it needs (its thread's last block) itself.
///
/// They live in a header so that TopoDem::height() inlines into the caller's loop: the
/// rover's bilinear query costs a few nanoseconds, and an out-of-line call plus the generic
/// kernel would double it (docs/accuracy-vs-time.md).

#include <regolith/topo/Query.hpp>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#if defined(__x86_64__) || defined(_M_X64)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>

namespace regolith::topo {

namespace kernel {

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
/// generic kernel (topo/src/Kernels.hpp, bilinear), so the fast and generic paths give the
/// same bits. False when a sample is missing: a NaN sample makes h NaN (0·NaN is NaN), so
/// one test covers them all, plus the declared nodata value if there is one.
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

/// A grid's part of a bilinear query, and its resident samples when it has them in one
/// array: for points whose cell lies inside the grid.
struct ResidentBilinear {
  const float* data = nullptr;  // null: samples not in one array (paged), or under 2×2
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

/// The address sample (0, 0) of the grid would have if a block's rows extended back to it,
/// in integer arithmetic (as a pointer it could lie outside any object): a query then finds
/// sample (r, c) at origin + (r·stride + c)·sizeof(float) with no subtraction of the
/// block's first row and column (fewer instructions on the random-access path).
[[nodiscard]] inline std::uintptr_t originOf(const float* data, std::size_t row0, std::size_t col0,
                                             std::size_t stride) noexcept {
  return reinterpret_cast<std::uintptr_t>(data) - (row0 * stride + col0) * sizeof(float);
}

/// A view of resident samples: rows × cols samples from (row0, col0), row-major with
/// `stride` floats between rows, and the fractional (u, v) whose whole bilinear cell lies
/// in it: uLo ≤ u < uHi and vLo ≤ v < vHi (empty when data is null). Whoever hands one out
/// keeps its memory alive while it is used.
struct BlockView {
  const float* data = nullptr;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0, stride = 0;
  double uLo = 0.0, uHi = 0.0, vLo = 0.0, vHi = 0.0;
  std::uintptr_t origin = 0;  // originOf(data, row0, col0, stride)

  [[nodiscard]] bool holds(std::size_t r, std::size_t c) const noexcept {
    return data != nullptr && r >= row0 && c >= col0 && r - row0 < rows && c - col0 < cols;
  }
};

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

/// Bilinear height (and gradient, when Grad) from a block (a BlockView, or a paged source's
/// own block type with the same members) whose whole cell (c, r) = (⌊u⌋, ⌊v⌋) holds (u, v),
/// given c and r. False leaves the point to the generic kernel (also for NaN: it fails the
/// bounds; and, when Grad, near a cell line: see ResidentBilinear::offLines).
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

/// Batch queries prefetch the cell of the point this many ahead (random points: the memory
/// misses of several points overlap instead of being paid one after another).
inline constexpr std::size_t kPrefetchAhead = 8;

/// Whether a batch jumps around the grid (random access, where prefetching pays), judged on
/// its first points: most of them more than a few cells from the one before. Along a path (a
/// rover's wheels) the cells are in cache already, and a loop that even checks for
/// prefetching ran a third slower (store_bench rover_batch), so such batches take a loop
/// without it. A batch no longer than the prefetch distance has nothing to prefetch (the
/// rover's six wheels of one step).
[[nodiscard]] inline bool scattered(const DemIndexer& m, std::span<const double> xs,
                                    std::span<const double> ys) noexcept {
  if (xs.size() <= kPrefetchAhead) return false;
  const std::size_t k = std::min<std::size_t>(xs.size(), 17);
  std::size_t jumps = 0;
  for (std::size_t i = 1; i < k; ++i) {
    const double du = m.u(xs[i]) - m.u(xs[i - 1]), dv = m.v(ys[i]) - m.v(ys[i - 1]);
    jumps += std::abs(du) + std::abs(dv) > 4.0 ? 1U : 0U;
  }
  return k > 1 && 2 * jumps > k - 1;
}

/// A heights() batch: points and answers (status may be empty: not wanted).
struct HeightBatch {
  std::span<const double> xs, ys;
  std::span<double> out;
  std::span<QueryStatus> status;
};
/// A surfaces() batch (either status may be empty).
struct SurfaceBatch {
  std::span<const double> xs, ys;
  std::span<double> heights;
  std::span<glm::dvec3> normals;
  std::span<QueryStatus> status, normalStatus;
};

/// What answers a batch's points that the bilinear fast path leaves (a function and its
/// context, so that it crosses a virtual call: see PagedQueries).
template <class Sample>
struct Fallback {
  Sample (*fn)(const void* context, double x, double y) = nullptr;
  const void* context = nullptr;
  Sample operator()(double x, double y) const { return fn(context, x, y); }
};

/// The cells of resident samples in one array, for the batch loops below. A cells type
/// gives `eval<Grad>(u, v, out)` (the fast path: false leaves the point to the fallback),
/// `prefetches()` (whether `prefetchCell()` does anything) and `prefetchCell(r, c)` (a hint
/// for the cell of sample (r, c) inside the sample centres).
struct ResidentCells {
  ResidentBilinear f;  // a copy: the loops' stores to double outputs could alias a reference
  template <bool Grad>
  [[nodiscard, gnu::always_inline]] bool eval(double u, double v, CellValue& out) const noexcept {
    return f.evalResident<Grad>(u, v, out);
  }
  [[nodiscard]] static constexpr bool prefetches() noexcept { return true; }
  void prefetchCell(std::size_t r, std::size_t c) const noexcept {
    const float* p = f.data + r * static_cast<std::size_t>(f.cols) + c;
    __builtin_prefetch(p);
    __builtin_prefetch(p + f.cols);
  }
};

/// heights() with the bilinear kernel: the fast path of `cells` on local copies (stores to
/// the outputs could alias the grid's own members, which would then be reloaded for every
/// point; so cells and m come by value), `generic(x, y)` for the points it leaves. Specialised on
/// the spacing's reciprocal being exact, on whether status is wanted and on prefetching (batches
/// that jump around the grid), so the loop body has no branches but the bounds and missing-sample
/// tests.
template <class Cells, class Generic>
void bilinearHeights(const Cells cells, const DemIndexer m, const ResidentBilinear& grid,
                     const HeightBatch& b, const Generic& generic) {
  const std::size_t n = b.xs.size();
  const auto xs = b.xs, ys = b.ys;
  const auto out = b.out;
  const auto status = b.status;
  const double uMax = grid.uMax, vMax = grid.vMax;
  auto loop = [&](auto recip, auto wantStatus, auto prefetch) {
    const auto u = [&](double x) { return recip ? (x - m.x0) * m.idx : (x - m.x0) / m.dx; };
    const auto v = [&](double y) { return recip ? (m.y0 - y) * m.idy : (m.y0 - y) / m.dy; };
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (prefetch) {
        if (i + kPrefetchAhead < n) {
          // Random access: fetch the cell of a point a few ahead, so its memory miss
          // overlaps this point's work.
          const std::size_t j = i + kPrefetchAhead;
          const double uj = u(xs[j]), vj = v(ys[j]);
          if (uj >= 0.0 && vj >= 0.0 && uj < uMax && vj < vMax)
            cells.prefetchCell(static_cast<std::size_t>(vj), static_cast<std::size_t>(uj));
        }
      }
      CellValue cv;
      if (cells.template eval<false>(u(xs[i]), v(ys[i]), cv)) [[likely]] {
        out[i] = cv.h;
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
  if (cells.prefetches() && scattered(m, xs, ys)) {
    run(Yes{});
  } else {
    run(No{});
  }
}

/// surfaces() with the bilinear kernel in the grid frame: as bilinearHeights(), the normal
/// from the height's four samples (gridNormal()).
template <class Cells, class Generic>
void bilinearSurfaces(const Cells cells, const DemIndexer m, const ResidentBilinear& grid,
                      const SurfaceBatch& b, const Generic& generic) {
  const std::size_t n = b.xs.size();
  const auto xs = b.xs, ys = b.ys;
  const auto heights = b.heights;
  const auto normals = b.normals;
  const auto status = b.status, normalStatus = b.normalStatus;
  const double uMax = grid.uMax, vMax = grid.vMax;
  auto loop = [&](auto prefetch) {
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (prefetch) {
        if (i + kPrefetchAhead < n) {
          const std::size_t j = i + kPrefetchAhead;
          const double uj = m.u(xs[j]), vj = m.v(ys[j]);
          if (uj >= 0.0 && vj >= 0.0 && uj < uMax && vj < vMax)
            cells.prefetchCell(static_cast<std::size_t>(vj), static_cast<std::size_t>(uj));
        }
      }
      CellValue cv;
      if (cells.template eval<true>(m.u(xs[i]), m.v(ys[i]), cv)) [[likely]] {
        heights[i] = cv.h;
        normals[i] = gridNormal(m, cv.dhdu, cv.dhdv);
        if (!status.empty()) status[i] = QueryStatus::Ok;
        if (!normalStatus.empty()) normalStatus[i] = QueryStatus::Ok;
        continue;
      }
      const SurfaceSample s = generic(xs[i], ys[i]);
      heights[i] = s.height;
      normals[i] = s.normal;
      if (!status.empty()) status[i] = s.status;
      if (!normalStatus.empty()) normalStatus[i] = s.normalStatus;
    }
  };
  if (cells.prefetches() && scattered(m, xs, ys)) {
    loop(std::true_type{});
  } else {
    loop(std::false_type{});
  }
}

}  // namespace kernel

/// The bilinear fast paths of a source whose samples are resident in blocks rather than in
/// one array (the store's pager, store::BlockSource). TopoDem and TopoPlanet call them when
/// the source gives them (SampleSource::paged()); the implementation keeps its own
/// per-thread state (the thread's last block, its hazard record) and instantiates the batch
/// loops above with its own cells, so topo holds no state for it. Every member may be
/// called from several threads at once.
class PagedQueries {
 public:
  /// The bilinear height at fractional index (u, v) from resident blocks, or NaN, which
  /// leaves the point to the generic kernel (not resident, a sample missing, outside the
  /// sample centres; an answered height is never NaN). Returned in a register: through an
  /// out parameter, point queries along a path measured 1.40–1.51× the in-memory query
  /// against 1.24–1.36× (store_bench store/resident/paged/rover). Never throws.
  [[nodiscard]] virtual double bilinearHeight(const kernel::ResidentBilinear& grid, double u,
                                              double v) const noexcept = 0;
  /// The bilinear height and gradient at (u, v), or false as bilinearHeight() (and near a
  /// cell line). Never throws.
  [[nodiscard]] virtual bool bilinearSurface(const kernel::ResidentBilinear& grid, double u,
                                             double v, kernel::CellValue& out) const noexcept = 0;
  /// kernel::bilinearHeights() and bilinearSurfaces() with this source's cells.
  virtual void bilinearHeights(const kernel::DemIndexer& m, const kernel::ResidentBilinear& grid,
                               const kernel::HeightBatch& b,
                               kernel::Fallback<HeightSample> generic) const = 0;
  virtual void bilinearSurfaces(const kernel::DemIndexer& m, const kernel::ResidentBilinear& grid,
                                const kernel::SurfaceBatch& b,
                                kernel::Fallback<SurfaceSample> generic) const = 0;
  /// A hint: the cell of sample (r, c) (rows r and r + 1) will be read soon. Requires r, c
  /// inside the grid.
  virtual void prefetchCell(std::size_t r, std::size_t c) const noexcept = 0;
  /// The calling thread's block holding sample (r, c), loaded if need be, for the generic
  /// kernels (which read stencil samples outside it through SampleSource::sample()). Valid on
  /// the calling thread until its next call into any PagedQueries. May throw (a load).
  [[nodiscard]] virtual const kernel::BlockView& threadBlock(std::size_t r,
                                                             std::size_t c) const = 0;

 protected:
  PagedQueries() = default;
  PagedQueries(const PagedQueries&) = default;
  PagedQueries(PagedQueries&&) = default;
  PagedQueries& operator=(const PagedQueries&) = default;
  PagedQueries& operator=(PagedQueries&&) = default;
  ~PagedQueries() = default;
};

}  // namespace regolith::topo
