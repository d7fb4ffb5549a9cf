// DEMs whose heights are the generated planet's (GenerateDem.hpp).
#include "GenerateDem.hpp"

#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace regolith::store::gen {

GridInfo demGridInfo(const std::string& name, const topo::TopoGrid& grid,
                     const topo::Placement& placement) {
  GridInfo info;
  info.name = name;
  info.kind = GridKind::Dem;
  info.rows = grid.rows();
  info.cols = grid.cols();
  info.x0 = grid.x0();
  info.y0 = grid.y0();
  info.spacingX = grid.spacingX();
  info.spacingY = grid.spacingY();
  const topo::Body& body = placement.body();
  info.bodyName = body.name();
  info.equatorialRadius = body.equatorialRadius();
  info.polarRadius = body.polarRadius();
  info.latitudeType = topo::LatitudeType::Planetodetic;
  info.placement = placementInfoOf(placement);
  return info;
}

namespace {
constexpr double kDegToRad = std::numbers::pi / 180.0;
}  // namespace

glm::dvec3 unitUnder(const topo::Placement& placement, double x, double y) {
  const topo::Geodetic g = placement.toGeodetic(x, y, 0.0);
  const double latDeg = placement.body().planetocentricFromPlanetodetic(g.latDeg);
  // As MarsPlanetGenerator::height(): longitude into [−180, 180), then the lattice's trig.
  const double lonDeg = g.lonDeg - 360.0 * std::floor((g.lonDeg + 180.0) / 360.0);
  const double phi = latDeg * kDegToRad, lambda = lonDeg * kDegToRad;
  const double cosLat = std::cos(phi);
  return {cosLat * std::cos(lambda), cosLat * std::sin(lambda), std::sin(phi)};
}

std::size_t planetRowsFor(double spacing, double radius, const std::string& operation) {
  const double rows = std::ceil(std::numbers::pi * radius / spacing);
  if (!(rows <= static_cast<double>(std::size_t{1} << 31U))) {
    throw InvalidArgument(
        core::format({.operation = operation,
                      .field = "spacing",
                      .value = core::number(spacing) + " m",
                      .expected = ">= " + core::number(std::numbers::pi * radius / 0x1.0p31) +
                                  " m (a planet grid of that resolution would exceed 2^31 rows)"}));
  }
  return static_cast<std::size_t>(std::max(2.0, rows));
}

MarsPlanetGenerator planetAt(const PlanetOf& planet, std::size_t rows, std::size_t threads,
                             const WriteOptions& write) {
  MarsPlanetOptions o;
  o.rows = rows;
  o.seed = planet.seed;
  o.ellipsoid = planet.ellipsoid;
  o.craterDensity = planet.craterDensity;
  o.threads = threads;
  o.write.executor = write.executor;
  return MarsPlanetGenerator(o);
}

PlanetDemSamples::PlanetDemSamples(MarsPlanetGenerator planet, topo::Placement placement,
                                   topo::TopoGrid grid, Extra extra, Covers covers)
    : planet_(std::move(planet)),
      placement_(std::move(placement)),
      grid_(grid),
      extra_(std::move(extra)),
      covers_(std::move(covers)) {}

float PlanetDemSamples::sample(std::size_t row, std::size_t col) const {
  float v = 0.0F;
  readWindow(row, col, 1, 1, std::span(&v, 1));
  return v;
}

void PlanetDemSamples::readWindow(std::size_t row0, std::size_t col0, std::size_t nrows,
                                  std::size_t ncols, std::span<float> out) const {
  const std::size_t n = nrows * ncols;
  std::vector<glm::dvec3> units(n);
  for (std::size_t r = 0; r < nrows; ++r) {
    for (std::size_t c = 0; c < ncols; ++c) {
      const glm::dvec2 p =
          grid_.sampleCentre(static_cast<double>(row0 + r), static_cast<double>(col0 + c));
      units[r * ncols + c] = unitUnder(placement_, p.x, p.y);
    }
  }
  std::vector<double> heights(n);
  planet_.heightsAt(units, ncols, heights);
  for (std::size_t r = 0; r < nrows; ++r) {
    for (std::size_t c = 0; c < ncols; ++c) {
      const std::size_t i = r * ncols + c;
      double h = heights[i];
      if (extra_) h += extra_(units[i]);
      if (covers_) {
        const glm::dvec2 p =
            grid_.sampleCentre(static_cast<double>(row0 + r), static_cast<double>(col0 + c));
        if (!covers_(p.x, p.y)) h = std::numeric_limits<double>::quiet_NaN();
      }
      out[i] = static_cast<float>(h);
    }
  }
}

}  // namespace regolith::store::gen
