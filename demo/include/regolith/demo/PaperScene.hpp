#pragma once
/// \file
/// The example scene of the JPL paper (section IV.B, figure 10): the Sun, Earth and Mars, the
/// Victoria Crater DEM on Mars, a rover on the DEM and cameras, as a scene graph: the demo
/// scene's layout (scene code lives here, not in the scene-graph module).

#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/scenegraph/SitePose.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/vec3.hpp>

namespace regolith::demo {

/// Drawable keys the paper scene gives its nodes (a renderer maps them to what it draws).
enum PaperDrawable : int {
  kDrawMars = 0,
  kDrawVictoria = 1,
  kDrawEarth = 2,
  kDrawRover = 3,
  kDrawSecondDem = 4,
};

/// Where things are. Lengths in metres, angles in degrees.
struct PaperSceneLayout {
  /// Mars (the body of the planet grid and of the DEM placements).
  topo::Body mars = topo::Body::marsEllipsoid();
  /// Heliocentric distances and ecliptic longitudes of Mars and Earth; Mars's spin angle
  /// (rotation of its body-fixed frame about its pole) and obliquity.
  double marsDistance = 2.279e11, marsLongitudeDeg = 30.0;
  double earthDistance = 1.496e11, earthLongitudeDeg = 75.0;
  double marsSpinDeg = 120.0, marsObliquityDeg = 25.19;
  double earthObliquityDeg = 23.44;
  /// The Victoria DEM: a local tangent plane at this planetodetic origin (the plane's x east,
  /// y north at heading 0, z up). Default: the site store::VictoriaGenerator uses.
  topo::Geodetic victoriaOrigin{-2.05, -5.5, -1400.0};
  double victoriaHeadingDeg = 0.0;
  /// A second DEM on Mars (same kind of placement), if `secondDem`.
  bool secondDem = false;
  topo::Geodetic secondDemOrigin{-2.0, -5.4, -1400.0};
  /// The rover's origin in the Victoria DEM's frame (x east, y north, z up; on the rim).
  glm::dvec3 roverInDem{0.0, -395.0, 8.0};
  double roverHeadingDeg = 0.0;  ///< clockwise from the DEM's +y
};

/// The nodes of a built paper scene.
struct PaperSceneNodes {
  scenegraph::NodeId sun = 0, earth = 0, mars = 0, victoria = 0, secondDem = 0, rover = 0;
  /// Cameras, as demo::paperCameras() declares them for the scene file: one 20 km over
  /// Victoria's origin looking down, the DEM's +y up in the image (north at heading 0; a
  /// child of Mars), the rover's mast camera (child of the rover, 2.1 m up in front of the
  /// mast head, looking ahead and 15° down), a chase camera behind the rover.
  scenegraph::NodeId orbitCamera = 0, mastCamera = 0, chaseCamera = 0;
};

/// Where a planet is in the heliocentric frame: `distance` metres from the Sun at ecliptic
/// longitude `longitudeDeg` (the ecliptic is the x-y plane).
[[nodiscard]] glm::dvec3 heliocentric(double distance, double longitudeDeg);

/// Builds the scene into an empty graph (whose root is taken as the Sun): Sun → Earth,
/// Sun → Mars → Victoria → rover (→ mast and chase cameras), Mars → orbit camera,
/// Mars → second DEM if asked. The bodies' poses are scenegraph::bodyPose()'s and the
/// cameras paperCameras()', as a scene file of demo::sceneDescription() gives them. Throws
/// InvalidArgument if the graph is not empty.
PaperSceneNodes buildPaperScene(scenegraph::SceneGraph& graph, const PaperSceneLayout& layout = {});

}  // namespace regolith::demo
