#include <regolith/compose/Dataset.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace regolith::compose {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

[[noreturn]] void bad(const std::string& op, const std::string& field, const std::string& value,
                      const char* expected) {
  throw InvalidArgument(
      core::format({.operation = op, .field = field, .value = value, .expected = expected}));
}

double smoothstep(double t) noexcept {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

/// Height range of a pyramid from its coarsest level of at most 2^20 samples (see
/// DatasetOptions::heightRange).
std::array<double, 2> estimateHeightRange(const std::vector<topo::PyramidLevel>& levels,
                                          const std::string& op) {
  std::size_t pick = levels.size() - 1;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    if (levels[i].grid.rows() * levels[i].grid.cols() <= (std::size_t{1} << 20)) {
      pick = i;
      break;
    }
  }
  const auto& lv = levels[pick];
  std::vector<float> buf(lv.grid.rows() * lv.grid.cols());
  lv.source->readWindow(0, 0, lv.grid.rows(), lv.grid.cols(), buf);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (float s : buf) {
    if (lv.grid.isNodata(s) || !std::isfinite(s)) continue;
    lo = std::min(lo, static_cast<double>(s));
    hi = std::max(hi, static_cast<double>(s));
  }
  if (!(lo <= hi)) {
    bad(op, "level " + std::to_string(pick) + " samples", "all missing",
        "some valid heights (or DatasetOptions::heightRange)");
  }
  if (pick == 0) return {lo, hi};
  const double pad = 0.25 * (hi - lo) + 100.0;
  return {lo - pad, hi + pad};
}

}  // namespace

double maskValue(const topo::SampleSource& mask, double u, double v) {
  const auto cols = static_cast<double>(mask.cols()), rows = static_cast<double>(mask.rows());
  u = std::clamp(u, 0.0, cols - 1.0);
  v = std::clamp(v, 0.0, rows - 1.0);
  const auto c0 = static_cast<std::size_t>(u), r0 = static_cast<std::size_t>(v);
  const std::size_t c1 = std::min(c0 + 1, mask.cols() - 1), r1 = std::min(r0 + 1, mask.rows() - 1);
  const double tu = u - static_cast<double>(c0), tv = v - static_cast<double>(r0);
  auto s = [&](std::size_t r, std::size_t c) {
    const auto x = static_cast<double>(mask.sample(r, c));
    return std::isnan(x) ? 0.0 : std::clamp(x, 0.0, 1.0);
  };
  const double top = s(r0, c0) + tu * (s(r0, c1) - s(r0, c0));
  const double bottom = s(r1, c0) + tu * (s(r1, c1) - s(r1, c0));
  return top + tv * (bottom - top);
}

const char* roleName(Role role) noexcept {
  switch (role) {
    case Role::Height: return "height";
    case Role::Albedo: return "albedo";
    case Role::Overlay: return "overlay";
  }
  return "unknown";
}

namespace {
// projectionQuality() given log(n) (n > 1): the compositions of several datasets ask for a
// quality per dataset and query, with n = kQualityN every time.
// α = 1 − max(|log anisotropy|, |log distortion|) / log n, clamped.
double qualityFromLogs(double anisotropy, double distortion, double logN) noexcept {
  const double alpha = 1.0 - std::max(anisotropy, distortion) / logN;
  return std::clamp(alpha, kMinQuality, 1.0);
}
double qualityGivenLogN(double groundX, double groundY, double nominal, double logN) noexcept {
  if (!(groundX > 0.0 && groundY > 0.0 && nominal > 0.0)) return kMinQuality;
  return qualityFromLogs(std::abs(std::log(groundX / groundY)),
                         std::abs(std::log(std::sqrt(groundX * groundY) / nominal)), logN);
}
// A function, not a global: a Dataset may be built during another file's static
// initialisation.
double logQualityN() noexcept {
  static const double v = std::log(kQualityN);
  return v;
}
}  // namespace

double projectionQuality(double groundX, double groundY, double nominal, double n) noexcept {
  if (!(n > 1.0)) return kMinQuality;
  return qualityGivenLogN(groundX, groundY, nominal, std::log(n));
}

std::shared_ptr<const Dataset> Dataset::planet(const topo::GridPyramid& pyramid,
                                               DatasetOptions options) {
  if (!pyramid.planetBody) {
    bad("compose::Dataset::planet()", "pyramid body", "unset",
        "a planet pyramid (latitude/longitude levels on a body)");
  }
  return std::shared_ptr<const Dataset>(new Dataset(pyramid, std::nullopt, std::move(options)));
}

