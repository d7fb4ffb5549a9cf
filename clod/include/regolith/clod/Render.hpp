#pragma once
/// \file
/// One-call headless rendering of a terrain to an image or a PNG file.

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/gl/Image.hpp>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <memory>
#include <optional>
#include <string>

namespace regolith::clod {

/// What to render. The camera is in the pyramid's scene frame (grid frame for a plane,
/// body-fixed for a planet); its width and height are the image size.
struct RenderRequest {
  Camera camera;
  ClipmapOptions clipmap;
  glm::vec4 background{0.02F, 0.02F, 0.04F, 1.0F};
  /// Clipmap focus; the camera's look-at point if unset.
  std::optional<glm::dvec3> focus;
  /// With height colours or lat/lon lines declared (clipmap.effects): draw their Legend into
  /// the image's top-right corner. renderToPng() also writes it beside the PNG as
  /// `<path>.legend.json` either way.
  bool legendInImage = true;
};

/// Throws InvalidArgument naming `operation`, the camera's field, its value and the
/// expectation, unless every number of `camera` is finite and in range (field of view in
/// (0, 180)°, near plane > 0, 1 to 16384 pixels a side, target other than the position) and
/// the eye lies outside the body: above the lowest sample of the terrain's cell under it
/// (however close), and on a planet farther from the centre than half the polar radius.
void checkCamera(const HeightPyramid& pyramid, const Camera& camera, const std::string& operation);

/// A camera at `position` looking along a heading (degrees clockwise from north: +y on a
/// plane, local north on a planet) and a pitch (degrees, negative looks down), with "up"
/// the pyramid's up at the position. Throws InvalidArgument for a pitch outside (−90, 90).
[[nodiscard]] Camera cameraFromHeadingPitch(const HeightPyramid& pyramid,
                                            const glm::dvec3& position, double headingDegrees,
                                            double pitchDegrees, double fovYDegrees, int width,
                                            int height);

/// An orbit camera: looks at scene point `target` from `distance` metres away, from the
/// direction given by a heading (degrees clockwise from north, the direction the camera
/// looks in) and an elevation above the target's horizon (degrees, in (0, 90]; 90 looks
/// straight down with north at the top of the image). The image's vertical is the target's
/// "up" tilted into the view plane, so the horizon stays level. Near plane: distance × 1e-3
/// (at least 5 cm). Throws InvalidArgument for an elevation outside (0, 90] or a distance
/// that is not positive and finite.
[[nodiscard]] Camera cameraLookingAt(const HeightPyramid& pyramid, const glm::dvec3& target,
                                     double headingDegrees, double elevationDegrees,
                                     double distance, double fovYDegrees, int width, int height);

/// Renders the terrain headless: creates an EGL surfaceless context if none is current on
/// this thread, loads every level synchronously around the focus, draws once. Throws
/// GlError if no GL 4.5 context can be made, InvalidArgument for a bad request.
[[nodiscard]] gl::RgbaImage renderImage(std::shared_ptr<const HeightPyramid> pyramid,
                                        const RenderRequest& request);

/// renderImage(), then writePng() to `path` (crash-safe: temporary name, then rename).
void renderToPng(std::shared_ptr<const HeightPyramid> pyramid, const RenderRequest& request,
                 const std::string& path);

}  // namespace regolith::clod
