// One zoom, no seams: from 10^8 m down to 2 m above a point of Mars and of the Moon, the
// near-field clipmap (levels within 180°), PGM and the ray-cast impostor draw one composed
// surface between them. Every frame: no pixel left undrawn where the body certainly is (the
// ray meets its lowest sphere, and so do the neighbours' rays), nothing non-finite; the far
// frames are the impostor's, the rest PGM's; and at the switch the two agree to the pixel.

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "compose/ComposeFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace regolith::farfield {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

double relief(double lat, double lon) {
  return 2000.0 * std::sin(3.0 * lat * kDeg) * std::cos(5.0 * lon * kDeg) +
         500.0 * std::sin(23.0 * lon * kDeg + 0.3) * std::cos(19.0 * lat * kDeg);
}

struct Counts {
  int body = 0, holes = 0, nonFinite = 0;
};

Counts inspect(const clod::Camera& cam, const gl::DepthImage& depth, double minRadius) {
  Counts c;
  const auto meets = [&](int x, int y) {
    const glm::dvec3 r = cam.ray(x + 0.5, y + 0.5);
    const double b = glm::dot(cam.position, r);
    const double q = glm::dot(cam.position, cam.position) - minRadius * minRadius;
    return b < 0.0 && b * b - q > 0.0;
  };
  for (int y = 1; y + 1 < cam.height; ++y) {
    for (int x = 1; x + 1 < cam.width; ++x) {
      const float z = depth.at(x, y);
      if (!std::isfinite(z)) ++c.nonFinite;
      if (!(meets(x, y) && meets(x - 1, y) && meets(x + 1, y) && meets(x, y - 1) &&
            meets(x, y + 1))) {
        continue;
      }
      ++c.body;
      if (!(z > 0.0F)) ++c.holes;
    }
  }
  return c;
}