std::shared_ptr<const Dataset> Dataset::dem(const topo::GridPyramid& pyramid,
                                            const topo::Placement& placement,
                                            DatasetOptions options) {
  if (pyramid.planetBody) {
    bad("compose::Dataset::dem()", "pyramid body", pyramid.planetBody->name(),
        "a planar pyramid (its placement puts it on the body)");
  }
  return std::shared_ptr<const Dataset>(new Dataset(pyramid, placement, std::move(options)));
}

Dataset::Dataset(const topo::GridPyramid& pyramid, std::optional<topo::Placement> placement,
                 DatasetOptions options)
    : options_(std::move(options)),
      body_(placement ? placement->body() : *pyramid.planetBody),
      placement_(std::move(placement)) {
  const std::string op = isPlanet() ? "compose::Dataset::planet()" : "compose::Dataset::dem()";
  const std::string who = "dataset '" + options_.name + "' ";
  if (pyramid.levels.empty()) bad(op, who + "pyramid", "empty", "at least one level");
  if (!(std::isfinite(options_.featherMetres) && options_.featherMetres >= 0.0)) {
    bad(op, who + "feather width", core::number(options_.featherMetres) + " m", "finite, >= 0");
  }
  latType_ = isPlanet() ? pyramid.latitudeType : topo::LatitudeType::Planetodetic;
  for (const auto& lv : pyramid.levels) {
    Level l{lv, std::nullopt, std::nullopt};
    if (isPlanet()) {
      // A coarse level of a grid with an odd number of rows reaches past a pole (its last
      // row averages one fine row): it is no valid planet grid, and neither is any coarser
      // one, so the dataset stops at the level below. Level 0 must be valid.
      if (!levels_.empty()) {
        const double slack = topo::kPoleOverhangPixels * lv.grid.spacingY();
        if (lv.grid.north() > 90.0 + slack || lv.grid.south() < -90.0 - slack) break;
      }
      l.planet.emplace(lv.grid, body_, latType_, lv.source);
    } else {
      l.dem.emplace(lv.grid, *placement_, lv.source);
    }
    levels_.push_back(std::move(l));
  }
  const topo::TopoGrid& g0 = levels_.front().level.grid;
  if (options_.mask && (options_.mask->rows() != g0.rows() || options_.mask->cols() != g0.cols())) {
    bad(op, who + "mask size",
        std::to_string(options_.mask->rows()) + " x " + std::to_string(options_.mask->cols()),
        "the size of level 0");
  }
  if (isPlanet()) {
    const auto& p = *levels_.front().planet;
    globalLon_ = p.isGlobalInLongitude();
    northPole_ = p.hasNorthCap();
    southPole_ = p.hasSouthCap();
    frame_.centre = 0.5 * (g0.west() + g0.east());
    frame_.turnLow = frame_.centre - 180.0;
    frame_.turnHigh = frame_.centre + 180.0;
    frame_.west = g0.west();
    frame_.east = g0.east();
    frame_.south = g0.south() - 1e-9;
    frame_.north = g0.north() + 1e-9;
    // planetocentricFromPlanetodetic() is the identity on a sphere.
    frame_.sameLatitude = latType_ == topo::LatitudeType::Planetodetic || body_.isSphere();
    plainPlanet_ = unfeathered();
    planet0_ = levels_.front().planet;
    const double r = (2.0 * body_.equatorialRadius() + body_.polarRadius()) / 3.0;
    groundSpacing_ = r * kDeg * std::sqrt(g0.spacingX() * g0.spacingY());
    // planetQuality()'s constants: the pixel's shape, and the body's radii on the equator
    // (the nominal pixel is the pixel's size there).
    planetAspect_ = g0.spacingX() / g0.spacingY();
    planetEquator_ = body_.equatorialRadius() * body_.meridianRadius(0.0);
    buildFeatherInterior();
  } else {
    groundSpacing_ = std::sqrt(g0.spacingX() * g0.spacingY());
  }
  if (!std::isfinite(options_.heightOffset)) {
    bad(op, who + "height offset", core::number(options_.heightOffset) + " m", "finite");
  }
  if (options_.heightRange) {
    const auto [lo, hi] = *options_.heightRange;
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo <= hi)) {
      bad(op, who + "height range", core::number(lo) + " .. " + core::number(hi) + " m",
          "finite, lowest <= highest");
    }
    heightRange_ = *options_.heightRange;
  } else {
    std::vector<topo::PyramidLevel> lv;
    lv.reserve(levels_.size());
    for (const auto& l : levels_) lv.push_back(l.level);
    heightRange_ = estimateHeightRange(lv, op + ": " + who);
  }
  heightRange_[0] += options_.heightOffset;
  heightRange_[1] += options_.heightOffset;
  buildQualityLattice();
  computeBounds();
}

