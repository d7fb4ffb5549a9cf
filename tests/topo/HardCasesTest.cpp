// The hard cases, one test per case, each named after its case.
#include <regolith/core/Error.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

using namespace regolith;
using namespace regolith::topo;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr Interpolation kAll[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                  Interpolation::Bicubic};

// Global 1° grid, west edge at `west`, sample value = 10·row + col/1000 (distinct values).
TopoPlanet indexPlanet(double west) {
  TopoGrid g(180, 360, west + 0.5, 89.5, 1.0, 1.0);
  return {
      g, Body::marsSphere(), LatitudeType::Planetocentric,
      InMemorySamples::fromFunction(180, 360, [](std::size_t r, std::size_t c) {
        return static_cast<float>(10.0 * static_cast<double>(r) + static_cast<double>(c) / 1000.0);
      })};
}
double at(const TopoPlanet& p, std::size_t r, std::size_t c) {
  return static_cast<double>(p.samples().sample(r, c));
}
}  // namespace

TEST(HardCases, LatitudeExactlyPlusAndMinus90) {
  const TopoPlanet p = indexPlanet(0.0);
  for (double lat : {90.0, -90.0}) {
    for (Interpolation k : kAll) {
      const SurfaceSample s0 = p.surface({lat, 0.0}, k, NormalFrame::BodyFixed);
      ASSERT_TRUE(s0.valid());
      EXPECT_TRUE(std::isfinite(s0.normal.x) && std::isfinite(s0.normal.y) &&
                  std::isfinite(s0.normal.z));
      EXPECT_NEAR(glm::length(s0.normal), 1.0, 1e-12);
      for (double lon : {-180.0, -90.0, 45.0, 180.0, 270.0}) {
        const SurfaceSample s = p.surface({lat, lon}, k, NormalFrame::BodyFixed);
        EXPECT_DOUBLE_EQ(s.height, s0.height) << "the pole has one height";
      }
    }
  }
  // The pole's own geometry: body-fixed position on the axis, toGeodetic back to ±90.
  const Body mars = Body::marsEllipsoid();
  const glm::dvec3 np = mars.toBodyFixed({90.0, 123.0, 5.0});
  EXPECT_NEAR(np.x, 0.0, 1e-9);
  EXPECT_NEAR(np.z, 3376205.0, 1e-6);
  const Geodetic g = mars.toGeodetic(np);
  EXPECT_DOUBLE_EQ(g.latDeg, 90.0);
  EXPECT_NEAR(g.height, 5.0, 1e-9);
  EXPECT_DOUBLE_EQ(mars.planetocentricFromPlanetodetic(-90.0), -90.0);
}

TEST(HardCases, LongitudesMinus180And180And360GiveTheSameSample) {
  for (double west : {0.0, -180.0}) {
    const TopoPlanet p = indexPlanet(west);
    for (Interpolation k : kAll) {
      const double a = p.height({30.0, -180.0}, k).height;
      EXPECT_EQ(a, p.height({30.0, 180.0}, k).height);
      EXPECT_EQ(p.height({30.0, 0.0}, k).height, p.height({30.0, 360.0}, k).height);
      EXPECT_EQ(p.height({30.0, 0.0}, k).height, p.height({30.0, -360.0}, k).height);
    }
  }
}

TEST(HardCases, AntimeridianInsideABilinearStencil) {
  // Grid −180…180: column 359 is centred at 179.5°, column 0 at −179.5°. A query at 179.8°
  // (row centre 29.5°, row 60) mixes them with weights 0.7 / 0.3.
  const TopoPlanet p = indexPlanet(-180.0);
  const double expect = 0.7 * at(p, 60, 359) + 0.3 * at(p, 60, 0);
  EXPECT_NEAR(p.height({29.5, 179.8}, Interpolation::Bilinear).height, expect, 1e-9);
  EXPECT_NEAR(p.height({29.5, -180.2}, Interpolation::Bilinear).height, expect, 1e-9);
}

