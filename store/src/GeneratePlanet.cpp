// The Mars-like planet generator (Generate.hpp).
//
// Every height is a sum evaluated in a fixed order: the base relief (a function of the
// point's body-fixed unit vector), then the craters that reach the point, band by band
// (largest first), cell by cell in (z-band, longitude-cell) order, crater by crater in each
// cell. Craters are drawn per cell from a hash of (seed, band, cell), so any window can
// find the craters near it without a global list, and a sample's value depends only on its
// own position: windows of any shape, and the point function height(), agree to the bit.
#include <regolith/core/Assert.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/store/Generate.hpp>

#include "GenerateNoise.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace regolith::store {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kRadToDeg = 180.0 / kPi;

// ---- craters -------------------------------------------------------------------------------

constexpr double kMaxDiameterKm = 1200.0;  // band 0: 600–1200 km
constexpr double kEjectaExtent = 2.5;      // ejecta reach this many crater radii
constexpr double kCratersPerCell = 3.0 / 4.0;
constexpr std::size_t kMaxBands = 20;
constexpr std::size_t kMaxOctaves = 24;

/// One crater: centre, size in radians of arc, and profile parameters in metres.
struct Crater {
  glm::dvec3 centre{0.0};
  double latDeg = 0.0, lonDeg = 0.0;
  double radius = 0.0;     // rim radius, radians of arc
  double influence = 0.0;  // kEjectaExtent · radius
  double influenceChord2 = 0.0;
  double depth = 0.0, rim = 0.0;  // m
  double floorFraction = 0.0;     // flat floor radius / rim radius (complex craters)
  double peak = 0.0;              // central peak height, m
  double survival = 0.0;          // uniform in [0, 1): kept on young plains if below a rate
};

/// Height added by a crater at r = distance / radius.
double craterProfile(const Crater& c, double r) noexcept {
  if (r < 1.0) {
    const double g = std::min(1.0, (1.0 - r * r) / (1.0 - c.floorFraction * c.floorFraction));
    double h = c.rim - (c.depth + c.rim) * g;
    if (c.peak > 0.0 && r < 0.2) {
      const double t = 1.0 - 25.0 * r * r;
      h += c.peak * t * t;
    }
    return h;
  }
  if (r >= kEjectaExtent) return 0.0;
  constexpr double kTail = 1.0 / (kEjectaExtent * kEjectaExtent * kEjectaExtent);
  return c.rim * (1.0 / (r * r * r) - kTail) / (1.0 - kTail);
}

/// The (z, longitude) cells of one size band: z = sin(latitude) in nz equal steps and
/// longitude in nlon equal steps, so every cell has the same area (Archimedes).
struct Band {
  std::size_t index = 0;
  std::uint64_t nz = 0, nlon = 0;
  double minDiameterKm = 0.0, maxDiameterKm = 0.0;
  double maxInfluence = 0.0;  // radians
  double lambda = 0.0;        // expected craters per cell
};

Band makeBand(std::size_t k, double radiusKm, double density) {
  Band b;
  b.index = k;
  b.nz = std::uint64_t{2} << k;
  b.nlon = std::uint64_t{4} << k;
  b.maxDiameterKm = kMaxDiameterKm / static_cast<double>(std::uint64_t{1} << k);
  b.minDiameterKm = 0.5 * b.maxDiameterKm;
  b.maxInfluence = kEjectaExtent * 0.5 * b.maxDiameterKm / radiusKm;
  b.lambda = kCratersPerCell * density;
  return b;
}

