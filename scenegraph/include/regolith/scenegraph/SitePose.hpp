#pragma once
/// \file
/// Poses of placed things: a body in its parent's frame, a DEM's local tangent plane on a
/// body, and a rover on a DEM.

#include <regolith/scenegraph/Pose.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/vec3.hpp>

namespace regolith::scenegraph {

/// The pose (body-fixed frame → parent) of a body whose centre is at `position` in its
/// parent's frame, tilted by `obliquityDeg` about the parent's x axis, then turned by
/// `spinDeg` about its own pole (z): the scene file's Body::pose (docs/scene-format.md).
[[nodiscard]] Pose bodyPose(const glm::dvec3& position, double obliquityDeg, double spinDeg);

/// The pose (DEM frame → body-fixed) of a DEM whose local tangent plane has this
/// planetodetic origin and heading.
[[nodiscard]] Pose tangentPlanePose(const topo::Body& body, const topo::Geodetic& origin,
                                    double headingDeg);

/// The pose of a rover at `position` (DEM frame) with a heading (degrees clockwise from +y),
/// its x forward, y left, z up.
[[nodiscard]] Pose roverPose(const glm::dvec3& position, double headingDeg);

}  // namespace regolith::scenegraph
