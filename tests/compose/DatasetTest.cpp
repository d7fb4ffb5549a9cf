// Dataset: the terms of the weight (coverage, quality), its bad-input refusals, and the
// feather mask against a brute-force distance in double.

#include <regolith/compose/Dataset.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/topo/Projection.hpp>

#include "compose/ComposeFixtures.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace regolith::compose {
namespace {

using testing::demPyramid;
using testing::globalPlanet;
using testing::named;

const topo::Body kMars = topo::Body::marsSphere();
constexpr double kDeg = std::numbers::pi / 180.0;

TEST(Dataset, ProjectionQualityFollowsKooima) {
  // α = 1 − |log k| / log n.
  EXPECT_DOUBLE_EQ(projectionQuality(1.0, 1.0, 1.0, 8.0), 1.0);
  EXPECT_NEAR(projectionQuality(0.5, 1.0, std::sqrt(0.5), 8.0), 1.0 - std::log(2.0) / std::log(8.0),
              1e-15);
  EXPECT_NEAR(projectionQuality(2.0, 2.0, 1.0, 8.0), 1.0 - std::log(2.0) / std::log(8.0), 1e-15);
  EXPECT_DOUBLE_EQ(projectionQuality(1.0, 8.0, std::sqrt(8.0), 8.0), kMinQuality);
  EXPECT_DOUBLE_EQ(projectionQuality(0.0, 1.0, 1.0, 8.0), kMinQuality);
}

TEST(Dataset, EquirectangularQualityFallsTowardsThePoles) {
  const auto d =
      Dataset::planet(globalPlanet(kMars, 1.0, [](double, double) { return 0.0; }), named("g"));
  double prev = 2.0;
  for (double lat : {0.0, 30.0, 60.0, 80.0, 89.9}) {
    const double q = d->evaluate(lat, 10.0).quality;
    EXPECT_NEAR(q,
                std::max(kMinQuality, 1.0 + std::log(std::cos(lat * kDeg)) / std::log(kQualityN)),
                1e-12);
    EXPECT_LT(q, prev + 1e-15);
    prev = q;
  }
}

TEST(Dataset, PolarStereographicQualityFallsAwayFromItsPole) {
  const auto ps = topo::PolarStereographic::withTrueScaleLatitude(
      kMars, topo::PolarStereographic::Pole::North, 90.0, 0.0);
  const auto d = Dataset::dem(demPyramid(20e3, 401, 401, [](double, double) { return 0.0; }),
                              topo::Placement(kMars, ps), named("cap"));
  // The scale factor of a polar stereographic map with true scale at its pole is
  // k = 2 / (1 + sin φ): a pixel there is 1/k of its nominal size on the ground.
  for (double lat : {89.0, 80.0, 70.0, 60.0}) {
    const double k = 2.0 / (1.0 + std::sin(lat * kDeg));
    EXPECT_NEAR(d->evaluate(lat, 30.0).quality, 1.0 - std::log(k) / std::log(kQualityN), 2e-3)
        << lat;
  }
}

TEST(Dataset, MaskScalesCoverageAndFeatherStartsAtTheEdge) {
  auto pyr = demPyramid(10.0, 101, 101, [](double, double) { return 5.0; });
  DatasetOptions o = named("masked", 100.0);
  // Mask: 1 in the west half, 0.25 in the east half.
  o.mask = topo::InMemorySamples::fromFunction(
      101, 101, [](std::size_t, std::size_t c) { return c < 50 ? 1.0F : 0.25F; });
  const topo::LocalTangentPlane ltp(kMars, {0.0, 0.0, 0.0});
  const auto d = Dataset::dem(pyr, topo::Placement(ltp), o);
  auto at = [&](double x, double y) {
    const topo::Geodetic g = ltp.inverse({x, y, 5.0});
    return d->evaluate(g.latDeg, g.lonDeg);
  };
  EXPECT_NEAR(at(-200.0, 0.0).coverage, 1.0, 1e-9);
  EXPECT_NEAR(at(200.0, 0.0).coverage, 0.25, 1e-9);
  // 50 m inside the west edge (x = −505): smoothstep(0.5) = 0.5.
  EXPECT_NEAR(at(-455.0, 0.0).coverage, 0.5, 1e-6);
  EXPECT_EQ(at(-600.0, 0.0).status, topo::QueryStatus::OutsideGrid);
  EXPECT_EQ(at(-600.0, 0.0).coverage, 0.0);
}

TEST(Dataset, SoleHeightIsEvaluatesHeightWhereItAnswersWithCoverage) {
  // soleHeightOrNan() (a composition's query where one dataset is the cell's only candidate; a
  // planet grid without feather or mask takes a shortcut) against evaluate(): true exactly
  // where evaluate() answers Ok with coverage > 0, and then the same height bit for bit.
  // coveredHeight() (a feathered top's query; a planet grid takes the coverage first): the
  // same, with the coverage bit for bit, and coverage 0 exactly where the height is NaN. A
  // global grid, a regional one with an offset (shortcut), the same feathered and masked
  // (general path), a planetocentric one on an ellipsoid and a DEM, at random points, on
  // their edges, across the seam and beyond a turn of longitude.
  const topo::Body ellipsoid = topo::Body::marsEllipsoid();
  const auto f = [](double lat, double lon) {
    return 100.0 * std::sin(3.0 * lat * kDeg) * std::cos(2.0 * lon * kDeg);
  };
  DatasetOptions offset = named("regional");
  offset.heightOffset = 12.5;
  DatasetOptions feathered = offset;
  feathered.featherMetres = 20000.0;
  DatasetOptions masked = offset;
  masked.mask = topo::InMemorySamples::fromFunction(
      40, 60, [](std::size_t r, std::size_t c) { return (r + c) % 7 == 0 ? 0.0F : 1.0F; });
  auto centric = testing::planetPyramid(ellipsoid, 29.875, 170.125, 0.25, 40, 60, f);
  centric.latitudeType = topo::LatitudeType::Planetocentric;
  const topo::LocalTangentPlane ltp(kMars, {10.0, 20.0, 0.0});
  const std::shared_ptr<const Dataset> datasets[] = {
      Dataset::planet(globalPlanet(kMars, 2.0,
                                   [&](double la, double lo) {
                                     // A hole: the shortcut declines its Nodata too.
                                     return la > 40.0 && la < 60.0 && lo > 0.0 && lo < 30.0
                                                ? std::numeric_limits<double>::quiet_NaN()
                                                : f(la, lo);
                                   }),
                      named("global")),
      Dataset::planet(testing::planetPyramid(kMars, 29.875, 170.125, 0.25, 40, 60, f), offset),
      Dataset::planet(testing::planetPyramid(kMars, 29.875, 170.125, 0.25, 40, 60, f), feathered),
      Dataset::planet(testing::planetPyramid(kMars, 29.875, 170.125, 0.25, 40, 60, f), masked),
      Dataset::planet(centric, named("centric")),
      Dataset::dem(demPyramid(100.0, 51, 51, [](double x, double y) { return 0.01 * (x - y); }),
                   topo::Placement(ltp), named("dem"))};
  std::vector<std::array<double, 2>> pts = {
      {30.0, 170.0}, {20.0, 185.0}, {20.125, 184.875}, {29.9999, 170.0001}, {20.0, -175.0},
      {20.0, 545.0}, {90.0, 0.0},   {-90.0, 180.0},    {10.0, 20.0},        {0.0, -180.0}};
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> lat(18.0, 32.0), lon(165.0, 190.0), any(-90.0, 90.0);
  for (int i = 0; i < 2000; ++i) pts.push_back({lat(rng), lon(rng)});
  for (int i = 0; i < 500; ++i) pts.push_back({any(rng), 4.0 * any(rng)});
  for (int i = 0; i < 200; ++i) pts.push_back({45.0 + 0.2 * any(rng), 15.0 + 0.2 * any(rng)});
  for (int i = 0; i < 200; ++i) {
    const topo::Geodetic g = ltp.inverse({50.0 * any(rng), 50.0 * any(rng), 0.0});
    pts.push_back({g.latDeg, g.lonDeg});
  }
  for (const auto& d : datasets) {
    int answered = 0, declined = 0, partial = 0;
    for (const auto& [la, lo] : pts) {
      const Contribution c = d->evaluate(la, lo, 0, false, false);
      const double h = d->soleHeightOrNan(la, lo, 0);
      const Dataset::CoveredHeight ch = d->coveredHeight(la, lo, 0);
      const bool expected = c.status == topo::QueryStatus::Ok && c.coverage > 0.0;
      ASSERT_EQ(!std::isnan(h), expected) << d->options().name << " at " << la << ", " << lo;
      ASSERT_EQ(ch.coverage > 0.0, expected) << d->options().name << " at " << la << ", " << lo;
      if (std::isnan(h)) {
        ASSERT_EQ(ch.coverage, 0.0);
        ++declined;
        continue;
      }
      ++answered;
      ASSERT_EQ(std::bit_cast<std::uint64_t>(h), std::bit_cast<std::uint64_t>(c.height))
          << d->options().name << " at " << la << ", " << lo;
      ASSERT_EQ(std::bit_cast<std::uint64_t>(ch.height), std::bit_cast<std::uint64_t>(c.height))
          << d->options().name << " at " << la << ", " << lo;
      ASSERT_EQ(std::bit_cast<std::uint64_t>(ch.coverage), std::bit_cast<std::uint64_t>(c.coverage))
          << d->options().name << " at " << la << ", " << lo;
      partial += c.coverage < 1.0 ? 1 : 0;
    }
    // Both outcomes were exercised for every dataset.
    EXPECT_GT(answered, 50) << d->options().name;
    EXPECT_GT(declined, 50) << d->options().name;
    if (!d->unfeathered()) {
      EXPECT_GT(partial, 50) << d->options().name;  // in the feather or the mask's slopes
    }
  }
  // A non-finite point is outside every planet grid (their grids' unchecked reads never see
  // one), global or not: no error, no height.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 5; ++k) {
    for (const auto& [la, lo] : {std::pair{nan, 10.0}, std::pair{20.0, nan}, std::pair{20.0, inf},
                                 std::pair{-inf, 0.0}, std::pair{25.0, -inf}}) {
      const Contribution c = datasets[k]->evaluate(la, lo);
      EXPECT_EQ(c.status, topo::QueryStatus::OutsideGrid) << k << ": " << la << ", " << lo;
      EXPECT_EQ(c.coverage, 0.0);
      EXPECT_EQ(datasets[k]->coveredHeight(la, lo, 0).coverage, 0.0);
      EXPECT_TRUE(std::isnan(datasets[k]->soleHeightOrNan(la, lo, 0)));
    }
  }
}

