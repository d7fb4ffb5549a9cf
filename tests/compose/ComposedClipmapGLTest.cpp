// One surface for the rover and the camera: a clipmap drawing the composed pyramid shows, at
// every pixel, the composed heights the CPU queries answer, across a dataset border and its
// feather. Oracle: the depth buffer, turned back into body-fixed points, against the CPU
// composition at the four level-0 samples around each point (the GPU draws two triangles
// per cell, so its height lies between the two triangulations of the cell).

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Projection.hpp>

#include "compose/ComposeFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace regolith::compose {
namespace {

using testing::demPyramid;
using testing::named;
using testing::planetPyramid;

constexpr double kDeg = std::numbers::pi / 180.0;

/// How far the GPU's height at a pixel lies outside the two triangulations of the CPU-composed
/// samples around it: 0 if between them. `uv` is the point's fractional (col, row) in level
/// 0, `h` its height in the grid's convention, `sag` how far flat facets may sag below the
/// body's curve between samples.
double bracketError(const ComposedSamples& level0, const glm::dvec2& uv, double h,
                    double sag = 0.0) {
  const auto c = static_cast<std::size_t>(uv.x), r = static_cast<std::size_t>(uv.y);
  const double tu = uv.x - static_cast<double>(c), tv = uv.y - static_cast<double>(r);
  const double h00 = level0.height(r, c), h01 = level0.height(r, c + 1);
  const double h10 = level0.height(r + 1, c), h11 = level0.height(r + 1, c + 1);
  const double a = tu >= tv ? h00 + tu * (h01 - h00) + tv * (h11 - h01)
                            : h00 + tv * (h10 - h00) + tu * (h11 - h10);
  const double b = tu + tv <= 1.0 ? h00 + tu * (h01 - h00) + tv * (h10 - h00)
                                  : h11 + (1.0 - tu) * (h10 - h11) + (1.0 - tv) * (h01 - h11);
  return std::max({0.0, std::min(a, b) - sag - h, h - std::max(a, b) - sag});
}

/// Each drawn pixel's body-fixed point, from the depth buffer (nothing for a pixel not drawn).
template <class Visit>
void forEachDrawnPoint(const clod::Camera& cam, const gl::DepthImage& depth, Visit visit) {
  const glm::dvec3 f = cam.forward();
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const float z = depth.at(x, y);
      if (z <= 0.0F) continue;
      const glm::dvec3 ray = cam.ray(x + 0.5, y + 0.5);
      visit(cam.position + (cam.viewDistance(z) / glm::dot(ray, f)) * ray);
    }
  }
}

