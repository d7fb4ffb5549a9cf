// Headless rendering into a numpy image (clod::renderImage).
#include <regolith/clod/Render.hpp>
#include <regolith/clod/TrackLayer.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Pager.hpp>

#include "Common.hpp"

#include <pybind11/stl.h>

#include <array>
#include <cstring>
#include <memory>
#include <optional>

namespace regolith::python {

namespace {

/// The renderer's pyramid of a terrain: every stored level of its grid, paged through the
/// terrain's own cache. DEMs are drawn in their grid frame (x east, y north, z height),
/// planets body-fixed.
std::shared_ptr<const clod::HeightPyramid> pyramidOf(const Terrain& t) {
  return std::make_shared<const clod::HeightPyramid>(
      store::Pager(t.store, t.cache).pyramid(t.grid));
}

glm::dvec3 vec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

py::array_t<std::uint8_t> render(const Terrain& t, const std::array<double, 3>& position,
                                 const std::optional<std::array<double, 3>>& lookAt,
                                 std::optional<double> heading, std::optional<double> pitch,
                                 double fov, int width, int height, double near, int clipmapSize,
                                 const std::array<float, 4>& background,
                                 std::shared_ptr<clod::TrackLayer> tracks) {
  const char* op = "regolith.render()";
  if (lookAt.has_value() == (heading.has_value() || pitch.has_value())) {
    throw InvalidArgument(std::string(op) +
                          ": give either look_at or heading_deg and pitch_deg, not both or none");
  }
  if (width <= 0 || height <= 0 || width > 8192 || height > 8192) {
    throw InvalidArgument(std::string(op) + ": image size " + std::to_string(width) + "x" +
                          std::to_string(height) + ", expected 1 to 8192 pixels a side");
  }
  auto pyramid = pyramidOf(t);
  clod::RenderRequest req;
  req.clipmap.size = clipmapSize;
  req.clipmap.effects.tracks = std::move(tracks);
  req.background = {background[0], background[1], background[2], background[3]};
  const glm::dvec3 eye = vec3(position);
  if (lookAt) {
    req.camera.position = eye;
    req.camera.target = vec3(*lookAt);
    req.camera.up = pyramid->up(eye);
    req.camera.fovYDegrees = fov;
    req.camera.width = width;
    req.camera.height = height;
  } else {
    req.camera = clod::cameraFromHeadingPitch(*pyramid, eye, heading.value_or(0.0),
                                              pitch.value_or(0.0), fov, width, height);
  }
  req.camera.near = near;
  gl::RgbaImage img;
  {
    const py::gil_scoped_release release;
    img = clod::renderImage(pyramid, req);
  }
  return imageArray(img);
}

}  // namespace

py::array_t<std::uint8_t> imageArray(const gl::RgbaImage& img) {
  py::array_t<std::uint8_t> out(
      {static_cast<py::ssize_t>(img.height), static_cast<py::ssize_t>(img.width), py::ssize_t{4}});
  std::memcpy(out.mutable_data(), img.rgba.data(), img.rgba.size());
  return out;
}

void bindRender(py::class_<DemTerrain, std::shared_ptr<DemTerrain>>& dem,
                py::class_<PlanetTerrain, std::shared_ptr<PlanetTerrain>>& planet) {
  const char* doc =
      "Renders the terrain headless (EGL surfaceless, Mesa llvmpipe: no GPU or display needed) "
      "into a (height, width, 4) uint8 RGBA array, row 0 at the top. The camera is in the "
      "scene frame: a DEM's grid frame (x east, y north, z height, metres), a planet's "
      "body-fixed frame (metres). Aim it with look_at=(x, y, z), or with heading_deg "
      "(clockwise from north) and pitch_deg (negative looks down). Every stored pyramid level "
      "is drawn through the terrain's cache. tracks: a TrackLayer whose ruts are drawn on a DEM "
      "(InvalidArgument on a planet). Raises GlError if no GL 4.5 context can be made.";
  const auto def = [&](auto& cls) {
    cls.def(
        "render",
        [](const typename std::decay_t<decltype(cls)>::type& t,
           const std::array<double, 3>& position,
           const std::optional<std::array<double, 3>>& lookAt, std::optional<double> heading,
           std::optional<double> pitch, double fov, int width, int height, double near,
           int clipmapSize, const std::array<float, 4>& background,
           std::shared_ptr<clod::TrackLayer> tracks) {
          return render(t, position, lookAt, heading, pitch, fov, width, height, near, clipmapSize,
                        background, std::move(tracks));
        },
        py::arg("position"), py::arg("look_at") = py::none(), py::arg("heading_deg") = py::none(),
        py::arg("pitch_deg") = py::none(), py::arg("fov_deg") = 45.0, py::arg("width") = 640,
        py::arg("height") = 480, py::arg("near") = 0.1, py::arg("clipmap_size") = 255,
        py::arg("background") = std::array<float, 4>{0.02F, 0.02F, 0.04F, 1.0F},
        py::arg("tracks") = py::none(), doc);
  };
  def(dem);
  def(planet);
}

}  // namespace regolith::python
