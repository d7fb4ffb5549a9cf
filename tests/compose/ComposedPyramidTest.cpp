// The composed surface as a renderer's pyramid: every sample is the composed height at its
// position, in the grid's own height convention; drawingFrame() picks a polar grid near a pole.

#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/topo/Projection.hpp>

#include "compose/ComposeFixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace regolith::compose {
namespace {

using testing::demPyramid;
using testing::globalPlanet;
using testing::named;

const topo::Body kMoon = topo::Body::moon();

std::shared_ptr<const ComposedSurface> moonSurface() {
  auto cat = std::make_shared<Catalogue>(kMoon);
  cat->add(Dataset::planet(
      globalPlanet(kMoon, 1.0, [](double lat, double lon) { return 100.0 * std::sin(lat) + lon; }),
      named("global")));
  cat->add(Dataset::dem(
      demPyramid(100.0, 201, 201, [](double x, double y) { return 500.0 + 0.01 * x - 0.02 * y; }),
      topo::Placement(topo::LocalTangentPlane(kMoon, {5.0, 5.0, 0.0}, 20.0)), named("site", 2e3)));
  return std::make_shared<const ComposedSurface>(cat->snapshot());
}

TEST(ComposedPyramid, PlanetSamplesAreTheComposedHeights) {
  const auto s = moonSurface();
  const topo::TopoGrid g(101, 101, 4.5, 5.5, 0.01, 0.01);
  const ComposedSamples samples(s, g, topo::LatitudeType::Planetodetic, 0.0);
  for (std::size_t r : {0UL, 30UL, 50UL, 100UL}) {
    for (std::size_t c : {0UL, 49UL, 77UL}) {
      const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      EXPECT_EQ(samples.height(r, c), s->height(p.y, p.x).height);
      EXPECT_EQ(samples.sample(r, c), static_cast<float>(s->height(p.y, p.x).height));
    }
  }
}

TEST(ComposedPyramid, TangentPlaneSamplesLieOnTheComposedSurface) {
  // A tangent plane's heights are along its own normal: the point (x, y, h) it stores must
  // lie on the composed surface, i.e. its geodetic height is the composed height there.
  const auto s = moonSurface();
  const topo::Placement plane(topo::LocalTangentPlane(kMoon, {5.0, 5.1, 0.0}, -10.0));
  const topo::TopoGrid g(81, 81, -20e3, 20e3, 500.0, 500.0);
  const ComposedSamples samples(s, g, plane, 0.0);
  for (std::size_t r = 0; r < 81; r += 8) {
    for (std::size_t c = 0; c < 81; c += 8) {
      const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      const double h = samples.height(r, c);
      const topo::Geodetic geo = plane.toGeodetic(p.x, p.y, h);
      EXPECT_NEAR(geo.height, s->height(geo.latDeg, geo.lonDeg).height, 1e-6) << r << "," << c;
    }
  }
}

TEST(ComposedPyramid, ADatasetsOwnLatticeReadsItsSamplesWhereItAloneIsTheSurface) {
  // The site DEM drawn on its own lattice: with `own`, interior samples are read directly;
  // every sample must equal the full composition's (to the 1e-5 m the iteration is run to).
  auto cat = std::make_shared<Catalogue>(kMoon);
  cat->add(Dataset::planet(
      globalPlanet(kMoon, 1.0, [](double lat, double lon) { return 100.0 * std::sin(lat) + lon; }),
      named("global")));
  const topo::Placement plane(topo::LocalTangentPlane(kMoon, {5.0, 5.0, 40.0}, 20.0));
  const auto pyr =
      demPyramid(100.0, 101, 101, [](double x, double y) { return 500.0 + 0.01 * x - 0.02 * y; });
  const auto site = Dataset::dem(pyr, plane, named("site", 1500.0));
  cat->add(site);
  const auto s = std::make_shared<const ComposedSurface>(cat->snapshot());
  const topo::TopoGrid& g = pyr.levels[0].grid;
  const ComposedSamples direct(s, g, plane, 100.0, site, 0), full(s, g, plane, 100.0);
  int same = 0;
  for (std::size_t r = 0; r < 101; r += 4) {
    for (std::size_t c = 0; c < 101; c += 4) {
      const double a = direct.height(r, c), b = full.height(r, c);
      EXPECT_NEAR(a, b, 1e-5) << r << "," << c;
      same += a == static_cast<double>(pyr.levels[0].source->sample(r, c));
    }
  }
  EXPECT_GT(same, 100);  // the interior (past the 15-sample feather) is read directly
  // A second dataset of the same tier overlapping it: no direct reads (the blend matters).
  cat->add(Dataset::dem(demPyramid(100.0, 21, 21, [](double, double) { return 0.0; }), plane,
                        named("overlap")));
  const auto s2 = std::make_shared<const ComposedSurface>(cat->snapshot());
  const ComposedSamples guarded(s2, g, plane, 100.0, site, 0);
  EXPECT_NEAR(guarded.height(50, 50), ComposedSamples(s2, g, plane, 100.0).height(50, 50), 1e-9);
  EXPECT_NE(guarded.height(50, 50), static_cast<double>(pyr.levels[0].source->sample(50, 50)));
}

TEST(ComposedPyramid, ACompositionOfACompositionComposesEachOnce) {
  // A dataset whose samples are a composed pyramid of another catalogue: its queries run
  // inside the outer composition's (nested per-thread scratch), and must not disturb it.
  const auto inner = moonSurface();
  const topo::TopoGrid g(201, 201, 4.0, 6.0, 0.01, 0.01);  // around the site
  topo::GridPyramid p = composedPlanetPyramid(inner, g, topo::LatitudeType::Planetodetic, 1);
  Catalogue outer(kMoon);
  DatasetOptions o = named("inner as one dataset");
  o.heightRange = std::array<double, 2>{-200.0, 800.0};
  outer.add(Dataset::planet(p, o));
  outer.add(Dataset::planet(globalPlanet(kMoon, 1.0, [](double, double) { return -50.0; }),
                            named("flat")));
  const ComposedSurface s(outer.snapshot(), Rules{Policy::FinestWins, 2.0});
  const topo::TopoPlanet direct(g, kMoon, topo::LatitudeType::Planetodetic, p.levels[0].source);
  for (double lat : {4.5, 5.0, 5.3}) {
    for (double lon : {4.2, 5.0, 5.9}) {
      EXPECT_NEAR(s.height(lat, lon).height, direct.height({lat, lon}).height, 1e-9)
          << lat << "," << lon;
    }
  }
  EXPECT_DOUBLE_EQ(s.height(-30.0, 100.0).height, -50.0);
}

TEST(ComposedPyramid, DrawingFrameIsPolarNearAPole) {
  const auto s = moonSurface();
  const DrawingFrame eq = drawingFrame(s, 10.0, 2000.0);
  EXPECT_FALSE(eq.polar);
  EXPECT_FALSE(eq.placement.has_value());
  ASSERT_TRUE(eq.pyramid.planetBody.has_value());
  EXPECT_NEAR(eq.pyramid.levels[0].grid.west(), -180.0, 1e-9);
  EXPECT_NEAR(eq.pyramid.levels[0].grid.north(), 90.0, 1e-9);
  const DrawingFrame south = drawingFrame(s, -70.0, 2000.0);
  ASSERT_TRUE(south.polar);
  ASSERT_NE(south.placement->polarStereographic(), nullptr);
  const topo::TopoGrid& g = south.pyramid.levels[0].grid;
  ASSERT_EQ(g.rows() % 2, 1U);
  // The centre sample is the pole, and its composed height is the pole's.
  const glm::dvec2 c =
      g.sampleCentre(static_cast<double>(g.rows() / 2), static_cast<double>(g.cols() / 2));
  EXPECT_NEAR(c.x, 0.0, 1e-6);
  EXPECT_NEAR(c.y, 0.0, 1e-6);
  const auto& src = dynamic_cast<const ComposedSamples&>(*south.pyramid.levels[0].source);
  EXPECT_NEAR(src.height(g.rows() / 2, g.cols() / 2), s->height(-90.0, 0.0).height, 1e-9);
  // Default spacing: the finest dataset's (100 m).
  EXPECT_NEAR(drawingFrame(s, 80.0).spacingMetres, 100.0, 1e-9);
  EXPECT_THROW((void)drawingFrame(s, 0.0, 1e-3), InvalidArgument);  // 2^32 columns
}

}  // namespace
}  // namespace regolith::compose
