#include <regolith/scenegraph/SitePose.hpp>
#include <regolith/topo/Projection.hpp>

#include <cmath>
#include <numbers>

namespace regolith::scenegraph {

Pose bodyPose(const glm::dvec3& position, double obliquityDeg, double spinDeg) {
  constexpr double deg = std::numbers::pi / 180.0;
  Pose p;
  p.translation = position;
  p.rotation = glm::angleAxis(obliquityDeg * deg, glm::dvec3(1.0, 0.0, 0.0)) *
               glm::angleAxis(spinDeg * deg, glm::dvec3(0.0, 0.0, 1.0));
  return p;
}

Pose tangentPlanePose(const topo::Body& body, const topo::Geodetic& origin, double headingDeg) {
  const topo::LocalTangentPlane plane(body, origin, headingDeg);
  return Pose::fromAxes(plane.originBodyFixed(), plane.xAxis(), plane.yAxis(), plane.zAxis());
}

Pose roverPose(const glm::dvec3& position, double headingDeg) {
  // Heading clockwise from +y (north at heading 0): forward = (sin h, cos h, 0).
  const double h = headingDeg * (std::numbers::pi / 180.0);
  const glm::dvec3 fwd{std::sin(h), std::cos(h), 0.0};
  const glm::dvec3 up{0.0, 0.0, 1.0};
  return Pose::fromAxes(position, fwd, glm::cross(up, fwd), up);
}

}  // namespace regolith::scenegraph
