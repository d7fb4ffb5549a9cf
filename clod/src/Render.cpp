#include <regolith/clod/Legend.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <EGL/egl.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <utility>

namespace regolith::clod {

namespace {

/// Unit local north and east where the pyramid's "up" is `up`: +y and +x on a plane; grid
/// north (+y) made horizontal on a placed DEM; towards the north pole on the horizontal
/// plane of a planet (any horizontal direction at a pole).
std::pair<glm::dvec3, glm::dvec3> northEast(const HeightPyramid& pyramid, const glm::dvec3& up) {
  glm::dvec3 north{0.0, 1.0, 0.0};
  if (pyramid.kind() == SurfaceKind::Planet) {
    north = glm::dvec3(0.0, 0.0, 1.0) - up * up.z;
    if (glm::length(north) < 1e-9) north = {1.0, 0.0, 0.0};  // at a pole
    north = glm::normalize(north);
  } else if (pyramid.placement()) {
    // A placed DEM: grid north (+y) in body-fixed coordinates.
    const glm::dvec3 gridNorth = pyramid.position(0.0, 1.0, 0.0) - pyramid.position(0.0, 0.0, 0.0);
    north = glm::normalize(gridNorth - up * glm::dot(gridNorth, up));
  }
  return {north, glm::cross(north, up)};
}

}  // namespace

Camera cameraFromHeadingPitch(const HeightPyramid& pyramid, const glm::dvec3& position,
                              double headingDegrees, double pitchDegrees, double fovYDegrees,
                              int width, int height) {
  if (!(pitchDegrees > -90.0 && pitchDegrees < 90.0))
    throw InvalidArgument("cameraFromHeadingPitch(): pitch " + std::to_string(pitchDegrees) +
                          "°, expected inside (−90, 90)");
  const glm::dvec3 up = pyramid.up(position);
  const auto [north, east] = northEast(pyramid, up);
  const double h = headingDegrees * std::numbers::pi / 180.0;
  const double p = pitchDegrees * std::numbers::pi / 180.0;
  const glm::dvec3 dir =
      std::cos(p) * (std::cos(h) * north + std::sin(h) * east) + std::sin(p) * up;
  Camera cam;
  cam.position = position;
  cam.target = position + dir * 100.0;
  cam.up = up;
  cam.fovYDegrees = fovYDegrees;
  cam.width = width;
  cam.height = height;
  return cam;
}

Camera cameraLookingAt(const HeightPyramid& pyramid, const glm::dvec3& target,
                       double headingDegrees, double elevationDegrees, double distance,
                       double fovYDegrees, int width, int height) {
  if (!(elevationDegrees > 0.0 && elevationDegrees <= 90.0))
    throw InvalidArgument("cameraLookingAt(): elevation " + std::to_string(elevationDegrees) +
                          "°, expected inside (0, 90]");
  if (!(distance > 0.0 && std::isfinite(distance)))
    throw InvalidArgument("cameraLookingAt(): distance " + std::to_string(distance) +
                          " m, expected positive and finite");
  const glm::dvec3 up = pyramid.up(target);
  const auto [north, east] = northEast(pyramid, up);
  const double h = headingDegrees * std::numbers::pi / 180.0;
  const double e = elevationDegrees * std::numbers::pi / 180.0;
  const glm::dvec3 ahead = std::cos(h) * north + std::sin(h) * east;  // horizontal heading
  const glm::dvec3 forward = std::cos(e) * ahead - std::sin(e) * up;
  Camera cam;
  cam.target = target;
  cam.position = target - forward * distance;
  // Perpendicular to forward and in the vertical plane of the view: level horizon, and
  // well defined looking straight down (then the heading's direction is the image's top).
  cam.up = std::sin(e) * ahead + std::cos(e) * up;
  cam.fovYDegrees = fovYDegrees;
  cam.width = width;
  cam.height = height;
  cam.near = std::max(0.05, distance * 1e-3);
  return cam;
}

namespace {

gl::RgbaImage render(std::shared_ptr<const HeightPyramid> pyramid, const RenderRequest& request,
                     std::optional<Legend>* legendOut) {
  if (!pyramid) throw InvalidArgument("renderImage(): pyramid is null");
  const Camera& cam = request.camera;
  if (!(cam.fovYDegrees > 0.0 && cam.fovYDegrees < 180.0))
    throw InvalidArgument("renderImage(): field of view " + std::to_string(cam.fovYDegrees) +
                          "°, expected inside (0, 180)");
  if (!(cam.near > 0.0))
    throw InvalidArgument("renderImage(): near plane " + std::to_string(cam.near) +
                          " m, expected > 0");
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  gl::RgbaImage image;
  {
    ClipmapTerrain terrain(std::move(pyramid), request.clipmap);
    terrain.setFocus(request.focus.value_or(cam.target));
    gl::RenderTarget target(cam.width, cam.height);
    target.clear(request.background);
    terrain.draw(cam);
    image = target.readColor();
    const Legend legend = Legend::of(terrain, cam);
    if (!legend.empty()) {
      if (request.legendInImage) legend.drawInto(image);
      if (legendOut != nullptr) *legendOut = legend;
    }
  }  // GL objects go before the context
  return image;
}

}  // namespace

gl::RgbaImage renderImage(std::shared_ptr<const HeightPyramid> pyramid,
                          const RenderRequest& request) {
  return render(std::move(pyramid), request, nullptr);
}

void renderToPng(std::shared_ptr<const HeightPyramid> pyramid, const RenderRequest& request,
                 const std::string& path) {
  std::optional<Legend> legend;
  gl::writePng(path, render(std::move(pyramid), request, &legend));
  if (legend) legend->writeJson(path + ".legend.json");
}

}  // namespace regolith::clod