/// Draws the craters of cell (i, j) of a band.
void cellCraters(const Band& b, std::uint64_t seed, std::uint64_t i, std::uint64_t j,
                 double radiusKm, std::vector<Crater>& out) {
  out.clear();
  gen::Random rng(gen::hashOf(seed, b.index, i, j));
  const std::size_t n = rng.poisson(b.lambda);
  const double dz = 2.0 / static_cast<double>(b.nz);
  const double dlon = 360.0 / static_cast<double>(b.nlon);
  // Cumulative N(>D) ∝ D^−2: inverse transform between the band's limits.
  const double lo2 = 1.0 / (b.minDiameterKm * b.minDiameterKm);
  const double hi2 = 1.0 / (b.maxDiameterKm * b.maxDiameterKm);
  for (std::size_t m = 0; m < n; ++m) {
    Crater c;
    const double z = std::clamp(-1.0 + (static_cast<double>(i) + rng.uniform()) * dz, -1.0, 1.0);
    c.lonDeg = -180.0 + (static_cast<double>(j) + rng.uniform()) * dlon;
    c.latDeg = std::asin(z) * kRadToDeg;
    const double rxy = std::sqrt(std::max(0.0, 1.0 - z * z));
    c.centre = {rxy * std::cos(c.lonDeg * kDegToRad), rxy * std::sin(c.lonDeg * kDegToRad), z};
    const double diameterKm = 1.0 / std::sqrt(lo2 - rng.uniform() * (lo2 - hi2));
    const double degradation = rng.uniform(0.3, 1.0);
    c.survival = rng.uniform();
    c.radius = 0.5 * diameterKm / radiusKm;
    c.influence = kEjectaExtent * c.radius;
    const double chord = 2.0 * std::sin(0.5 * c.influence);
    c.influenceChord2 = chord * chord;
    // Mars: simple craters d/D ≈ 0.2; complex ones d ≈ 0.36·D^0.49 km (Garvin et al. 2003);
    // basins capped at 6 km. Rims a quarter of the depth. Older craters are shallower.
    const double freshDepthKm =
        std::min({0.2 * diameterKm, 0.36 * std::pow(diameterKm, 0.49), 6.0});
    c.depth = 1000.0 * freshDepthKm * degradation;
    c.rim = 0.25 * c.depth;
    if (diameterKm > 7.0) {
      c.floorFraction = std::min(0.6, 0.2 + 0.1 * std::log2(diameterKm / 7.0));
    }
    if (diameterKm > 20.0 && diameterKm < 200.0) c.peak = 0.3 * c.depth;
    out.push_back(c);
  }
}

// ---- lattices ------------------------------------------------------------------------------

/// Rows [r0, r0 + nr) and cols [c0, c0 + nc) of a lat/lon lattice: latitude y0 − r·dy and
/// longitude x0 + c·dx (degrees), always computed from the absolute index so that a sample's
/// position does not depend on the window it is computed in.
struct Lattice {
  double y0 = 0.0, dy = 1.0;
  std::size_t r0 = 0, nr = 0;
  double x0 = 0.0, dx = 1.0;
  std::size_t c0 = 0, nc = 0;
  [[nodiscard]] double lat(std::size_t r) const noexcept {
    return y0 - static_cast<double>(r) * dy;
  }
  [[nodiscard]] double lon(std::size_t c) const noexcept {
    return x0 + static_cast<double>(c) * dx;
  }
};

/// Sines and cosines of a lattice's rows and columns.
struct Trig {
  std::vector<double> sinLat, cosLat, sinLon, cosLon;
  explicit Trig(const Lattice& l) : sinLat(l.nr), cosLat(l.nr), sinLon(l.nc), cosLon(l.nc) {
    for (std::size_t r = 0; r < l.nr; ++r) {
      const double phi = l.lat(l.r0 + r) * kDegToRad;
      sinLat[r] = std::sin(phi);
      cosLat[r] = std::cos(phi);
    }
    for (std::size_t c = 0; c < l.nc; ++c) {
      const double lambda = l.lon(l.c0 + c) * kDegToRad;
      sinLon[c] = std::sin(lambda);
      cosLon[c] = std::cos(lambda);
    }
  }
  [[nodiscard]] glm::dvec3 unit(std::size_t r, std::size_t c) const noexcept {
    return {cosLat[r] * cosLon[c], cosLat[r] * sinLon[c], sinLat[r]};
  }
};

/// Where a set of points lies, for the crater search: planetocentric latitudes latLo…latHi and
/// longitudes lonLo…lonHi (degrees, lonLo ≤ lonHi, possibly beyond ±180°), or every longitude.
struct Extent {
  double latLo = 0.0, latHi = 0.0;
  double lonLo = 0.0, lonHi = 0.0;
  bool allLon = false;
};