TEST(ComposedClipmapGLTest, GpuHeightsAreTheCpuCompositionAcrossABorderAndItsFeather) {
  test::glContext();
  const topo::Body mars = topo::Body::marsSphere();
  const double r = mars.equatorialRadius();
  const double lat0 = 18.4, lon0 = 77.5;
  // A coarse regional grid (0.01°, 590 m) and a fine tangent-plane DEM (1 m, 401 × 401)
  // 20 m above it, feathered over 60 m: a wrong composition is off by metres.
  Catalogue cat(mars);
  cat.add(Dataset::planet(planetPyramid(mars, 19.0, 77.0, 0.01, 101, 101,
                                        [](double lat, double lon) {
                                          return -2500.0 +
                                                 30.0 * std::sin(40.0 * lat) * std::cos(30.0 * lon);
                                        }),
                          named("coarse")));
  cat.add(Dataset::dem(demPyramid(1.0, 401, 401,
                                  [](double x, double y) {
                                    return -2480.0 + 5.0 * std::sin(x / 20.0) * std::cos(y / 30.0);
                                  }),
                       topo::Placement(topo::LocalTangentPlane(mars, {lat0, lon0, 0.0})),
                       named("fine", 60.0)));
  const auto surface =
      std::make_shared<const ComposedSurface>(cat.snapshot(), Rules{Policy::FinestWins, 2.0});

  // Render grid: 1e-5° (0.59 m) centred 160 m east of the DEM's origin, so that level 0's
  // window (±59 m) holds the DEM at full weight (x < 140.5 m), its feather and, past its
  // east border (x = 200.5 m), the coarse grid alone.
  const double d = 1e-5;
  const double lonC = lon0 + 160.0 / (r * std::cos(lat0 * kDeg) * kDeg);
  const topo::TopoGrid grid(1025, 1025, lonC - 512 * d, lat0 + 512 * d, d, d);
  const topo::GridPyramid composed = composedPlanetPyramid(surface, grid);
  const auto& level0 = dynamic_cast<const ComposedSamples&>(*composed.levels[0].source);
  const glm::dmat3 enu = mars.enuFrame(lat0, lonC);
  clod::ClipmapOptions options;
  options.lightDirection = glm::vec3(glm::normalize(0.8 * enu[0] + 0.3 * enu[1] + 0.5 * enu[2]));
  clod::ClipmapTerrain terrain(std::make_shared<const clod::HeightPyramid>(composed), options);

  const double hC = surface->height(lat0, lonC).height;
  clod::Camera cam;
  cam.target = mars.toBodyFixed({lat0, lonC, hC});
  cam.position = cam.target + 120.0 * enu[2] - 50.0 * enu[1];
  cam.up = enu[1];
  cam.fovYDegrees = 40.0;
  cam.width = cam.height = 256;
  cam.near = 0.5;
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  terrain.draw(cam);
  const gl::DepthImage depth = target.readDepth();
  test::savePng("composed_clipmap_border", target.readColor());

  int checked = 0, inside = 0, feather = 0, outside = 0;
  double worst = 0.0;
  forEachDrawnPoint(cam, depth, [&](const glm::dvec3& p) {
    const topo::Geodetic g = mars.toGeodetic(p);
    const glm::dvec2 uv = grid.fractionalIndex(g.lonDeg, g.latDeg);
    // Only level 0's inner window (the focus ± 100 samples), where level 0 draws alone.
    if (std::abs(uv.x - 512.0) > 100.0 || std::abs(uv.y - 512.0) > 100.0) return;
    worst = std::max(worst, bracketError(level0, uv, g.height));
    ++checked;
    const auto shares = surface->weights(g.latDeg, g.lonDeg);
    double fine = 0.0;
    for (const Share& sh : shares) fine += sh.id == 2 ? sh.weight : 0.0;
    (fine > 0.999 ? inside : fine > 0.001 ? feather : outside)++;
  });
  std::printf(
      "checked %d pixels (%d on the fine DEM, %d in its feather, %d outside): worst %.2e m\n",
      checked, inside, feather, outside, worst);
  EXPECT_GE(checked, 10000);
  EXPECT_GT(inside, 1000);
  EXPECT_GT(feather, 1000);
  EXPECT_GT(outside, 1000);
  EXPECT_LE(worst, 1e-3);
}

