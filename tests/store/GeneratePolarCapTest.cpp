// PolarCapGenerator: the store it writes, read back with Store (not through the generator),
// against PROJ's polar stereographic positions and the planet's point function at the cap's
// resolution; agreement with a coarse planet within the detail it omits (an analytic bound);
// the layered deposits; determinism; errors.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>

#include "support/ProjOracle.hpp"
#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;
using Pole = PolarCapOptions::Pole;
using test::Proj;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

fs::path scratch(const std::string& name) { return test::scratchFile("gencap", name); }

/// A 91 × 91 cap at 20 km (|lat| ≥ 75°), without deposits unless asked.
PolarCapOptions smallCap(Pole pole = Pole::North, std::uint64_t seed = 7) {
  PolarCapOptions o;
  o.pole = pole;
  o.spacing = 20000.0;
  o.planet.seed = seed;
  o.troughDepth = 0.0;
  o.threads = 1;
  o.write.patchRows = 32;
  o.write.patchCols = 32;
  return o;
}

topo::Body bodyOf(bool ellipsoid) {
  return ellipsoid ? topo::Body::marsEllipsoid() : topo::Body::marsSphere();
}

/// The planet the cap documents: rows = ⌈π·a / spacing⌉, the cap's seed, body and craters.
MarsPlanetGenerator planetAtCapResolution(const PolarCapOptions& cap) {
  MarsPlanetOptions o;
  o.rows = static_cast<std::size_t>(
      std::ceil(kPi * bodyOf(cap.planet.ellipsoid).equatorialRadius() / cap.spacing));
  o.seed = cap.planet.seed;
  o.ellipsoid = cap.planet.ellipsoid;
  o.craterDensity = cap.planet.craterDensity;
  o.threads = 1;
  return MarsPlanetGenerator(o);
}

/// Planetocentric latitude of a planetodetic one on an ellipsoid (a, b), written out here.
double planetocentric(double latDeg, double a, double b) {
  if (std::abs(latDeg) == 90.0) return latDeg;
  return std::atan(b * b / (a * a) * std::tan(latDeg * kDeg)) / kDeg;
}

glm::dvec3 unitOf(double latDeg, double lonDeg) {
  return {std::cos(latDeg * kDeg) * std::cos(lonDeg * kDeg),
          std::cos(latDeg * kDeg) * std::sin(lonDeg * kDeg), std::sin(latDeg * kDeg)};
}

/// The grid point of sample (row, col), from the stored attributes.
glm::dvec2 pointOf(const GridInfo& info, std::size_t row, std::size_t col) {
  return {info.x0 + static_cast<double>(col) * info.spacingX,
          info.y0 - static_cast<double>(row) * info.spacingY};
}

/// Planetocentric latitude and longitude in [−180, 180) under a DEM's grid point, through
/// the stored placement.
std::array<double, 2> latLonUnder(const topo::Placement& p, const glm::dvec2& xy) {
  const topo::Geodetic g = p.toGeodetic(xy.x, xy.y, 0.0);
  const double lon = g.lonDeg - 360.0 * std::floor((g.lonDeg + 180.0) / 360.0);
  return {p.body().planetocentricFromPlanetodetic(g.latDeg), lon};
}

