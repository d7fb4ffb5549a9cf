// TopoDem surface queries (height and normal) against a brute-force reference in long
// double: the analytic bilinear patch, Keys interpolant and nearest-sample differences of a
// quadratic sampled at integer indices. Every sample source (in memory, in blocks, sample by
// sample) and both the single and the batch query must give the reference, and each other's
// bits, at random points, on cell lines and a few ulps either side of them, across block
// edges, in the half-pixel border, outside the grid and next to holes.
#include <regolith/topo/TopoDem.hpp>

#include "support/TestSources.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::topo;
using regolith::test::BlockSource;
using regolith::test::SampleOnlySource;

namespace {

using Real = long double;

// h(c, r) = α c² + β r² + γ c r + δ c + ε r + ζ at sample (row r, col c): integers, exact
// in float for the grids below (|h| < 2^24).
struct Quadratic {
  Real a = 3, b = -2, g = 1, d = -7, e = 5, z = 100;
  [[nodiscard]] Real at(Real c, Real r) const {
    return a * c * c + b * r * r + g * c * r + d * c + e * r + z;
  }
};

// Holes: samples that are NaN, or the declared nodata value.
struct Hole {
  std::size_t r, c;
  bool nan;
};

struct Case {
  std::size_t rows, cols;
  double x0, y0, dx, dy;
  std::optional<float> nodata;
  std::vector<Hole> holes;
};

std::vector<float> samplesOf(const Case& k, const Quadratic& q) {
  std::vector<float> s(k.rows * k.cols);
  for (std::size_t r = 0; r < k.rows; ++r) {
    for (std::size_t c = 0; c < k.cols; ++c) {
      s[r * k.cols + c] = static_cast<float>(q.at(static_cast<Real>(c), static_cast<Real>(r)));
    }
  }
  for (const Hole& h : k.holes) {
    s[h.r * k.cols + h.c] = h.nan ? std::numeric_limits<float>::quiet_NaN() : *k.nodata;
  }
  return s;
}

// The expected answer at one point, or nothing for the value where the rules leave the
// reference out (a normal that falls back to nearest-sample differences).
struct Expected {
  QueryStatus status = QueryStatus::OutsideGrid, normalStatus = QueryStatus::OutsideGrid;
  Real h = 0;
  Real dhdu = 0, dhdv = 0;  // per index
  bool normalKnown = false;
};

bool isHole(const Case& k, long r, long c) {
  return std::any_of(k.holes.begin(), k.holes.end(), [&](const Hole& h) {
    return static_cast<long>(h.r) == r && static_cast<long>(h.c) == c;
  });
}

// Fractional indices of (x, y), snapped onto a sample line within 1e-9 (docs/queries.md: a
// point on a line to a few ulps is on it) and then clamped to the sample centres; false
// outside the pixel extent.
bool indexOf(const Case& k, double x, double y, Real& u, Real& v) {
  u = (static_cast<Real>(x) - k.x0) / k.dx;
  v = (k.y0 - static_cast<Real>(y)) / k.dy;
  const Real tol = 1e-9L;
  const Real cmax = static_cast<Real>(k.cols) - 1, rmax = static_cast<Real>(k.rows) - 1;
  if (u < -0.5L - tol || u > cmax + 0.5L + tol || v < -0.5L - tol || v > rmax + 0.5L + tol) {
    return false;
  }
  if (std::abs(u - std::round(u)) <= tol) u = std::round(u);
  if (std::abs(v - std::round(v)) <= tol) v = std::round(v);
  u = std::clamp(u, Real{0}, cmax);
  v = std::clamp(v, Real{0}, rmax);
  return true;
}

// Bilinear: the cell (⌊u⌋, ⌊v⌋), the last one on the far edges. Over a quadratic the patch is
// α[(2c+1)u − c(c+1)] + β[(2r+1)v − r(r+1)] + γuv + δu + εv + ζ (bilinear interpolation
// takes c² to its secant and reproduces cr), so ∂h/∂u = α(2c+1) + γv + δ and
// ∂h/∂v = β(2r+1) + γu + ε. A hole with weight 0 leaves the height; the normal then comes
// from the other three samples (the row and column that have both ends).
Expected bilinearRef(const Case& k, const Quadratic& q, double x, double y) {
  Expected e;
  Real u = 0, v = 0;
  if (!indexOf(k, x, y, u, v)) return e;
  const long c = std::min(static_cast<long>(std::floor(u)), static_cast<long>(k.cols) - 2);
  const long r = std::min(static_cast<long>(std::floor(v)), static_cast<long>(k.rows) - 2);
  const Real tu = u - static_cast<Real>(c), tv = v - static_cast<Real>(r);
  const Real rc = static_cast<Real>(c), rr = static_cast<Real>(r);
  const bool m00 = isHole(k, r, c), m01 = isHole(k, r, c + 1), m10 = isHole(k, r + 1, c),
             m11 = isHole(k, r + 1, c + 1);
  const Real w00 = (1 - tu) * (1 - tv), w01 = tu * (1 - tv), w10 = (1 - tu) * tv, w11 = tu * tv;
  if ((m00 && w00 != 0) || (m01 && w01 != 0) || (m10 && w10 != 0) || (m11 && w11 != 0)) {
    e.status = e.normalStatus = QueryStatus::Nodata;
    return e;
  }
  e.status = QueryStatus::Ok;
  e.h = q.a * ((2 * rc + 1) * u - rc * (rc + 1)) + q.b * ((2 * rr + 1) * v - rr * (rr + 1)) +
        q.g * u * v + q.d * u + q.e * v + q.z;
  const int missing = int(m00) + int(m01) + int(m10) + int(m11);
  if (missing == 0) {
    e.normalStatus = QueryStatus::Ok;
    e.normalKnown = true;
    e.dhdu = q.a * (2 * rc + 1) + q.g * v + q.d;
    e.dhdv = q.b * (2 * rr + 1) + q.g * u + q.e;
  } else if (missing == 1) {
    e.normalStatus = QueryStatus::Ok;
    e.normalKnown = true;
    const Real rowUsed = m00 || m01 ? rr + 1 : rr, colUsed = m00 || m10 ? rc + 1 : rc;
    e.dhdu = q.a * (2 * rc + 1) + q.g * rowUsed + q.d;
    e.dhdv = q.b * (2 * rr + 1) + q.g * colUsed + q.e;
  }
  return e;
}

// Bicubic (Keys, with its own extrapolation beyond the edges) is exact for a quadratic: the
// quadratic itself at the clamped point. Used on grids without holes.
Expected bicubicRef(const Case& k, const Quadratic& q, double x, double y) {
  Expected e;
  Real u = 0, v = 0;
  if (!indexOf(k, x, y, u, v)) return e;
  e.status = e.normalStatus = QueryStatus::Ok;
  e.normalKnown = true;
  e.h = q.at(u, v);
  e.dhdu = 2 * q.a * u + q.g * v + q.d;
  e.dhdv = 2 * q.b * v + q.g * u + q.e;
  return e;
}

// Nearest: the sample at ⌊u + ½⌋, its normal from central differences of its neighbours,
// one-sided on the grid's edges. Used on grids without holes.
Expected nearestRef(const Case& k, const Quadratic& q, double x, double y) {
  Expected e;
  Real u = 0, v = 0;
  if (!indexOf(k, x, y, u, v)) return e;
  const Real c = std::floor(u + 0.5L), r = std::floor(v + 0.5L);
  const Real cmax = static_cast<Real>(k.cols) - 1, rmax = static_cast<Real>(k.rows) - 1;
  e.status = e.normalStatus = QueryStatus::Ok;
  e.normalKnown = true;
  e.h = q.at(c, r);
  const Real cl = std::max(c - 1, Real{0}), ch = std::min(c + 1, cmax);
  const Real rl = std::max(r - 1, Real{0}), rh = std::min(r + 1, rmax);
  e.dhdu = (q.at(ch, r) - q.at(cl, r)) / (ch - cl);
  e.dhdv = (q.at(c, rh) - q.at(c, rl)) / (rh - rl);
  return e;
}

// The unit normal of the reference gradient in the grid frame (row 0 north).
glm::dvec3 normalOf(const Case& k, const Expected& e) {
  const Real hx = e.dhdu / k.dx, hy = -e.dhdv / k.dy;
  const Real len = std::sqrt(hx * hx + hy * hy + 1);
  return {static_cast<double>(-hx / len), static_cast<double>(-hy / len),
          static_cast<double>(1 / len)};
}

// Points that probe the hard places of a grid: random ones, every cell line and a few ulps
// either side of it (on both axes), the half-pixel border and just outside it.
std::vector<glm::dvec2> probePoints(const Case& k, unsigned seed) {
  std::vector<glm::dvec2> p;
  std::mt19937 rng(seed);
  const double w = static_cast<double>(k.cols) * k.dx, hgt = static_cast<double>(k.rows) * k.dy;
  const double west = k.x0 - 0.5 * k.dx, north = k.y0 + 0.5 * k.dy;
  std::uniform_real_distribution<double> ux(west - 0.3 * k.dx, west + w + 0.3 * k.dx);
  std::uniform_real_distribution<double> uy(north - hgt - 0.3 * k.dy, north + 0.3 * k.dy);
  std::uniform_real_distribution<double> frac(0.0, 1.0);
  for (int i = 0; i < 3000; ++i) p.emplace_back(ux(rng), uy(rng));
  const auto lineX = [&](std::size_t c) { return k.x0 + static_cast<double>(c) * k.dx; };
  const auto lineY = [&](std::size_t r) { return k.y0 - static_cast<double>(r) * k.dy; };
  const auto nudged = [](double s) {
    return std::vector<double>{s, std::nextafter(s, -1e300), std::nextafter(s, 1e300),
                               std::nextafter(std::nextafter(s, -1e300), -1e300),
                               std::nextafter(std::nextafter(s, 1e300), 1e300)};
  };
  for (std::size_t c = 0; c < k.cols; ++c) {
    for (const double x : nudged(lineX(c))) {
      p.emplace_back(x, lineY(0) - frac(rng) * static_cast<double>(k.rows - 1) * k.dy);
    }
  }
  for (std::size_t r = 0; r < k.rows; ++r) {
    for (const double y : nudged(lineY(r))) {
      p.emplace_back(lineX(0) + frac(rng) * static_cast<double>(k.cols - 1) * k.dx, y);
    }
  }
  for (std::size_t r = 0; r < k.rows; r += 3) {  // sample centres and their neighbours
    for (std::size_t c = 0; c < k.cols; c += 2) {
      for (const double x : nudged(lineX(c))) p.emplace_back(x, lineY(r));
      for (const double y : nudged(lineY(r))) p.emplace_back(lineX(c), y);
    }
  }
  // The borders: just outside, on the pixel extent's edge, in the half-pixel border.
  for (const double f : {-0.25, -1e-6, 0.0, 1e-6, 0.25, 0.5, 0.75}) {
    p.emplace_back(west + f * k.dx, lineY(k.rows / 2));
    p.emplace_back(west + w - f * k.dx, lineY(k.rows / 3) - 0.3 * k.dy);
    p.emplace_back(lineX(k.cols / 2) + 0.1 * k.dx, north - f * k.dy);
    p.emplace_back(lineX(k.cols / 3), north - hgt + f * k.dy);
    p.emplace_back(west + f * k.dx, north - f * k.dy);  // a corner
  }
  return p;
}

constexpr Real kHeightTol = 1e-9L;  // metres, on heights of at most 1e5
constexpr double kNormalTol = 1e-12;

// Checks one answer against the reference; returns a description of the first mismatch.
std::string mismatch(const Case& k, const Expected& e, const SurfaceSample& s) {
  if (s.status != e.status) return "status " + std::string(statusName(s.status));
  if (s.normalStatus != e.normalStatus)
    return "normalStatus " + std::string(statusName(s.normalStatus));
  if (e.status != QueryStatus::Ok) {
    return std::isnan(s.height) ? "" : "height is not NaN";
  }
  if (std::abs(static_cast<Real>(s.height) - e.h) > kHeightTol * std::max(Real{1}, std::abs(e.h))) {
    return "height " + std::to_string(s.height);
  }
  if (e.normalStatus != QueryStatus::Ok) return std::isnan(s.normal.x) ? "" : "normal not NaN";
  if (!e.normalKnown) return "";
  const glm::dvec3 n = normalOf(k, e);
  if (glm::length(s.normal - n) > kNormalTol) {
    return "normal (" + std::to_string(s.normal.x) + ", " + std::to_string(s.normal.y) + ", " +
           std::to_string(s.normal.z) + ")";
  }
  return "";
}

Placement plane() {
  return Placement(LocalTangentPlane(Body::marsSphere(), {-2.05, -5.5, 0.0}, 0.0));
}

bool sameBits(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
bool sameBits(const glm::dvec3& a, const glm::dvec3& b) {
  return sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z);
}

// Runs every probe point of case k through the three sources, single and batch, and checks
// each against ref and against the generic path's bits.
template <class Ref>
void checkCase(const Case& k, Interpolation interp, Ref ref, const std::string& name) {
  const Quadratic q;
  const std::vector<float> s = samplesOf(k, q);
  const TopoGrid g(k.rows, k.cols, k.x0, k.y0, k.dx, k.dy, k.nodata);
  const TopoDem mem(g, plane(), std::make_shared<InMemorySamples>(k.rows, k.cols, s));
  const TopoDem blocks(g, plane(), std::make_shared<BlockSource>(k.rows, k.cols, s));
  const TopoDem generic(g, plane(), std::make_shared<SampleOnlySource>(k.rows, k.cols, s));
  const std::vector<glm::dvec2> pts = probePoints(k, 7);
  std::vector<double> xs, ys;
  for (const glm::dvec2& p : pts) {
    xs.push_back(p.x);
    ys.push_back(p.y);
  }
  const std::size_t n = pts.size();
  int checked = 0, failures = 0;
  for (const TopoDem* dem : {&mem, &blocks, &generic}) {
    const char* src = dem == &mem ? "in memory" : dem == &blocks ? "blocks" : "sample by sample";
    std::vector<double> hs(n);
    std::vector<glm::dvec3> ns(n);
    std::vector<QueryStatus> st(n), nst(n);
    dem->surfaces(xs, ys, hs, ns, st, interp, NormalFrame::Grid, nst);
    for (std::size_t i = 0; i < n && failures < 10; ++i) {
      const SurfaceSample one = dem->surface(xs[i], ys[i], interp);
      const SurfaceSample gen = generic.surface(xs[i], ys[i], interp);
      const std::string why = mismatch(k, ref(k, q, xs[i], ys[i]), one);
      const bool batchSame = sameBits(hs[i], one.height) && sameBits(ns[i], one.normal) &&
                             st[i] == one.status && nst[i] == one.normalStatus;
      const bool genericSame = sameBits(one.height, gen.height) &&
                               sameBits(one.normal, gen.normal) && one.status == gen.status &&
                               one.normalStatus == gen.normalStatus;
      // height() does not snap points within a few ulps of a line onto it (a height is
      // continuous there), so it is held to the reference only.
      const Expected e = ref(k, q, xs[i], ys[i]);
      const HeightSample hq = dem->height(xs[i], ys[i], interp);
      const bool heightSame =
          hq.status == e.status &&
          (e.status != QueryStatus::Ok || std::abs(static_cast<Real>(hq.height) - e.h) <=
                                              kHeightTol * std::max(Real{1}, std::abs(e.h)));
      if (!why.empty() || !batchSame || !genericSame || !heightSame) {
        ++failures;
        ADD_FAILURE() << name << ", " << src << ", point " << i << " (" << xs[i] << ", " << ys[i]
                      << "): " << (why.empty() ? "" : why + "; ")
                      << (batchSame ? "" : "batch differs; ")
                      << (genericSame ? "" : "differs from the generic path; ")
                      << (heightSame ? "" : "height() differs from the reference");
      }
      checked += one.normalValid() ? 1 : 0;
    }
  }
  EXPECT_GT(checked, static_cast<int>(n)) << name;  // most points have a normal
}

}  // namespace

