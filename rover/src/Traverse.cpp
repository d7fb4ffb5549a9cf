#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

namespace regolith::rover {

namespace {

using Clock = std::chrono::steady_clock;

void checkOptions(const TraverseOptions& o) {
  const std::string op = "rover::runTraverse(): ";
  if (!(std::isfinite(o.speed) && o.speed > 0.0)) {
    throw InvalidArgument(op + "speed is " + core::number(o.speed) +
                          " m/s, expected finite and > 0");
  }
  if (!(std::isfinite(o.step) && o.step > 0.0)) {
    throw InvalidArgument(op + "step is " + core::number(o.step) + " s, expected finite and > 0");
  }
  if (o.path.size() < 2) {
    throw InvalidArgument(op + "path has " + std::to_string(o.path.size()) +
                          " waypoints, expected at least 2");
  }
  for (std::size_t i = 0; i < o.path.size(); ++i) {
    const glm::dvec2 p = o.path[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y))) {
      throw InvalidArgument(op + "path waypoint " + std::to_string(i) + " is (" +
                            core::number(p.x) + ", " + core::number(p.y) +
                            "), expected finite grid coordinates in metres");
    }
    if (i > 0 && p == o.path[i - 1]) {
      throw InvalidArgument(op + "path waypoint " + std::to_string(i) +
                            " repeats the one before it (" + core::number(p.x) + ", " +
                            core::number(p.y) + ")");
    }
  }
}

/// Every wheel stays inside the grid's pixel extent if every waypoint is at least the rover's
/// reach from its edges: the extent shrunk by the reach is convex, so whole segments stay
/// in it.
void checkPathInside(const TraverseOptions& o, const topo::TopoGrid& g, double reach) {
  for (std::size_t i = 0; i < o.path.size(); ++i) {
    const glm::dvec2 p = o.path[i];
    if (p.x - reach < g.west() || p.x + reach > g.east() || p.y - reach < g.south() ||
        p.y + reach > g.north()) {
      throw InvalidArgument(
          "rover::runTraverse(): path waypoint " + std::to_string(i) + " (" + core::number(p.x) +
          ", " + core::number(p.y) + ") puts a wheel (reach " + core::number(reach) +
          " m) outside the grid: x must lie in [" + core::number(g.west() + reach) + ", " +
          core::number(g.east() - reach) + "] and y in [" + core::number(g.south() + reach) + ", " +
          core::number(g.north() - reach) + "]");
    }
  }
}

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

TraverseResult runTraverse(const topo::TopoDem& dem, const TraverseOptions& options,
                           const StepCallback& onStep) {
  checkOptions(options);
  const Rover rover(options.geometry);
  checkPathInside(options, dem.grid(), options.geometry.reach());

  // Cumulative lengths of the path's segments.
  std::vector<double> cumulative{0.0};
  for (std::size_t i = 1; i < options.path.size(); ++i) {
    cumulative.push_back(cumulative.back() + glm::distance(options.path[i - 1], options.path[i]));
  }
  const double total = cumulative.back();
  const double ds = options.speed * options.step;
  std::size_t steps = static_cast<std::size_t>(std::floor(total / ds)) + 1;
  if (options.maxSteps > 0) steps = std::min(steps, options.maxSteps);

  TraverseResult result;
  StepState state;
  std::array<double, kWheels> xs{}, ys{}, hs{};
  std::array<glm::dvec3, kWheels> ns{};
  std::array<topo::QueryStatus, kWheels> st{}, normalSt{};
  Clock::duration queryTime{};
  std::size_t segment = 0;
  const auto start = Clock::now();
  for (std::size_t k = 0; k < steps; ++k) {
    const double d = std::min(static_cast<double>(k) * ds, total);
    while (segment + 2 < cumulative.size() && d > cumulative[segment + 1]) ++segment;
    const glm::dvec2 a = options.path[segment], b = options.path[segment + 1];
    const double t = (d - cumulative[segment]) / (cumulative[segment + 1] - cumulative[segment]);
    const glm::dvec2 p = a + t * (b - a);
    state.ground = {p.x, p.y, std::atan2(b.x - a.x, b.y - a.y)};

    const auto wheels = rover.wheelPositions(state.ground);
    for (std::size_t i = 0; i < kWheels; ++i) xs[i] = wheels[i].x, ys[i] = wheels[i].y;
    const auto q0 = Clock::now();
    dem.surfaces(xs, ys, hs, ns, st, options.interpolation, topo::NormalFrame::Grid, normalSt);
    queryTime += Clock::now() - q0;
    for (std::size_t i = 0; i < kWheels; ++i) {
      // A wheel needs its height and its normal (WheelContact: both valid, or status says
      // why not); the normal's status is the stricter of the two.
      state.wheels[i] = {xs[i], ys[i], hs[i], ns[i], normalSt[i]};
    }
    state.chassis = rover.settle(state.ground, state.wheels);
    state.step = k;
    state.time = static_cast<double>(k) * options.step;
    state.distance = d;

    result.steps = k + 1;
    result.queries += kWheels;
    result.distance = d;
    result.maxTilt = std::max(result.maxTilt, std::acos(std::clamp(state.chassis.up.z, -1.0, 1.0)));
    result.maxResidual = std::max(result.maxResidual, state.chassis.residual);
    if (onStep && !onStep(state)) break;
  }
  result.totalSeconds = seconds(Clock::now() - start);
  result.querySeconds = seconds(queryTime);
  result.queriesPerSecond =
      result.querySeconds > 0.0 ? static_cast<double>(result.queries) / result.querySeconds : 0.0;
  return result;
}

std::vector<glm::dvec2> defaultVictoriaPath(double scale) {
  // From the western plains to the rim, then along the outer rim (radius 430 m, outside the
  // crest's 375 m ± 4 %) northwards and round to the north-east.
  std::vector<glm::dvec2> path{{-560.0, -90.0}, {-430.0, -20.0}};
  constexpr double kRadius = 430.0;
  for (int deg = 170; deg >= 50; deg -= 20) {
    const double a = static_cast<double>(deg) * std::numbers::pi / 180.0;
    path.push_back({kRadius * std::cos(a), kRadius * std::sin(a)});
  }
  for (glm::dvec2& p : path) p *= scale;
  return path;
}

}  // namespace regolith::rover