Extent extentOf(const Lattice& l) noexcept {
  return {l.lat(l.r0 + l.nr - 1), l.lat(l.r0), l.lon(l.c0), l.lon(l.c0 + l.nc - 1), false};
}

/// Angle between two unit vectors, from their chord (accurate at small angles).
double angleBetween(const glm::dvec3& a, const glm::dvec3& b) noexcept {
  const double chord = glm::length(a - b);
  return 2.0 * std::asin(std::min(1.0, 0.5 * chord));
}

/// A body-fixed unit vector from planetocentric latitude and longitude in degrees.
glm::dvec3 unitOf(double latDeg, double lonDeg) noexcept {
  const double phi = latDeg * kDegToRad, lambda = lonDeg * kDegToRad;
  return {std::cos(phi) * std::cos(lambda), std::cos(phi) * std::sin(lambda), std::sin(phi)};
}

/// A seeded unit vector at a latitude within [latLo, latHi] degrees (uniform in area).
glm::dvec3 randomUnit(gen::Random& rng, double latLoDeg, double latHiDeg) {
  const double z = rng.uniform(std::sin(latLoDeg * kDegToRad), std::sin(latHiDeg * kDegToRad));
  return unitOf(std::asin(z) * kRadToDeg, rng.uniform(-180.0, 180.0));
}

}  // namespace

// ---- the generator ---------------------------------------------------------------------------

struct MarsPlanetGenerator::Impl {
  struct Volcano {
    glm::dvec3 centre{0.0};
    double height = 0.0, radius = 0.0;  // m, radians
  };

  MarsPlanetOptions options;
  GridInfo info;
  double radiusKm = 0.0;
  std::size_t octaves = 1;
  std::vector<Band> bands;
  std::uint64_t noiseSeed = 0, craterSeed = 0, boundarySeed = 0;
  glm::dvec3 dichotomyAxis{0.0, 0.0, 1.0};
  glm::dvec3 tharsis{1.0, 0.0, 0.0};
  std::array<Volcano, 3> volcanoes{};

  explicit Impl(MarsPlanetOptions o);
  [[nodiscard]] double base(const glm::dvec3& u) const noexcept;
  [[nodiscard]] double dichotomy(const glm::dvec3& u) const noexcept;
  [[nodiscard]] bool kept(const Crater& c) const noexcept;
  /// Calls visit(crater) for every kept crater of a band that may reach a point of `e`, in
  /// the fixed order (z-band cell, longitude cell, crater) every window uses.
  template <class Visit>
  void forEachCrater(const Band& band, const Extent& e, Visit&& visit) const;
  /// Heights of a lattice's samples.
  void evaluate(const Lattice& l, double* out) const;
  /// Heights at nr × nc unit vectors (row-major).
  void evaluate(const glm::dvec3* units, std::size_t nr, std::size_t nc, double* out) const;
  /// Runs part(row0, rows) over rows [0, nr) of an nr × nc window, split over the threads of
  /// options.threads on options.write.executor.
  void inParallel(std::size_t nr, std::size_t nc,
                  const std::function<void(std::size_t, std::size_t)>& part) const;
  void evaluateParallel(const Lattice& l, double* out) const;
};

