#include <regolith/rover/TrackPresser.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/topo/Projection.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace regolith::scene {

double bilinearHeight(const clod::HeightPyramid::Level& level, double col, double row) {
  const auto& g = level.grid;
  const double c = std::clamp(col, 0.0, static_cast<double>(g.cols() - 1));
  const double r = std::clamp(row, 0.0, static_cast<double>(g.rows() - 1));
  const auto c0 =
      static_cast<std::size_t>(std::min(std::floor(c), static_cast<double>(g.cols() - 2)));
  const auto r0 =
      static_cast<std::size_t>(std::min(std::floor(r), static_cast<double>(g.rows() - 2)));
  const double fc = c - static_cast<double>(c0), fr = r - static_cast<double>(r0);
  const auto s = [&](std::size_t rr, std::size_t cc) {
    return static_cast<double>(level.source->sample(rr, cc));
  };
  return (1 - fr) * ((1 - fc) * s(r0, c0) + fc * s(r0, c0 + 1)) +
         fr * ((1 - fc) * s(r0 + 1, c0) + fc * s(r0 + 1, c0 + 1));
}

double planetHeightAt(const clod::HeightPyramid& planet, const topo::Geodetic& site) {
  const double latC = planet.body()->planetocentricFromPlanetodetic(site.latDeg);
  const auto& level = planet.level(0);
  const glm::dvec2 idx = level.grid.fractionalIndex(topo::wrapLongitude180(site.lonDeg), latC);
  return bilinearHeight(level, idx.x, idx.y);
}

double demHeightAt(const clod::HeightPyramid& dem, double x, double y) {
  const auto& level = dem.level(0);
  const glm::dvec2 idx = level.grid.fractionalIndex(x, y);
  return bilinearHeight(level, idx.x, idx.y);
}

topo::GridPyramid levelsOf(const clod::HeightPyramid& p) {
  topo::GridPyramid g;
  for (std::size_t l = 0; l < p.levelCount(); ++l) g.levels.push_back(p.level(l));
  g.planetBody = p.kind() == clod::SurfaceKind::Planet ? p.body() : std::nullopt;
  g.latitudeType = p.latitudeType();
  return g;
}

std::size_t planetLevelsWithFarField(const clod::HeightPyramid& planet, int clipmapSize) {
  // Level k's window spans (size − 1) × its latitude spacing; keep those within 180°.
  std::size_t levels = 0;
  while (levels < planet.levelCount() &&
         (clipmapSize - 1) * std::abs(planet.level(levels).grid.spacingY()) <= 180.0) {
    ++levels;
  }
  return std::max<std::size_t>(levels, 1);
}

std::shared_ptr<const farfield::HeightLayers> farFieldLayers(
    const clod::HeightPyramid& planet, const compose::ComposedSurface* composed) {
  farfield::LayerOptions lo;
  lo.equirectWidth = 2048;
  lo.capSize = 512;
  if (composed) {
    return std::make_shared<const farfield::HeightLayers>(
        farfield::HeightLayers::fromSurface(*composed, lo));
  }
  // The planet grid at its finest level at most 4096 samples wide, read whole.
  std::size_t k = 0;
  while (k + 1 < planet.levelCount() && planet.level(k).grid.cols() > 4096) ++k;
  return std::make_shared<const farfield::HeightLayers>(farfield::HeightLayers::fromPlanetGrid(
      *planet.body(), planet.level(k).grid, *planet.level(k).source, planet.latitudeType(), lo));
}

farfield::PgmOptions planetFarFieldOptions(const glm::vec3& albedo) {
  farfield::PgmOptions po;
  // 256²: with the even-error spread of its rays (PgmOptions::evenError) its error is 2.6–4.6×
  // lower than the even 512² grid's, in 0.4–0.5× the time (docs/far-field.md, stop 44).
  po.gridWidth = po.gridHeight = 256;
  // A smaller grid while its cells span under 2 pixels (a planet seen whole): about 5× less
  // time for that frame on llvmpipe, for about 0.1 px more error (docs/far-field.md, "The
  // mesh pass"); near views keep the full grid.
  po.minCellPixels = 2.0;
  po.heightColours = false;
  po.high = albedo;
  po.ambient = clod::ClipmapOptions{}.ambient;
  return po;
}

TraverseEnd driveAndPress(const topo::TopoDem& dem, const rover::TraverseOptions& options,
                          rover::TrackLayer* tracks, const rover::StepCallback& onStep) {
  TraverseEnd end;
  std::optional<rover::TrackPresser> presser;  // one imprint of all six wheels every 5 cm
  if (tracks) presser.emplace(*tracks);
  end.result = rover::runTraverse(dem, options, [&](const rover::StepState& s) {
    if (presser && presser->press(s)) ++end.imprints;
    end.last = s.chassis;
    return onStep ? onStep(s) : true;
  });
  return end;
}

}  // namespace regolith::scene
