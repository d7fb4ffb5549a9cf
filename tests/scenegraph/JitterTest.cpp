// Screen-space jitter of the rover and nearby terrain vertices as the rover moves across
// Victoria in 1 mm steps, for naive float32 pipelines and the re-rooted one (issue 6).
#include <regolith/core/Error.hpp>
#include <regolith/demo/PaperScene.hpp>
#include <regolith/scenegraph/Jitter.hpp>

#include <gtest/gtest.h>

#include <cstdio>

namespace regolith::scenegraph {
namespace {

using demo::buildPaperScene;
using demo::PaperSceneLayout;
using demo::PaperSceneNodes;

struct RoverRun {
  SceneGraph graph{"sun"};
  PaperSceneLayout layout;
  PaperSceneNodes nodes;
  std::vector<TrackedPoint> points;
  glm::dvec3 start{0.0};

  explicit RoverRun(glm::dvec3 s) : start(s) {
    layout.roverInDem = s;
    nodes = buildPaperScene(graph, layout);
    // Rover body corners and mast head (rover frame), and DEM vertices on the 1 m grid
    // ahead of the rover (DEM frame), all in the chase camera's view.
    for (const glm::dvec3 p : {glm::dvec3(0.8, 0.6, 0.2), glm::dvec3(-0.8, -0.6, 0.2),
                               glm::dvec3(0.3, 0.0, 1.5), glm::dvec3(0.0, 0.0, 0.0)})
      points.push_back({nodes.rover, p});
    for (int dy = 2; dy <= 12; dy += 2)
      for (int dx = -3; dx <= 3; dx += 2)
        points.push_back({nodes.victoria, glm::round(s) + glm::dvec3(dx, dy, -0.3)});
  }

  JitterResult run(Pipeline pipeline, NodeId focus, NodeId world, std::size_t frames) {
    return measureJitter(
        graph, nodes.chaseCamera, focus, world, pipeline, points, frames,
        [this](SceneGraph& g, std::size_t i) {
          // 1 mm per frame along the rover's heading (+y of the DEM: towards the centre).
          g.setLocal(nodes.rover,
                     roverPose(start + glm::dvec3(0.0, 0.001 * static_cast<double>(i), 0.0), 0.0));
        });
  }
};

void print(const JitterResult& r) {
  std::printf("  %-40s jitter %12.6g px  error %12.6g px  lost %zu\n", r.name.c_str(), r.jitterPx,
              r.errorPx, r.lost);
}

TEST(JitterTest, RerootedStaysBelowOneHundredthOfAPixelNaiveDoesNot) {
  // On the rim (y = −395 m) and 550 m out in the corner of the DEM, 400 frames each.
  for (const glm::dvec3 start : {glm::dvec3(0.0, -395.0, 8.0), glm::dvec3(550.0, 550.0, 1.0)}) {
    RoverRun run(start);
    const std::size_t frames = 400;
    const JitterResult sun = run.run(Pipeline::NaiveWorld, run.nodes.sun, run.nodes.sun, frames);
    const JitterResult mars = run.run(Pipeline::NaiveWorld, run.nodes.mars, run.nodes.mars, frames);
    const JitterResult rerooted =
        run.run(Pipeline::Rerooted, run.nodes.victoria, run.nodes.sun, frames);
    const JitterResult rover = run.run(Pipeline::Rerooted, run.nodes.rover, run.nodes.sun, frames);
    std::printf("rover from (%.0f, %.0f) m, %zu frames of 1 mm, %zu points:\n", start.x, start.y,
                frames, run.points.size());
    for (const auto& r : {sun, mars, rerooted, rover}) print(r);
    EXPECT_LT(rerooted.jitterPx, 0.01);
    EXPECT_LT(rerooted.errorPx, 0.01);
    EXPECT_EQ(rerooted.lost, 0U);
    EXPECT_LT(rover.jitterPx, 0.01);
    // The naive Sun-rooted pipeline cannot even place the scene: float spacing at 2.3e11 m
    // is 16 km, so the camera and everything near it collapse.
    EXPECT_TRUE(sun.lost > 0 || sun.jitterPx > 100.0) << sun.jitterPx;
    // Body-fixed float (spacing 0.25 m at 3.4e6 m) still jitters by whole pixels.
    EXPECT_GT(mars.jitterPx, 1.0);
  }
}

TEST(JitterTest, RejectsBadIntrinsics) {
  RoverRun run({0.0, -395.0, 8.0});
  JitterCamera bad;
  bad.fovYDegrees = 0.0;
  EXPECT_THROW(measureJitter(
                   run.graph, run.nodes.chaseCamera, run.nodes.victoria, run.nodes.sun,
                   Pipeline::Rerooted, run.points, 2, [](SceneGraph&, std::size_t) {}, bad),
               InvalidArgument);
}

}  // namespace
}  // namespace regolith::scenegraph