TEST(Dataset, PlanetGridsOfOneBodyAndPixelShapeShareTheirQuality) {
  // samePlanetQuality() (the composition leaves such grids' shared quality out of their
  // weights): true exactly for planet grids of one body and level-0 pixel shape, whatever
  // their extent and pixel size, and then quality() is equal, bit for bit, at every point
  // inside both. Kooima's quality of a latitude/longitude pixel, from its two sides on the
  // ellipsoid in double, is the oracle for each grid's value.
  const auto f = [](double, double) { return 0.0; };
  const auto global = Dataset::planet(globalPlanet(kMars, 0.5, f), named("global"));
  const auto part = Dataset::planet(testing::planetPyramid(kMars, 59.75, 10.25, 0.5, 100, 80, f),
                                    named("part", 5000.0, 3));
  const auto finer = Dataset::planet(testing::planetPyramid(kMars, 59.75, 10.25, 0.25, 100, 80, f),
                                     named("finer"));
  // The same longitude spacing, half the latitude spacing.
  topo::GridPyramid anisotropic = testing::planetPyramid(kMars, 59.75, 10.25, 0.5, 100, 80, f);
  anisotropic.levels[0].grid = topo::TopoGrid(100, 80, 10.25, 59.75, 0.5, 0.25);
  const auto wider = Dataset::planet(anisotropic, named("wider"));
  const auto moon = Dataset::planet(globalPlanet(topo::Body::moon(), 0.5, f), named("moon"));
  const auto dem =
      Dataset::dem(demPyramid(100.0, 11, 11, f),
                   topo::Placement(topo::LocalTangentPlane(kMars, {0.0, 0.0, 0.0})), named("dem"));
  EXPECT_TRUE(global->samePlanetQuality(*part));
  EXPECT_TRUE(part->samePlanetQuality(*global));
  EXPECT_TRUE(global->samePlanetQuality(*global));
  EXPECT_TRUE(global->samePlanetQuality(*finer));
  EXPECT_TRUE(finer->samePlanetQuality(*part));
  EXPECT_FALSE(global->samePlanetQuality(*wider));
  EXPECT_FALSE(global->samePlanetQuality(*moon));
  EXPECT_FALSE(global->samePlanetQuality(*dem));
  EXPECT_FALSE(dem->samePlanetQuality(*dem));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> lat(11.0, 59.0), lon(11.0, 49.0);
  for (int i = 0; i < 500; ++i) {
    const double la = lat(rng), lo = lon(rng);
    ASSERT_EQ(global->quality(la, lo), part->quality(la, lo)) << la << ", " << lo;
    if (la > 35.0 && lo < 30.0) {  // inside the finer grid
      ASSERT_EQ(global->quality(la, lo), finer->quality(la, lo)) << la << ", " << lo;
    }
  }
  // Each grid's quality against the rule from its own pixel (spacings sx × sy degrees):
  // sides gx = N·cos φ·sx and gy = M·sy, the nominal pixel the same on the equator.
  const auto kooima = [](double phi, double sx, double sy) {
    const double d = kDeg;
    const double gx = kMars.primeVerticalRadius(phi) * std::cos(phi * d) * sx * d;
    const double gy = kMars.meridianRadius(phi) * sy * d;
    const double nominal =
        std::sqrt(kMars.equatorialRadius() * sx * d * kMars.meridianRadius(0.0) * sy * d);
    return projectionQuality(gx, gy, nominal, kQualityN);
  };
  for (const double la : {35.5, 40.0, 47.0, 52.25, 59.5}) {
    EXPECT_NEAR(global->quality(la, 20.0), kooima(la, 0.5, 0.5), 1e-12) << la;
    EXPECT_NEAR(finer->quality(la, 20.0), kooima(la, 0.25, 0.25), 1e-12) << la;
    EXPECT_NEAR(wider->quality(la, 20.0), kooima(la, 0.5, 0.25), 1e-12) << la;
    EXPECT_NE(wider->quality(la, 20.0), global->quality(la, 20.0)) << la;
  }
}

