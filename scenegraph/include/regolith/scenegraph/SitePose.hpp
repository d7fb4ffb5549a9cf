#pragma once
/// \file
/// Poses of things placed on a body: a DEM's local tangent plane and a rover on a DEM.

#include <regolith/scenegraph/Pose.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/vec3.hpp>

namespace regolith::scenegraph {

/// The pose (DEM frame → body-fixed) of a DEM whose local tangent plane has this
/// planetodetic origin and heading.
[[nodiscard]] Pose tangentPlanePose(const topo::Body& body, const topo::Geodetic& origin,
                                    double headingDeg);

/// The pose of a rover at `position` (DEM frame) with a heading (degrees clockwise from +y),
/// its x forward, y left, z up.
[[nodiscard]] Pose roverPose(const glm::dvec3& position, double headingDeg);

}  // namespace regolith::scenegraph
