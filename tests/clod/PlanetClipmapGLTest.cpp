// Clipmaps over a spheroid: a global latitude/longitude grid on the Mars sphere, seen over
// the north pole, the south pole and the ±180° meridian, with the focus moving across both.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace regolith::clod {
namespace {

const glm::vec4 kMagenta{1.0F, 0.0F, 1.0F, 1.0F};
const double kR = 3396190.0;
// Bounds on |rendered radius − true radius|. Near the focus level 0 draws (0.35° cells:
// chord sag 16 m, linear interpolation of the 400 m ripple ~20 m); farther out level 3
// (2.8° cells of 2×2-averaged samples: chord sag 1 km, ripple smoothed away) may draw.
// A stretched or misplaced triangle is off by tens of kilometres.
const double kNearBound = 60.0;
const double kFarBound = 1200.0;

/// Heights (m) as a smooth function of the unit body-fixed direction: continuous across the
/// seam and over the poles by construction.
double relief(const glm::dvec3& u) {
  return 3000.0 * std::sin(8.0 * u.x) * std::cos(6.0 * u.y) + 1500.0 * std::sin(5.0 * u.z) +
         400.0 * std::sin(40.0 * u.x + 30.0 * u.z);
}

glm::dvec3 unit(double latDeg, double lonDeg) { return test::unitDirection(latDeg, lonDeg); }

std::shared_ptr<const HeightPyramid> marsPyramid(std::size_t rows) {
  return test::spherePyramid(rows, relief);
}

struct Check {
  int disk = 0;            // pixels whose ray meets the sphere below the lowest terrain
  int holes = 0;           // of those, pixels left at the clear colour
  double worst = 0.0;      // largest |rendered radius − (R + relief)| over drawn pixels, m
  double worstNear = 0.0;  // the same within 8° of the focus (level 0's 0.35° cells)
};

/// Renders and checks every pixel: inside the disk nothing may stay magenta, and each drawn
/// pixel's surface point (from depth) must lie on the relief surface.
Check renderAndCheck(ClipmapTerrain& terrain, const Camera& cam, const std::string& png) {
  const glm::dvec3 focus = glm::normalize(cam.target);
  // A low sun from the local east of the focus, so the relief shows in the pictures.
  ClipmapOptions opt = terrain.options();
  glm::dvec3 east = glm::cross(glm::dvec3(0.0, 0.0, 1.0), focus);
  if (glm::length(east) < 1e-6) east = {0.0, 1.0, 0.0};
  opt.lightDirection = glm::vec3(glm::normalize(0.35 * focus + glm::normalize(east)));
  terrain.setOptions(opt);
  gl::RenderTarget target(cam.width, cam.height);
  target.clear(kMagenta);
  terrain.draw(cam);
  const gl::RgbaImage color = target.readColor();
  const gl::DepthImage depth = target.readDepth();
  test::savePng(png, color);
  Check c;
  const double inner = kR - 5000.0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
      const double b = glm::dot(cam.position, d);
      const double disc = b * b - (glm::dot(cam.position, cam.position) - inner * inner);
      const bool inDisk = disc > 0.0 && -b - std::sqrt(disc) > 0.0;
      const float z = depth.at(x, y);
      if (inDisk) {
        ++c.disk;
        if (color.is(x, y, 255, 0, 255)) ++c.holes;
      }
      if (z <= 0.0F) continue;
      const glm::dvec3 p = cam.position + cam.viewDistance(z) / glm::dot(d, cam.forward()) * d;
      const double err = std::abs(glm::length(p) - (kR + relief(glm::normalize(p))));
      c.worst = std::max(c.worst, err);
      if (glm::dot(glm::normalize(p), focus) > std::cos(8.0 * M_PI / 180.0))
        c.worstNear = std::max(c.worstNear, err);
    }
  return c;
}

Camera orbitCamera(double latDeg, double lonDeg, double altitude) {
  Camera cam;
  cam.position = unit(latDeg, lonDeg) * (kR + altitude);
  cam.target = unit(latDeg, lonDeg) * kR;
  // Up: towards the north pole, or along +x when looking straight down a pole.
  cam.up = std::abs(latDeg) > 89.0 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0);
  cam.fovYDegrees = 60.0;
  cam.width = 320;
  cam.height = 320;
  cam.near = 100.0;
  return cam;
}

ClipmapOptions planetOptions() {
  ClipmapOptions opt;
  opt.size = 63;  // 22° of latitude at level 0: several levels and their seams in view
  opt.lightDirection = {0.3F, 0.5F, 0.8F};
  return opt;
}

TEST(PlanetClipmapGLTest, OverThePolesNoHoleNoStretchedTriangle) {
  test::glContext();
  const auto pyramid = marsPyramid(512);
  ClipmapTerrain terrain(pyramid, planetOptions());
  for (const double lat : {90.0, -90.0}) {
    // Looking straight down on the pole, then obliquely across it.
    Camera cam = orbitCamera(lat, 30.0, 900e3);
    terrain.setFocus(cam.target);
    const std::string name = lat > 0 ? "north" : "south";
    const Check top = renderAndCheck(terrain, cam, "planet_pole_" + name + "_top");
    EXPECT_GT(top.disk, 30000);
    EXPECT_EQ(top.holes, 0) << name;
    EXPECT_LT(top.worstNear, kNearBound) << name;
    EXPECT_LT(top.worst, kFarBound) << name;

    cam.position = unit(lat > 0 ? 70.0 : -70.0, 200.0) * (kR + 600e3);
    cam.target = unit(lat, 0.0) * kR;
    cam.up = unit(0.0, 0.0) * 0.0 + glm::dvec3(0.0, 0.0, lat > 0 ? 1.0 : -1.0);
    const Check oblique = renderAndCheck(terrain, cam, "planet_pole_" + name + "_oblique");
    EXPECT_EQ(oblique.holes, 0) << name;
    EXPECT_LT(oblique.worstNear, kNearBound) << name;
    EXPECT_LT(oblique.worst, kFarBound) << name;
    std::printf("%s pole: radius error near/all %.1f/%.1f m (top), %.1f/%.1f m (oblique)\n",
                name.c_str(), top.worstNear, top.worst, oblique.worstNear, oblique.worst);
  }
}

TEST(PlanetClipmapGLTest, TheSeamIsInvisibleAndTheFocusCrossesIt) {
  test::glContext();
  const auto pyramid = marsPyramid(512);
  ClipmapTerrain terrain(pyramid, planetOptions());
  // Fly along the equator across ±180° and then over the north pole.
  const double path[][2] = {{0.0, 170.0},   {0.0, 176.0},   {0.0, 180.0},
                            {0.0, -176.0},  {20.0, -171.0}, {60.0, -171.0},
                            {85.0, -171.0}, {89.0, 9.0},    {80.0, 9.0}};
  int step = 0;
  for (const auto& ll : path) {
    Camera cam = orbitCamera(ll[0], ll[1], 700e3);
    cam.position = unit(ll[0] - 8.0, ll[1] + 3.0) * (kR + 700e3);
    terrain.setFocus(cam.target);
    const Check c = renderAndCheck(terrain, cam, "planet_path_" + std::to_string(step));
    EXPECT_EQ(c.holes, 0) << "step " << step;
    EXPECT_LT(c.worstNear, kNearBound) << "step " << step;
    EXPECT_LT(c.worst, kFarBound) << "step " << step;
    std::printf("step %d: radius error near/all %.1f/%.1f m\n", step, c.worstNear, c.worst);
    ++step;
  }
}

}  // namespace
}  // namespace regolith::clod