TEST(TopoDemNormal, BilinearNormalsAreThePatchGradientEverywhere) {
  // 1 m, a power of two (0.5 m) and spacings whose reciprocals are inexact, with origins
  // far from zero (sample lines then come out of the division a few ulps off).
  const Case cases[] = {
      {23, 17, 0.0, 0.0, 1.0, 1.0, std::nullopt, {}},
      {20, 26, -3.0, 8.0, 0.5, 0.5, std::nullopt, {}},
      {19, 21, 1234.5, -987.25, 0.3, 0.7, std::nullopt, {}},
      {16, 15, 5.0e5, 2.0e5, 3.0, 3.0, std::nullopt, {}},
      {2, 2, 0.0, 0.0, 1.0, 1.0, std::nullopt, {}},  // one cell
  };
  for (std::size_t i = 0; i < std::size(cases); ++i) {
    checkCase(cases[i], Interpolation::Bilinear, bilinearRef, "case " + std::to_string(i));
  }
}

TEST(TopoDemNormal, BilinearNormalsNextToHolesFollowTheFallbackRules) {
  // Isolated holes (NaN and the declared value), inside blocks, on a block's edge and on
  // the grid's border: a cell with a hole of non-zero weight has neither height nor normal;
  // one whose hole has weight zero keeps its height and takes the plane of its other three
  // samples.
  const Case k{24,
               22,
               10.0,
               -4.0,
               2.0,
               2.0,
               -9999.0f,
               {{3, 3, true},
                {6, 9, false},
                {7, 4, true},
                {0, 12, false},
                {23, 0, true},
                {12, 21, false},
                {16, 15, true}}};
  checkCase(k, Interpolation::Bilinear, bilinearRef, "holes");
}

