#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "Kernels.hpp"

#include <glm/geometric.hpp>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>

namespace regolith::topo {
namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kEdgeTol = 1e-9;  // degrees: how close an edge must be to ±90°/360° spans

double meanOfRow(const SampleSource& src, const TopoGrid& g, std::size_t row) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t c = 0; c < g.cols(); ++c) {
    const float s = src.sample(row, c);
    if (!g.isNodata(s)) {
      sum += static_cast<double>(s);
      ++n;
    }
  }
  return n == 0 ? kNan : sum / static_cast<double>(n);
}
}  // namespace

struct TopoPlanet::Located {
  double u = 0.0, v = 0.0;
  int cap = 0;     // +1 north polar cap, −1 south polar cap, 0 none
  double t = 0.0;  // blend towards the pole inside a cap, 0…1
  bool inside = false;
};

// The pole heights of a planet and its copies. Two threads that reach an unknown pole at
// once may both compute its mean (the same number) and store it. Atomics
// rather than a once-flag: topo takes no lock (docs/architecture.md).
struct TopoPlanet::Poles {
  TopoPlanet::RowMean mean;           // empty: the rows read sample by sample
  bool north = false, south = false;  // whether the grid reaches that pole
  std::atomic<double> northHeight{kNan}, southHeight{kNan};
  std::atomic<bool> northKnown{false}, southKnown{false};
};

TopoPlanet::TopoPlanet(TopoGrid grid, Body body, LatitudeType latitudeType,
                       std::shared_ptr<const SampleSource> samples)
    : TopoPlanet(std::move(grid), std::move(body), latitudeType, std::move(samples), RowMean(),
                 false) {}

TopoPlanet::TopoPlanet(TopoGrid grid, Body body, LatitudeType latitudeType,
                       std::shared_ptr<const SampleSource> samples, RowMean rowMean)
    : TopoPlanet(std::move(grid), std::move(body), latitudeType, std::move(samples),
                 std::move(rowMean), true) {}

TopoPlanet::TopoPlanet(TopoGrid grid, Body body, LatitudeType latitudeType,
                       std::shared_ptr<const SampleSource> samples, RowMean rowMean,
                       bool rowMeanGiven)
    : grid_(std::move(grid)),
      body_(std::move(body)),
      latType_(latitudeType),
      samples_(std::move(samples)),
      poles_(std::make_shared<Poles>()) {
  constexpr const char* op = "TopoPlanet()";
  if (!samples_)
    throw InvalidArgument(std::string(op) + ": samples is null, expected a SampleSource");
  if (rowMeanGiven && !rowMean) {
    throw InvalidArgument(std::string(op) + ": rowMean is empty, expected a function");
  }
  if (samples_->rows() != grid_.rows() || samples_->cols() != grid_.cols()) {
    throw InvalidArgument(std::string(op) + ": samples are " + core::number(samples_->rows()) +
                          "x" + core::number(samples_->cols()) + ", expected the grid's " +
                          core::number(grid_.rows()) + "x" + core::number(grid_.cols()));
  }
  const double poleTol = kPoleOverhangPixels * grid_.spacingY();
  if (grid_.north() > 90.0 + poleTol || grid_.south() < -90.0 - poleTol) {
    throw InvalidArgument(std::string(op) + ": grid spans latitudes " +
                          core::number(grid_.south()) + " to " + core::number(grid_.north()) +
                          " deg, expected within [-90, 90]");
  }
  const double span = static_cast<double>(grid_.cols()) * grid_.spacingX();
  if (span > 360.0 + kEdgeTol) {
    throw InvalidArgument(std::string(op) + ": grid spans " + core::number(span) +
                          " deg of longitude, expected at most 360");
  }
  global_ = std::abs(span - 360.0) <= kEdgeTol;
  const double lastLat = grid_.y0() - static_cast<double>(grid_.rows() - 1) * grid_.spacingY();
  northCap_ = grid_.north() >= 90.0 - kEdgeTol && grid_.y0() < 90.0;
  southCap_ = grid_.south() <= -90.0 + kEdgeTol && lastLat > -90.0;
  northPoleV_ = (grid_.y0() - 90.0) / grid_.spacingY();
  southPoleV_ = (grid_.y0() + 90.0) / grid_.spacingY();
  slack_ = grid_.edgeSlack();
  resident_ = samples_->contiguous();
  paged_ = samples_->paged();
  poles_->mean = std::move(rowMean);
  poles_->north = northCap_ || grid_.y0() >= 90.0;
  poles_->south = southCap_ || lastLat <= -90.0;
}

