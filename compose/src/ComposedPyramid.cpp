#include <regolith/compose/ComposedPyramid.hpp>

#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace regolith::compose {

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;

std::shared_ptr<const ComposedSurface> checked(std::shared_ptr<const ComposedSurface> s) {
  if (!s) {
    throw InvalidArgument(core::format({.operation = "compose::ComposedSamples()",
                                        .field = "surface",
                                        .value = "null",
                                        .expected = "a composed surface"}));
  }
  return s;
}

std::size_t levelsFor(const topo::TopoGrid& grid, std::size_t levels) {
  if (levels > 0) return levels;
  std::size_t n = 1;
  for (std::size_t r = grid.rows(), c = grid.cols(); r > 2 || c > 2; r = (r + 1) / 2, c = (c + 1) / 2) ++n;
  return n;
}
}  // namespace

ComposedSamples::ComposedSamples(std::shared_ptr<const ComposedSurface> surface,
                                 const topo::TopoGrid& grid, topo::LatitudeType latitudeType,
                                 double groundMetres)
    : surface_(checked(std::move(surface))), grid_(grid), latType_(latitudeType), metres_(groundMetres) {}

ComposedSamples::ComposedSamples(std::shared_ptr<const ComposedSurface> surface,
                                 const topo::TopoGrid& grid, const topo::Placement& placement,
                                 double groundMetres)
    : surface_(checked(std::move(surface))), grid_(grid), placement_(placement), metres_(groundMetres) {}

double ComposedSamples::height(std::size_t row, std::size_t col) const {
  const glm::dvec2 xy = grid_.sampleCentre(static_cast<double>(row), static_cast<double>(col));
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  const topo::Body& body = surface_->body();
  if (!placement_) {
    const double lat = std::clamp(body.toPlanetodetic(xy.y, latType_), -90.0, 90.0);
    const topo::HeightSample h = surface_->heightAt(lat, xy.x, metres_);
    return h.valid() ? h.height : nan;
  }
  try {
    if (placement_->localTangentPlane() == nullptr) {
      const topo::Geodetic g = placement_->toGeodetic(xy.x, xy.y, 0.0);
      const topo::HeightSample h = surface_->heightAt(g.latDeg, g.lonDeg, metres_);
      return h.valid() ? h.height : nan;
    }
    // Along the plane's normal: h such that the point (x, y, h) lies on the composed surface.
    double h = 0.0;
    for (int it = 0; it < 12; ++it) {
      const topo::Geodetic g = placement_->toGeodetic(xy.x, xy.y, h);
      const topo::HeightSample s = surface_->heightAt(g.latDeg, g.lonDeg, metres_);
      if (!s.valid()) return nan;
      const double residual = s.height - g.height;
      h += residual;
      if (std::abs(residual) < 1e-7) break;
    }
    return h;
  } catch (const DomainError&) {
    return nan;  // no image under this placement
  }
}

float ComposedSamples::sample(std::size_t row, std::size_t col) const {
  return static_cast<float>(height(row, col));
}

void ComposedSamples::readWindow(std::size_t row0, std::size_t col0, std::size_t nrows,
                                 std::size_t ncols, std::span<float> out) const {
  for (std::size_t r = 0; r < nrows; ++r) {
    for (std::size_t c = 0; c < ncols; ++c) out[r * ncols + c] = sample(row0 + r, col0 + c);
  }
}

topo::GridPyramid composedPlanetPyramid(const std::shared_ptr<const ComposedSurface>& surface,
                                        const topo::TopoGrid& grid, topo::LatitudeType latitudeType,
                                        std::size_t levels) {
  topo::GridPyramid p;
  p.planetBody = checked(surface)->body();
  p.latitudeType = latitudeType;
  const double r = (2.0 * p.planetBody->equatorialRadius() + p.planetBody->polarRadius()) / 3.0;
  topo::TopoGrid g = grid;
  const std::size_t n = levelsFor(grid, levels);
  for (std::size_t l = 0; l < n; ++l) {
    const double metres = r * kDeg * std::sqrt(g.spacingX() * g.spacingY());
    p.levels.push_back({g, std::make_shared<ComposedSamples>(surface, g, latitudeType, metres)});
    g = topo::coarserGrid(g);
  }
  return p;
}

topo::GridPyramid composedDemPyramid(const std::shared_ptr<const ComposedSurface>& surface,
                                     const topo::TopoGrid& grid, const topo::Placement& placement,
                                     std::size_t levels) {
  topo::GridPyramid p;
  topo::TopoGrid g = grid;
  const std::size_t n = levelsFor(grid, levels);
  for (std::size_t l = 0; l < n; ++l) {
    const double metres = std::sqrt(g.spacingX() * g.spacingY());
    p.levels.push_back({g, std::make_shared<ComposedSamples>(checked(surface), g, placement, metres)});
    g = topo::coarserGrid(g);
  }
  return p;
}

}  // namespace regolith::compose