TEST(HardCases, AntimeridianInsideABicubicStencil) {
  const TopoPlanet p = indexPlanet(-180.0);
  // Keys weights at t = 0.3 for samples at offsets −1, 0, 1, 2 from column 359.
  const double t = 0.3;
  const double w[4] = {0.5 * (-t * t * t + 2 * t * t - t), 0.5 * (3 * t * t * t - 5 * t * t + 2),
                       0.5 * (-3 * t * t * t + 4 * t * t + t), 0.5 * (t * t * t - t * t)};
  const double expect =
      w[0] * at(p, 60, 358) + w[1] * at(p, 60, 359) + w[2] * at(p, 60, 0) + w[3] * at(p, 60, 1);
  EXPECT_NEAR(p.height({29.5, 179.8}, Interpolation::Bicubic).height, expect, 1e-9);
}

TEST(HardCases, TwoQueriesOneMillimetreApartAtPlanetaryRadius) {
  // A DEM in equirectangular metres at Marth crater (x ≈ 2.1e6 m), slope 0.3 along x.
  const Body mars = Body::marsSphere();
  const double x0 = 2108000.0, y0 = 746000.0, slope = 0.3;
  const TopoGrid g(8, 8, x0, y0, 1.0, 1.0);
  const TopoDem dem(g, Placement(mars, Equirectangular(3396190.0, 0.0, 0.0)),
                    InMemorySamples::fromFunction(8, 8, [&](std::size_t, std::size_t c) {
                      return static_cast<float>(slope * static_cast<double>(c));
                    }));
  for (Interpolation k : {Interpolation::Bilinear, Interpolation::Bicubic}) {
    const double x = x0 + 3.123456, y = y0 - 3.5;
    const double h1 = dem.height(x, y, k).height, h2 = dem.height(x + 1e-3, y, k).height;
    EXPECT_NEAR(h2 - h1, slope * 1e-3, 1e-9);  // x's ulp here is 4.7e-10 m
    // The body-fixed points are 1 mm apart (times the map scale), not float noise.
    const double d = glm::length(dem.toBodyFixed(x + 1e-3, y, h2) - dem.toBodyFixed(x, y, h1));
    // East: 1 mm of map x is cos φ mm of ground on this φts = 0 map; up: slope × 1 mm.
    EXPECT_NEAR(d, std::hypot(1e-3 * std::cos(y / 3396190.0), slope * 1e-3), 1e-8);
  }
  // A planet: longitudes 1 mm apart on the equator of Mars.
  const TopoGrid pg(180, 360, 0.5, 89.5, 1.0, 1.0);
  const double perDeg = 50.0;  // metres of height per degree of longitude
  const TopoPlanet planet(pg, mars, LatitudeType::Planetocentric,
                          InMemorySamples::fromFunction(180, 360, [&](std::size_t, std::size_t c) {
                            return static_cast<float>(perDeg * static_cast<double>(c));
                          }));
  const double dLon = 1e-3 / (3396190.0 * kDeg);
  const double a = planet.height({0.25, 100.3}).height,
               b = planet.height({0.25, 100.3 + dLon}).height;
  EXPECT_NEAR((b - a) / (perDeg * dLon), 1.0, 1e-5);  // lon's ulp is 1e-6 of dLon
}

