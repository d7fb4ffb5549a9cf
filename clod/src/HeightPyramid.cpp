#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/topo/Pyramid.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace regolith::clod {

HeightPyramid::HeightPyramid(std::vector<Level> levels, SurfaceKind kind,
                             std::optional<topo::Body> body, topo::LatitudeType latitudeType)
    : levels_(std::move(levels)), kind_(kind), body_(std::move(body)), latType_(latitudeType) {
  if (levels_.empty()) throw InvalidArgument("HeightPyramid(): no levels, expected at least one");
  if (kind_ == SurfaceKind::Planet && !body_)
    throw InvalidArgument("HeightPyramid(): a Planet pyramid needs a body");
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    const auto& l = levels_[i];
    const std::string where = "HeightPyramid(): level " + std::to_string(i);
    if (!l.source) throw InvalidArgument(where + ": source is null");
    if (l.source->rows() != l.grid.rows() || l.source->cols() != l.grid.cols())
      throw InvalidArgument(where + ": source is " + std::to_string(l.source->rows()) + " x " +
                            std::to_string(l.source->cols()) + ", grid is " +
                            std::to_string(l.grid.rows()) + " x " + std::to_string(l.grid.cols()));
    if (i > 0) {
      const auto& p = levels_[i - 1].grid;
      const auto twice = [](double coarse, double fine) {
        return std::abs(coarse - 2.0 * fine) <= 1e-6 * coarse;
      };
      if (!twice(l.grid.spacingX(), p.spacingX()) || !twice(l.grid.spacingY(), p.spacingY()))
        throw InvalidArgument(where + ": spacing " + std::to_string(l.grid.spacingX()) + " x " +
                              std::to_string(l.grid.spacingY()) + ", expected twice level " +
                              std::to_string(i - 1) + "'s (" + std::to_string(p.spacingX()) +
                              " x " + std::to_string(p.spacingY()) + ")");
    }
  }
}

HeightPyramid::HeightPyramid(topo::GridPyramid pyramid)
    : HeightPyramid(std::move(pyramid.levels),
                    pyramid.planetBody ? SurfaceKind::Planet : SurfaceKind::Plane,
                    std::move(pyramid.planetBody), pyramid.latitudeType) {}

HeightPyramid::HeightPyramid(std::vector<Level> levels, topo::Placement placement)
    : HeightPyramid(std::move(levels), SurfaceKind::Plane, placement.body()) {
  placement_ = std::move(placement);
}

HeightPyramid HeightPyramid::fromSamples(const topo::TopoGrid& grid,
                                         std::shared_ptr<const topo::SampleSource> samples,
                                         const topo::Placement& placement, std::size_t levelCount) {
  HeightPyramid flat = fromSamples(grid, std::move(samples), SurfaceKind::Plane, std::nullopt,
                                   topo::LatitudeType::Planetocentric, levelCount);
  return HeightPyramid(std::move(flat.levels_), placement);
}

HeightPyramid HeightPyramid::fromSamples(const topo::TopoGrid& grid,
                                         std::shared_ptr<const topo::SampleSource> samples,
                                         SurfaceKind kind, std::optional<topo::Body> body,
                                         topo::LatitudeType latitudeType, std::size_t levelCount) {
  if (!samples) throw InvalidArgument("HeightPyramid::fromSamples(): samples are null");
  std::size_t rows = grid.rows(), cols = grid.cols();
  std::vector<float> fine(rows * cols);
  samples->readWindow(0, 0, rows, cols, fine);
  std::vector<Level> levels;
  levels.push_back({grid, std::move(samples)});
  for (auto& v : fine)
    if (grid.isNodata(v)) v = std::numeric_limits<float>::quiet_NaN();
  const topo::TopoGrid* g = &grid;
  while ((levelCount == 0 && (rows > 2 || cols > 2)) ||
         (levelCount != 0 && levels.size() < levelCount)) {
    const topo::TopoGrid cg = topo::coarserGrid(*g);
    const std::size_t r2 = cg.rows(), c2 = cg.cols();
    std::vector<float> coarse(r2 * c2);
    topo::downsample2x2(
        fine.data(), rows, cols, coarse.data(), r2, c2, [](float v) { return std::isnan(v); },
        std::numeric_limits<float>::quiet_NaN());
    levels.push_back({cg, std::make_shared<topo::InMemorySamples>(r2, c2, coarse)});
    g = &levels.back().grid;
    fine = std::move(coarse);
    rows = r2;
    cols = c2;
  }
  return HeightPyramid(std::move(levels), kind, std::move(body), latitudeType);
}

glm::dvec3 HeightPyramid::position(double x, double y, double h) const {
  if (placement_) return placement_->toBodyFixed(x, y, h);
  if (kind_ == SurfaceKind::Plane) return {x, y, h};
  const double lat = body_->toPlanetodetic(y, latType_);
  return body_->toBodyFixed(topo::Geodetic{lat, x, h});
}

glm::dvec2 HeightPyramid::gridPoint(const glm::dvec3& p) const {
  if (placement_) {
    const glm::dvec3 g = placement_->fromBodyFixed(p);
    return {g.x, g.y};
  }
  if (kind_ == SurfaceKind::Plane) return {p.x, p.y};
  const topo::Geodetic g = body_->toGeodetic(p);
  return {g.lonDeg, body_->fromPlanetodetic(g.latDeg, latType_)};
}

glm::dvec3 HeightPyramid::up(const glm::dvec3& p) const {
  if (placement_) {
    const glm::dvec3 g = placement_->fromBodyFixed(p);
    return placement_->normalToBodyFixed({0.0, 0.0, 1.0}, g.x, g.y, g.z);
  }
  if (kind_ == SurfaceKind::Plane) return {0.0, 0.0, 1.0};
  const topo::Geodetic g = body_->toGeodetic(p);
  return body_->enuFrame(g.latDeg, g.lonDeg)[2];
}

}  // namespace regolith::clod