// Inlined into its callers: called, it returned its point through memory, written field by
// field and read back by soleHeightOrNan() as one 16-byte pair, a store-forwarding stall that
// serialised consecutive queries (soleHeightOrNan() took 2.2× TopoPlanet's own query; 1.0× inlined,
// compose_bench's SoleHeight against PlainPaged).
[[gnu::always_inline]] inline Dataset::GridPoint Dataset::locatePlanet(
    double latDeg, double lonDeg) const noexcept {
  GridPoint p;
  const PlanetFrame& f = frame_;
  // The longitude in the turn nearest the grid's centre, so a grid spanning ±180° or
  // 0…360° finds its points either way.
  // (Kept as given when already in that turn: wrapping would round it by an ulp of 540.)
  p.x = lonDeg >= f.turnLow && lonDeg < f.turnHigh
            ? lonDeg
            : f.centre + topo::wrapLongitude180(lonDeg - f.centre);
  p.y = f.sameLatitude ? latDeg : body_.planetocentricFromPlanetodetic(latDeg);
  p.mapped = true;
  // A non-finite longitude is in no grid (a NaN latitude fails the range test): the grid's
  // unchecked query is never given one.
  const bool inLon = globalLon_ ? std::isfinite(p.x) : (p.x >= f.west && p.x <= f.east);
  p.inside = inLon && p.y >= f.south && p.y <= f.north;
  return p;
}

Dataset::GridPoint Dataset::locate(double latDeg, double lonDeg) const {
  if (isPlanet()) return locatePlanet(latDeg, lonDeg);
  const topo::TopoGrid& g = levels_.front().level.grid;
  GridPoint p;
  try {
    const double h = 0.5 * (heightRange_[0] + heightRange_[1]);
    const glm::dvec3 xyh =
        placement_->fromGeodeticNear({latDeg, lonDeg, h}, 0.5 * (g.west() + g.east()));
    p.x = xyh.x;
    p.y = xyh.y;
    p.mapped = std::isfinite(p.x) && std::isfinite(p.y);
    // A tangent plane's (x, y) are those of the point's foot on the plane, which the point
    // on the far side of the body shares: there it lies about a diameter below the plane.
    // Half the polar radius below is far beyond any DEM's own curvature drop (R·(1 − cos θ)
    // for a DEM reaching θ from its origin: 0.13 R at 30°).
    p.farSide = placement_->localTangentPlane() != nullptr && xyh.z < h - 0.5 * body_.polarRadius();
  } catch (const DomainError&) {
    p.mapped = false;
  }
  p.inside = p.mapped && !p.farSide && g.contains(p.x, p.y);
  return p;
}

bool Dataset::contains(double latDeg, double lonDeg) const { return locate(latDeg, lonDeg).inside; }

// A planet grid's feather interior: the box of grid coordinates at least featherMetres from
// every edge coverageAt() measures, found from the smallest radii of curvature the grid
// reaches (the meridian's on the equator or at a pole, the parallel's at the latitude
// farthest from the equator), widened by a millionth for the rounding. Inside it the
// feather is exactly 1 (smoothstep of at least 1), which coverageAt() then takes without
// its cosine. Left empty where a parallel in the grid has no length (a pole).
void Dataset::buildFeatherInterior() {
  const double f = options_.featherMetres;
  if (!(f > 0.0 && std::isfinite(f))) return;
  const topo::TopoGrid& grid = levels_.front().level.grid;
  const double latNorth = body_.toPlanetodetic(std::clamp(grid.north(), -90.0, 90.0), latType_);
  const double latSouth = body_.toPlanetodetic(std::clamp(grid.south(), -90.0, 90.0), latType_);
  const double farthest = std::max(std::abs(latNorth), std::abs(latSouth));
  const double meridian = std::min(body_.meridianRadius(0.0), body_.meridianRadius(90.0)) * kDeg;
  const double parallel = body_.primeVerticalRadius(farthest) * std::cos(farthest * kDeg) * kDeg;
  constexpr double kWider = 1.0 + 1e-6;
  const double inf = std::numeric_limits<double>::infinity();
  FeatherInterior b;
  b.south = southPole_ ? -inf : grid.south() + kWider * f / meridian;
  b.north = northPole_ ? inf : grid.north() - kWider * f / meridian;
  if (globalLon_) {
    b.west = -inf;
    b.east = inf;
  } else if (parallel > 0.0) {
    b.west = grid.west() + kWider * f / parallel;
    b.east = grid.east() - kWider * f / parallel;
  } else {
    return;  // the parallels shrink to a point: no box
  }
  featherInterior_ = b;
}

