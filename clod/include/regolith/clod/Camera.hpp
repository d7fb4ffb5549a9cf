#pragma once
/// \file
/// A perspective camera in double precision with a reversed-Z projection.

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace regolith::clod {

/// A pinhole camera. Position, target and up are in the scene's frame, in metres, double:
/// for a DEM the grid frame (x east, y north, z = height), for a planet the body-fixed
/// frame. The GPU gets only camera-relative float data: viewProjection() maps a position
/// minus `position` to clip space.
///
/// Projection: reversed Z with an infinite far plane, so the depth buffer holds
/// near / (distance along the view axis): 1 at the near plane, 0 at infinity. Value type.
struct Camera {
  glm::dvec3 position{0.0, 0.0, 100.0};
  glm::dvec3 target{0.0, 0.0, 0.0};
  glm::dvec3 up{0.0, 0.0, 1.0};
  double fovYDegrees = 45.0;  ///< vertical field of view
  int width = 640, height = 480;
  double near = 0.1;  ///< metres

  /// Unit view direction.
  [[nodiscard]] glm::dvec3 forward() const noexcept;
  /// Rows: right, true up, −forward (world → eye rotation).
  [[nodiscard]] glm::dmat3 rotation() const noexcept;
  /// Projection × rotation, in float, for camera-relative positions.
  [[nodiscard]] glm::mat4 viewProjection() const noexcept;
  /// Focal length in pixels (vertical).
  [[nodiscard]] double focalPixels() const noexcept;

  /// Projects a world point: x right and y down in pixels (pixel centres at +0.5, origin
  /// top-left), and the depth-buffer value near / viewDistance. Depth ≤ 0 if behind.
  [[nodiscard]] glm::dvec3 project(const glm::dvec3& world) const noexcept;
  /// The unit world direction through pixel position (x, y) (same pixel convention).
  [[nodiscard]] glm::dvec3 ray(double x, double y) const noexcept;
  /// Distance along the view axis encoded by a depth-buffer value.
  [[nodiscard]] double viewDistance(double depth) const noexcept { return near / depth; }
};

}  // namespace regolith::clod