double TopoPlanet::poleHeight(bool north) const {
  Poles& p = *poles_;
  std::atomic<bool>& known = north ? p.northKnown : p.southKnown;
  std::atomic<double>& height = north ? p.northHeight : p.southHeight;
  if (known.load(std::memory_order_acquire)) return height.load(std::memory_order_relaxed);
  if (!(north ? p.north : p.south)) return kNan;
  // May throw (a paged source): then asked again next time.
  const std::size_t row = north ? 0 : grid_.rows() - 1;
  const double mean = p.mean ? p.mean(row) : meanOfRow(*samples_, grid_, row);
  height.store(mean, std::memory_order_relaxed);
  known.store(true, std::memory_order_release);
  return mean;
}

TopoPlanet::Located TopoPlanet::locate(const LatLon& ll) const {
  Located L;
  const double west = grid_.west();
  const double rel = ll.lonDeg - west;
  // A longitude a few ulps west of the west edge (an edge computed another way) is on it,
  // not a turn further east.
  const double lon = (rel >= 0.0 && rel < 360.0) ? ll.lonDeg
                     : (rel < 0.0 && rel >= -slack_.x * grid_.spacingX())
                         ? west
                         : west + wrapLongitude360(rel);
  L.u = (lon - grid_.x0()) / grid_.spacingX();
  // On a sample line to a few ulps is on it (a hole beside it then has zero weight).
  L.u = detail::snapToLine(L.u, slack_.x);
  const double cmax = static_cast<double>(grid_.cols()) - 1.0;
  if (!global_) {
    if (L.u > cmax + 0.5 + slack_.x) return L;
    L.u = std::clamp(L.u, 0.0, cmax);
  }
  const double rmax = static_cast<double>(grid_.rows()) - 1.0;
  L.v = (grid_.y0() - ll.latDeg) / grid_.spacingY();
  L.v = detail::snapToLine(L.v, slack_.y);
  if (L.v < 0.0) {
    if (northCap_) {
      L.cap = 1;
      L.t = std::min(L.v / northPoleV_, 1.0);
    } else if (L.v < -0.5 - slack_.y) {
      return L;
    }
    L.v = 0.0;
  } else if (L.v > rmax) {
    if (southCap_) {
      L.cap = -1;
      L.t = std::min((L.v - rmax) / (southPoleV_ - rmax), 1.0);
    } else if (L.v > rmax + 0.5 + slack_.y) {
      return L;
    }
    L.v = rmax;
  }
  L.inside = true;
  return L;
}