double Dataset::coverageAt(const GridPoint& g, double latDeg) const {
  if (!g.inside) return 0.0;
  const topo::TopoGrid& grid = levels_.front().level.grid;
  double c = 1.0;
  const FeatherInterior& box = featherInterior_;
  if (options_.featherMetres > 0.0 &&
      !(g.x >= box.west && g.x <= box.east && g.y >= box.south && g.y <= box.north)) {
    double d = std::numeric_limits<double>::infinity();
    if (isPlanet()) {
      const double lat = latDeg * kDeg;
      const double m = body_.meridianRadius(latDeg) * kDeg;
      const double n = body_.primeVerticalRadius(latDeg) * std::cos(lat) * kDeg;
      if (!northPole_) d = std::min(d, (grid.north() - g.y) * m);
      if (!southPole_) d = std::min(d, (g.y - grid.south()) * m);
      if (!globalLon_) d = std::min(d, std::min(g.x - grid.west(), grid.east() - g.x) * n);
    } else {
      d = std::min({g.x - grid.west(), grid.east() - g.x, g.y - grid.south(), grid.north() - g.y});
    }
    c = smoothstep(d / options_.featherMetres);
  }
  if (options_.mask && c > 0.0) {
    const glm::dvec2 uv = grid.fractionalIndex(g.x, g.y);
    c *= maskValue(*options_.mask, uv.x, uv.y);
  }
  return c;
}

// A pixel of sx by sy degrees measures gx = p·sx and gy = m·sy (radians; p the parallel's
// radius, m the meridian's), and the nominal pixel √(a·sx · m₀·sy) (its size on the
// equator). So gx / gy = (p / m)·(sx / sy) and √(gx·gy) / nominal = √(p·m / (a·m₀)): the
// quality depends on the pixel's shape, not its size, and grids of one body and one pixel
// shape have one quality at a latitude, bit for bit (samePlanetQuality()).
double Dataset::planetQuality(double latDeg) const {
  const double lat = std::clamp(latDeg, -90.0, 90.0);
  const double p = body_.primeVerticalRadius(lat) * std::cos(lat * kDeg);
  const double m = body_.meridianRadius(lat);
  if (!(p > 0.0)) return kMinQuality;  // a pole: the pixel is a sliver
  return qualityFromLogs(std::abs(std::log(p / m * planetAspect_)),
                         0.5 * std::abs(std::log(p * m / planetEquator_)), logQualityN());
}

double Dataset::qualityAt(const GridPoint& g) const {
  const topo::TopoGrid& grid = levels_.front().level.grid;
  if (isPlanet())
    return planetQuality(body_.toPlanetodetic(std::clamp(g.y, -90.0, 90.0), latType_));
  const double n = static_cast<double>(kQualityLattice - 1);
  const double u = std::clamp((g.x - grid.west()) / (grid.east() - grid.west()), 0.0, 1.0) * n;
  const double v = std::clamp((grid.north() - g.y) / (grid.north() - grid.south()), 0.0, 1.0) * n;
  const auto c0 = std::min(static_cast<std::size_t>(u), kQualityLattice - 2);
  const auto r0 = std::min(static_cast<std::size_t>(v), kQualityLattice - 2);
  const double tu = u - static_cast<double>(c0), tv = v - static_cast<double>(r0);
  const double* q = quality_.data() + r0 * kQualityLattice + c0;
  const double top = q[0] + tu * (q[1] - q[0]);
  const double bottom = q[kQualityLattice] + tu * (q[kQualityLattice + 1] - q[kQualityLattice]);
  return top + tv * (bottom - top);
}

