// Does PGM still need the paper's near/far two-pass rasterisation (§6)? The paper had a
// 24-bit fixed-point depth buffer; Regolith uses reversed-Z float depth with an infinite far
// plane (gl::RenderTarget, clod::Camera). Two shells δ apart (δ = 1e-6 of the distance) are
// drawn in either order in one pass each, at Earth and Mars scale: the outer shell must win
// everywhere both cover, whichever is drawn first.

#include <regolith/clod/Camera.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace regolith::farfield {
namespace {

struct Case {
  const char* name;
  topo::Body body;
  glm::dvec3 position, target, up;
  double delta;  ///< metres between the shells
};

TEST(DepthPrecisionGL, OnePassResolvesOneMillionthOfTheDistanceAtPlanetScale) {
  test::glContext();
  const topo::Body earth = topo::Body::earthWgs84();
  const topo::Body mars = topo::Body::marsEllipsoid();
  const double re = earth.equatorialRadius(), rm = mars.equatorialRadius();
  const glm::dmat3 enu = earth.enuFrame(30.0, 10.0);
  const glm::dvec3 low = earth.toBodyFixed({30.0, 10.0, 400e3});
  // δ: 1e-6 of the distance to the centre from 3 R; from 400 km up, 1 m (2.5e-6 of the
  // nearest ground, 4e-7 of the horizon 2300 km away).
  const Case cases[] = {
      {"earth_global",
       earth,
       {3.0 * re, 0.0, 0.0},
       {0.0, 0.0, 0.0},
       {0.0, 0.0, 1.0},
       3.0 * re * 1e-6},
      {"earth_low_orbit", earth, low, low + enu[1] - 0.2 * enu[2], enu[2], 1.0},
      {"mars_global",
       mars,
       {0.0, -3.0 * rm, 1.0e6},
       {0.0, 0.0, 0.0},
       {0.0, 0.0, 1.0},
       3.0 * rm * 1e-6},
  };
  for (const Case& c : cases) {
    clod::Camera cam;
    cam.position = c.position;
    cam.target = c.target;
    cam.up = c.up;
    cam.width = 256;
    cam.height = 256;
    cam.near = 1.0;
    const double delta = c.delta;
    LayerOptions lo;
    lo.equirectWidth = 256;
    lo.capSize = 64;
    const HeightLayers inner = HeightLayers::build(
        c.body, [](double, double, double) { return 0.0; }, lo);
    const HeightLayers outer = HeightLayers::build(
        c.body, [delta](double, double, double) { return delta; }, lo);
    PgmOptions po;
    po.gridWidth = po.gridHeight = 1024;
    po.readback = PrimaryReadback::Fixed;
    po.heightColours = false;
    po.ambient = 1.0F;  // flat colours: red inner, green outer
    po.high = {1.0F, 0.0F, 0.0F};
    PgmRenderer red(inner, po);
    po.high = {0.0F, 1.0F, 0.0F};
    PgmRenderer green(outer, po);
    gl::RenderTarget target(cam.width, cam.height);
    const glm::dvec3 sun(1.0, 0.0, 0.0);
    for (const bool outerFirst : {false, true}) {
      target.clear({0.0F, 0.0F, 0.0F, 1.0F});
      if (outerFirst) {
        green.draw(target, cam, sun);
        red.draw(target, cam, sun);
      } else {
        red.draw(target, cam, sun);
        green.draw(target, cam, sun);
      }
      const gl::RgbaImage img = target.readColor();
      test::savePng(std::string("depth_") + c.name + (outerFirst ? "_outer_first" : "_inner_first"),
                    img);
      int green_ = 0, red_ = 0;
      for (int y = 1; y + 1 < cam.height; ++y) {
        for (int x = 1; x + 1 < cam.width; ++x) {
          // Inner pixels of the body only (its four neighbours drawn too): not the limb,
          // where the outer shell alone is visible anyway.
          bool interior = true;
          for (const auto& [dx, dy] : {std::pair{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
            const auto* p = img.pixel(x + dx, y + dy);
            interior = interior && (p[0] > 128 || p[1] > 128);
          }
          if (!interior) continue;
          const auto* p = img.pixel(x, y);
          (p[1] > 128 ? green_ : red_)++;
        }
      }
      std::printf(
          "%s, %s drawn first: shells %.3g m apart, eye %.3g m from the centre: outer "
          "shell %d px, inner %d px\n",
          c.name, outerFirst ? "outer" : "inner", delta, glm::length(c.position), green_, red_);
      EXPECT_GT(green_, 5000) << c.name;
      EXPECT_EQ(red_, 0) << c.name << (outerFirst ? " outer first" : " inner first");
    }
  }
}

}  // namespace
}  // namespace regolith::farfield
