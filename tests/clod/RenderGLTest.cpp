#include <regolith/clod/Render.hpp>
#include <regolith/topo/Error.hpp>

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

}  // namespace
}  // namespace regolith::clod
