// Transforms between representations: planet region → tangent-plane DEM, and back.
#include <regolith/core/Error.hpp>
#include <regolith/topo/Resample.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace regolith;
using namespace regolith::topo;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;

// A planet region near Victoria crater (2.05°S, 5.5°W) with a smooth bump, 0.001° pixels.
TopoPlanet regionPlanet(const Body& body) {
  const double d = 0.001;
  TopoGrid g(200, 200, -5.6 + d / 2, -1.95 - d / 2, d, d);
  return {g, body, LatitudeType::Planetodetic,
          InMemorySamples::fromFunction(200, 200, [&](std::size_t r, std::size_t c) {
            const glm::dvec2 p = g.sampleCentre(double(r), double(c));
            const double dx = (p.x + 5.5) / 0.03, dy = (p.y + 2.05) / 0.03;
            return float(-1400.0 + 60.0 * std::exp(-(dx * dx + dy * dy)));
          })};
}
}  // namespace

TEST(Resample, PlanetToTangentPlaneDemPutsEverySampleOnThePlanetSurface) {
  const Body mars = Body::marsEllipsoid();
  const TopoPlanet planet = regionPlanet(mars);
  const LocalTangentPlane plane(mars, {-2.05, -5.5, -1400.0}, 15.0);
  const TopoGrid demGrid(41, 41, -2000.0, 2000.0, 100.0, 100.0);
  const TopoDem dem = resamplePlanetToDem(planet, plane, demGrid, Interpolation::Bicubic);
  EXPECT_EQ(dem.placement().kind(), Placement::Kind::LocalTangentPlane);
  for (std::size_t r = 0; r < 41; r += 5) {
    for (std::size_t c = 0; c < 41; c += 5) {
      const glm::dvec3 p = dem.samplePosition(r, c);
      const Geodetic g = mars.toGeodetic(p);
      const double t = planet.height({g.latDeg, g.lonDeg}, Interpolation::Bicubic).height;
      EXPECT_NEAR(g.height, t, 1e-3) << r << "," << c;  // float storage of heights
    }
  }
  EXPECT_NEAR(dem.height(0.0, 0.0).height, 60.0, 0.01);  // the bump's top, at the origin
}

TEST(Resample, CurvatureIsKeptNotFlattenedAway) {
  // A constant-height sphere planet: the DEM must follow the sphere of radius R' = R + h0
  // below the tangent plane, z = sqrt(R'² − d²) − R' (≈ −0.59 m at 2 km on Mars).
  const Body mars = Body::marsSphere();
  const double h0 = -1400.0;
  const TopoGrid g(400, 400, -5.8 + 0.0005, -1.75 - 0.0005, 0.001, 0.001);
  const TopoPlanet flat(
      g, mars, LatitudeType::Planetocentric,
      std::make_shared<InMemorySamples>(400, 400, std::vector<float>(400 * 400, float(h0))));
  const LocalTangentPlane plane(mars, {-2.05, -5.5, h0}, 40.0);
  const TopoDem dem =
      resamplePlanetToDem(flat, plane, TopoGrid(9, 9, -2000.0, 2000.0, 500.0, 500.0));
  const double rp = 3396190.0 + h0;
  for (std::size_t r = 0; r < 9; ++r) {
    for (std::size_t c = 0; c < 9; ++c) {
      const glm::dvec2 p = dem.grid().sampleCentre(double(r), double(c));
      const double d2 = p.x * p.x + p.y * p.y;
      EXPECT_NEAR(dem.samples().sample(r, c), std::sqrt(rp * rp - d2) - rp, 1e-4);
    }
  }
  EXPECT_LT(dem.samples().sample(0, 0), -1.1);
}

TEST(Resample, DemToPlanetAndBackRecoversTheSurface) {
  const Body mars = Body::marsSphere();
  const TopoPlanet planet = regionPlanet(mars);
  const LocalTangentPlane plane(mars, {-2.05, -5.5, -1400.0});
  const TopoDem dem =
      resamplePlanetToDem(planet, plane, TopoGrid(81, 81, -2000.0, 2000.0, 50.0, 50.0));
  // Back onto a lat/lon grid inside the DEM's footprint.
  const double d = 0.002;
  const TopoGrid ll(20, 20, -5.52 + d / 2, -2.03 - d / 2, d, d);
  const TopoPlanet back = resampleDemToPlanet(dem, ll, LatitudeType::Planetodetic);
  double maxErr = 0.0;
  for (std::size_t r = 0; r < 20; ++r) {
    for (std::size_t c = 0; c < 20; ++c) {
      const glm::dvec2 p = ll.sampleCentre(double(r), double(c));
      const double want = planet.height({p.y, p.x}, Interpolation::Bicubic).height;
      const double got = back.samples().sample(r, c);
      maxErr = std::max(maxErr, std::abs(got - want));
    }
  }
  EXPECT_LT(maxErr, 0.05);  // two bicubic resamplings of a 60 m bump at 50 m spacing
  // Outside the DEM's footprint the result is NaN, never zero.
  const TopoGrid far(2, 2, 10.0, 10.0, 0.1, 0.1);
  const TopoPlanet none = resampleDemToPlanet(dem, far, LatitudeType::Planetodetic);
  EXPECT_TRUE(std::isnan(none.samples().sample(0, 0)));
}

TEST(Resample, RejectsAPlaneOnAnotherBody) {
  const TopoPlanet planet = regionPlanet(Body::marsSphere());
  const LocalTangentPlane moonPlane(Body::moon(), {0, 0, 0});
  EXPECT_THROW((void)resamplePlanetToDem(planet, moonPlane, TopoGrid(2, 2, 0, 0, 1, 1)),
               InvalidArgument);
}