MarsPlanetGenerator::Impl::Impl(MarsPlanetOptions o) : options(std::move(o)) {
  const std::string op = "store::MarsPlanetGenerator(): ";
  if (options.rows < 2) {
    throw InvalidArgument(op + "rows " + std::to_string(options.rows) + ", expected >= 2");
  }
  if (options.rows > (std::size_t{1} << 31U)) {
    throw InvalidArgument(op + "rows " + std::to_string(options.rows) + ", expected <= 2^31");
  }
  if (!(std::isfinite(options.craterDensity) && options.craterDensity >= 0.0)) {
    throw InvalidArgument(op + "crater density " + std::to_string(options.craterDensity) +
                          ", expected a finite number >= 0");
  }
  if (options.gridName.empty()) throw InvalidArgument(op + "empty grid name");

  const topo::Body body =
      options.ellipsoid ? topo::Body::marsEllipsoid() : topo::Body::marsSphere();
  const double spacingDeg = 180.0 / static_cast<double>(options.rows);
  info.name = options.gridName;
  info.kind = GridKind::Planet;
  info.rows = options.rows;
  info.cols = 2 * options.rows;
  info.spacingX = spacingDeg;
  info.spacingY = spacingDeg;
  info.x0 = -180.0 + 0.5 * spacingDeg;
  info.y0 = 90.0 - 0.5 * spacingDeg;
  info.bodyName = body.name();
  info.equatorialRadius = body.equatorialRadius();
  info.polarRadius = body.polarRadius();
  info.latitudeType = topo::LatitudeType::Planetocentric;
  radiusKm = body.equatorialRadius() / 1000.0;

  // Octave o has lattice cells of R / (2·2^o); keep those at least two samples wide.
  const double spacingRad = spacingDeg * kDegToRad;
  octaves = 1;
  while (octaves < kMaxOctaves &&
         2.0 * static_cast<double>(std::uint64_t{1} << octaves) * 2.0 * spacingRad <= 1.0) {
    ++octaves;
  }
  // Crater band k (diameters maxD/2^(k+1) … maxD/2^k) while its smallest crater spans at
  // least three samples.
  const double spacingKm = radiusKm * spacingRad;
  if (options.craterDensity > 0.0) {
    for (std::size_t k = 0; k < kMaxBands; ++k) {
      Band b = makeBand(k, radiusKm, options.craterDensity);
      if (b.minDiameterKm < 3.0 * spacingKm) break;
      bands.push_back(b);
    }
  }

  noiseSeed = gen::hashOf(options.seed, 1);
  craterSeed = gen::hashOf(options.seed, 2);
  boundarySeed = gen::hashOf(options.seed, 3);
  gen::Random rng(gen::hashOf(options.seed, 4));
  // The dichotomy's axis: within 30° of the north pole; Tharsis near the equator; three
  // shields on its flanks.
  dichotomyAxis = randomUnit(rng, 60.0, 90.0);
  tharsis = randomUnit(rng, -15.0, 15.0);
  const std::array<double, 3> heights{18000.0, 12000.0, 10000.0};
  for (std::size_t v = 0; v < volcanoes.size(); ++v) {
    const glm::dvec3 offset = randomUnit(rng, -90.0, 90.0);
    volcanoes[v].centre = glm::normalize(tharsis + 0.25 * offset);
    volcanoes[v].height = heights[v];
    volcanoes[v].radius = rng.uniform(0.06, 0.1);
  }
}

double MarsPlanetGenerator::Impl::dichotomy(const glm::dvec3& u) const noexcept {
  return glm::dot(u, dichotomyAxis) + 0.12 * gen::fbm(u * 2.5, 3, 0.5, boundarySeed);
}

bool MarsPlanetGenerator::Impl::kept(const Crater& c) const noexcept {
  // The lowlands are younger: a third of the craters survive there (in every size band
  // alike, so the size distribution keeps its slope).
  return c.survival < 1.0 / 3.0 || dichotomy(c.centre) < 0.33;
}

double MarsPlanetGenerator::Impl::base(const glm::dvec3& u) const noexcept {
  // Dichotomy: northern lowlands about 5 km below the southern highlands, along a wavy
  // boundary that leaves about a third of the planet low.
  double h = -2500.0 * std::tanh((dichotomy(u) - 0.33) / 0.15);
  // Tharsis: a 4 km bulge about 1000 km in radius; shields with summit calderas.
  const double dt = angleBetween(u, tharsis) / 0.3;
  h += 4000.0 * std::exp(-dt * dt);
  for (const Volcano& v : volcanoes) {
    const double a = angleBetween(u, v.centre) / v.radius;
    if (a < 1.0) {
      h += v.height * std::pow(1.0 - a, 1.5);
      if (a < 0.08) h -= 0.1 * v.height * (1.0 - a / 0.08);
    }
  }
  // Fractal relief: fBm with the lowest octave's cells half a planetary radius wide.
  h += 1800.0 * gen::fbm(u * 2.0, octaves, 0.5, noiseSeed);
  return h;
}

