#pragma once
/// \file
/// A rover traverse: a six-wheel rover drives a path across a stored DEM at a fixed time
/// step, querying the terrain under every wheel through the pager at every step.

#include <regolith/rover/Rover.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Query.hpp>

#include <glm/vec2.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace regolith::rover {

/// What a traverse drives on and how.
struct TraverseOptions {
  /// The store and the DEM grid in it (a GridKind::Dem grid, level `level`).
  std::filesystem::path store;
  std::string grid = "victoria";
  std::size_t level = 0;
  /// The patch cache's byte budget (> 0) and eviction policy.
  std::size_t cacheBytes = std::size_t{64} << 20;
  store::CachePolicy policy = store::CachePolicy::Lru;
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
  /// The patch cache's counters after this step's queries.
  store::CacheStats cache;
};

/// Called after every step; returning false stops the traverse (the result then counts the
/// steps done).
using StepCallback = std::function<bool(const StepState&)>;

/// What a traverse measured.
struct TraverseResult {
  std::size_t steps = 0;
  std::size_t queries = 0;       // wheel queries (height + normal), 6 per step
  double distance = 0.0;         // m driven
  double querySeconds = 0.0;     // wall time inside the wheel queries only
  double totalSeconds = 0.0;     // wall time of the whole loop (settling and callback included)
  double queriesPerSecond = 0.0; // queries / querySeconds
  store::CacheStats cache;       // the cache's counters at the end
  store::ReadCounters reads;     // the store's hyperslab reads and bytes read
  std::size_t peakResidentBytes = 0;  // largest resident size sampled (every step)
  std::size_t budgetBytes = 0;
  double maxTilt = 0.0;          // largest chassis tilt (angle of `up` from vertical), rad
  double maxResidual = 0.0;      // largest ChassisPose::residual, m
};

/// Opens `options.store`, pages grid `options.grid` through a PatchCache of
/// `options.cacheBytes`, and drives the path, calling `onStep` (may be empty) after every
/// step. Throws regolith::InvalidArgument naming the option for a bad budget, speed, step,
/// path (fewer than two waypoints, NaN/inf, repeated waypoints) or a path that takes a wheel
/// outside the grid (naming the waypoint and the grid's extent); store::StoreError for a
/// missing or unusable store or grid; regolith::DomainError if a wheel lands on nodata.
TraverseResult runTraverse(const TraverseOptions& options, const StepCallback& onStep = {});

/// A path that crosses the default Victoria-like DEM (VictoriaGenerator defaults: 1201 m
/// square centred on the crater): from the western plains over the rim, across the floor
/// and up to the eastern rim, `scale` times the default size.
[[nodiscard]] std::vector<glm::dvec2> defaultVictoriaPath(double scale = 1.0);

}  // namespace regolith::rover