namespace {
// Calls fn with the accessor that fits the source: array loads when resident, else loads
// from the calling thread's block (the one holding the cell at fractional (u, v)), asking
// the source only for stencil samples outside it.
template <bool Grad, class Fn>
detail::KernelResult planetAccessor(const TopoGrid& g, const SampleSource& src, bool global,
                                    bool northCap, bool southCap, double u, double v, Fn&& fn) {
  const long rows = static_cast<long>(g.rows()), cols = static_cast<long>(g.cols());
  const bool even = cols % 2 == 0;
  const bool rn = global && even && northCap, rs = global && even && southCap;
  if (const float* d = src.contiguous()) {
    return fn(detail::PlanetAcc<detail::MemFetch>{{d, cols}, rows, cols, global, rn, rs});
  }
  const long r = std::clamp(detail::floorToLong(v), 0L, rows - 1);
  long c = detail::floorToLong(u);
  c = global ? ((c % cols) + cols) % cols : std::clamp(c, 0L, cols - 1);
  const kernel::BlockView& tb =
      detail::blockOf(src, static_cast<std::size_t>(r), static_cast<std::size_t>(c));
  return fn(detail::PlanetAcc<detail::BlockFetch>{{&src, &tb}, rows, cols, global, rn, rs});
}

// Longitudes beyond a turn reduced exactly (wrapLongitude180), so that 1e308 is the meridian
// fmod(1e308, 360) names, not what rounding of lon − west leaves of it.
LatLon reduced(const LatLon& given) noexcept {
  return {given.latDeg,
          std::abs(given.lonDeg) > 360.0 ? wrapLongitude180(given.lonDeg) : given.lonDeg};
}

[[noreturn]] void throwBadLatLon(const LatLon& ll, const char* op) {
  requireFinite(ll.latDeg, op, "latitude");
  requireFinite(ll.lonDeg, op, "longitude");
  throw InvalidArgument(std::string(op) + ": latitude is " + core::number(ll.latDeg) +
                        " deg, expected within [-90, 90]");
}
// One test on the common path (|lat| <= 90 is false for NaN), the messages out of line.
inline void requireLatLon(const LatLon& ll, const char* op) {
  if (!(std::abs(ll.latDeg) <= 90.0 && std::isfinite(ll.lonDeg))) [[unlikely]]
    throwBadLatLon(ll, op);
}
// Checks every point of a batch before anything is written; the message names the index.
void requireLatLons(std::span<const double> lats, std::span<const double> lons, const char* op) {
  for (std::size_t i = 0; i < lats.size(); ++i) {
    try {
      requireLatLon({lats[i], lons[i]}, op);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(std::string(e.what()) + " (point " + core::number(i) + ")");
    }
  }
}
}  // namespace

HeightSample TopoPlanet::height(const LatLon& ll, Interpolation interp) const {
  requireLatLon(ll, "TopoPlanet::height()");
  return heightUnchecked(ll, interp);
}

HeightSample TopoPlanet::heightUnchecked(const LatLon& ll, Interpolation interp) const {
  const SurfaceSample s = surfaceImpl(ll, interp, NormalFrame::Grid, false);
  return {s.height, s.status};
}

SurfaceSample TopoPlanet::surface(const LatLon& ll, Interpolation interp, NormalFrame frame) const {
  requireLatLon(ll, "TopoPlanet::surface()");
  return surfaceImpl(ll, interp, frame, true);
}

bool TopoPlanet::bilinearFast(double u, double v, bool grad, detail::KernelResult& k) const {
  kernel::ResidentBilinear f;
  f.rows = static_cast<long>(grid_.rows());
  f.cols = static_cast<long>(grid_.cols());
  if (f.rows < 2 || f.cols < 2) return false;
  f.data = resident_;
  // Strict bounds: the seam's cell (the last column of a global grid, whose right-hand
  // samples are column 0) and the last row go through the generic kernel.
  f.uMax = static_cast<double>(grid_.cols()) - 1.0;
  f.vMax = static_cast<double>(grid_.rows()) - 1.0;
  f.nodata = detail::nodataOrNan(grid_);
  f.hasNodata = grid_.nodata().has_value() && !std::isnan(*grid_.nodata());
  f.snapU = 2.0 * slack_.x;
  f.snapV = 2.0 * slack_.y;
  kernel::CellValue cv;
  bool ok = false;
  if (resident_ != nullptr) {
    ok = grad ? f.evalResident<true>(u, v, cv) : f.evalResident<false>(u, v, cv);
  } else {
    if (paged_ != nullptr && grad) {
      ok = paged_->bilinearSurface(f, u, v, cv);
    } else if (paged_ != nullptr) {
      cv.h = paged_->bilinearHeight(f, u, v);
      ok = cv.h == cv.h;
    }
  }
  if (!ok) return false;
  k.h = cv.h;
  k.dhdu = cv.dhdu;
  k.dhdv = cv.dhdv;
  k.status = k.gradStatus = QueryStatus::Ok;
  return true;
}

