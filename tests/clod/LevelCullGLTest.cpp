// ClipmapOptions::cullLevels: a level whose bounding sphere lies outside the view frustum, or
// on a planet wholly behind the horizon, is left out. Culling must change no pixel: each view
// is drawn by a terrain that culls and by one that does not, and the colour and depth images
// must be equal bit for bit, while the culling terrain does leave levels out (so the views
// test something): the focus on the far side of the planet, at its limb and off to the side
// of a low view, views of the sky from the ground, and a plane DEM seen from beside and above.
//
// One exception, on a planet: a clipmap alone (no far field, no other level on the near side)
// lets the far side show through the body where its own windows leave the near side undrawn.
// Those pixels, whose drawn point lies behind the body's lowest sphere as seen from the eye
// (a ray no real render leaves open), are what horizon culling removes; they are counted, and
// every other pixel must be equal.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace regolith::clod {
namespace {

const double kR = 3396190.0;

glm::dvec3 unit(double latDeg, double lonDeg) { return test::unitDirection(latDeg, lonDeg); }

std::shared_ptr<const HeightPyramid> marsPyramid(std::size_t rows) {
  return test::spherePyramid(rows, [](const glm::dvec3& u) {
    return 4000.0 * std::sin(7.0 * u.x) * std::cos(5.0 * u.y) + 2000.0 * std::sin(4.0 * u.z);
  });
}

struct View {
  std::string name;
  Camera camera;
  glm::dvec3 focus;
};

Camera look(const glm::dvec3& from, const glm::dvec3& at, const glm::dvec3& up) {
  Camera c;
  c.position = from;
  c.target = at;
  c.up = up;
  c.fovYDegrees = 50.0;
  c.width = 160;
  c.height = 120;
  c.near = 1.0;
  return c;
}

// True if the segment from the eye to p passes through the ball of radius r about the origin.
bool behindBall(const glm::dvec3& eye, const glm::dvec3& p, double r) {
  const glm::dvec3 d = p - eye;
  const double t = std::clamp(-glm::dot(eye, d) / glm::dot(d, d), 0.0, 1.0);
  return glm::length(eye + t * d) < r;
}

struct Totals {
  std::size_t culled = 0;      // levels the culling terrain left out
  std::size_t seeThrough = 0;  // pixels showing the far side through the body (not compared)
};

// Draws every view with both terrains; expects equal images, but for the pixels that show
// through a ball of radius `body` (0: none) about the origin.
Totals compare(ClipmapTerrain& culling, ClipmapTerrain& drawingAll, const std::vector<View>& views,
               double body) {
  Totals total;
  for (const View& v : views) {
    gl::RgbaImage colour[2];
    gl::DepthImage depth[2];
    std::size_t levels[2] = {0, 0};
    ClipmapTerrain* terrains[2] = {&culling, &drawingAll};
    for (int t = 0; t < 2; ++t) {
      (void)terrains[t]->setFocus(v.focus);
      gl::RenderTarget target(v.camera.width, v.camera.height);
      target.clear({1.0F, 0.0F, 1.0F, 1.0F});
      const ClipmapFrame f = terrains[t]->draw(v.camera);
      levels[t] = f.levelsDrawn;
      if (t == 0) {
        total.culled += f.levelsCulled;
      } else {
        EXPECT_EQ(f.levelsCulled, 0U) << v.name;
      }
      colour[t] = target.readColor();
      depth[t] = target.readDepth();
    }
    test::savePng("level_cull_" + v.name, colour[0]);
    test::savePng("level_cull_" + v.name + "_all", colour[1]);
    std::size_t differing = 0, through = 0;
    for (int y = 0; y < v.camera.height; ++y) {
      for (int x = 0; x < v.camera.width; ++x) {
        const float z = depth[1].at(x, y);
        if (body > 0.0 && z > 0.0F) {
          const glm::dvec3 ray = v.camera.ray(x + 0.5, y + 0.5);
          const glm::dvec3 p = v.camera.position +
                               v.camera.viewDistance(z) / glm::dot(ray, v.camera.forward()) * ray;
          if (behindBall(v.camera.position, p, body)) {
            ++through;
            continue;
          }
        }
        const auto* a = colour[0].pixel(x, y);
        const auto* b = colour[1].pixel(x, y);
        const bool same =
            a[0] == b[0] && a[1] == b[1] && a[2] == b[2] && a[3] == b[3] && depth[0].at(x, y) == z;
        differing += same ? 0U : 1U;
      }
    }
    EXPECT_EQ(differing, 0U) << v.name;
    EXPECT_LE(levels[0], levels[1]) << v.name;
    total.seeThrough += through;
    std::printf("%-28s levels drawn %zu of %zu, %zu pixels through the body\n", v.name.c_str(),
                levels[0], levels[1], through);
  }
  return total;
}

TEST(LevelCullGL, CullingChangesNoPixelOfAPlanet) {
  test::glContext();
  const auto pyramid = marsPyramid(256);
  ClipmapOptions o;
  o.size = 31;  // 22° at level 0: levels from regional to global
  ClipmapTerrain culling(pyramid, o);
  o.cullLevels = false;
  ClipmapTerrain drawingAll(pyramid, o);

  const glm::dvec3 z(0.0, 0.0, 1.0);
  const glm::dvec3 sub = unit(20.0, 30.0);
  std::vector<View> views;
  // The focus under the camera, and on the far side, at the limb and off to one side.
  const Camera high = look(sub * (kR + 3000e3), glm::dvec3(0.0), z);
  views.push_back({"high_focus_below", high, sub * kR});
  views.push_back({"high_focus_antipode", high, -sub * kR});
  views.push_back({"high_focus_limb", high, unit(20.0, 120.0) * kR});
  const Camera low = look(sub * (kR + 400e3), sub * kR, z);
  views.push_back({"low_focus_off_to_the_side", low, unit(-10.0, 60.0) * kR});
  views.push_back({"low_focus_antipode", low, -sub * kR});
  // Grazing: from 5 km up towards the horizon, the focus below and behind.
  const glm::dvec3 east = glm::normalize(glm::cross(z, sub));
  const Camera grazing = look(sub * (kR + 5e3), sub * (kR + 5e3) + 1e6 * east, sub);
  views.push_back({"grazing_focus_below", grazing, sub * kR});
  views.push_back({"grazing_focus_behind", grazing, unit(20.0, 10.0) * kR});
  // The sky from just above the ground, and from far out looking away.
  views.push_back(
      {"sky_from_the_ground", look(sub * (kR + 10e3), sub * (kR + 1e7), east), sub * kR});
  views.push_back({"away_from_far_out", look(sub * 4.0 * kR, sub * 8.0 * kR, z), sub * kR});
  // The pole and the seam.
  views.push_back({"pole", look(z * (kR + 2000e3), glm::dvec3(0.0), glm::dvec3(1.0, 0.0, 0.0)),
                   unit(70.0, 180.0) * kR});
  views.push_back(
      {"seam", look(unit(0.0, 180.0) * (kR + 800e3), glm::dvec3(0.0), z), unit(0.0, -170.0) * kR});
  // The relief reaches 6 km below the sphere (4000 + 2000 m): nothing drawn lies inside.
  const Totals t = compare(culling, drawingAll, views, kR - 6000.0);
  EXPECT_GT(t.culled, 5U);
}

TEST(LevelCullGL, CullingChangesNoPixelOfAPlaneDem) {
  test::glContext();
  const auto pyramid = test::planePyramid(test::centredGrid(1025, 1025, 1.0), test::hills);
  ClipmapOptions o;
  o.size = 63;
  ClipmapTerrain culling(pyramid, o);
  o.cullLevels = false;
  ClipmapTerrain drawingAll(pyramid, o);
  const glm::dvec3 z(0.0, 0.0, 1.0);
  std::vector<View> views;
  views.push_back({"dem_above", look({0.0, 0.0, -900.0}, {0.0, 1.0, -1400.0}, z), {0.0, 0.0, 0.0}});
  views.push_back(
      {"dem_oblique", look({-300.0, -300.0, -1300.0}, {0.0, 0.0, -1400.0}, z), {0.0, 0.0, 0.0}});
  views.push_back({"dem_focus_aside",
                   look({200.0, 200.0, -1200.0}, {300.0, 300.0, -1400.0}, z),
                   {-400.0, -400.0, 0.0}});
  views.push_back({"dem_looking_away",
                   look({0.0, 0.0, -1300.0}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}),
                   {0.0, 0.0, 0.0}});
  views.push_back({"dem_from_outside",
                   look({-3000.0, 0.0, -1300.0}, {-4000.0, 0.0, -1300.0}, z),
                   {0.0, 0.0, 0.0}});
  const Totals t = compare(culling, drawingAll, views, 0.0);
  EXPECT_GT(t.culled, 2U);
  EXPECT_EQ(t.seeThrough, 0U);
}

}  // namespace
}  // namespace regolith::clod