std::array<double, 2> Dataset::coverageQuality(double latDeg, double lonDeg) const {
  const GridPoint g = locate(latDeg, lonDeg);
  const double c = coverageAt(g, latDeg);
  return {c, g.inside ? qualityAt(g) : kMinQuality};
}

void Dataset::buildQualityLattice() {
  if (isPlanet()) return;  // planet grids compute theirs exactly (planetQuality())
  const topo::TopoGrid& grid = levels_.front().level.grid;
  quality_.assign(kQualityLattice * kQualityLattice, kMinQuality);
  const double n = static_cast<double>(kQualityLattice - 1);
  for (std::size_t r = 0; r < kQualityLattice; ++r) {
    const double y = grid.north() - (grid.north() - grid.south()) * static_cast<double>(r) / n;
    for (std::size_t c = 0; c < kQualityLattice; ++c) {
      const double x = grid.west() + (grid.east() - grid.west()) * static_cast<double>(c) / n;
      try {
        const glm::dmat3 j = placement_->jacobian(x, y, 0.0);
        const double gx = glm::length(j[0]) * grid.spacingX();
        const double gy = glm::length(j[1]) * grid.spacingY();
        quality_[r * kQualityLattice + c] = qualityGivenLogN(gx, gy, groundSpacing_, logQualityN());
      } catch (const DomainError&) {  // NOLINT(bugprone-empty-catch): no image, lowest quality
      }
    }
  }
}

void Dataset::computeBounds() {
  const double a = body_.equatorialRadius(), b = body_.polarRadius();
  const auto [hlo, hhi] = heightRange_;
  if (isPlanet() && globalLon_) {
    const double lo = levels_.front().level.grid.south(), hi = levels_.front().level.grid.north();
    const double zr = b + std::max(hhi, 0.0);
    const double xr = a + std::max(hhi, 0.0);
    const double zlo = lo <= -90.0 + 1e-9 ? -zr : std::sin(lo * kDeg) * zr - 0.01 * zr;
    const double zhi = hi >= 90.0 - 1e-9 ? zr : std::sin(hi * kDeg) * zr + 0.01 * zr;
    bounds_ = {glm::dvec3(-xr, -xr, std::max(-zr, zlo)), glm::dvec3(xr, xr, std::min(zr, zhi))};
    ellipsoidHeights_ = heightRange_;
    return;
  }
  double eLow = std::numeric_limits<double>::infinity(), eHigh = -eLow;
  constexpr std::size_t kN = 17;
  const topo::TopoGrid& grid = levels_.front().level.grid;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  double step = 0.0;
  std::vector<glm::dvec3> prevRow(kN, glm::dvec3(std::numeric_limits<double>::quiet_NaN()));
  for (std::size_t r = 0; r < kN; ++r) {
    const double y =
        grid.north() - (grid.north() - grid.south()) * static_cast<double>(r) / (kN - 1);
    glm::dvec3 prev(std::numeric_limits<double>::quiet_NaN());
    for (std::size_t c = 0; c < kN; ++c) {
      const double x =
          grid.west() + (grid.east() - grid.west()) * static_cast<double>(c) / (kN - 1);
      glm::dvec3 p0, p1;
      try {
        if (isPlanet()) {
          const double lat = body_.toPlanetodetic(std::clamp(y, -90.0, 90.0), latType_);
          p0 = body_.toBodyFixed({lat, x, hlo});
          p1 = body_.toBodyFixed({lat, x, hhi});
        } else {
          p0 = placement_->toBodyFixed(x, y, hlo);
          p1 = placement_->toBodyFixed(x, y, hhi);
        }
      } catch (const DomainError&) {
        prev = glm::dvec3(std::numeric_limits<double>::quiet_NaN());
        prevRow[c] = prev;
        continue;
      }
      lo = glm::min(lo, glm::min(p0, p1));
      hi = glm::max(hi, glm::max(p0, p1));
      if (isPlanet()) {
        eLow = std::min(eLow, hlo);
        eHigh = std::max(eHigh, hhi);
      } else {
        eLow = std::min(eLow, std::min(body_.toGeodetic(p0).height, body_.toGeodetic(p1).height));
        eHigh = std::max(eHigh, std::max(body_.toGeodetic(p0).height, body_.toGeodetic(p1).height));
      }
      if (std::isfinite(prev.x)) step = std::max(step, glm::length(p1 - prev));
      if (std::isfinite(prevRow[c].x)) step = std::max(step, glm::length(p1 - prevRow[c]));
      prev = p1;
      prevRow[c] = p1;
    }
  }
  // Between lattice points the surface bulges by at most the sagitta of the step on the
  // body (step²/8R), far less than the quarter step added here; a tangent-plane DEM is flat.
  const glm::dvec3 pad(0.25 * step + 1.0);
  bounds_ = {lo - pad, hi + pad};
  ellipsoidHeights_ =
      std::isfinite(eLow) ? std::array<double, 2>{eLow - pad.x, eHigh + pad.x} : heightRange_;
}