bool bitwiseEqual(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(GeneratePolarCap, StoredPlacementRoundTrips) {
  for (const Pole pole : {Pole::North, Pole::South}) {
    for (const bool ellipsoid : {false, true}) {
      PolarCapOptions o = smallCap(pole);
      o.planet.ellipsoid = ellipsoid;
      const fs::path path = scratch("roundtrip.h5");
      PolarCapGenerator(o).write(path);
      const Store s = Store::open(path);
      const std::string name = pole == Pole::North ? "north_cap" : "south_cap";
      ASSERT_TRUE(s.hasGrid(name));
      const GridInfo& info = s.grid(name);
      const topo::Body body = bodyOf(ellipsoid);
      EXPECT_EQ(info.kind, GridKind::Dem);
      EXPECT_EQ(info.placement.kind, PlacementInfo::Kind::PolarStereographic);
      EXPECT_EQ(info.placement.pole, pole == Pole::North ? 1 : -1);
      ASSERT_TRUE(info.placement.scaleFactor.has_value());
      EXPECT_EQ(*info.placement.scaleFactor, 1.0);
      EXPECT_FALSE(info.placement.latTrueScaleDeg.has_value());
      EXPECT_EQ(info.placement.lonCentreDeg, 0.0);
      EXPECT_EQ(info.placement.falseEasting, 0.0);
      EXPECT_EQ(info.placement.falseNorthing, 0.0);
      EXPECT_EQ(info.equatorialRadius, body.equatorialRadius());
      EXPECT_EQ(info.polarRadius, body.polarRadius());
      EXPECT_EQ(info.spacingX, 20000.0);
      EXPECT_EQ(info.spacingY, 20000.0);
      EXPECT_EQ(info.rows, info.cols);
      EXPECT_EQ(info.x0, -info.y0);
      EXPECT_EQ(info.x0, -0.5 * static_cast<double>(info.cols - 1) * info.spacingX);

      // The square holds the circle |lat| = 75° (PROJ: the middle of each edge is at or
      // below 75°), and is the smallest that does at this spacing (one spacing inwards is
      // above 75°).
      const Proj ps("+proj=stere +lat_0=" + std::string(pole == Pole::North ? "90" : "-90") +
                    " +lon_0=0 +k=1 +x_0=0 +y_0=0" + test::projEllipsoid(body));
      ASSERT_TRUE(ps.ok()) << ps.error();
      const double edge = info.y0;
      for (const double inset : {0.0, info.spacingY}) {
        const glm::dvec3 ll = ps.trans(PJ_INV, 0.0, edge - inset);
        const double latc =
            planetocentric(proj_todeg(ll.y), body.equatorialRadius(), body.polarRadius());
        if (inset == 0.0) {
          EXPECT_LE(std::abs(latc), 75.0 + 1e-9);
        } else {
          EXPECT_GT(std::abs(latc), 75.0);
        }
      }
    }
  }
}

TEST(GeneratePolarCap, SamplesSitWherePROJPutsThemAndHoldThePlanetThere) {
  // PROJ's inverse polar stereographic gives each sample's latitude and longitude; the stored
  // height there is the planet's at the cap's resolution (to the float rounding).
  for (const Pole pole : {Pole::North, Pole::South}) {
    for (const bool ellipsoid : {false, true}) {
      PolarCapOptions o = smallCap(pole, 11);
      o.planet.ellipsoid = ellipsoid;
      const fs::path path = scratch("proj.h5");
      PolarCapGenerator(o).write(path);
      const Store s = Store::open(path);
      const GridInfo info = s.grid(pole == Pole::North ? "north_cap" : "south_cap");
      const std::vector<float> v = test::readLevel0(path, info.name);
      const topo::Body body = bodyOf(ellipsoid);
      const Proj ps("+proj=stere +lat_0=" + std::string(pole == Pole::North ? "90" : "-90") +
                    " +lon_0=0 +k=1 +x_0=0 +y_0=0" + test::projEllipsoid(body));
      ASSERT_TRUE(ps.ok()) << ps.error();
      const topo::Placement placement = placementOf(info);
      const MarsPlanetGenerator planet = planetAtCapResolution(o);
      const std::size_t n = info.rows, mid = n / 2;
      const std::array<std::array<std::size_t, 2>, 9> samples{{{0, 0},
                                                               {0, n - 1},
                                                               {n - 1, 0},
                                                               {n - 1, n - 1},
                                                               {mid, mid},
                                                               {0, mid},
                                                               {mid, 3},
                                                               {17, 62},
                                                               {80, 9}}};
      for (const auto& [row, col] : samples) {
        const glm::dvec2 xy = pointOf(info, row, col);
        const glm::dvec3 ll = ps.trans(PJ_INV, xy.x, xy.y);
        ASSERT_EQ(ps.lastError(), 0);
        const double latDet = proj_todeg(ll.y), lon = proj_todeg(ll.x);
        // The stored placement agrees with PROJ.
        const topo::Geodetic g = placement.toGeodetic(xy.x, xy.y, 0.0);
        EXPECT_NEAR(g.latDeg, latDet, 1e-9) << row << ", " << col;
        if (std::abs(latDet) < 89.999) {
          EXPECT_NEAR(std::remainder(g.lonDeg - lon, 360.0), 0.0, 1e-9) << row << ", " << col;
        }
        const double latc = planetocentric(latDet, body.equatorialRadius(), body.polarRadius());
        const double expected = planet.height(latc, lon);
        const float got = v[row * n + col];
        EXPECT_NEAR(got, expected, 1e-3 + 2.0 * std::abs(expected) * 0x1.0p-24)
            << "sample " << row << ", " << col << (ellipsoid ? " ellipsoid" : " sphere");
      }
    }
  }
}

TEST(GeneratePolarCap, EverySampleIsThePlanetAtTheCapResolution) {
  // Without deposits, every stored sample is the planet's point function at the cap's
  // resolution under that sample, to the bit (after the float cast).
  const PolarCapOptions o = smallCap(Pole::South, 3);
  const PolarCapGenerator cap(o);
  const fs::path path = scratch("planet.h5");
  cap.write(path);
  const Store s = Store::open(path);
  const GridInfo info = s.grid("south_cap");
  const std::vector<float> v = test::readLevel0(path, "south_cap");
  const topo::Placement placement = placementOf(info);
  const MarsPlanetGenerator planet = planetAtCapResolution(o);
  EXPECT_EQ(cap.planet().options().rows, planet.options().rows);
  EXPECT_GT(planet.octaves(), 0U);
  std::size_t differ = 0;
  for (std::size_t r = 0; r < info.rows; ++r) {
    for (std::size_t c = 0; c < info.cols; ++c) {
      const auto [lat, lon] = latLonUnder(placement, pointOf(info, r, c));
      differ += v[r * info.cols + c] == static_cast<float>(planet.height(lat, lon)) ? 0U : 1U;
    }
  }
  EXPECT_EQ(differ, 0U);
  ASSERT_TRUE(info.statistics.has_value());
  EXPECT_EQ(info.statistics->validSamples, v.size());
  EXPECT_EQ(info.statistics->min, static_cast<double>(*std::min_element(v.begin(), v.end())));
  EXPECT_EQ(info.statistics->max, static_cast<double>(*std::max_element(v.begin(), v.end())));
}

TEST(GeneratePolarCap, AgreesWithACoarsePlanetWithinTheDetailItOmits) {
  // cap − coarse = the fBm octaves and crater bands the coarse grid leaves out. Bound:
  // gradient noise is a convex combination of corner terms g·f with g two ±1 components and
  // |f_i| ≤ 1, so |noise| ≤ 2 and the octaves o ≥ K add at most 1800·2·Σ 0.5^o; a crater of
  // an omitted band adds at most depth + central peak (≤ 0.3·depth) + rim, and only within
  // its ejecta (2.5 radii).
  const PolarCapOptions o = smallCap(Pole::North, 5);
  const PolarCapGenerator cap(o);
  MarsPlanetOptions co;
  co.rows = 90;  // 2°, about 119 km
  co.seed = 5;
  co.threads = 1;
  const MarsPlanetGenerator coarse(co);
  const MarsPlanetGenerator& fine = cap.planet();
  ASSERT_LT(coarse.octaves(), fine.octaves());
  ASSERT_LT(coarse.craterBands(), fine.craterBands());
  double octaveBound = 0.0;
  for (std::size_t k = coarse.octaves(); k < fine.octaves(); ++k) {
    octaveBound += 1800.0 * 2.0 * std::pow(0.5, static_cast<double>(k));
  }
  struct Omitted {
    glm::dvec3 centre;
    double reach, bound;
  };
  std::vector<Omitted> omitted;
  const double radiusKm = 3396.19;
  for (const GeneratedCrater& c : fine.craters()) {
    if (c.band < coarse.craterBands() || std::abs(c.latDeg) < 60.0) continue;
    omitted.push_back({unitOf(c.latDeg, c.lonDeg), 2.5 * 0.5 * c.diameterKm / radiusKm * 1.0001,
                       1.3 * c.depth + c.rim});
  }
  ASSERT_FALSE(omitted.empty());

  const fs::path path = scratch("coarse.h5");
  cap.write(path);
  const Store s = Store::open(path);
  const GridInfo info = s.grid("north_cap");
  const std::vector<float> v = test::readLevel0(path, "north_cap");
  const topo::Placement placement = placementOf(info);
  double worst = 0.0, largest = 0.0;  // largest |difference| / bound, largest |difference|
  for (std::size_t r = 0; r < info.rows; ++r) {
    for (std::size_t c = 0; c < info.cols; ++c) {
      const auto [lat, lon] = latLonUnder(placement, pointOf(info, r, c));
      const glm::dvec3 u = unitOf(lat, lon);
      double bound = octaveBound;
      for (const Omitted& m : omitted) {
        if (std::acos(std::clamp(glm::dot(u, m.centre), -1.0, 1.0)) < m.reach) bound += m.bound;
      }
      const double stored = v[r * info.cols + c];
      const double diff = std::abs(stored - coarse.height(lat, lon));
      const double tolerance = bound + std::abs(stored) * 0x1.0p-23;
      ASSERT_LE(diff, tolerance) << "sample " << r << ", " << c;
      worst = std::max(worst, diff / tolerance);
      largest = std::max(largest, diff);
    }
  }
  test::report("cap_minus_coarse_max_m", largest);
  test::report("cap_minus_coarse_max_over_bound", worst);
  // The cap does hold detail the coarse grid lacks.
  EXPECT_GT(largest, 0.1 * octaveBound);
}

TEST(GeneratePolarCap, DepositsAreSpiralTroughsWithinTheirReach) {
  PolarCapOptions flat = smallCap(Pole::North, 9);
  flat.spacing = 10000.0;
  PolarCapOptions troughs = flat;
  troughs.troughDepth = 500.0;
  const PolarCapGenerator a(flat), b(troughs);
  a.write(scratch("flat.h5"));
  b.write(scratch("troughs.h5"));
  const std::vector<float> va = test::readLevel0(scratch("flat.h5"), "north_cap");
  const std::vector<float> vb = test::readLevel0(scratch("troughs.h5"), "north_cap");
  ASSERT_EQ(va.size(), vb.size());
  const GridInfo info = b.gridInfo();
  const topo::Placement placement = placementOf(info);
  EXPECT_DOUBLE_EQ(b.depositReachDeg(), 12.0);  // 0.8 · (90 − 75)
  double deepest = 0.0;
  std::size_t inTroughs = 0, onTheRidges = 0;
  for (std::size_t r = 0; r < info.rows; ++r) {
    for (std::size_t c = 0; c < info.cols; ++c) {
      const auto [lat, lon] = latLonUnder(placement, pointOf(info, r, c));
      const double fromPole = 90.0 - lat;
      const double d =
          static_cast<double>(vb[r * info.cols + c]) - static_cast<double>(va[r * info.cols + c]);
      const double slack = 2.0 * std::abs(static_cast<double>(va[r * info.cols + c])) * 0x1.0p-24;
      if (fromPole >= 12.0 || fromPole <= 1.2) {
        EXPECT_EQ(d, 0.0) << r << ", " << c;  // beyond the reach, and no pinch at the pole
      }
      EXPECT_LE(d, slack);
      EXPECT_GE(d, -500.0 - slack);
      // The generator's own deposit function, at the same unit vector.
      EXPECT_NEAR(d, b.depositHeight(unitOf(lat, lon)), slack + 1e-9);
      deepest = std::min(deepest, d);
      if (fromPole > 4.0 && fromPole < 8.0) (d < -250.0 ? inTroughs : onTheRidges) += 1;
    }
  }
  EXPECT_LT(deepest, -450.0);
  // Troughs are narrow: well under half of the full-strength ring lies deeper than half the
  // depth, and some does.
  EXPECT_GT(inTroughs, 0U);
  EXPECT_GT(onTheRidges, 2 * inTroughs);
  // A spiral, not rings: along one circle around the pole the depth goes up and down
  // kTroughArms times per turn.
  const double colat = 6.0 * kDeg;
  int crossings = 0;
  bool below = b.depositHeight(unitOf(90.0 - 6.0, -180.0)) < -100.0;
  for (int k = 1; k <= 3600; ++k) {
    const double lon = -180.0 + 0.1 * k;
    const bool now =
        b.depositHeight({std::sin(colat) * std::cos(lon * kDeg),
                         std::sin(colat) * std::sin(lon * kDeg), std::cos(colat)}) < -250.0;
    crossings += now != below ? 1 : 0;
    below = now;
  }
  EXPECT_GE(crossings, 2 * PolarCapGenerator::kTroughArms);
}

TEST(GeneratePolarCap, SameSeedIsBitIdenticalWhateverThePatchesAndThreads) {
  PolarCapOptions a = smallCap(Pole::North, 21);
  a.troughDepth = 300.0;
  PolarCapOptions b = a;
  b.write.patchRows = 48;
  b.write.patchCols = 20;
  b.threads = 3;
  PolarCapOptions c = a;
  c.planet.seed = 22;
  PolarCapGenerator(a).write(scratch("a.h5"));
  PolarCapGenerator(b).write(scratch("b.h5"));
  PolarCapGenerator(c).write(scratch("c.h5"));
  const std::vector<float> va = test::readLevel0(scratch("a.h5"), "north_cap");
  EXPECT_TRUE(bitwiseEqual(va, test::readLevel0(scratch("b.h5"), "north_cap")));
  EXPECT_FALSE(bitwiseEqual(va, test::readLevel0(scratch("c.h5"), "north_cap")));
  for (const float h : va) ASSERT_TRUE(std::isfinite(h));
}

TEST(GeneratePolarCap, BadOptionsAreRefusedWithClearMessages) {
  PolarCapOptions o = smallCap();
  o.minLatitudeDeg = 90.0;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { PolarCapGenerator{o}; }),
            "store::PolarCapGenerator(): minimum latitude is 90 degrees, expected > 0 and < 90");
  o = smallCap();
  o.spacing = -5.0;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { PolarCapGenerator{o}; }),
            "store::PolarCapGenerator(): spacing is -5 m, expected a finite number > 0");
  o = smallCap();
  o.spacing = 0.001;
  EXPECT_NE(test::messageOf<InvalidArgument>([&] {
              PolarCapGenerator{o};
            }).find("store::PolarCapGenerator(): spacing is 0.001 m, expected >= "),
            std::string::npos);
  o = smallCap();
  o.troughDepth = std::nan("");
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { PolarCapGenerator{o}; }),
            "store::PolarCapGenerator(): trough depth is nan m, expected a finite number >= 0");
  o = smallCap();
  o.planet.craterDensity = -1.0;
  EXPECT_THROW(PolarCapGenerator{o}, InvalidArgument);
}
