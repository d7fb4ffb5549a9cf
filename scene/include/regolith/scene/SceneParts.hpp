#pragma once
/// \file
/// The pieces every scene is built from, shared by Scene and the demo (demo/MarsVictoria):
/// heights read off a pyramid in double, the planet clipmap's levels beside the far field,
/// the far field of a planet and its draw, and a traverse that presses wheel tracks.

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <memory>

namespace regolith::scene {

/// Bilinear height of a pyramid level at fractional (col, row), clamped to the grid, metres.
[[nodiscard]] double bilinearHeight(const clod::HeightPyramid::Level& level, double col,
                                    double row);
/// A planet's surface height (above its reference surface) at a planetodetic site, bilinear
/// in its finest level.
[[nodiscard]] double planetHeightAt(const clod::HeightPyramid& planet, const topo::Geodetic& site);
/// A DEM's height at grid (x, y), bilinear in its finest level.
[[nodiscard]] double demHeightAt(const clod::HeightPyramid& dem, double x, double y);

/// The planet pyramid's levels as a topo::GridPyramid (for the catalogue).
[[nodiscard]] topo::GridPyramid levelsOf(const clod::HeightPyramid& pyramid);

/// The planet clipmap levels to draw beside the far field: those whose window of
/// `clipmapSize` vertices spans at most 180° of latitude (a wider one reaches over a pole
/// onto ground it already covers), at least one.
[[nodiscard]] std::size_t planetLevelsWithFarField(const clod::HeightPyramid& planet,
                                                   int clipmapSize);

/// A planet's heights for the far field: the composed surface if any, else the planet grid
/// (its finest level at most 4096 samples wide), resampled into farfield::HeightLayers
/// (global 2048 × 1024 and 512² caps).
[[nodiscard]] std::shared_ptr<const farfield::HeightLayers> farFieldLayers(
    const clod::HeightPyramid& planet, const compose::ComposedSurface* composed);

/// The far field's settings for a planet drawn with a terrain's albedo and clod's ambient,
/// so the clipmap and PGM look alike where they meet (render::SceneRenderer::addFarField):
/// a 256² grid with the even-error spread of its rays, thinned while its cells span under 2
/// pixels (PgmOptions::minCellPixels).
[[nodiscard]] farfield::PgmOptions planetFarFieldOptions(const glm::vec3& albedo);

/// A traverse over `dem` that presses the six wheels into `tracks` every
/// rover::RoverRuts::kSpacingMetres of travel (tracks may be null: nothing is pressed).
/// Returns where the rover stopped (grid x, y, heading in radians clockwise from +y). Throws
/// as rover::runTraverse().
struct TraverseEnd {
  rover::TraverseResult result;
  rover::ChassisPose last;
  std::size_t imprints = 0;
};
TraverseEnd driveAndPress(const topo::TopoDem& dem, const rover::TraverseOptions& options,
                          rover::TrackLayer* tracks, const rover::StepCallback& onStep = {});

}  // namespace regolith::scene
