#pragma once
/// \file
/// A rover traverse: a six-wheel rover drives a path across a DEM at a fixed time step,
/// querying the terrain under every wheel at every step. The DEM is any topo::TopoDem: in
/// memory, or paged from a store (store::Pager::dem()), whose cache the caller owns and reads.

#include <regolith/rover/Rover.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <glm/vec2.hpp>

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

namespace regolith::rover {

/// How the rover drives.
struct TraverseOptions {
  /// Waypoints in the DEM's grid frame (x east, y north, metres); at least two, finite,
  /// consecutive ones distinct. The rover drives the polyline at constant speed, heading
  /// along the current segment; every wheel must stay inside the grid's pixel extent.
  std::vector<glm::dvec2> path;
  /// Speed (m/s, > 0) and time step (s, > 0): the rover moves speed·step per step.
  double speed = 1.0;
  double step = 0.001;
  /// Stop after this many steps (0: at the end of the path).
  std::size_t maxSteps = 0;
  /// Kernel of the wheel queries.
  topo::Interpolation interpolation = topo::Interpolation::Bilinear;
  RoverGeometry geometry{};
};

/// One step, as the callback sees it: the six wheel contacts (grid frame) and the chassis.
struct StepState {
  std::size_t step = 0;
  double time = 0.0;      // s since the start
  double distance = 0.0;  // m driven along the path
  GroundPose ground;
  std::array<WheelContact, kWheels> wheels;
  ChassisPose chassis;
};

/// Called after every step; returning false stops the traverse (the result then counts the
/// steps done).
using StepCallback = std::function<bool(const StepState&)>;

/// What a traverse measured.
struct TraverseResult {
  std::size_t steps = 0;
  std::size_t queries = 0;        // wheel queries (height + normal), 6 per step
  double distance = 0.0;          // m driven
  double querySeconds = 0.0;      // wall time inside the wheel queries only
  double totalSeconds = 0.0;      // wall time of the whole loop (settling and callback included)
  double queriesPerSecond = 0.0;  // queries / querySeconds
  double maxTilt = 0.0;           // largest chassis tilt (angle of `up` from vertical), rad
  double maxResidual = 0.0;       // largest ChassisPose::residual, m
};

/// Drives `options.path` over `dem`, calling `onStep` (may be empty) after every step. The
/// wheel queries are `dem.surfaces()` in the grid frame, one batch of six per step. Throws
/// regolith::InvalidArgument naming the option for a bad speed, step or path (fewer than two
/// waypoints, NaN/inf, repeated waypoints) or a path that takes a wheel outside the grid
/// (naming the waypoint and the grid's extent); regolith::DomainError if a wheel lands on
/// nodata; whatever the DEM's samples throw (a paged store's StoreError).
TraverseResult runTraverse(const topo::TopoDem& dem, const TraverseOptions& options,
                           const StepCallback& onStep = {});

/// A path that crosses the default Victoria-like DEM (VictoriaGenerator defaults: 1201 m
/// square centred on the crater): from the western plains over the rim, across the floor
/// and up to the eastern rim, `scale` times the default size.
[[nodiscard]] std::vector<glm::dvec2> defaultVictoriaPath(double scale = 1.0);

}  // namespace regolith::rover
