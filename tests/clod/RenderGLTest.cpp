#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>

#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

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
  const gl::RgbaImage img = gl::readPng(path);
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

// Issue 16 item 9: cameras whose up (the local vertical) is parallel to the view direction,
// at nadir, aimed at the body's centre, above a pole, and one at 1e12 m; and one at
// R + 1 mm looking at the horizon. Each renders the planet: no NaN view matrix, so no empty
// image (the pixels that are terrain are counted against the background).
TEST(RenderGLTest, CamerasAtNadirAtThePoleAndFarAwayRenderThePlanet) {
  test::glContext();
  const std::size_t rows = 128, cols = 256;
  const double d = 180.0 / static_cast<double>(rows);
  const topo::TopoGrid grid(rows, cols, -180.0 + 0.5 * d, 90.0 - 0.5 * d, d, d);
  auto samples = topo::InMemorySamples::fromFunction(rows, cols, [](std::size_t r, std::size_t c) {
    return static_cast<float>((r + c) % 7) * 50.0F;
  });
  const auto pyramid = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, SurfaceKind::Planet, topo::Body::marsSphere()));
  const double r = topo::Body::marsSphere().equatorialRadius();
  struct View {
    const char* name;
    glm::dvec3 eye, target;
    double fov;
    double minTerrain;  // fraction of the image that must be terrain
  };
  const glm::dvec3 site = pyramid->position(20.0, 10.0, 0.0);
  const glm::dvec3 above = pyramid->position(20.0, 10.0, 1e6);
  const glm::dvec3 pole = pyramid->position(0.0, 90.0, 1e6);
  const glm::dvec3 low = pyramid->position(20.0, 10.0, 3000.0 + 0.001);  // above every sample
  const glm::dvec3 north = glm::normalize(pyramid->position(20.0, 10.1, 3000.0) - low);
  const glm::dvec3 far = 1e12 * glm::normalize(above);
  const std::vector<View> views = {
      {"nadir", above, site, 40.0, 0.99},
      {"body_centre", above, glm::dvec3(0.0), 40.0, 0.99},
      {"pole", pole, glm::dvec3(0.0), 40.0, 0.99},
      {"horizon_at_R_plus_1mm", low, low + 1000.0 * north, 60.0, 0.05},
      {"far_1e12m", far, glm::dvec3(0.0), 4.0 * r / 1e12 * 180.0 / M_PI, 0.05},
  };
  for (const View& v : views) {
    RenderRequest req;
    req.camera.position = v.eye;
    req.camera.target = v.target;
    req.camera.up = pyramid->up(v.eye);  // parallel to the view in all but the horizon view
    req.camera.fovYDegrees = v.fov;
    req.camera.width = 64;
    req.camera.height = 48;
    req.camera.near = std::max(0.05, 1e-3 * glm::length(v.target - v.eye));
    req.clipmap.size = 257;  // a window of 360° at this grid's 1.40625°, all round the pole
    req.background = {0.0F, 0.0F, 1.0F, 1.0F};
    const gl::RgbaImage img = renderImage(pyramid, req);
    test::savePng(std::string("edge_camera_") + v.name, img);
    int terrain = 0;
    for (int y = 0; y < img.height; ++y) {
      for (int x = 0; x < img.width; ++x) terrain += img.is(x, y, 0, 0, 255) ? 0 : 1;
    }
    EXPECT_GE(terrain, static_cast<int>(v.minTerrain * img.width * img.height)) << v.name;
  }
}

}  // namespace
}  // namespace regolith::clod