TEST(ComposedClipmapGLTest, PolarCapBlendIsDrawnAsTheCpuComposesIt) {
  // The north pole of a Mars sphere: a 1° global grid (poor at the pole) and a 50 m polar
  // stereographic cap (±4 km) with detail the global grid lacks, feathered over 1.5 km, drawn
  // on drawingFrame()'s polar grid. At every pixel near the pole the GPU's height must lie
  // between the two triangulations of the CPU-composed samples around it.
  test::glContext();
  const topo::Body mars = topo::Body::marsSphere();
  Catalogue cat(mars);
  cat.add(Dataset::planet(testing::globalPlanet(mars, 1.0,
                                                [](double lat, double lon) {
                                                  return 300.0 * std::cos(lat * kDeg) *
                                                         std::sin(3.0 * lon * kDeg);
                                                }),
                          named("global")));
  const auto ps = topo::PolarStereographic::withScaleFactor(
      mars, topo::PolarStereographic::Pole::North, 1.0, 0.0);
  cat.add(Dataset::dem(demPyramid(50.0, 161, 161,
                                  [](double x, double y) {
                                    return 40.0 * std::sin(x / 300.0) * std::cos(y / 400.0) + 20.0;
                                  }),
                       topo::Placement(mars, ps), named("cap", 1500.0)));
  const auto surface = std::make_shared<const ComposedSurface>(cat.snapshot());
  const DrawingFrame frame = drawingFrame(surface, 89.9, 50.0);
  ASSERT_TRUE(frame.polar);
  const topo::Placement& placement = *frame.placement;
  const topo::TopoGrid& grid = frame.pyramid.levels[0].grid;
  const auto& level0 = dynamic_cast<const ComposedSamples&>(*frame.pyramid.levels[0].source);
  const glm::dmat3 enu = mars.enuFrame(90.0, 0.0);
  clod::ClipmapOptions options;
  options.lightDirection = glm::vec3(glm::normalize(0.7 * enu[0] + 0.4 * enu[1] + 0.6 * enu[2]));
  clod::ClipmapTerrain terrain(
      std::make_shared<const clod::HeightPyramid>(frame.pyramid.levels, placement), options);
  clod::Camera cam;
  // Focus 3 km from the pole along x, so level 0's window (±127 samples, ±6.3 km) holds the
  // cap's interior, its feather and the global grid beyond it.
  cam.target = placement.toBodyFixed(3e3, 0.0, surface->height(89.95, 90.0).height);
  cam.position = placement.toBodyFixed(3e3, -6e3, 7e3);
  cam.up = enu[2];
  cam.fovYDegrees = 50.0;
  cam.width = cam.height = 256;
  cam.near = 2.0;
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  terrain.draw(cam);
  const gl::DepthImage depth = target.readDepth();
  test::savePng("composed_clipmap_pole", target.readColor());
  const glm::dvec2 focus = grid.fractionalIndex(3e3, 0.0);
  int checked = 0, cap = 0, feather = 0, global = 0;
  double worst = 0.0;
  // Flat facets between samples 50 m apart sag below the body's curve by 50²/8R.
  const double sag = 50.0 * 50.0 / (8.0 * mars.equatorialRadius());
  forEachDrawnPoint(cam, depth, [&](const glm::dvec3& p) {
    const glm::dvec3 xyh = placement.fromBodyFixed(p);
    const glm::dvec2 uv = grid.fractionalIndex(xyh.x, xyh.y);
    if (std::abs(uv.x - focus.x) > 100.0 || std::abs(uv.y - focus.y) > 100.0) return;
    // Relative to the view distance: the GPU's positions and depths are float32, and this
    // view is 9 km deep (the border test's, 150 m, keeps its errors under 1e-3 m).
    worst = std::max(worst, bracketError(level0, uv, xyh.z, sag) / glm::length(p - cam.position));
    ++checked;
    const double d = std::max(std::abs(xyh.x), std::abs(xyh.y));  // cap edge at 4025 m
    (d < 4025.0 - 1500.0 ? cap : d < 4025.0 ? feather : global)++;
  });
  std::printf(
      "pole: checked %d pixels (%d cap, %d feather, %d global only): worst %.2e of the view "
      "distance\n",
      checked, cap, feather, global, worst);
  EXPECT_GE(checked, 10000);
  EXPECT_GT(cap, 1000);
  EXPECT_GT(feather, 1000);
  EXPECT_GT(global, 1000);
  EXPECT_LE(worst, 1e-6);  // about 8 float32 ulps
}

