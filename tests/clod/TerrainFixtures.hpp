#pragma once
// Analytic terrains for the clod image tests: a plane DEM on a grid centred at (0, 0), and a
// global latitude/longitude grid on the Mars sphere.

#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec3.hpp>

#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>
#include <numbers>

namespace regolith::test {

/// rows × cols samples at `spacing` metres, sample centres symmetric about (0, 0).
inline topo::TopoGrid centredGrid(std::size_t rows, std::size_t cols, double spacing) {
  return topo::TopoGrid(rows, cols, -0.5 * static_cast<double>(cols - 1) * spacing,
                        0.5 * static_cast<double>(rows - 1) * spacing, spacing, spacing);
}

/// A plane pyramid whose level-0 sample at (x, y) is f(x, y).
inline std::shared_ptr<const clod::HeightPyramid> planePyramid(
    const topo::TopoGrid& grid, const std::function<double(double, double)>& f) {
  auto samples = topo::InMemorySamples::fromFunction(
      grid.rows(), grid.cols(), [&](std::size_t r, std::size_t c) {
        const auto p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
        return static_cast<float>(f(p.x, p.y));
      });
  return std::make_shared<const clod::HeightPyramid>(
      clod::HeightPyramid::fromSamples(grid, samples, clod::SurfaceKind::Plane));
}

/// The unit body-fixed direction of (latitude, longitude), degrees.
inline glm::dvec3 unitDirection(double latDeg, double lonDeg) {
  const double la = latDeg * std::numbers::pi / 180.0, lo = lonDeg * std::numbers::pi / 180.0;
  return {std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la)};
}

/// A global latitude/longitude planet pyramid on the Mars sphere, rows × 2·rows samples,
/// whose sample at unit direction u is relief(u): continuous across the seam and over the
/// poles by construction.
inline std::shared_ptr<const clod::HeightPyramid> spherePyramid(
    std::size_t rows, const std::function<double(const glm::dvec3&)>& relief) {
  const std::size_t cols = 2 * rows;
  const double d = 180.0 / static_cast<double>(rows);
  const topo::TopoGrid grid(rows, cols, -180.0 + 0.5 * d, 90.0 - 0.5 * d, d, d);
  auto samples = topo::InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
    const auto p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return static_cast<float>(relief(unitDirection(p.y, p.x)));
  });
  return std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      grid, samples, clod::SurfaceKind::Planet, topo::Body::marsSphere()));
}

/// A simple crater: a parabolic bowl of the given depth below the rim crest inside radius
/// R, the crest (height rimHeight above the plain at `base`) at r = R, a Gaussian flank
/// outside. The crest is the highest point.
struct Crater {
  double base = -1400.0, radius = 200.0, depth = 60.0, rimHeight = 15.0, flank = 60.0;
  [[nodiscard]] double operator()(double x, double y) const {
    const double r = std::hypot(x, y);
    if (r < radius) return base + rimHeight - depth * (1.0 - (r / radius) * (r / radius));
    const double t = (r - radius) / flank;
    return base + rimHeight * std::exp(-t * t);
  }
};

/// Rolling hills with a crater: a rough surface for crack and reference tests.
inline double hills(double x, double y) {
  return Crater{}(x, y) + 12.0 * std::sin(x / 37.0) * std::cos(y / 53.0) +
         4.0 * std::sin((x + 2.0 * y) / 11.0) + 1.5 * std::cos((3.0 * x - y) / 5.0);
}

}  // namespace regolith::test
