#pragma once
/// \file
/// A rigid transform in double precision: the edge of a scene graph.

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

namespace regolith::scenegraph {

/// A rigid transform from a child frame to its parent frame: p_parent = rotation · p_child +
/// translation. Metres and unit quaternions, double. Value type; every member is pure.
struct Pose {
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};  ///< unit quaternion (w, x, y, z)

  /// The identity.
  [[nodiscard]] static Pose identity() noexcept { return {}; }
  /// A pose whose rotation has the given columns: the child's x, y, z axes expressed in the
  /// parent frame (orthonormal, right-handed), and whose origin is at `origin` (parent).
  [[nodiscard]] static Pose fromAxes(const glm::dvec3& origin, const glm::dvec3& xAxis,
                                     const glm::dvec3& yAxis, const glm::dvec3& zAxis);
  /// A camera pose (GL eye convention: the camera looks along its −z, +y is up in the
  /// image) at `eye` looking at `target` with `up` roughly up, all in the parent frame.
  /// An `up` within 1e-6 rad of the view direction (a camera at nadir, or looking at the
  /// body's centre, with the local vertical as up) is replaced as topo::viewUp() says. Throws
  /// InvalidArgument if eye = target.
  [[nodiscard]] static Pose lookAt(const glm::dvec3& eye, const glm::dvec3& target,
                                   const glm::dvec3& up);
  /// A child-frame point in the parent frame.
  [[nodiscard]] glm::dvec3 apply(const glm::dvec3& p) const noexcept {
    return rotation * p + translation;
  }
  /// A child-frame direction in the parent frame.
  [[nodiscard]] glm::dvec3 applyVector(const glm::dvec3& v) const noexcept { return rotation * v; }
  /// The rotation as a matrix (columns: the child's axes in the parent frame).
  [[nodiscard]] glm::dmat3 matrix() const noexcept { return glm::mat3_cast(rotation); }
  /// The parent → child transform.
  [[nodiscard]] Pose inverse() const noexcept;
};

/// Composition: (a * b) applies b, then a (a: middle → outer, b: inner → middle).
[[nodiscard]] Pose operator*(const Pose& a, const Pose& b) noexcept;

}  // namespace regolith::scenegraph