namespace {

constexpr double kMargin = 1e-6;  // radians: candidate filters stay conservative

/// The longitude cells of a band whose craters may reach points of an extent, in ascending order
/// (the sum's order must not depend on the window). A cap of radius ρ around a point at latitude φ
/// spans asin(sin ρ / cos φ) of longitude, unless it holds a pole.
std::vector<std::uint64_t> longitudeCells(const Band& band, const Extent& e) {
  const double rho = band.maxInfluence + kMargin;
  const double absLat = std::max(std::abs(e.latHi), std::abs(e.latLo));
  std::vector<std::uint64_t> js;
  bool allLon = e.allLon || absLat * kDegToRad + rho >= 0.5 * kPi;
  double lonLo = 0.0, lonHi = 0.0;
  if (!allLon) {
    const double spread =
        std::asin(std::min(1.0, std::sin(rho) / std::cos(absLat * kDegToRad))) * kRadToDeg +
        kMargin;
    lonLo = e.lonLo - spread;
    lonHi = e.lonHi + spread;
    allLon = lonHi - lonLo >= 360.0;
  }
  if (allLon) {
    js.resize(band.nlon);
    for (std::uint64_t j = 0; j < band.nlon; ++j) js[j] = j;
    return js;
  }
  const double dlon = 360.0 / static_cast<double>(band.nlon);
  const auto first = static_cast<std::int64_t>(std::floor((lonLo + 180.0) / dlon));
  const auto last = static_cast<std::int64_t>(std::floor((lonHi + 180.0) / dlon));
  const auto n = static_cast<std::int64_t>(band.nlon);
  for (std::int64_t j = first; j <= last; ++j) {
    js.push_back(static_cast<std::uint64_t>(((j % n) + n) % n));
  }
  std::sort(js.begin(), js.end());
  js.erase(std::unique(js.begin(), js.end()), js.end());
  return js;
}

/// The z-band cells [first, last] of a band whose craters may reach points of an extent.
std::pair<std::uint64_t, std::uint64_t> latitudeCells(const Band& band, const Extent& e) {
  const double rhoDeg = (band.maxInfluence + kMargin) * kRadToDeg;
  const double latLo = std::max(-90.0, e.latLo - rhoDeg);
  const double latHi = std::min(90.0, e.latHi + rhoDeg);
  const double dz = 2.0 / static_cast<double>(band.nz);
  const auto zCell = [&](double latDeg) {
    const double f = std::floor((std::sin(latDeg * kDegToRad) + 1.0) / dz);
    return static_cast<std::uint64_t>(std::clamp(f, 0.0, static_cast<double>(band.nz - 1)));
  };
  return {zCell(latLo), zCell(latHi)};
}

/// Adds one crater's profile to the lattice samples it reaches. Row and column ranges are
/// conservative pre-filters; the chord test decides, the same way for every window.
void splat(const Crater& c, const Lattice& l, const Trig& t, double* out) {
  const double reachDeg = (c.influence + kMargin) * kRadToDeg;
  // Rows whose latitude lies within the crater's reach.
  const double rFirst = std::ceil((l.y0 - (c.latDeg + reachDeg)) / l.dy);
  const double rLast = std::floor((l.y0 - (c.latDeg - reachDeg)) / l.dy);
  const double lo = std::max(rFirst, static_cast<double>(l.r0));
  const double hi = std::min(rLast, static_cast<double>(l.r0 + l.nr - 1));
  if (lo > hi) return;
  const double sinC = std::sin(c.latDeg * kDegToRad), cosC = std::cos(c.latDeg * kDegToRad);
  const double cosReach = std::cos(c.influence + kMargin);
  for (auto r = static_cast<std::size_t>(lo); r <= static_cast<std::size_t>(hi); ++r) {
    const std::size_t rr = r - l.r0;
    // Longitude half-width of the cap on this row.
    const double denom = t.cosLat[rr] * cosC;
    double halfDeg = 180.0;
    if (denom > 1e-12) {
      const double q = (cosReach - t.sinLat[rr] * sinC) / denom;
      if (q > 1.0 + 1e-9) continue;
      if (q > -1.0) halfDeg = std::acos(std::min(1.0, q)) * kRadToDeg + kMargin * kRadToDeg;
    }
    const auto visit = [&](std::size_t cc) {
      const glm::dvec3 d = t.unit(rr, cc) - c.centre;
      const double chord2 = glm::dot(d, d);
      if (chord2 >= c.influenceChord2) return;
      const double angle = 2.0 * std::asin(std::min(1.0, 0.5 * std::sqrt(chord2)));
      out[rr * l.nc + cc] += craterProfile(c, angle / c.radius);
    };
    if (halfDeg >= 180.0) {
      for (std::size_t cc = 0; cc < l.nc; ++cc) visit(cc);
      continue;
    }
    for (const double shift : {-360.0, 0.0, 360.0}) {
      const double cFirst = std::ceil((c.lonDeg - halfDeg + shift - l.x0) / l.dx);
      const double cLast = std::floor((c.lonDeg + halfDeg + shift - l.x0) / l.dx);
      const double a = std::max(cFirst, static_cast<double>(l.c0));
      const double b = std::min(cLast, static_cast<double>(l.c0 + l.nc - 1));
      for (double cd = a; cd <= b; cd += 1.0) visit(static_cast<std::size_t>(cd) - l.c0);
    }
  }
}

/// The extent of a set of unit vectors: their latitude range, and the shortest longitude
/// interval that holds them all (every longitude if a point is at a pole or they span 180°
/// or more).
Extent extentOf(std::span<const glm::dvec3> units) noexcept {
  Extent e{90.0, -90.0, 0.0, 0.0, false};
  const double refLon = std::atan2(units[0].y, units[0].x) * kRadToDeg;
  double lo = 0.0, hi = 0.0;
  for (const glm::dvec3& u : units) {
    const double lat = std::asin(std::clamp(u.z, -1.0, 1.0)) * kRadToDeg;
    e.latLo = std::min(e.latLo, lat);
    e.latHi = std::max(e.latHi, lat);
    if (std::hypot(u.x, u.y) < 1e-12) {
      e.allLon = true;
      continue;
    }
    double rel = std::atan2(u.y, u.x) * kRadToDeg - refLon;
    rel -= 360.0 * std::floor((rel + 180.0) / 360.0);
    lo = std::min(lo, rel);
    hi = std::max(hi, rel);
  }
  e.allLon = e.allLon || hi - lo >= 180.0;
  e.lonLo = refLon + lo;
  e.lonHi = refLon + hi;
  return e;
}

/// A block of up to kTileSide × kTileSide points of a grid of unit vectors (by index), with
/// a ball that holds them: centre and radius as a chord (straight-line distance).
struct Tile {
  std::size_t r0 = 0, r1 = 0, c0 = 0, c1 = 0;
  glm::dvec3 centre{0.0};
  double radius = 0.0;
};
constexpr std::size_t kTileSide = 16;

std::vector<Tile> tilesOf(const glm::dvec3* units, std::size_t nr, std::size_t nc) {
  std::vector<Tile> tiles;
  for (std::size_t r0 = 0; r0 < nr; r0 += kTileSide) {
    for (std::size_t c0 = 0; c0 < nc; c0 += kTileSide) {
      Tile t{r0, std::min(nr, r0 + kTileSide), c0, std::min(nc, c0 + kTileSide)};
      t.centre = units[((t.r0 + t.r1) / 2) * nc + (t.c0 + t.c1) / 2];
      for (std::size_t r = t.r0; r < t.r1; ++r) {
        for (std::size_t c = t.c0; c < t.c1; ++c) {
          t.radius = std::max(t.radius, glm::length(units[r * nc + c] - t.centre));
        }
      }
      tiles.push_back(t);
    }
  }
  return tiles;
}

/// As splat() above, for a grid of unit vectors: the tiles a crater's reach may meet are
/// pre-filtered by the triangle inequality on chords; the chord test decides, with the same
/// arithmetic as on a lattice, so a point gets the same bits either way.
void splat(const Crater& c, const std::vector<Tile>& tiles, const glm::dvec3* units, std::size_t nc,
           double* out) {
  const double reach = std::sqrt(c.influenceChord2) + 1e-9;
  for (const Tile& t : tiles) {
    if (glm::length(t.centre - c.centre) >= reach + t.radius) continue;
    for (std::size_t r = t.r0; r < t.r1; ++r) {
      for (std::size_t cc = t.c0; cc < t.c1; ++cc) {
        const glm::dvec3 d = units[r * nc + cc] - c.centre;
        const double chord2 = glm::dot(d, d);
        if (chord2 >= c.influenceChord2) continue;
        const double angle = 2.0 * std::asin(std::min(1.0, 0.5 * std::sqrt(chord2)));
        out[r * nc + cc] += craterProfile(c, angle / c.radius);
      }
    }
  }
}

}  // namespace