TEST(HardCases, BicubicOnA1xNAndA2x2Grid) {
  const Placement pl(LocalTangentPlane(Body::moon(), {0, 0, 0}));
  // 1×N: a single row; rows clamp, so bicubic is the 1-D Keys cubic along the row.
  const TopoGrid row(1, 6, 0.0, 0.0, 1.0, 1.0);
  const std::vector<float> v{0, 1, 4, 9, 16, 25};
  const TopoDem d1(row, pl, std::make_shared<InMemorySamples>(1, 6, v));
  for (double x : {1.5, 2.25, 3.75}) {
    for (double y : {0.5, 0.0, -0.5}) {
      const SurfaceSample s = d1.surface(x, y, Interpolation::Bicubic);
      ASSERT_TRUE(s.valid());
      EXPECT_NEAR(s.height, x * x, 1e-9);  // Keys is exact for quadratics
      EXPECT_NEAR(-s.normal.x / s.normal.z, 2 * x, 1e-9);
      EXPECT_DOUBLE_EQ(s.normal.y, 0.0);
    }
  }
  // 2×2: the centre is the mean, the corners are the samples, nothing is NaN.
  const TopoGrid sq(2, 2, 0.0, 0.0, 1.0, 1.0);
  const TopoDem d2(sq, pl,
                   std::make_shared<InMemorySamples>(2, 2, std::vector<float>{1, 3, 5, 11}));
  EXPECT_DOUBLE_EQ(d2.height(0.5, -0.5, Interpolation::Bicubic).height, 5.0);
  EXPECT_DOUBLE_EQ(d2.height(0.0, 0.0, Interpolation::Bicubic).height, 1.0);
  EXPECT_DOUBLE_EQ(d2.height(1.0, -1.0, Interpolation::Bicubic).height, 11.0);
  for (double x = -0.5; x <= 1.5; x += 0.125) {
    for (double y = 0.5; y >= -1.5; y -= 0.125) {
      const SurfaceSample s = d2.surface(x, y, Interpolation::Bicubic);
      ASSERT_TRUE(s.valid());
      EXPECT_GE(s.height, 1.0 - 1e-12);
      EXPECT_LE(s.height, 11.0 + 1e-12);
      EXPECT_NEAR(glm::length(s.normal), 1.0, 1e-12);
    }
  }
}

TEST(HardCases, NanOrInfInputCoordinatesGiveAClearError) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Body mars = Body::marsSphere();
  const TopoDem dem(TopoGrid(2, 2, 0, 0, 1, 1), Placement(LocalTangentPlane(mars, {0, 0, 0})),
                    std::make_shared<InMemorySamples>(2, 2, std::vector<float>(4)));
  const TopoPlanet planet = indexPlanet(0.0);
  EXPECT_THROW((void)dem.height(nan, 0), InvalidArgument);
  EXPECT_THROW((void)dem.height(0, -inf), InvalidArgument);
  EXPECT_THROW((void)planet.height({nan, 0}), InvalidArgument);
  EXPECT_THROW((void)planet.surface({0, inf}), InvalidArgument);
  const auto ps =
      PolarStereographic::withScaleFactor(mars, PolarStereographic::Pole::North, 1.0, 0.0);
  EXPECT_THROW((void)ps.forward({nan, 0}), InvalidArgument);
  EXPECT_THROW((void)ps.inverse({0, inf}), InvalidArgument);
  const Equirectangular eq(3396190.0, 0.0, 0.0);
  EXPECT_THROW((void)eq.forward({0, nan}), InvalidArgument);
  EXPECT_THROW(LocalTangentPlane(mars, {nan, 0, 0}), InvalidArgument);
  try {
    (void)planet.height({0.0, inf});
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "TopoPlanet::height(): longitude is inf, expected a finite number");
  }
}