TEST(Dataset, RefusesBadOptionsWithClearMessages) {
  auto pyr = demPyramid(10.0, 11, 11, [](double, double) { return 0.0; });
  const topo::Placement pl(topo::LocalTangentPlane(kMars, {0.0, 0.0, 0.0}));
  auto message = [&](DatasetOptions o) {
    try {
      (void)Dataset::dem(pyr, pl, std::move(o));
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  DatasetOptions o = named("x", -1.0);
  EXPECT_NE(message(o).find("feather width"), std::string::npos) << message(o);
  o = named("x");
  o.mask = topo::InMemorySamples::fromFunction(5, 5, [](std::size_t, std::size_t) { return 1.0F; });
  EXPECT_NE(message(o).find("mask size"), std::string::npos) << message(o);
  o = named("x");
  o.heightRange = std::array<double, 2>{5.0, -5.0};
  EXPECT_NE(message(o).find("height range"), std::string::npos) << message(o);
  o = named("holes");
  auto empty = demPyramid(10.0, 3, 3,
                          [](double, double) { return std::numeric_limits<double>::quiet_NaN(); });
  try {
    (void)Dataset::dem(empty, pl, o);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("all missing"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)Dataset::planet(pyr, named("flat")), InvalidArgument);
  EXPECT_THROW((void)Dataset::dem(globalPlanet(kMars, 10.0, [](double, double) { return 0.0; }), pl,
                                  named("p")),
               InvalidArgument);
}

TEST(Dataset, PlanetFeatherIsTheDistanceToTheEdgesItHas) {
  // A planet grid's feather coverage against its rule in double: smoothstep of the smallest
  // ground distance to an edge the grid has (along the meridian to its north and south
  // edges, unless it reaches a pole; along the parallel to its west and east edges, unless
  // it spans all longitudes), with the radii of curvature at the point. coverageAt() takes
  // 1 without that arithmetic inside a box found from the grid's smallest radii: the points
  // cluster where the box ends, on a sphere, an ellipsoid (planetodetic and planetocentric
  // grids, one reaching 80°) and a band around all longitudes.
  const topo::Body ellipsoid = topo::Body::marsEllipsoid();
  const auto flat = [](double, double) { return 0.0; };
  struct Case {
    topo::Body body;
    topo::GridPyramid pyramid;
    double feather;
  };
  auto centric = testing::planetPyramid(ellipsoid, 79.75, -29.75, 0.5, 40, 120, flat);
  centric.latitudeType = topo::LatitudeType::Planetocentric;
  std::vector<Case> cases;
  cases.push_back(
      {kMars, testing::planetPyramid(kMars, 29.875, 170.125, 0.25, 40, 60, flat), 60e3});
  cases.push_back(
      {ellipsoid, testing::planetPyramid(ellipsoid, 79.75, -29.75, 0.5, 40, 120, flat), 90e3});
  cases.push_back({ellipsoid, centric, 90e3});
  cases.push_back(
      {ellipsoid, testing::planetPyramid(ellipsoid, -40.5, -179.5, 1.0, 20, 360, flat), 150e3});
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Case& k : cases) {
    const auto d = Dataset::planet(k.pyramid, named("feathered", k.feather));
    const topo::TopoGrid& g = k.pyramid.levels[0].grid;
    const bool allLon = g.east() - g.west() >= 360.0 - 1e-9;
    int partial = 0, full = 0;
    for (int i = 0; i < 20000; ++i) {
      // Grid coordinates (lon, lat in the grid's latitude type), half of them within two
      // feather widths of an edge.
      double y = g.south() + (g.north() - g.south()) * unit(rng);
      double x = g.west() + (g.east() - g.west()) * unit(rng);
      if (i % 2 == 0) {
        const double du = 2.0 * k.feather / (k.body.meridianRadius(0.0) * kDeg) * unit(rng);
        switch (i % 8) {
          case 0: y = g.north() - du; break;
          case 2: y = g.south() + du; break;
          case 4: x = g.west() + du / std::cos(std::abs(y) * kDeg); break;
          default: x = g.east() - du / std::cos(std::abs(y) * kDeg); break;
        }
        x = std::clamp(x, g.west(), g.east());
      }
      const double lat = k.body.toPlanetodetic(y, k.pyramid.latitudeType);
      const double m = k.body.meridianRadius(lat) * kDeg;
      const double p = k.body.primeVerticalRadius(lat) * std::cos(lat * kDeg) * kDeg;
      double dist = std::min((g.north() - y) * m, (y - g.south()) * m);
      if (!allLon) dist = std::min({dist, (x - g.west()) * p, (g.east() - x) * p});
      const double expected = testing::smoothstep(dist / k.feather);
      const double got = d->coverageQuality(lat, x)[0];
      ASSERT_NEAR(got, expected, 1e-12) << "grid " << &k - cases.data() << " at " << y << ", " << x;
      if (expected == 1.0) {
        ASSERT_EQ(got, 1.0);
      }
      partial += expected < 1.0 ? 1 : 0;
      full += expected == 1.0 ? 1 : 0;
    }
    EXPECT_GT(partial, 2000) << &k - cases.data();
    EXPECT_GT(full, 2000) << &k - cases.data();
  }
}

TEST(Dataset, FeatherMaskMatchesBruteForceDistance) {
  const std::size_t rows = 37, cols = 53;
  std::mt19937 rng(2);
  std::bernoulli_distribution hole(0.03);
  std::vector<float> h(rows * cols, 1.0F);
  for (float& v : h) {
    if (hole(rng)) v = std::numeric_limits<float>::quiet_NaN();
  }
  const topo::TopoGrid grid(rows, cols, 0.0, 0.0, 1.0, 1.0);
  const topo::InMemorySamples src(rows, cols, h);
  for (bool edge : {false, true}) {
    const double width = 6.0;
    const auto mask = featherMask(grid, src, width, edge);
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t c = 0; c < cols; ++c) {
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t rr = 0; rr < rows; ++rr) {
          for (std::size_t cc = 0; cc < cols; ++cc) {
            if (std::isnan(h[rr * cols + cc])) {
              best = std::min(best, std::hypot(double(rr) - double(r), double(cc) - double(c)));
            }
          }
        }
        if (edge) {
          best = std::min(
              {best, double(r) + 1.0, double(c) + 1.0, double(rows - r), double(cols - c)});
        }
        const double expected = testing::smoothstep(best / width);
        EXPECT_NEAR(mask->sample(r, c), expected, 1e-6) << r << "," << c << " edge " << edge;
      }
    }
  }
  EXPECT_THROW((void)featherMask(grid, src, 0.0), InvalidArgument);
}

}  // namespace
}  // namespace regolith::compose