TEST(TopoDemNormal, BicubicAndNearestNormalsAreUnchanged) {
  // Keys' cubic is exact for a quadratic up to the border; nearest takes central
  // differences, one-sided on the edges.
  const Case k{18, 20, -40.0, 30.0, 0.5, 0.5, std::nullopt, {}};
  checkCase(k, Interpolation::Bicubic, bicubicRef, "bicubic");
  checkCase(k, Interpolation::Nearest, nearestRef, "nearest");
}

TEST(TopoDemNormal, BodyFixedNormalsFromTheFastPathEqualTheGenericOnes) {
  const Case k{20, 20, 0.0, 0.0, 1.0, 1.0, -9999.0f, {{5, 5, false}}};
  const Quadratic q;
  const std::vector<float> s = samplesOf(k, q);
  const TopoGrid g(k.rows, k.cols, k.x0, k.y0, k.dx, k.dy, k.nodata);
  const TopoDem mem(g, plane(), std::make_shared<InMemorySamples>(k.rows, k.cols, s));
  const TopoDem generic(g, plane(), std::make_shared<SampleOnlySource>(k.rows, k.cols, s));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-1.0, 20.0), y(-20.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const double px = x(rng), py = y(rng);
    const SurfaceSample a = mem.surface(px, py, Interpolation::Bilinear, NormalFrame::BodyFixed);
    const SurfaceSample b =
        generic.surface(px, py, Interpolation::Bilinear, NormalFrame::BodyFixed);
    ASSERT_EQ(a.status, b.status);
    ASSERT_EQ(a.normalStatus, b.normalStatus);
    ASSERT_TRUE(sameBits(a.height, b.height));
    ASSERT_TRUE(sameBits(a.normal, b.normal)) << px << ", " << py;
    if (a.normalValid()) {
      EXPECT_NEAR(glm::length(a.normal), 1.0, 1e-15);
    }
  }
}