TEST(HardCases, SpacingOfOneMillimetreAndOneHundredKilometres) {
  const Placement pl(LocalTangentPlane(Body::marsSphere(), {10, 20, 0}));
  for (double d : {1e-3, 1e5}) {
    const TopoGrid g(6, 6, 0.0, 0.0, d, d);
    // h = 0.5·x: slope 0.5 whatever the spacing. (Samples are float32: at 1 mm spacing a
    // height offset of metres would quantize slopes to ~1e-4; stores keep such DEMs with
    // an offset, see docs/queries.md.)
    const TopoDem dem(g, pl, InMemorySamples::fromFunction(6, 6, [&](std::size_t, std::size_t c) {
                        return static_cast<float>(0.5 * static_cast<double>(c) * d);
                      }));
    for (Interpolation k : {Interpolation::Bilinear, Interpolation::Bicubic}) {
      const double x = 2.37 * d, y = -3.1 * d;
      const SurfaceSample s = dem.surface(x, y, k);
      ASSERT_TRUE(s.valid());
      EXPECT_NEAR(s.height, 0.5 * x, 1e-6 * std::max(1.0, d)) << "spacing " << d;
      EXPECT_NEAR(-s.normal.x / s.normal.z, 0.5, 1e-5) << "spacing " << d;
      EXPECT_NEAR(s.normal.y, 0.0, 1e-12);
    }
    EXPECT_EQ(dem.height(5.51 * d, 0.0).status, QueryStatus::OutsideGrid);
    EXPECT_TRUE(dem.height(5.49 * d, 0.0).valid());
  }
}

TEST(HardCases, AProjectionEvaluatedExactlyAtItsPoleAndItsAntipode) {
  const Body mars = Body::marsEllipsoid();
  using Pole = PolarStereographic::Pole;
  for (Pole pole : {Pole::North, Pole::South}) {
    const double sign = pole == Pole::North ? 1.0 : -1.0;
    const auto ps =
        PolarStereographic::withTrueScaleLatitude(mars, pole, sign * 70.0, 45.0, 1000.0, -2000.0);
    const glm::dvec2 xy = ps.forward({sign * 90.0, 123.0});
    EXPECT_EQ(xy, glm::dvec2(1000.0, -2000.0));
    const LatLon back = ps.inverse(xy);
    EXPECT_EQ(back.latDeg, sign * 90.0);
    EXPECT_EQ(back.lonDeg, 45.0);
    try {
      (void)ps.forward({-sign * 90.0, 0.0});
      FAIL() << "antipode accepted";
    } catch (const DomainError& e) {
      EXPECT_NE(std::string(e.what()).find("opposite the projection's centre"), std::string::npos);
    }
    // One ulp short of the antipode is finite and round-trips.
    const double nearAnti = -sign * std::nextafter(90.0, 0.0);
    const glm::dvec2 far = ps.forward({nearAnti, 10.0});
    EXPECT_TRUE(std::isfinite(far.x) && std::isfinite(far.y));
  }
  // Equirectangular: the poles are the map's top and bottom edges; the antipodal meridian
  // is its seam, and both sides of the seam invert to the same meridian.
  const Equirectangular eq(3396190.0, 30.0, 20.0);
  for (double lat : {90.0, -90.0}) {
    const LatLon ll = eq.inverse(eq.forward({lat, 77.0}));
    EXPECT_EQ(ll.latDeg, lat);
  }
  const glm::dvec2 seam = eq.forward({10.0, 200.0});
  EXPECT_NEAR(seam.x, -3396190.0 * std::numbers::pi * std::cos(30.0 * kDeg), 1e-6);
  EXPECT_NEAR(wrapLongitude180(eq.inverse(seam).lonDeg - 200.0), 0.0, 1e-9);
  EXPECT_NEAR(wrapLongitude180(eq.inverse({-seam.x, seam.y}).lonDeg - 200.0), 0.0, 1e-9);
  // Local tangent plane: its origin maps to exactly 0, its antipode to z = −(2R + 2h).
  const LocalTangentPlane ltp(Body::marsSphere(), {-2.05, -5.5, 100.0}, 33.0);
  const glm::dvec3 o = ltp.forward({-2.05, -5.5, 100.0});
  EXPECT_EQ(o, glm::dvec3(0.0));
  const glm::dvec3 anti = ltp.forward({2.05, 174.5, 100.0});
  EXPECT_NEAR(anti.z, -2.0 * (3396190.0 + 100.0), 1e-6);
  EXPECT_NEAR(std::hypot(anti.x, anti.y), 0.0, 1e-6);
}
