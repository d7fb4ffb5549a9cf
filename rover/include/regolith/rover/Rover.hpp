#pragma once
/// \file
/// A six-wheel rover: where its wheels touch a DEM, and how its chassis settles on them.

#include <regolith/topo/Query.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <limits>

namespace regolith::rover {

/// Number of wheels (three axles, two sides).
inline constexpr std::size_t kWheels = 6;

/// The wheel layout of a six-wheel rover (three axles), in metres, in the chassis frame:
/// forward along the heading, left across it. Wheel i sits on axle i / 2 (0 front, 1 middle,
/// 2 rear) and side i % 2 (0 left, 1 right). Defaults are Curiosity-like. Value type.
struct RoverGeometry {
  /// Forward offsets of the front, middle and rear axles from the chassis centre.
  std::array<double, 3> axleOffsets{1.10, 0.0, -1.00};
  /// Distance between the left and right wheel centres.
  double trackWidth = 2.20;
  /// Height of the chassis reference point above the wheel-contact plane, along its normal.
  double clearance = 0.66;

  /// Distance from the chassis centre to the farthest wheel contact, m.
  [[nodiscard]] double reach() const noexcept;
};

/// A rover's position on the ground plane: grid-frame x (east) and y (north) in metres, and
/// the heading in radians clockwise from +y (north), so forward is (sin h, cos h).
struct GroundPose {
  double x = 0.0, y = 0.0, heading = 0.0;
};

/// What one wheel touches: the grid-frame point (x, y, metres), the terrain height there
/// (metres) and the unit terrain normal in the grid frame (x, y, h). Height and normal are
/// NaN unless status is Ok.
struct WheelContact {
  double x = 0.0, y = 0.0;
  double height = std::numeric_limits<double>::quiet_NaN();
  glm::dvec3 normal{std::numeric_limits<double>::quiet_NaN()};
  topo::QueryStatus status = topo::QueryStatus::OutsideGrid;
};

/// The chassis settled on its six contacts: the least-squares plane z = h + gx·dx + gy·dy
/// through the contact points (dx, dy from the chassis centre), in the grid frame.
/// - height: the plane's height under the chassis centre (m);
/// - position: the chassis reference point, `clearance` above the plane along its normal;
/// - up: the plane's unit normal; forward: the unit vector in the plane whose horizontal
///   part points along the heading;
/// - heading (as given), pitch (nose up positive) and roll (right side down positive), in
///   radians: the chassis frame is yaw(heading), then pitch about the left axis, then roll
///   about the forward axis;
/// - residual: RMS distance (vertical, m) of the contacts from the plane; 0 when all six
///   wheels touch a plane.
struct ChassisPose {
  double x = 0.0, y = 0.0, height = 0.0;
  glm::dvec3 position{0.0};
  glm::dvec3 up{0.0, 0.0, 1.0};
  glm::dvec3 forward{0.0, 1.0, 0.0};
  double heading = 0.0, pitch = 0.0, roll = 0.0;
  double residual = 0.0;
};

/// The rover's kinematics: wheel footprints for a ground pose, and the settled chassis.
/// Wheel footprints are placed horizontally from the ground pose (the chassis tilt moves them
/// by at most reach·(1 − cos tilt), under 1 cm at 5°). Value type; thread-safe.
class Rover {
 public:
  /// Throws regolith::InvalidArgument for a non-finite or non-positive track width, a
  /// non-finite axle offset or clearance, or axle offsets that are not strictly decreasing
  /// (front, middle, rear).
  explicit Rover(RoverGeometry geometry = {});

  [[nodiscard]] const RoverGeometry& geometry() const noexcept { return geometry_; }

  /// Grid-frame (x, y) of each wheel's contact for a ground pose (order: see RoverGeometry).
  [[nodiscard]] std::array<glm::dvec2, kWheels> wheelPositions(const GroundPose& pose) const;

  /// Settles the chassis on six contacts (ChassisPose). Throws regolith::DomainError if a
  /// contact is not Ok (no height to stand on), naming the wheel and its position.
  [[nodiscard]] ChassisPose settle(const GroundPose& pose,
                                   const std::array<WheelContact, kWheels>& contacts) const;

 private:
  RoverGeometry geometry_;
};

}  // namespace regolith::rover
