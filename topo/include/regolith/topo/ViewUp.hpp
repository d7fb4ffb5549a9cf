#pragma once
/// \file
/// The one rule every camera uses for its up vector (clod::Camera, scenegraph::Pose::lookAt).
/// Pure geometry: it lives in topo so that a renderer and the scene graph share it without
/// depending on each other.

#include <glm/vec3.hpp>

namespace regolith::topo {

/// The up vector a view along `forward` uses: `up` itself, unless it is zero, not finite or
/// within 1e-6 rad of parallel to forward (its cross product with forward is then mostly
/// rounding, and the view matrix would be NaN or noise: a camera at nadir, or looking at the
/// body's centre, with the local vertical as up). Then the axis of the frame (x, y or z)
/// most perpendicular to forward, made perpendicular to it. `forward` must be non-zero.
[[nodiscard]] glm::dvec3 viewUp(const glm::dvec3& forward, const glm::dvec3& up) noexcept;

}  // namespace regolith::topo