template <class Visit>
void MarsPlanetGenerator::Impl::forEachCrater(const Band& band, const Extent& e,
                                              Visit&& visit) const {
  const auto [iLo, iHi] = latitudeCells(band, e);
  const std::vector<std::uint64_t> js = longitudeCells(band, e);
  std::vector<Crater> craters;
  for (std::uint64_t i = iLo; i <= iHi; ++i) {
    for (const std::uint64_t j : js) {
      cellCraters(band, craterSeed, i, j, radiusKm, craters);
      for (const Crater& c : craters) {
        if (kept(c)) visit(c);
      }
    }
  }
}

void MarsPlanetGenerator::Impl::evaluate(const Lattice& l, double* out) const {
  const Trig t(l);
  for (std::size_t r = 0; r < l.nr; ++r) {
    for (std::size_t c = 0; c < l.nc; ++c) out[r * l.nc + c] = base(t.unit(r, c));
  }
  const Extent e = extentOf(l);
  for (const Band& b : bands) {
    forEachCrater(b, e, [&](const Crater& c) { splat(c, l, t, out); });
  }
}

void MarsPlanetGenerator::Impl::evaluate(const glm::dvec3* units, std::size_t nr, std::size_t nc,
                                         double* out) const {
  const std::size_t n = nr * nc;
  for (std::size_t i = 0; i < n; ++i) out[i] = base(units[i]);
  if (bands.empty() || n == 0) return;
  const Extent e = extentOf(std::span(units, n));
  const std::vector<Tile> tiles = tilesOf(units, nr, nc);
  for (const Band& b : bands) {
    forEachCrater(b, e, [&](const Crater& c) { splat(c, tiles, units, nc, out); });
  }
}

