#include <regolith/core/Error.hpp>
#include <regolith/demo/PaperScene.hpp>
#include <regolith/topo/Projection.hpp>

#include <cmath>
#include <numbers>

namespace regolith::demo {

using scenegraph::NodeKind;
using scenegraph::Pose;
using scenegraph::roverPose;
using scenegraph::SceneGraph;
using scenegraph::tangentPlanePose;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Pose rotationAbout(const glm::dvec3& axis, double degrees) {
  Pose p;
  p.rotation = glm::angleAxis(degrees * kDeg, glm::normalize(axis));
  return p;
}

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
  // Heliocentric frame: the ecliptic is the x-y plane.
  const auto orbitPose = [](double distance, double longitudeDeg) {
    Pose p;
    p.translation = heliocentric(distance, longitudeDeg);
    return p;
  };
  Pose earth = orbitPose(layout.earthDistance, layout.earthLongitudeDeg) *
               rotationAbout({1.0, 0.0, 0.0}, layout.earthObliquityDeg);
  n.earth = graph.add(n.sun, "earth", earth, NodeKind::Terrain, kDrawEarth);
  // Mars body-fixed frame: tilted by the obliquity, turned by its spin angle.
  const Pose mars = orbitPose(layout.marsDistance, layout.marsLongitudeDeg) *
                    rotationAbout({1.0, 0.0, 0.0}, layout.marsObliquityDeg) *
                    rotationAbout({0.0, 0.0, 1.0}, layout.marsSpinDeg);
  n.mars = graph.add(n.sun, "mars", mars, NodeKind::Terrain, kDrawMars);
  n.victoria =
      graph.add(n.mars, "victoria",
                tangentPlanePose(layout.mars, layout.victoriaOrigin, layout.victoriaHeadingDeg),
                NodeKind::Terrain, kDrawVictoria);
  if (layout.secondDem)
    n.secondDem =
        graph.add(n.mars, "second_dem", tangentPlanePose(layout.mars, layout.secondDemOrigin, 0.0),
                  NodeKind::Terrain, kDrawSecondDem);
  n.rover = graph.add(n.victoria, "rover", roverPose(layout.roverInDem, layout.roverHeadingDeg),
                      NodeKind::Object, kDrawRover);
  // Rover frame: x forward, y left, z up. Mast camera 2.1 m up, just ahead of the mast head
  // of render::roverMesh(), looking 15° down ahead.
  n.mastCamera =
      graph.add(n.rover, "mast_camera",
                Pose::lookAt({0.85, 0.0, 2.1},
                             {0.85 + std::cos(15.0 * kDeg), 0.0, 2.1 - std::sin(15.0 * kDeg)},
                             {0.0, 0.0, 1.0}),
                NodeKind::Camera);
  n.chaseCamera =
      graph.add(n.rover, "chase_camera",
                Pose::lookAt({-8.0, 0.0, 3.0}, {0.0, 0.0, 0.5}, {0.0, 0.0, 1.0}), NodeKind::Camera);
  // Orbit camera: 20 km above Victoria, looking straight down, north up in the image.
  const topo::LocalTangentPlane site(layout.mars, layout.victoriaOrigin, 0.0);
  const glm::dvec3 above = site.toBodyFixed({0.0, 0.0, 20e3});
  n.orbitCamera =
      graph.add(n.mars, "orbit_camera", Pose::lookAt(above, site.originBodyFixed(), site.yAxis()),
                NodeKind::Camera);
  return n;
}

}  // namespace regolith::demo
