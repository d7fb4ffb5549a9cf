// The hand-off between the near-field clipmap and the PGM far field, both drawing one
// composed surface (a catalogue of a global grid and a finer regional DEM): the clipmap is
// drawn first, PGM fills in around it (PgmRenderer::draw(keepDrawn)). Checked per pixel
// against each side drawn alone and against the body's lowest sphere.

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "compose/ComposeFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace regolith::farfield {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

double relief(double lat, double lon) {
  return 1500.0 * std::sin(3.0 * lat * kDeg) * std::cos(5.0 * lon * kDeg) +
         600.0 * std::sin(17.0 * lon * kDeg + 0.3) * std::cos(11.0 * lat * kDeg);
}

/// Distance along the pixel's ray to what the depth image holds there (NaN if nothing).
double alongRay(const clod::Camera& cam, const gl::DepthImage& depth, int x, int y) {
  const float z = depth.at(x, y);
  if (!(z > 0.0F)) return std::nan("");
  return cam.viewDistance(z) / glm::dot(cam.ray(x + 0.5, y + 0.5), cam.forward());
}

TEST(HandOffGL, ClipmapAndFarFieldMeetWithoutGapOrBand) {
  test::glContext();
  const topo::Body mars = topo::Body::marsSphere();
  compose::Catalogue cat(mars);
  compose::DatasetOptions global;
  global.name = "global";
  cat.add(compose::Dataset::planet(compose::testing::globalPlanet(mars, 0.25, relief), global));
  const auto surface = std::make_shared<const compose::ComposedSurface>(cat.snapshot());

  // The far field: layers composed from the catalogue. The near field: a clipmap over a
  // regional grid of the same composed surface around the focus.
  LayerOptions lo;
  lo.equirectWidth = 2048;
  lo.capSize = 256;
  const HeightLayers layers = HeightLayers::fromSurface(*surface, lo);
  const double lat0 = 12.0, lon0 = 40.0, step = 0.02;  // 1.2 km
  const topo::TopoGrid grid(1201, 1201, lon0 - 600 * step, lat0 + 600 * step, step, step);
  clod::ClipmapOptions co;
  co.size = 127;
  co.levels = 2;  // about 300 km across: the far field draws the rest up to the horizon
  const glm::dmat3 enu = mars.enuFrame(lat0, lon0);
  co.lightDirection = glm::vec3(glm::normalize(0.6 * enu[0] + 0.2 * enu[1] + 0.7 * enu[2]));
  clod::ClipmapTerrain clipmap(
      std::make_shared<const clod::HeightPyramid>(compose::composedPlanetPyramid(surface, grid)),
      co);
  PgmOptions po;
  po.gridWidth = po.gridHeight = 512;
  po.heightColours = false;  // the clipmap's albedo and lighting, so the two look alike
  po.high = co.albedo;
  po.ambient = co.ambient;
  po.readback = PrimaryReadback::Fixed;  // the same geometry in every render compared
  PgmRenderer pgm(layers, po);

  const glm::dvec3 focus = mars.toBodyFixed({lat0, lon0, relief(lat0, lon0)});
  clod::Camera cam;
  cam.position = mars.toBodyFixed({lat0 - 0.4, lon0, 60000.0});
  cam.target = mars.toBodyFixed({lat0 + 4.0, lon0, 0.0});
  cam.up = enu[2];
  cam.fovYDegrees = 50.0;
  cam.width = 400;
  cam.height = 300;
  cam.near = 1.0;
  clipmap.setFocus(focus);
  clipmap.finishLoading();
  const glm::dvec3 sun(co.lightDirection);

  gl::RenderTarget target(cam.width, cam.height);
  const auto render = [&](bool near, bool far) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    if (near) clipmap.draw(cam);
    if (far) pgm.draw(target, cam, sun, near);
    return std::pair{target.readColor(), target.readDepth()};
  };
  const auto [farColour, farDepth] = render(false, true);
  const auto [nearColour, nearDepth] = render(true, false);
  const auto [bothColour, bothDepth] = render(true, true);
  test::savePng("handoff_far_only", farColour);
  test::savePng("handoff_near_only", nearColour);
  test::savePng("handoff_both", bothColour);

  int body = 0, holes = 0, nearPixels = 0, farPixels = 0, notNear = 0, notFar = 0;
  std::vector<double> diffs;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const double both = alongRay(cam, bothDepth, x, y);
      const double nearD = alongRay(cam, nearDepth, x, y);
      const double farD = alongRay(cam, farDepth, x, y);
      // Every pixel whose ray meets the lowest sphere sees the body and must be drawn.
      const glm::dvec3 ray = cam.ray(x + 0.5, y + 0.5);
      const double bq = glm::dot(cam.position, ray);
      const double cq = glm::dot(cam.position, cam.position) - pgm.minRadius() * pgm.minRadius();
      if (bq * bq - cq > 0.0 && bq < 0.0) {
        ++body;
        if (std::isnan(both)) ++holes;
      }
      if (!std::isnan(nearD)) {
        ++nearPixels;
        if (both != nearD) ++notNear;  // the clipmap keeps every pixel it drew
        // The data's own difference: the two surfaces' distance along the ray, as the angle
        // it subtends seen from the side (× focal: pixels), where both drew.
        if (!std::isnan(farD)) {
          const glm::dvec3 p = cam.position + nearD * ray;
          const double incidence = std::abs(glm::dot(glm::normalize(p), ray));
          diffs.push_back(std::abs(nearD - farD) * incidence / nearD * cam.focalPixels());
        }
      } else if (!std::isnan(farD)) {
        ++farPixels;
        if (both != farD) ++notFar;  // elsewhere the far field, exactly as it draws alone
      }
    }
  }
  std::sort(diffs.begin(), diffs.end());
  const auto pct = [&](double q) {
    return diffs.empty()
               ? 0.0
               : diffs[static_cast<std::size_t>(q * static_cast<double>(diffs.size() - 1))];
  };
  std::printf(
      "body %d px, holes %d; near %d px (changed %d), far %d px (changed %d); near vs far "
      "surface: median %.3f px, 95th %.3f px, max %.3f px over %zu px\n",
      body, holes, nearPixels, notNear, farPixels, notFar, pct(0.5), pct(0.95),
      diffs.empty() ? 0.0 : diffs.back(), diffs.size());
  EXPECT_GT(nearPixels, cam.width * cam.height / 10);  // the clipmap really draws part of it
  EXPECT_GT(farPixels, cam.width * cam.height / 20);   // and so does the far field
  EXPECT_EQ(holes, 0);
  EXPECT_EQ(notNear, 0);
  EXPECT_EQ(notFar, 0);
  // Where both draw, the two surfaces agree to a fraction of a pixel: no band shows.
  EXPECT_LT(pct(0.95), 0.5);
}

}  // namespace
}  // namespace regolith::farfield