void MarsPlanetGenerator::Impl::inParallel(
    std::size_t nr, std::size_t nc,
    const std::function<void(std::size_t, std::size_t)>& part) const {
  core::Executor* executor = options.write.executor;
  std::size_t threads = options.threads != 0  ? options.threads
                        : executor != nullptr ? executor->concurrency() + 1
                                              : core::availableCores();
  threads = std::clamp<std::size_t>(threads, 1, 64);
  threads = std::min(threads, std::max<std::size_t>(1, nr * nc / 4096));
  threads = std::min(threads, nr);
  if (threads <= 1) {
    part(0, nr);
    return;
  }
  const std::size_t per = (nr + threads - 1) / threads;
  const std::size_t parts = (nr + per - 1) / per;
  core::parallelFor(
      executor, parts, [&](std::size_t k) { part(k * per, std::min(per, nr - k * per)); },
      static_cast<unsigned>(threads));
}

void MarsPlanetGenerator::Impl::evaluateParallel(const Lattice& l, double* out) const {
  inParallel(l.nr, l.nc, [&](std::size_t r0, std::size_t nr) {
    Lattice p = l;
    p.r0 = l.r0 + r0;
    p.nr = nr;
    evaluate(p, out + r0 * l.nc);
  });
}

namespace {

/// The samples of a planet, computed window by window.
class PlanetSamples final : public topo::SampleSource {
 public:
  using Evaluate =
      std::function<void(std::size_t, std::size_t, std::size_t, std::size_t, std::span<float>)>;
  PlanetSamples(std::size_t rows, std::size_t cols, Evaluate evaluate)
      : rows_(rows), cols_(cols), evaluate_(std::move(evaluate)) {}
  [[nodiscard]] std::size_t rows() const noexcept override { return rows_; }
  [[nodiscard]] std::size_t cols() const noexcept override { return cols_; }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override {
    float v = 0.0F;
    evaluate_(row, col, 1, 1, std::span(&v, 1));
    return v;
  }
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override {
    evaluate_(row0, col0, nrows, ncols, out);
  }

