#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/Projection.hpp>

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
  for (std::size_t r = grid.rows(), c = grid.cols(); r > 2 || c > 2;
       r = (r + 1) / 2, c = (c + 1) / 2)
    ++n;
  return n;
}
}  // namespace

ComposedSamples::ComposedSamples(std::shared_ptr<const ComposedSurface> surface,
                                 const topo::TopoGrid& grid, topo::LatitudeType latitudeType,
                                 double groundMetres)
    : surface_(checked(std::move(surface))),
      grid_(grid),
      latType_(latitudeType),
      metres_(groundMetres) {}

ComposedSamples::ComposedSamples(std::shared_ptr<const ComposedSurface> surface,
                                 const topo::TopoGrid& grid, const topo::Placement& placement,
                                 double groundMetres, std::shared_ptr<const Dataset> own,
                                 std::size_t ownLevel)
    : surface_(checked(std::move(surface))),
      grid_(grid),
      placement_(placement),
      metres_(groundMetres) {
  if (!own || own->isPlanet() || own->options().mask || ownLevel >= own->levelCount() ||
      own->levelFor(groundMetres) != ownLevel) {
    return;
  }
  // The same lattice: own's level `ownLevel` has this grid's geometry.
  const topo::TopoGrid& og = own->level(ownLevel).grid;
  const double tol = 1e-9 * std::max(og.spacingX(), 1.0);
  if (og.rows() != grid.rows() || og.cols() != grid.cols() || std::abs(og.x0() - grid.x0()) > tol ||
      std::abs(og.y0() - grid.y0()) > tol || std::abs(og.spacingX() - grid.spacingX()) > tol ||
      std::abs(og.spacingY() - grid.spacingY()) > tol) {
    return;
  }
  // No dataset of own's tier or above may overlap it (docs/composition.md "Tiers"): then
  // wherever own's coverage is 1, the layers below it are hidden and it is the surface.
  const Rules& rules = surface_->rules();
  const double ratio = rules.spacingRatio();
  const auto& b = own->bounds();
  for (const auto& e : surface_->snapshot().entries()) {
    const Dataset& d = *e.dataset;
    if (&d == own.get() || d.options().role != Role::Height) continue;
    const bool below = d.options().priority < own->options().priority ||
                       (d.options().priority == own->options().priority &&
                        d.groundSpacing() > own->groundSpacing() * ratio);
    const auto& db = d.bounds();
    const bool overlaps = db[0].x <= b[1].x && db[1].x >= b[0].x && db[0].y <= b[1].y &&
                          db[1].y >= b[0].y && db[0].z <= b[1].z && db[1].z >= b[0].z;
    if (overlaps && !below) return;
  }
  own_ = std::move(own);
  ownSource_ = own_->level(ownLevel).source;
  ownGrid0_ = own_->level(0).grid;
}

