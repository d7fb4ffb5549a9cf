#include <regolith/clod/Legend.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
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

std::string text(const glm::dvec3& v) {
  std::string s(1, '(');  // not "(" + ...: GCC 12's -Wrestrict false positive
  s += core::number(v.x);
  s += ", ";
  s += core::number(v.y);
  s += ", ";
  s += core::number(v.z);
  s += ')';
  return s;
}

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

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
  const char* op = "cameraFromHeadingPitch()";
  if (!(pitchDegrees > -90.0 && pitchDegrees < 90.0))
    throw InvalidArgument(
        core::format({op, {}, "pitch", core::number(pitchDegrees) + " deg", "inside (-90, 90)"}));
  if (!std::isfinite(headingDegrees))
    throw InvalidArgument(
        core::format({op, {}, "heading", core::number(headingDegrees) + " deg", "finite"}));
  if (!finite(position))
    throw InvalidArgument(core::format({op, {}, "camera position", text(position), "finite"}));
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
  const char* op = "cameraLookingAt()";
  if (!(elevationDegrees > 0.0 && elevationDegrees <= 90.0))
    throw InvalidArgument(core::format(
        {op, {}, "elevation", core::number(elevationDegrees) + " deg", "inside (0, 90]"}));
  if (!(distance > 0.0 && std::isfinite(distance)))
    throw InvalidArgument(
        core::format({op, {}, "distance", core::number(distance) + " m", "finite and > 0"}));
  if (!std::isfinite(headingDegrees))
    throw InvalidArgument(
        core::format({op, {}, "heading", core::number(headingDegrees) + " deg", "finite"}));
  if (!finite(target))
    throw InvalidArgument(core::format({op, {}, "target", text(target), "finite"}));
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

/// The lowest valid sample of the grid cell around grid point (x, y), from the finest level
/// that has one: the bilinear surface there lies at or above it. nullopt off the grid or
/// over nodata at every level.
std::optional<double> lowestSampleAround(const HeightPyramid& pyramid, double x, double y) {
  for (std::size_t l = 0; l < pyramid.levelCount(); ++l) {
    const auto& level = pyramid.level(l);
    const glm::dvec2 f = level.grid.fractionalIndex(x, y);  // (col, row)
    const double cols = static_cast<double>(level.grid.cols());
    const double rows = static_cast<double>(level.grid.rows());
    if (!(f.x > -1.0 && f.y > -1.0 && f.x < cols && f.y < rows)) return std::nullopt;
    std::optional<double> lowest;
    for (const double r : {std::floor(f.y), std::ceil(f.y)}) {
      for (const double c : {std::floor(f.x), std::ceil(f.x)}) {
        if (r < 0.0 || c < 0.0 || r >= rows || c >= cols) continue;
        const float s =
            level.source->sample(static_cast<std::size_t>(r), static_cast<std::size_t>(c));
        if (std::isnan(s) || level.grid.isNodata(s)) continue;
        lowest = std::min(lowest.value_or(static_cast<double>(s)), static_cast<double>(s));
      }
    }
    if (lowest) return lowest;
  }
  return std::nullopt;
}

/// Throws InvalidArgument if the eye lies inside the body: below the lowest sample of the
/// terrain's cell under it (so a camera above the surface, however close, is never refused),
/// or, on a planet, nearer the centre than half the polar radius (where no grid point is).
void refuseEyeInsideBody(const HeightPyramid& pyramid, const glm::dvec3& eye,
                         const std::string& operation) {
  const std::string expected = "above the terrain's surface (the camera is inside the body)";
  if (pyramid.kind() == SurfaceKind::Planet &&
      glm::length(eye) < 0.5 * pyramid.body()->polarRadius()) {
    throw InvalidArgument(core::format(
        {operation,
         {},
         "camera position",
         text(eye) + " m, " + core::number(glm::length(eye)) + " m from the body's centre",
         expected}));
  }
  glm::dvec2 g = pyramid.gridPoint(eye);
  if (pyramid.kind() == SurfaceKind::Planet && !pyramid.level(0).grid.contains(g.x, g.y)) {
    g.x += g.x < 0.0 ? 360.0 : -360.0;  // a grid in 0…360 degrees of longitude
  }
  const std::optional<double> ground = lowestSampleAround(pyramid, g.x, g.y);
  if (!ground) return;
  const glm::dvec3 surface = pyramid.position(g.x, g.y, *ground);
  const double above = glm::dot(eye - surface, pyramid.up(surface));
  if (above < 0.0) {
    throw InvalidArgument(
        core::format({operation,
                      {},
                      "camera position",
                      text(eye) + " m, " + core::number(-above) + " m below the surface",
                      expected}));
  }
}

}  // namespace

void checkCamera(const HeightPyramid& pyramid, const Camera& cam, const std::string& operation) {
  const auto refuse = [&operation](const std::string& field, const std::string& value,
                                   const char* exp) {
    throw InvalidArgument(core::format({operation, {}, field, value, exp}));
  };
  if (!finite(cam.position)) refuse("camera position", text(cam.position), "finite");
  if (!finite(cam.target)) refuse("camera target", text(cam.target), "finite");
  if (!finite(cam.up)) refuse("camera up", text(cam.up), "finite");
  if (!(glm::length(cam.target - cam.position) > 0.0))
    refuse("camera target", text(cam.target), "a point other than the camera position");
  if (!(cam.fovYDegrees > 0.0 && cam.fovYDegrees < 180.0))
    refuse("field of view", core::number(cam.fovYDegrees) + " deg", "inside (0, 180)");
  if (!(cam.near > 0.0 && std::isfinite(cam.near)))
    refuse("near plane", core::number(cam.near) + " m", "finite and > 0");
  if (cam.width < 1 || cam.height < 1 || cam.width > 16384 || cam.height > 16384) {
    refuse("image size", std::to_string(cam.width) + " x " + std::to_string(cam.height),
           "1 to 16384 pixels a side");
  }
  refuseEyeInsideBody(pyramid, cam.position, operation);
}

namespace {

gl::RgbaImage render(std::shared_ptr<const HeightPyramid> pyramid, const RenderRequest& request,
                     std::optional<Legend>* legendOut) {
  if (!pyramid) throw InvalidArgument("renderImage(): pyramid is null");
  const Camera& cam = request.camera;
  checkCamera(*pyramid, cam, "renderImage()");
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
