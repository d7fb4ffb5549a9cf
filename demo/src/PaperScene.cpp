#include <regolith/core/Assert.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/demo/PaperScene.hpp>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

namespace regolith::demo {

using scenegraph::NodeKind;
using scenegraph::Pose;
using scenegraph::roverPose;
using scenegraph::SceneGraph;
using scenegraph::tangentPlanePose;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace

glm::dvec3 heliocentric(double distance, double longitudeDeg) {
  return distance * glm::dvec3(std::cos(longitudeDeg * kDeg), std::sin(longitudeDeg * kDeg), 0.0);
}

PaperSceneNodes buildPaperScene(SceneGraph& graph, const PaperSceneLayout& layout) {
  if (graph.size() != 1)
    throw InvalidArgument("buildPaperScene(): the graph has " + std::to_string(graph.size()) +
                          " nodes, expected an empty graph (its root only)");
  PaperSceneNodes n;
  n.sun = graph.root();
  // Heliocentric frame: the ecliptic is the x-y plane. A body's pose is the scene file's
  // (scenegraph::bodyPose(), as scene::Scene places bodies): tilted by its obliquity, turned
  // by its spin about its pole.
  n.earth =
      graph.add(n.sun, "earth",
                scenegraph::bodyPose(heliocentric(layout.earthDistance, layout.earthLongitudeDeg),
                                     layout.earthObliquityDeg, 0.0),
                NodeKind::Terrain, kDrawEarth);
  const Pose mars = scenegraph::bodyPose(heliocentric(layout.marsDistance, layout.marsLongitudeDeg),
                                         layout.marsObliquityDeg, layout.marsSpinDeg);
  n.mars = graph.add(n.sun, "mars", mars, NodeKind::Terrain, kDrawMars);
  const Pose victoria =
      tangentPlanePose(layout.mars, layout.victoriaOrigin, layout.victoriaHeadingDeg);
  n.victoria = graph.add(n.mars, "victoria", victoria, NodeKind::Terrain, kDrawVictoria);
  if (layout.secondDem)
    n.secondDem =
        graph.add(n.mars, "second_dem", tangentPlanePose(layout.mars, layout.secondDemOrigin, 0.0),
                  NodeKind::Terrain, kDrawSecondDem);
  n.rover = graph.add(n.victoria, "rover", roverPose(layout.roverInDem, layout.roverHeadingDeg),
                      NodeKind::Object, kDrawRover);
  // The cameras the scene file declares (paperCameras(): orbit, mast, chase, in that order):
  // the mast and chase cameras in the rover's frame, the orbit camera in Victoria's, hung
  // here from Mars through the DEM's pose.
  const std::vector<scene::Camera> cameras = paperCameras();
  const auto pose = [&](std::size_t i, [[maybe_unused]] const char* name) {
    const scene::Camera& c = cameras.at(i);
    REGOLITH_ASSERT(c.name == name, "paperCameras(): orbit, mast, chase");
    return Pose::lookAt({c.eye[0], c.eye[1], c.eye[2]}, {c.lookAt[0], c.lookAt[1], c.lookAt[2]},
                        {c.up[0], c.up[1], c.up[2]});
  };
  n.mastCamera = graph.add(n.rover, "mast_camera", pose(1, "mast_camera"), NodeKind::Camera);
  n.chaseCamera = graph.add(n.rover, "chase_camera", pose(2, "chase_camera"), NodeKind::Camera);
  n.orbitCamera =
      graph.add(n.mars, "orbit_camera", victoria * pose(0, "orbit_camera"), NodeKind::Camera);
  return n;
}

}  // namespace regolith::demo
