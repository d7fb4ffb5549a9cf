#pragma once
/// \file
/// One terrain drawn headless through SceneRenderer: its clipmap and, for a planet, its far
/// field wherever the clipmap left the image empty (`regolith render` of a store or a
/// catalogue file). clod::renderImage() draws the clipmap alone.

#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/clod/Legend.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/Image.hpp>

#include <memory>
#include <optional>
#include <string>

namespace regolith::farfield {
class HeightLayers;
}  // namespace regolith::farfield

namespace regolith::render {

/// A planet's far field for renderTerrain() (SceneRenderer::addFarField()).
struct TerrainFarField {
  std::shared_ptr<const farfield::HeightLayers> layers;
  farfield::PgmOptions options;
};

/// What renderTerrain() drew.
struct TerrainImage {
  gl::RgbaImage image;
  /// The legend of the declared height colours and lat/lon lines (none declared: nullopt),
  /// drawn into the image's top-right corner when the request says so.
  std::optional<clod::Legend> legend;
};

/// Draws `pyramid` as the only terrain of a one-node scene through SceneRenderer, headless
/// (an EGL surfaceless context is made if none is current): `request.camera` in the
/// pyramid's scene frame, the clipmap (`request.clipmap`) centred on `request.focus` or
/// else the camera's look-at point and loaded whole before the frame is drawn, lit by
/// `request.clipmap.lightDirection`; then, with `farField` (a pyramid drawn body-fixed: a
/// Planet one, or one with a placement), the far field (PGM, or the ray-cast impostor from
/// far away) wherever the clipmap left the image empty, lit by the same light. Throws
/// InvalidArgument naming "render::renderTerrain()" for a null pyramid, a camera
/// clod::checkCamera() refuses, or a far field on a pyramid in a grid frame; GlError
/// without GL 4.5.
[[nodiscard]] TerrainImage renderTerrain(std::shared_ptr<const clod::HeightPyramid> pyramid,
                                         const clod::RenderRequest& request,
                                         const std::optional<TerrainFarField>& farField = {});

/// renderTerrain(), then the PNG at `path` (crash-safe: a temporary name, fsync, rename)
/// and the legend beside it as `<path>.legend.json` when there is one.
void renderTerrainToPng(std::shared_ptr<const clod::HeightPyramid> pyramid,
                        const clod::RenderRequest& request,
                        const std::optional<TerrainFarField>& farField, const std::string& path);

}  // namespace regolith::render