double ComposedSamples::height(std::size_t row, std::size_t col) const {
  const glm::dvec2 xy = grid_.sampleCentre(static_cast<double>(row), static_cast<double>(col));
  if (own_) {
    // Past own's feather (coverage exactly 1) and on a valid sample: own is the surface.
    const double feather = own_->options().featherMetres;
    const double d = std::min({xy.x - ownGrid0_.west(), ownGrid0_.east() - xy.x,
                               xy.y - ownGrid0_.south(), ownGrid0_.north() - xy.y});
    if (d >= feather && d >= 0.0) {
      const float v = ownSource_->sample(row, col);
      if (!std::isnan(v)) return static_cast<double>(v) + own_->options().heightOffset;
    }
  }
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
    // The plane's normal and the body's differ by the grid's extent over the radius, so each
    // step shrinks the error by that angle times the slope. Samples are stored as floats (an
    // ulp of 1e-4 m at 1000 m), so 1e-5 m is enough. The start is fixed (0), so a sample
    // never depends on the samples read before it.
    double h = 0.0;
    for (int it = 0; it < 12; ++it) {
      const topo::Geodetic g = placement_->toGeodetic(xy.x, xy.y, h);
      const topo::HeightSample s = surface_->heightAt(g.latDeg, g.lonDeg, metres_);
      if (!s.valid()) return nan;
      const double residual = s.height - g.height;
      h += residual;
      if (std::abs(residual) < 1e-5) break;
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
                                     std::size_t levels,
                                     const std::shared_ptr<const Dataset>& own) {
  topo::GridPyramid p;
  topo::TopoGrid g = grid;
  const std::size_t n = levelsFor(grid, levels);
  for (std::size_t l = 0; l < n; ++l) {
    const double metres = std::sqrt(g.spacingX() * g.spacingY());
    p.levels.push_back(
        {g, std::make_shared<ComposedSamples>(checked(surface), g, placement, metres, own, l)});
    g = topo::coarserGrid(g);
  }
  return p;
}

DrawingFrame drawingFrame(const std::shared_ptr<const ComposedSurface>& surface, double lookLatDeg,
                          double spacingMetres) {
  constexpr const char* op = "compose::drawingFrame()";
  const topo::Body& body = checked(surface)->body();
  const double metresPerDegree = body.equatorialRadius() * kDeg;
  if (!(spacingMetres > 0.0)) {
    double finest = std::numeric_limits<double>::infinity();
    for (const auto& e : surface->snapshot().entries()) {
      if (e.dataset->options().role == Role::Height)
        finest = std::min(finest, e.dataset->groundSpacing());
    }
    if (!std::isfinite(finest)) {
      throw InvalidArgument(core::format({.operation = op,
                                          .field = "height datasets of the catalogue",
                                          .value = "none",
                                          .expected = "at least one dataset of role height"}));
    }
    spacingMetres = finest;
  }
  spacingMetres = std::max(spacingMetres, 1e-3);
  DrawingFrame f;
  if (std::abs(lookLatDeg) < 50.0) {
    // Whole pixels on the sphere: 180 / step rows, rounded, twice as many columns.
    const double step = spacingMetres / metresPerDegree;
    const double rowsD = std::max(2.0, std::round(180.0 / step));
    if (2.0 * rowsD > static_cast<double>(std::size_t{1} << 31)) {
      throw InvalidArgument(
          core::format({.operation = op,
                        .field = "spacing",
                        .value = core::number(spacingMetres) + " m",
                        .expected = "coarse enough for at most 2^31 columns around the body"}));
    }
    const auto rows = static_cast<std::size_t>(rowsD);
    const double dy = 180.0 / rowsD;
    const topo::TopoGrid g(rows, 2 * rows, -180.0 + 0.5 * dy, 90.0 - 0.5 * dy, dy, dy);
    f.pyramid = composedPlanetPyramid(surface, g, topo::LatitudeType::Planetodetic);
    f.spacingMetres = dy * metresPerDegree;
    return f;
  }
  const auto pole = lookLatDeg > 0 ? topo::PolarStereographic::Pole::North
                                   : topo::PolarStereographic::Pole::South;
  const topo::Placement placement(body,
                                  topo::PolarStereographic::withScaleFactor(body, pole, 1.0, 0.0));
  const double half =
      2.0 * body.equatorialRadius() * std::tan(40.0 * kDeg);  // down to 10° latitude
  const double halfSamples = std::ceil(half / spacingMetres);
  if (2.0 * halfSamples + 1.0 > static_cast<double>(std::size_t{1} << 31)) {
    throw InvalidArgument(
        core::format({.operation = op,
                      .field = "polar grid spacing",
                      .value = core::number(spacingMetres) + " m",
                      .expected = "coarse enough for at most 2^31 samples a side"}));
  }
  const auto n =
      static_cast<std::size_t>(2.0 * halfSamples + 1.0);  // the pole is the centre sample
  const double h = halfSamples * spacingMetres;
  f.pyramid = composedDemPyramid(surface, topo::TopoGrid(n, n, -h, h, spacingMetres, spacingMetres),
                                 placement);
  f.placement = placement;
  f.spacingMetres = spacingMetres;
  f.polar = true;
  return f;
}

}  // namespace regolith::compose