 private:
  std::size_t rows_, cols_;
  Evaluate evaluate_;
};

}  // namespace

MarsPlanetGenerator::MarsPlanetGenerator(MarsPlanetOptions options)
    : impl_(std::make_shared<const Impl>(std::move(options))) {}

const MarsPlanetOptions& MarsPlanetGenerator::options() const noexcept { return impl_->options; }
GridInfo MarsPlanetGenerator::gridInfo() const { return impl_->info; }
std::size_t MarsPlanetGenerator::octaves() const noexcept { return impl_->octaves; }
std::size_t MarsPlanetGenerator::craterBands() const noexcept { return impl_->bands.size(); }

std::vector<GeneratedCrater> MarsPlanetGenerator::craters() const {
  std::vector<GeneratedCrater> all;
  std::vector<Crater> cell;
  for (const Band& b : impl_->bands) {
    for (std::uint64_t i = 0; i < b.nz; ++i) {
      for (std::uint64_t j = 0; j < b.nlon; ++j) {
        cellCraters(b, impl_->craterSeed, i, j, impl_->radiusKm, cell);
        for (const Crater& c : cell) {
          if (!impl_->kept(c)) continue;
          all.push_back(
              {b.index, c.latDeg, c.lonDeg, 2.0 * c.radius * impl_->radiusKm, c.depth, c.rim});
        }
      }
    }
  }
  return all;
}

double MarsPlanetGenerator::height(double latDeg, double lonDeg) const {
  if (!(std::isfinite(latDeg) && std::isfinite(lonDeg) && std::abs(latDeg) <= 90.0)) {
    throw InvalidArgument("store::MarsPlanetGenerator::height(): latitude " +
                          std::to_string(latDeg) + ", longitude " + std::to_string(lonDeg) +
                          ", expected finite values with |latitude| <= 90");
  }
  // Longitude into [−180, 180): unchanged for every sample centre of the grid.
  const double lon = lonDeg - 360.0 * std::floor((lonDeg + 180.0) / 360.0);
  Lattice l;
  l.y0 = latDeg;
  l.nr = 1;
  l.x0 = lon;
  l.nc = 1;
  double h = 0.0;
  impl_->evaluate(l, &h);
  return h;
}

void MarsPlanetGenerator::heightsAt(std::span<const glm::dvec3> units, std::size_t cols,
                                    std::span<double> out) const {
  REGOLITH_ASSERT(cols > 0 && units.size() % cols == 0 && out.size() == units.size(),
                  "heightsAt(): units must be rows x cols, out as many");
  const std::size_t rows = units.size() / cols;
  impl_->inParallel(rows, cols, [&](std::size_t r0, std::size_t nr) {
    impl_->evaluate(units.data() + r0 * cols, nr, cols, out.data() + r0 * cols);
  });
}

std::shared_ptr<const topo::SampleSource> MarsPlanetGenerator::samples() const {
  const std::shared_ptr<const Impl> impl = impl_;
  return std::make_shared<PlanetSamples>(impl->info.rows, impl->info.cols,
                                         [impl](std::size_t row0, std::size_t col0, std::size_t nr,
                                                std::size_t nc, std::span<float> out) {
                                           Lattice l;
                                           l.y0 = impl->info.y0;
                                           l.dy = impl->info.spacingY;
                                           l.r0 = row0;
                                           l.nr = nr;
                                           l.x0 = impl->info.x0;
                                           l.dx = impl->info.spacingX;
                                           l.c0 = col0;
                                           l.nc = nc;
                                           std::vector<double> heights(nr * nc);
                                           impl->evaluateParallel(l, heights.data());
                                           for (std::size_t i = 0; i < heights.size(); ++i)
                                             out[i] = static_cast<float>(heights[i]);
                                         });
}

void MarsPlanetGenerator::write(const std::filesystem::path& path) const {
  const GridSource grid{gridInfo(), samples()};
  writeStore(path, std::span(&grid, 1), impl_->options.write);
}

}  // namespace regolith::store
