// Precision at planetary radius: positions reach the GPU only relative to the camera
// (level anchors minus the camera in double), so a 1 mm camera move at Mars radius moves
// the rendered surface by 1 mm, not by float noise (float spacing is 0.25 m at 3.4e6 m).

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace regolith::clod {
namespace {

TEST(ClipmapPrecisionGLTest, OneMillimetreAtMarsRadiusMovesTheSurfaceOneMillimetre) {
  test::glContext();
  const topo::Body mars = topo::Body::marsSphere();
  // A 1025² regional grid of 1e-5° (0.59 m) samples at Jezero, flat at −2500 m.
  const double d = 1e-5, lat0 = 18.4, lon0 = 77.5;
  const topo::TopoGrid grid(1025, 1025, lon0 - 512 * d, lat0 + 512 * d, d, d);
  auto samples = std::make_shared<topo::InMemorySamples>(1025, 1025,
                                                         std::vector<float>(1025 * 1025, -2500.0F));
  const auto pyramid = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, SurfaceKind::Planet, mars));
  ClipmapTerrain terrain(pyramid, ClipmapOptions{});

  const glm::dmat3 enu = mars.enuFrame(lat0, lon0);
  Camera cam;
  cam.target = mars.toBodyFixed({lat0, lon0, -2500.0});
  cam.position = mars.toBodyFixed({lat0, lon0, -2500.0 + 50.0});
  cam.up = enu[1];
  cam.fovYDegrees = 40.0;
  cam.width = cam.height = 200;
  cam.near = 0.05;
  terrain.setFocus(cam.target);
  ASSERT_GT(glm::length(cam.position), 3.39e6);

  gl::RenderTarget target(cam.width, cam.height);
  const auto shoot = [&](const Camera& c) {
    target.clear({1.0F, 0.0F, 1.0F, 1.0F});
    terrain.draw(c);
    return std::pair{target.readDepth(), target.readColor()};
  };
  const auto [depth0, color0] = shoot(cam);
  test::savePng("precision_mars_50m", color0);

  // Down the view axis by 1 mm: every pixel's view distance to the (locally flat) surface
  // shrinks by 1 mm (the sphere's curvature changes that by < 1 µm over this footprint).
  Camera down = cam;
  down.position = cam.position + cam.forward() * 1e-3;
  down.target = cam.target + cam.forward() * 1e-3;
  const auto [depth1, color1] = shoot(down);
  double sum = 0.0, worst = 0.0;
  int n = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      ASSERT_GT(depth0.at(x, y), 0.0F);
      ASSERT_GT(depth1.at(x, y), 0.0F);
      const double moved = cam.viewDistance(depth0.at(x, y)) - down.viewDistance(depth1.at(x, y));
      sum += moved;
      worst = std::max(worst, std::abs(moved - 1e-3));
      ++n;
    }
  std::printf("1 mm down: mean %.4f mm, worst deviation %.4f mm\n", sum / n * 1e3, worst * 1e3);
  EXPECT_NEAR(sum / n, 1e-3, 5e-6);
  EXPECT_LT(worst, 5e-5);  // float noise at this radius would be ±125 mm

  // Sideways by 1 mm: 1 mm · f / 50 m = 0.011 px. Depths stay within 0.1 mm, and colours
  // barely change (a handful of pixels on rounding edges at most).
  Camera side = cam;
  const glm::dvec3 right = glm::transpose(cam.rotation())[0];
  side.position = cam.position + right * 1e-3;
  side.target = cam.target + right * 1e-3;
  const auto [depth2, color2] = shoot(side);
  double worstSide = 0.0;
  int changed = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      worstSide = std::max(worstSide, std::abs(cam.viewDistance(depth0.at(x, y)) -
                                               side.viewDistance(depth2.at(x, y))));
      const auto* a = color0.pixel(x, y);
      const auto* b = color2.pixel(x, y);
      if (std::abs(a[0] - b[0]) > 1 || std::abs(a[1] - b[1]) > 1 || std::abs(a[2] - b[2]) > 1)
        ++changed;
    }
  std::printf("1 mm sideways: worst depth change %.4f mm, %d pixels changed colour\n",
              worstSide * 1e3, changed);
  EXPECT_LT(worstSide, 1e-4);
  EXPECT_LT(changed, cam.width * cam.height / 1000);
}

}  // namespace
}  // namespace regolith::clod