void TopoPlanet::prefetch(const LatLon& given) const noexcept {
  if (!std::isfinite(given.latDeg) || !std::isfinite(given.lonDeg) || std::abs(given.latDeg) > 90.0)
    return;
  const LatLon ll = reduced(given);
  const Located L = locate(ll);
  if (!L.inside || L.cap != 0) return;
  // locate() keeps u and v within the sample centres (u < cols for a global grid).
  const auto r = static_cast<std::size_t>(L.v), c = static_cast<std::size_t>(L.u);
  if (r >= grid_.rows() || c >= grid_.cols()) return;
  if (resident_ != nullptr) {
    const float* p = resident_ + r * grid_.cols() + c;
    __builtin_prefetch(p);
    if (r + 1 < grid_.rows()) __builtin_prefetch(p + grid_.cols());
  } else if (paged_ != nullptr) {
    paged_->prefetchCell(r, c);
  }
}

SurfaceSample TopoPlanet::surfaceImpl(const LatLon& given, Interpolation interp, NormalFrame frame,
                                      bool wantNormal) const {
  const LatLon ll = reduced(given);
  SurfaceSample s;
  const Located L = locate(ll);
  if (!L.inside) return s;
  const double nd = detail::nodataOrNan(grid_);
  // Bilinear between the caps, in a cell that is not the seam's: the DEM's fast path (the
  // resident samples, or the thread's block and the lock-free block table of a paged source)
  // on the cell locate() chose. Same samples, same arithmetic (kernel::bilinearPatch), so the
  // same bits as the generic kernel below, which answers whatever the fast path declines.
  detail::KernelResult k;
  const bool fast =
      interp == Interpolation::Bilinear && L.cap == 0 && bilinearFast(L.u, L.v, wantNormal, k);
  auto eval = [&](auto grad) {
    constexpr bool G = decltype(grad)::value;
    return planetAccessor<G>(
        grid_, *samples_, global_, northCap_, southCap_, L.u, L.v,
        [&](const auto& acc) { return detail::evaluate<G>(interp, acc, L.u, L.v, nd); });
  };
  // Bilinear and bicubic caps are a cubic Hermite blend in latitude (below), which needs the
  // kernel's gradient at the cap's edge even for a height.
  const bool hermiteCap = L.cap != 0 && interp != Interpolation::Nearest;
  const bool analytic = (wantNormal && L.cap == 0) || hermiteCap;
  if (!fast) {
    k = analytic ? planetAccessor<true>(grid_, *samples_, global_, northCap_, southCap_, L.u, L.v,
                                        [&](const auto& acc) {
                                          return detail::evaluateSurface(interp, acc, L.u, L.v, nd);
                                        })
                 : eval(std::false_type{});
  }
  s.status = k.status;
  s.normalStatus = k.status;
  if (k.status != QueryStatus::Ok) return s;
  double h = k.h, dhdu = k.dhdu, dhdv = k.dhdv;
  if (L.cap != 0) {
    const double pole = poleHeight(L.cap > 0);
    if (std::isnan(pole)) {
      s.status = s.normalStatus = QueryStatus::Nodata;
      return s;
    }
    const double t = L.t;
    if (hermiteCap) {
      // h(t) from the edge row (t = 0: the kernel's height H and slope) to the pole (t = 1:
      // the pole's height, slope 0), with v = v_edge + t·D. The cap then joins the grid with
      // a continuous gradient (C1, as bicubic promises; bilinear's cells are C0 between
      // themselves anyway), and the pole's gradient is 0: one normal there, the body's up,
      // whatever the longitude.
      const double rmax = static_cast<double>(grid_.rows()) - 1.0;
      const double d = L.cap > 0 ? northPoleV_ : southPoleV_ - rmax;
      const bool slope = k.gradStatus == QueryStatus::Ok;
      const double m0 = slope ? k.dhdv * d : 0.0, m0u = slope ? k.dhduv * d : 0.0;
      const double t2 = t * t, t3 = t2 * t;
      const double h00 = 2.0 * t3 - 3.0 * t2 + 1.0, h10 = t3 - 2.0 * t2 + t,
                   h01 = 3.0 * t2 - 2.0 * t3;
      const double d00 = 6.0 * t2 - 6.0 * t, d10 = 3.0 * t2 - 4.0 * t + 1.0,
                   d01 = 6.0 * t - 6.0 * t2;
      h = k.h * h00 + m0 * h10 + pole * h01;
      dhdu = k.dhdu * h00 + m0u * h10;
      dhdv = (k.h * d00 + m0 * d10 + pole * d01) / d;
    } else {
      h = (1.0 - t) * h + t * pole;
    }
  }
  s.height = h;
  if (!wantNormal) return s;

  // One sine and cosine of the planetodetic latitude (one sincos call, and on an ellipsoid's
  // planetocentric grid a square root instead of the conversion's arctangent) serve the
  // latitude conversion's derivative, both radii of curvature and the body-fixed frame.
  const Body::SinCos sc = body_.planetodeticSinCos(ll.latDeg, latType_);
  const double sinD = sc.sin, cosD = sc.cos;
  glm::dvec3 enu;
  if (analytic && (cosD > 1e-9 || hermiteCap)) {
    s.normalStatus = k.gradStatus;
    if (k.gradStatus != QueryStatus::Ok) return s;
    // Surface S(φ, λ) = X(φ, λ) + h·U: its normal in ENU is (−h_e, −h_n, 1) with
    // h_e = h_λ / ((N + h) cos φ) and h_n = h_φ / (M + h), φ planetodetic. In a Hermite cap
    // h_λ vanishes as (1 − t)² towards the pole and cos φ as (1 − t): h_e → 0 there.
    const double hLam = dhdu / (grid_.spacingX() * kDeg);
    double hPhi = -dhdv / (grid_.spacingY() * kDeg);
    if (latType_ == LatitudeType::Planetocentric && !body_.isSphere()) {
      const double q = (body_.polarRadius() / body_.equatorialRadius()) *
                       (body_.polarRadius() / body_.equatorialRadius());
      hPhi *= q / (cosD * cosD + q * q * sinD * sinD);  // ∂φc/∂φd
    }
    const Body::Radii radii = body_.radiiOfCurvature(sinD);
    const double he = cosD > 1e-300 ? hLam / ((radii.primeVertical + h) * cosD) : 0.0;
    const double hn = hPhi / (radii.meridian + h);
    enu = glm::normalize(glm::dvec3(-he, -hn, 1.0));
  } else {
    enu = capNormalEnu(ll, interp, h);
    if (std::isnan(enu.x)) {
      // The normal's tangent-plane stencil reaches a hole; the height is still valid.
      s.normalStatus = QueryStatus::Nodata;
      return s;
    }
    s.normalStatus = QueryStatus::Ok;
  }
  s.normal = frame == NormalFrame::Grid ? enu : Body::enuFrameOf(sinD, cosD, ll.lonDeg) * enu;
  return s;
}

