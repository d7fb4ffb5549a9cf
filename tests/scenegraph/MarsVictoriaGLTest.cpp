// scenegraph::MarsVictoriaScene and scenegraph::renderFlyover(): the fly-over writes readable PNGs
// from Mars whole down to the rover, switching the focus on the way.
#include <regolith/clod/Image.hpp>
#include <regolith/scenegraph/MarsVictoria.hpp>
#include <regolith/topo/Error.hpp>

#include "clod/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace regolith::scenegraph {
namespace {

MarsVictoriaOptions small() {
  MarsVictoriaOptions o;
  o.planetRows = 180;
  o.demSize = 301;
  o.demSpacing = 4.0;
  o.secondDem = false;
  o.clipmapSize = 63;
  return o;
}

TEST(MarsVictoriaGLTest, FlyoverGoesFromMarsWholeToTheRover) {
  test::glContext();
  const auto dir = std::filesystem::path(::testing::TempDir()) / "regolith_flyover_test";
  std::filesystem::remove_all(dir);
  FlyoverOptions o;
  o.outputDir = dir;
  o.frames = 5;
  o.width = 96;
  o.height = 64;
  o.scene = small();
  int calls = 0;
  o.progress = [&](int done, int all, const std::filesystem::path& p) {
    ++calls;
    EXPECT_EQ(done, calls);
    EXPECT_EQ(all, 5);
    EXPECT_TRUE(std::filesystem::exists(p));
  };
  const FlyoverSummary s = renderFlyover(o);
  EXPECT_EQ(calls, 5);
  ASSERT_EQ(s.files.size(), 6U);  // 5 frames and multiview.png
  EXPECT_GT(s.focusSwitchFrame, 0);
  EXPECT_LT(s.focusSwitchFrame, 5);
  EXPECT_NEAR(s.startDistance, 8.0e6, 1.0);
  EXPECT_NEAR(s.endDistance, 6.0, 0.5);
  const clod::RgbaImage first = clod::readPng(s.files.front().string());
  const clod::RgbaImage last = clod::readPng(s.files[4].string());
  EXPECT_EQ(first.width, 96);
  EXPECT_EQ(first.height, 64);
  // First frame: Mars whole, in the middle, with space in the corners.
  const auto* centre = first.pixel(48, 32);
  EXPECT_GT(centre[0], 60);
  EXPECT_TRUE(first.is(0, 0, 5, 5, 10));  // the background (0.02, 0.02, 0.04)
  // Last frame: the rover (grey: r = g = b) in the middle of the view.
  const auto* rover = last.pixel(48, 32);
  EXPECT_NEAR(rover[0], rover[1], 8);
  EXPECT_NEAR(rover[1], rover[2], 8);
  // Its surroundings are the DEM (green over red).
  const auto* ground = last.pixel(48, 60);
  EXPECT_GT(ground[1], ground[0]);
  std::filesystem::remove_all(dir);
}

TEST(MarsVictoriaGLTest, FlyoverCameraEndsLookingAtTheRover) {
  const glm::dvec3 rover{0.0, -395.0, 5.0};
  for (const double t : {0.0, 0.5, 1.0}) {
    const Pose cam = flyoverCamera(t, rover);
    const glm::dvec3 inEye = cam.inverse().apply(rover + glm::dvec3(0.0, 0.0, 0.8));
    EXPECT_NEAR(inEye.x, 0.0, 1e-6 * glm::length(inEye));
    EXPECT_NEAR(inEye.y, 0.0, 1e-6 * glm::length(inEye));
    EXPECT_LT(inEye.z, 0.0);
  }
}

TEST(MarsVictoriaGLTest, RejectsBadOptions) {
  FlyoverOptions o;
  o.frames = 1;
  EXPECT_THROW(renderFlyover(o), InvalidArgument);
  o.frames = 2;
  o.width = 0;
  EXPECT_THROW(renderFlyover(o), InvalidArgument);
}

}  // namespace
}  // namespace regolith::scenegraph