void zoom(const topo::Body& body, const std::string& name) {
  test::glContext();
  compose::Catalogue cat(body);
  compose::DatasetOptions o;
  o.name = "global";
  cat.add(compose::Dataset::planet(compose::testing::globalPlanet(body, 0.25, relief), o));
  const auto surface = std::make_shared<const compose::ComposedSurface>(cat.snapshot());
  LayerOptions lo;
  lo.equirectWidth = 1024;
  lo.capSize = 256;
  auto layers = std::make_shared<const HeightLayers>(HeightLayers::fromSurface(*surface, lo));

  const double lat0 = -30.0, lon0 = 179.9;  // by the ±180° seam
  const double step = 0.005;
  const topo::TopoGrid grid(801, 801, lon0 - 400 * step, lat0 + 400 * step, step, step);
  const glm::dmat3 enu = body.enuFrame(lat0, lon0);
  const glm::dvec3 sun = glm::normalize(0.5 * enu[0] + 0.3 * enu[1] + 0.8 * enu[2]);
  clod::ClipmapOptions co;
  co.size = 63;
  co.levels = 3;
  co.lightDirection = glm::vec3(sun);  // one light for both sides
  clod::ClipmapTerrain clipmap(
      std::make_shared<const clod::HeightPyramid>(compose::composedPlanetPyramid(surface, grid)),
      co);
  PgmOptions po;
  po.gridWidth = po.gridHeight = 256;
  po.heightColours = false;
  po.high = co.albedo;
  po.ambient = co.ambient;
  FarField far(layers, po);

  const glm::dvec3 focus = body.toBodyFixed({lat0, lon0, surface->height(lat0, lon0).height});
  clipmap.setFocus(focus);
  clipmap.finishLoading();
  gl::RenderTarget target(160, 120);
  int impostor = 0, pgm = 0;
  double lastImpostor = 0.0, firstPgm = 0.0;
  const int steps = 24;
  for (int i = 0; i <= steps; ++i) {
    const double dist = std::exp(std::log(1e8) + (std::log(2.0) - std::log(1e8)) * i / steps);
    // From above, tilting towards the horizon as the camera comes down.
    const double tilt = std::clamp(1.0 - std::log10(dist) / 7.0, 0.0, 0.8);
    const glm::dvec3 dir = glm::normalize((1.0 - tilt) * enu[2] - tilt * enu[1] + 0.01 * enu[0]);
    clod::Camera cam;
    cam.position = focus + dist * dir;
    cam.target = focus;
    cam.up = enu[1] + enu[2];
    cam.fovYDegrees = 50.0;
    cam.width = 160;
    cam.height = 120;
    cam.near = std::clamp(0.01 * dist, 0.05, 1000.0);
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    clipmap.draw(cam);
    const FarFieldFrame f = far.draw(target, cam, sun, true);
    const gl::DepthImage depth = target.readDepth();
    const Counts c = inspect(cam, depth, far.pgm().minRadius());
    if (f.mode == FarFieldMode::Impostor) {
      ++impostor;
      lastImpostor = dist;
    } else if (f.mode == FarFieldMode::Pgm) {
      ++pgm;
      if (firstPgm == 0.0) firstPgm = dist;
    }
    std::printf("%s %.4g m: %s, body %d px, holes %d\n", name.c_str(), dist,
                f.mode == FarFieldMode::Impostor ? "impostor"
                : f.mode == FarFieldMode::Pgm    ? "pgm"
                                                 : "none",
                c.body, c.holes);
    if (i % 6 == 0) test::savePng("zoom_" + name + "_" + std::to_string(i), target.readColor());
    EXPECT_EQ(c.holes, 0) << name << " at " << dist << " m";
    EXPECT_EQ(c.nonFinite, 0) << name << " at " << dist << " m";
    EXPECT_NE(f.mode, FarFieldMode::None) << name << " at " << dist << " m";
  }
  EXPECT_GT(impostor, 0) << name;
  EXPECT_GT(pgm, 0) << name;
  EXPECT_GT(lastImpostor, firstPgm) << name;  // far frames are the impostor's, then PGM's

  // At the switch: the view just inside (PGM, r_s → 0⁺) and the impostor drawn from the
  // same place agree on coverage to within a pixel at the limb.
  double lo_ = firstPgm, hi = lastImpostor;
  const glm::dvec3 dir = glm::normalize(enu[2] + 0.01 * enu[0]);
  for (int k = 0; k < 60; ++k) {
    const double mid = std::sqrt(lo_ * hi);
    const ReferenceSpheres s = referenceSpheres(
        glm::length(focus + mid * dir), far.pgm().primaryRadius(), far.pgm().maxRadius(), po.zeta);
    (s.secondaryExists() ? lo_ : hi) = mid;
  }
  clod::Camera cam;
  cam.position = focus + lo_ * dir;
  cam.target = focus;
  cam.up = enu[1];
  cam.fovYDegrees = 50.0;
  cam.width = cam.height = 200;
  cam.near = 1000.0;
  gl::RenderTarget a(200, 200), b(200, 200);
  a.clear({0.0F, 0.0F, 0.0F, 1.0F});
  const FarFieldFrame fa = far.draw(a, cam, sun, false);
  ASSERT_EQ(fa.mode, FarFieldMode::Pgm) << name;
  b.clear({0.0F, 0.0F, 0.0F, 1.0F});
  b.bind();
  GlobeBody g;
  g.a = body.equatorialRadius();
  g.b = body.polarRadius();
  (void)far.globe().draw(cam, g, sun);
  const gl::DepthImage da = a.readDepth(), db = b.readDepth();
  int differ = 0;
  for (int y = 1; y + 1 < 199; ++y) {
    for (int x = 1; x + 1 < 199; ++x) {
      const bool pa = da.at(x, y) > 0.0F, pb = db.at(x, y) > 0.0F;
      if (pa == pb) continue;
      bool nearEdge = false;  // within 2 px of the impostor's limb (relief ≤ 1 px there)
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const int xx = std::clamp(x + dx, 0, 199), yy = std::clamp(y + dy, 0, 199);
          nearEdge = nearEdge || (db.at(xx, yy) > 0.0F) != pb;
        }
      }
      differ += nearEdge ? 0 : 1;
    }
  }
  std::printf(
      "%s: switch at %.4g m from the focus; PGM and impostor differ off the limb at %d px\n",
      name.c_str(), lo_, differ);
  EXPECT_EQ(differ, 0) << name;
}

TEST(ZoomGL, MarsFromAHundredMillionMetresToTwo) { zoom(topo::Body::marsEllipsoid(), "mars"); }

TEST(ZoomGL, MoonFromAHundredMillionMetresToTwo) { zoom(topo::Body::moon(), "moon"); }

}  // namespace
}  // namespace regolith::farfield