glm::dvec3 TopoPlanet::capNormalEnu(const LatLon& ll, Interpolation interp, double) const {
  // Near and at a pole latitude/longitude derivatives degenerate, so the normal comes from
  // four heights a quarter row apart along east and north in the tangent plane, which
  // stay well defined at the pole itself. East/north are taken at the given longitude,
  // except at the pole itself: one point, so one stencil (that of longitude 0) and one
  // body-fixed normal, expressed in the ENU frame of the longitude given.
  const double latD = body_.toPlanetodetic(ll.latDeg, latType_);
  const double stencilLon = std::abs(latD) == 90.0 ? 0.0 : ll.lonDeg;
  const glm::dmat3 enu = body_.enuFrame(latD, stencilLon);
  const glm::dvec3 p0 = body_.toBodyFixed({latD, stencilLon, 0.0});
  const double delta = 0.25 * grid_.spacingY() * kDeg * body_.meridianRadius(latD);
  glm::dvec3 pts[4];
  const glm::dvec3 offs[4] = {delta * enu[0], -delta * enu[0], delta * enu[1], -delta * enu[1]};
  for (int i = 0; i < 4; ++i) {
    const Geodetic g = body_.toGeodetic(p0 + offs[i]);
    const LatLon q{body_.fromPlanetodetic(g.latDeg, latType_), g.lonDeg};
    const SurfaceSample hs = surfaceImpl(q, interp, NormalFrame::Grid, false);
    if (!hs.valid()) return glm::dvec3(kNan);
    pts[i] = body_.toBodyFixed({g.latDeg, g.lonDeg, hs.height});
  }
  const glm::dvec3 n = glm::normalize(glm::cross(pts[0] - pts[1], pts[2] - pts[3]));
  const glm::dmat3 out = stencilLon == ll.lonDeg ? enu : body_.enuFrame(latD, ll.lonDeg);
  return {glm::dot(n, out[0]), glm::dot(n, out[1]), glm::dot(n, out[2])};
}

