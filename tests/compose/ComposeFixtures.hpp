#pragma once
// In-memory datasets with analytic heights for the composition tests.

#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/topo/Pyramid.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace regolith::compose::testing {

/// A one-level planet pyramid: lat/lon grid with sample centres from (lat0, lon0) (north-west
/// centre) at `step` degrees, rows × cols, heights f(lat, lon).
inline topo::GridPyramid planetPyramid(const topo::Body& body, double lat0, double lon0,
                                       double step, std::size_t rows, std::size_t cols,
                                       const std::function<double(double, double)>& f) {
  topo::TopoGrid grid(rows, cols, lon0, lat0, step, step);
  auto src = topo::InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
    return static_cast<float>(
        f(lat0 - static_cast<double>(r) * step, lon0 + static_cast<double>(c) * step));
  });
  topo::GridPyramid p;
  p.levels.push_back({grid, src});
  p.planetBody = body;
  p.latitudeType = topo::LatitudeType::Planetodetic;
  return p;
}

/// A global planet at `step` degrees (pixel extent exactly −180…180, −90…90).
inline topo::GridPyramid globalPlanet(const topo::Body& body, double step,
                                      const std::function<double(double, double)>& f) {
  const auto rows = static_cast<std::size_t>(std::lround(180.0 / step));
  const auto cols = static_cast<std::size_t>(std::lround(360.0 / step));
  return planetPyramid(body, 90.0 - 0.5 * step, -180.0 + 0.5 * step, step, rows, cols, f);
}

/// A one-level planar pyramid centred on (0, 0): rows × cols samples at `spacing` metres,
/// heights f(x, y).
inline topo::GridPyramid demPyramid(double spacing, std::size_t rows, std::size_t cols,
                                    const std::function<double(double, double)>& f, double cx = 0.0,
                                    double cy = 0.0) {
  const double x0 = cx - 0.5 * spacing * static_cast<double>(cols - 1);
  const double y0 = cy + 0.5 * spacing * static_cast<double>(rows - 1);
  topo::TopoGrid grid(rows, cols, x0, y0, spacing, spacing);
  auto src = topo::InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
    return static_cast<float>(
        f(x0 + static_cast<double>(c) * spacing, y0 - static_cast<double>(r) * spacing));
  });
  topo::GridPyramid p;
  p.levels.push_back({grid, src});
  return p;
}

inline DatasetOptions named(std::string name, double feather = 0.0, int priority = 0) {
  DatasetOptions o;
  o.name = std::move(name);
  o.featherMetres = feather;
  o.priority = priority;
  return o;
}

inline double smoothstep(double t) {
  t = std::fmin(1.0, std::fmax(0.0, t));
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace regolith::compose::testing