TEST(ComposedClipmapGLTest, NestedAndOverlappingDemsDrawAsOneSurfaceWithoutCracks) {
  // Any number of DEMs on a planet, drawn as one composed clipmap (no cut-outs, no skirts): a
  // 1 m DEM with a 0.25 m DEM nested inside it, a second 1 m DEM overlapping it at another
  // heading, and three more around them. Every pixel below the horizon is drawn, and level
  // 0's heights are the CPU composition.
  test::glContext();
  const topo::Body mars = topo::Body::marsSphere();
  const double lat0 = -2.0, lon0 = -5.5;
  Catalogue cat(mars);
  cat.add(Dataset::planet(planetPyramid(mars, -1.5, -6.0, 0.01, 101, 101,
                                        [](double lat, double lon) {
                                          return 20.0 * std::sin(50.0 * lat + 30.0 * lon);
                                        }),
                          named("planet")));
  const auto bumps = [](double amplitude, double wave, double h0) {
    return [=](double x, double y) {
      return h0 + amplitude * std::sin(x / wave) * std::cos(y / (1.3 * wave));
    };
  };
  const auto tangent = [&](double east, double north, double heading) {
    const double m = mars.equatorialRadius() * kDeg;
    return topo::Placement(
        topo::LocalTangentPlane(mars, {lat0 + north / m, lon0 + east / m, 0.0}, heading));
  };
  cat.add(Dataset::dem(demPyramid(1.0, 301, 301, bumps(3.0, 15.0, 10.0)), tangent(0.0, 0.0, 0.0),
                       named("A 1 m", 30.0)));
  cat.add(Dataset::dem(demPyramid(0.25, 241, 241, bumps(0.5, 2.0, 11.0)), tangent(-20.0, 10.0, 0.0),
                       named("B 0.25 m inside A", 8.0)));
  cat.add(Dataset::dem(demPyramid(1.0, 201, 201, bumps(2.0, 9.0, 14.0)), tangent(140.0, 40.0, 35.0),
                       named("C 1 m across A's border", 25.0)));
  for (int k = 0; k < 3; ++k) {
    cat.add(Dataset::dem(demPyramid(2.0, 101, 101, bumps(1.0, 20.0, 12.0 + k)),
                         tangent(-180.0 + 90.0 * k, -150.0, 10.0 * k), named("D", 20.0)));
  }
  const auto surface = std::make_shared<const ComposedSurface>(cat.snapshot());
  ASSERT_EQ(surface->snapshot().size(), 7U);
  // Drawn on one latitude/longitude grid at 0.25 m around the DEMs.
  const double d = 0.25 / (mars.equatorialRadius() * kDeg);
  const topo::TopoGrid grid(2049, 2049, lon0 - 1024 * d, lat0 + 1024 * d, d, d);
  const topo::GridPyramid composed = composedPlanetPyramid(surface, grid);
  const auto& level0 = dynamic_cast<const ComposedSamples&>(*composed.levels[0].source);
  const glm::dmat3 enu = mars.enuFrame(lat0, lon0);
  clod::ClipmapOptions options;
  options.lightDirection = glm::vec3(glm::normalize(0.8 * enu[0] + 0.3 * enu[1] + 0.5 * enu[2]));
  clod::ClipmapTerrain terrain(std::make_shared<const clod::HeightPyramid>(composed), options);
  clod::Camera cam;
  cam.target = mars.toBodyFixed({lat0, lon0, surface->height(lat0, lon0).height});
  cam.position = cam.target + 60.0 * enu[2] - 45.0 * enu[1] - 10.0 * enu[0];
  cam.up = enu[2];
  cam.fovYDegrees = 60.0;
  cam.width = cam.height = 256;
  cam.near = 0.5;
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  terrain.draw(cam);
  const gl::DepthImage depth = target.readDepth();
  test::savePng("composed_clipmap_nested", target.readColor());
  // No crack: the view looks down steeply enough that every pixel sees terrain.
  int undrawn = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) undrawn += depth.at(x, y) <= 0.0F ? 1 : 0;
  }
  EXPECT_EQ(undrawn, 0);
  int checked = 0, nested = 0, blended = 0;
  double worst = 0.0;
  forEachDrawnPoint(cam, depth, [&](const glm::dvec3& p) {
    const topo::Geodetic g = mars.toGeodetic(p);
    const glm::dvec2 uv = grid.fractionalIndex(g.lonDeg, g.latDeg);
    if (std::abs(uv.x - 1024.0) > 100.0 || std::abs(uv.y - 1024.0) > 100.0) return;
    worst = std::max(worst, bracketError(level0, uv, g.height));
    ++checked;
    std::size_t sharing = 0;
    for (const Share& sh : surface->weights(g.latDeg, g.lonDeg)) {
      // B and A are one tier (4 times finer: Rules::tierRatio), so inside B's feather B has
      // 16/17 of the weight and A the rest.
      nested += sh.id == 3 && sh.weight > 0.9 ? 1 : 0;
      sharing += sh.weight > 0.001 ? 1 : 0;
    }
    blended += sharing > 1 ? 1 : 0;
  });
  std::printf(
      "nested: checked %d pixels (%d mostly on the 0.25 m DEM, %d blending two or more): worst "
      "%.2e m\n",
      checked, nested, blended, worst);
  EXPECT_GE(checked, 10000);
  EXPECT_GT(nested, 1000);
  EXPECT_GT(blended, 500);
  EXPECT_LE(worst, 1e-3);
}

}  // namespace
}  // namespace regolith::compose