void TopoPlanet::heights(std::span<const double> latsDeg, std::span<const double> lonsDeg,
                         std::span<double> out, std::span<QueryStatus> status,
                         Interpolation interp) const {
  constexpr const char* op = "TopoPlanet::heights()";
  const std::size_t n = latsDeg.size();
  if (lonsDeg.size() != n || out.size() != n || (!status.empty() && status.size() != n)) {
    throw InvalidArgument(std::string(op) + ": arrays have lengths " + core::number(n) + ", " +
                          core::number(lonsDeg.size()) + ", " + core::number(out.size()) + ", " +
                          core::number(status.size()) + ", expected equal lengths");
  }
  requireLatLons(latsDeg, lonsDeg, op);
  for (std::size_t i = 0; i < n; ++i) {
    const SurfaceSample s = surfaceImpl({latsDeg[i], lonsDeg[i]}, interp, NormalFrame::Grid, false);
    out[i] = s.height;
    if (!status.empty()) status[i] = s.status;
  }
}

void TopoPlanet::surfaces(std::span<const double> latsDeg, std::span<const double> lonsDeg,
                          std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                          std::span<QueryStatus> status, Interpolation interp, NormalFrame frame,
                          std::span<QueryStatus> normalStatus) const {
  constexpr const char* op = "TopoPlanet::surfaces()";
  const std::size_t n = latsDeg.size();
  if (lonsDeg.size() != n || outHeights.size() != n || outNormals.size() != n ||
      (!status.empty() && status.size() != n) ||
      (!normalStatus.empty() && normalStatus.size() != n)) {
    throw InvalidArgument(std::string(op) + ": arrays differ in length, expected " +
                          core::number(n) + " elements each");
  }
  requireLatLons(latsDeg, lonsDeg, op);
  for (std::size_t i = 0; i < n; ++i) {
    const SurfaceSample s = surfaceImpl({latsDeg[i], lonsDeg[i]}, interp, frame, true);
    outHeights[i] = s.height;
    outNormals[i] = s.normal;
    if (!status.empty()) status[i] = s.status;
    if (!normalStatus.empty()) normalStatus[i] = s.normalStatus;
  }
}

Geodetic TopoPlanet::toGeodetic(const LatLon& ll, double h) const {
  requireLatLon(ll, "TopoPlanet::toGeodetic()");
  return {body_.toPlanetodetic(ll.latDeg, latType_), ll.lonDeg, h};
}

glm::dvec3 TopoPlanet::toBodyFixed(const LatLon& ll, double h) const {
  return body_.toBodyFixed(toGeodetic(ll, h));
}

}  // namespace regolith::topo
