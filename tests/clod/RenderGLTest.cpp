#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>

#include "GlContext.hpp"
#include "TerrainFixtures.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

namespace regolith::clod {
namespace {

TEST(RenderGLTest, RendersAPngThatShowsTheTerrainWhereTheCameraLooks) {
  test::glContext();
  const auto grid = test::centredGrid(513, 513, 1.0);
  const auto pyramid = test::planePyramid(grid, test::Crater{-1400.0, 120.0, 40.0, 10.0, 40.0});
  // From 300 m south and 200 m up, heading north, pitched down at the crater.
  const glm::dvec3 eye{0.0, -300.0, -1400.0 + 200.0};
  const double pitch = -std::atan2(200.0, 300.0) * 180.0 / M_PI;
  RenderRequest req;
  req.camera = cameraFromHeadingPitch(*pyramid, eye, 0.0, pitch, 40.0, 320, 200);
  EXPECT_NEAR(glm::dot(req.camera.forward(), glm::normalize(glm::dvec3(0, 300, -200))), 1.0, 1e-12);
  req.background = {0.0F, 0.0F, 1.0F, 1.0F};
  const auto path = (std::filesystem::temp_directory_path() / "regolith_render_test.png").string();
  renderToPng(pyramid, req, path);
  const RgbaImage img = readPng(path);
  std::remove(path.c_str());
  test::savePng("render_to_png", img);
  ASSERT_EQ(img.width, 320);
  ASSERT_EQ(img.height, 200);
  EXPECT_FALSE(img.is(160, 100, 0, 0, 255));  // the crater at the centre is terrain
  EXPECT_FALSE(img.is(160, 199, 0, 0, 255));  // the ground below it too
  // Heading east instead: the crater leaves the centre, the terrain stays below.
  req.camera = cameraFromHeadingPitch(*pyramid, eye, 90.0, pitch, 40.0, 320, 200);
  EXPECT_NEAR(req.camera.forward().x, std::cos(pitch * M_PI / 180.0), 1e-12);
  EXPECT_THROW((void)cameraFromHeadingPitch(*pyramid, eye, 0.0, 90.0, 40.0, 320, 200),
               InvalidArgument);
  req.camera.fovYDegrees = 0.0;
  EXPECT_THROW((void)renderImage(pyramid, req), InvalidArgument);
}

TEST(RenderGLTest, CameraLookingAtOrbitsTheTargetAtTheGivenHeadingAndElevation) {
  const auto pyramid =
      test::planePyramid(test::centredGrid(33, 33, 1.0), test::Crater{0.0, 5.0, 1.0, 1.0, 2.0});
  const glm::dvec3 target{3.0, -2.0, 7.0};
  for (const double heading : {0.0, 30.0, 90.0, 200.0}) {
    for (const double elevation : {10.0, 45.0, 89.0, 90.0}) {
      const Camera cam = cameraLookingAt(*pyramid, target, heading, elevation, 50.0, 40.0, 64, 48);
      const double h = heading * M_PI / 180.0, e = elevation * M_PI / 180.0;
      // The camera looks along the heading (x east, y north on a plane), down at elevation.
      const glm::dvec3 expected{std::cos(e) * std::sin(h), std::cos(e) * std::cos(h), -std::sin(e)};
      EXPECT_NEAR(glm::dot(cam.forward(), expected), 1.0, 1e-12) << heading << " " << elevation;
      EXPECT_NEAR(glm::length(cam.position - target), 50.0, 1e-9);
      EXPECT_NEAR(glm::dot(cam.up, cam.forward()), 0.0, 1e-12);  // never degenerate
      const glm::dvec3 p = cam.project(target);  // the target is at the image centre
      EXPECT_NEAR(p.x, 32.0, 1e-9);
      EXPECT_NEAR(p.y, 24.0, 1e-9);
      // A point north of the target is higher in the image (smaller y) unless looking south.
      const glm::dvec3 north = cam.project(target + glm::dvec3(0.0, 1.0, 0.0));
      if (std::cos(h) > 0.1) {
        EXPECT_LT(north.y, p.y);
      }
      if (std::cos(h) < -0.1) {
        EXPECT_GT(north.y, p.y);
      }
    }
  }
  EXPECT_THROW((void)cameraLookingAt(*pyramid, target, 0.0, 0.0, 50.0, 40.0, 64, 48),
               InvalidArgument);
  EXPECT_THROW((void)cameraLookingAt(*pyramid, target, 0.0, 91.0, 50.0, 40.0, 64, 48),
               InvalidArgument);
  EXPECT_THROW((void)cameraLookingAt(*pyramid, target, 0.0, 45.0, -1.0, 40.0, 64, 48),
               InvalidArgument);
}

}  // namespace
}  // namespace regolith::clod