std::size_t Dataset::levelFor(double metres) const noexcept {
  std::size_t l = 0;
  while (l + 1 < levels_.size() &&
         groundSpacing_ * std::ldexp(1.0, static_cast<int>(l + 1)) <= metres * (1.0 + 1e-9)) {
    ++l;
  }
  return l;
}

bool Dataset::samePlanetQuality(const Dataset& other) const noexcept {
  if (!isPlanet() || !other.isPlanet()) return false;
  // planetQuality()'s inputs: the radii and the pixel's shape (not its size).
  return body_.equatorialRadius() == other.body_.equatorialRadius() &&
         body_.polarRadius() == other.body_.polarRadius() && planetAspect_ == other.planetAspect_ &&
         planetEquator_ == other.planetEquator_;
}

double Dataset::quality(double latDeg, double lonDeg) const {
  const GridPoint g = locate(latDeg, lonDeg);
  if (!g.inside) return kMinQuality;
  // A planet's quality depends on the planetodetic latitude only: no round trip through the
  // grid's latitude type.
  return isPlanet() ? planetQuality(latDeg) : qualityAt(g);
}

double Dataset::qualityInside(double latDeg, double lonDeg) const {
  return isPlanet() ? planetQuality(latDeg) : qualityAt(locate(latDeg, lonDeg));
}

void Dataset::prefetch(double latDeg, double lonDeg, std::size_t level) const noexcept {
  if (!isPlanet()) return;
  const GridPoint g = locate(latDeg, lonDeg);
  if (g.inside) levels_[std::min(level, levels_.size() - 1)].planet->prefetch({g.y, g.x});
}

Contribution Dataset::evaluate(double latDeg, double lonDeg, std::size_t level, bool wantSlope,
                               bool wantQuality) const {
  Contribution out;
  evaluateInto(latDeg, lonDeg, level, wantSlope, wantQuality, out);
  return out;
}

// A std::optional<double> returned here (stop 41 to 43) had its flag written as a byte and
// read back with the height as one 16-byte pair, a store-forwarding stall on each query (a
// tenth of Composed/1's time in perf): the height alone, NaN for none.
double Dataset::soleHeightOrNan(double latDeg, double lonDeg, std::size_t level, bool full) const {
  constexpr double none = std::numeric_limits<double>::quiet_NaN();
  if (plainPlanet_) {
    // evaluateInto()'s planet path with coverageAt() = 1 inside the grid.
    const GridPoint g = locatePlanet(latDeg, lonDeg);
    if (!g.inside) return none;
    const topo::TopoPlanet& planet =
        level == 0 ? *planet0_ : *levels_[std::min(level, levels_.size() - 1)].planet;
    const topo::HeightSample h = planet.heightUnchecked({g.y, g.x}, topo::Interpolation::Bilinear);
    if (!h.valid()) return none;
    return h.height + options_.heightOffset;
  }
  Contribution c;
  evaluateInto(latDeg, lonDeg, level, false, false, c);
  if (c.status != topo::QueryStatus::Ok || !(full ? c.coverage == 1.0 : c.coverage > 0.0)) {
    return none;
  }
  return c.height;
}

Dataset::CoveredHeight Dataset::coveredHeight(double latDeg, double lonDeg,
                                              std::size_t level) const {
  constexpr CoveredHeight none{std::numeric_limits<double>::quiet_NaN(), 0.0};
  if (isPlanet()) {
    // evaluateInto()'s planet path, the coverage first: it depends on the point alone.
    const GridPoint g = locatePlanet(latDeg, lonDeg);
    if (!g.inside) return none;
    const double c = coverageAt(g, latDeg);
    if (!(c > 0.0)) return none;
    const topo::TopoPlanet& planet =
        level == 0 ? *planet0_ : *levels_[std::min(level, levels_.size() - 1)].planet;
    const topo::HeightSample h = planet.heightUnchecked({g.y, g.x}, topo::Interpolation::Bilinear);
    if (!h.valid()) return none;
    return {h.height + options_.heightOffset, c};
  }
  Contribution c;
  evaluateInto(latDeg, lonDeg, level, false, false, c);
  if (c.status != topo::QueryStatus::Ok || !(c.coverage > 0.0)) return none;
  return {c.height, c.coverage};
}

void Dataset::evaluateInto(double latDeg, double lonDeg, std::size_t level, bool wantSlope,
                           bool wantQuality, Contribution& out) const {
  out = Contribution{};
  const GridPoint g = locate(latDeg, lonDeg);
  if (!g.mapped) {
    out.status = out.normalStatus = topo::QueryStatus::Unmappable;
    return;
  }
  if (!g.inside) return;
  const Level& lv = levels_[std::min(level, levels_.size() - 1)];
  const auto bilinear = topo::Interpolation::Bilinear;
  const auto bodyFixed = topo::NormalFrame::BodyFixed;
  topo::SurfaceSample s;
  if (isPlanet()) {
    const topo::LatLon ll{g.y, g.x};
    if (wantSlope) {
      s = lv.planet->surface(ll, bilinear, bodyFixed);
    } else {
      // The point is checked (evaluate()'s contract), and so is its conversion.
      const topo::HeightSample h = lv.planet->heightUnchecked(ll, bilinear);
      s.height = h.height;
      s.status = h.status;
    }
  } else if (const auto* ltp = placement_->localTangentPlane()) {
    // Heights are along the plane's normal: find the height H on the query point's normal
    // line whose plane coordinates (x, y, h) lie on the DEM (h = DEM(x, y)). The plane's
    // normal and the body's differ by the DEM's extent over the radius, so each step shrinks
    // the error by about that angle times the slope: a few steps reach 1e-6 m.
    // From the middle of the height range: a fixed start, so a point's answer never depends
    // on the queries before it.
    double height = 0.5 * (heightRange_[0] + heightRange_[1]);
    double x = g.x, y = g.y;
    for (int it = 0; it < 12; ++it) {
      const glm::dvec3 p = ltp->forward({latDeg, lonDeg, height});
      x = p.x;
      y = p.y;
      const topo::HeightSample h = lv.dem->height(x, y, bilinear);
      if (!h.valid()) {
        s.status = h.status;
        break;
      }
      const double residual = h.height + options_.heightOffset - p.z;
      height += residual;
      s.status = topo::QueryStatus::Ok;
      if (std::abs(residual) < 1e-6) break;
    }
    if (s.status == topo::QueryStatus::Ok) {
      s.height = height;
      if (wantSlope) {
        const topo::SurfaceSample n = lv.dem->surface(x, y, bilinear, bodyFixed);
        s.normal = n.normal;
        s.normalStatus = n.normalStatus;
      }
    }
  } else {
    if (wantSlope) {
      s = lv.dem->surface(g.x, g.y, bilinear, bodyFixed);
    } else {
      const topo::HeightSample h = lv.dem->height(g.x, g.y, bilinear);
      s.height = h.height;
      s.status = h.status;
    }
  }
  out.status = s.status;
  if (!s.valid()) return;
  // The tangent plane's iteration has applied the offset already.
  out.height = placement_ && placement_->localTangentPlane() != nullptr
                   ? s.height
                   : s.height + options_.heightOffset;
  out.coverage = coverageAt(g, latDeg);
  // quality()'s value: a planet's from the query's own latitude (no round trip through the
  // grid's latitude type).
  if (wantQuality) out.quality = isPlanet() ? planetQuality(latDeg) : qualityAt(g);
  if (wantSlope) {
    out.normalStatus = s.normalStatus;
    if (s.normalValid()) {
      const glm::dmat3 enu = body_.enuFrame(latDeg, lonDeg);
      const double ne = glm::dot(s.normal, enu[0]), nn = glm::dot(s.normal, enu[1]);
      const double nu = glm::dot(s.normal, enu[2]);
      if (nu > 1e-12) {
        out.slope = {-ne / nu, -nn / nu};
      } else {
        out.normalStatus = topo::QueryStatus::Unmappable;  // a vertical face has no slope
      }
    }
  }
}

}  // namespace regolith::compose
