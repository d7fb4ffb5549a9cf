// Headless rendering into a numpy image (render::renderTerrain(): the scene renderer, as
// `regolith render`).
#include <regolith/clod/EffectList.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/render/TerrainImage.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Pager.hpp>

#include "Common.hpp"

#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <numbers>
#include <optional>
#include <string>

namespace regolith::python {

namespace {

/// The renderer's pyramid of a terrain: every stored level of its grid, paged through the
/// terrain's own cache, its hints loaded on `loader` (the clipmap's). DEMs are drawn in their
/// grid frame (x east, y north, z height), or `placed` on their body (body-fixed, for lat/lon
/// lines); planets body-fixed.
std::shared_ptr<const clod::HeightPyramid> pyramidOf(const Terrain& t, bool placed,
                                                     std::shared_ptr<core::Executor> loader) {
  const store::GridInfo& info = t.store->grid(t.grid);
  topo::GridPyramid p = store::Pager(t.store, t.cache).pyramid(t.grid, std::move(loader));
  if (placed && info.kind == store::GridKind::Dem) {
    return std::make_shared<const clod::HeightPyramid>(std::move(p.levels),
                                                       store::placementOf(info));
  }
  return std::make_shared<const clod::HeightPyramid>(std::move(p));
}

glm::dvec3 vec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

constexpr const char* kOp = "regolith.render()";

std::string typeName(const py::handle& o) {
  return py::str(py::type::of(o).attr("__name__")).cast<std::string>();
}

/// A number parameter of effects[name][key]: a real number (not a bool), else InvalidArgument.
double numberParameter(const py::handle& v, const std::string& where) {
  if (py::isinstance<py::bool_>(v) ||
      !(py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v)))
    throw InvalidArgument(std::string(kOp) + ": " + where + " is a " + typeName(v) +
                          ", expected a number");
  return v.cast<double>();
}

/// The effects render() was asked for: names and parameters (clod::EffectRequest, checked
/// later by clod::effectsOf()), and the TrackLayer that draws tracks.
struct PyEffects {
  clod::EffectRequest request;
  std::shared_ptr<rover::TrackLayer> tracks;
  clod::EffectOptionNames spelling = clod::kPythonEffectOptions;
};

/// The parameters of effects[name] (a dict): each key known for that effect.
void addParameters(PyEffects& out, const std::string& name, const py::dict& params) {
  const std::string where = "effects['" + name + "']";
  const auto unknown = [&](const std::string& key, const char* known) {
    throw InvalidArgument(std::string(kOp) + ": " + where + " has no parameter '" + key +
                          "', expected " + known);
  };
  for (const auto& [k, v] : params) {
    if (!py::isinstance<py::str>(k))
      throw InvalidArgument(std::string(kOp) + ": " + where + " has a key of type " + typeName(k) +
                            ", expected parameter names (str)");
    const std::string key = k.cast<std::string>();
    std::string at = where;  // effects['name']['key']
    at += "['";
    at += key;
    at += "']";
    if (name == "height-colours") {
      if (key != "range") unknown(key, "range");
      py::sequence seq;
      if (!py::isinstance<py::sequence>(v) || py::isinstance<py::str>(v) || py::len(v) != 2)
        throw InvalidArgument(std::string(kOp) + ": " + at + " is a " + typeName(v) +
                              ", expected (low, high) in metres");
      seq = v.cast<py::sequence>();
      out.request.heightRange =
          std::array<double, 2>{numberParameter(seq[0], at), numberParameter(seq[1], at)};
      out.spelling.heightRange = "effects['height-colours']['range']";
    } else if (name == "latlon") {
      if (key != "spacing") unknown(key, "spacing");
      out.request.latLonSpacing = numberParameter(v, at);
    } else if (name == "noise") {
      if (key == "amplitude") {
        out.request.noiseAmplitude = numberParameter(v, at);
      } else if (key == "wavelength") {
        out.request.noiseWavelength = numberParameter(v, at);
      } else if (key == "octaves") {
        if (py::isinstance<py::bool_>(v) || !py::isinstance<py::int_>(v))
          throw InvalidArgument(std::string(kOp) + ": " + at + " is a " + typeName(v) +
                                ", expected an int (1 to 8)");
        const long long o = v.cast<long long>();
        out.request.noiseOctaves = o < 0 ? -1 : o > 1000 ? 1000 : static_cast<int>(o);
      } else {
        unknown(key, "amplitude, wavelength, octaves");
      }
    } else {  // tracks
      unknown(key, "none (give the TrackLayer itself: effects={'tracks': layer})");
    }
  }
}

/// Parses render()'s effects: None, a comma-separated str, a list/tuple of names, or a dict
/// name -> None/True (defaults), False (not declared), a dict of parameters, or (tracks) a
/// TrackLayer. `tracks` is the tracks= keyword: without effects it declares tracks alone.
PyEffects parseEffects(const py::object& effects,
                       const std::optional<std::array<double, 2>>& heightRange,
                       std::shared_ptr<rover::TrackLayer> tracks) {
  PyEffects out;
  const auto& sp = clod::kPythonEffectOptions;
  if (effects.is_none()) {
    out.request.tracks = tracks != nullptr;  // as before effects=: tracks= alone draws ruts
  } else if (py::isinstance<py::str>(effects)) {
    clod::addEffectList(out.request, effects.cast<std::string>(), kOp, sp);
  } else if (py::isinstance<py::dict>(effects)) {
    for (const auto& [k, v] : effects.cast<py::dict>()) {
      if (!py::isinstance<py::str>(k))
        throw InvalidArgument(std::string(kOp) + ": effects has a key of type " + typeName(k) +
                              ", expected effect names (str)");
      const std::string name = k.cast<std::string>();
      clod::EffectRequest probe;
      clod::addEffectName(probe, name, kOp, sp);                      // refuses unknown names
      if (py::isinstance<py::bool_>(v) && !v.cast<bool>()) continue;  // False: not declared
      clod::addEffectName(out.request, name, kOp, sp);
      if (v.is_none() || py::isinstance<py::bool_>(v)) continue;
      if (name == "tracks" && py::isinstance<rover::TrackLayer>(v)) {
        if (tracks)
          throw InvalidArgument(
              std::string(kOp) +
              ": give the TrackLayer as tracks= or as effects['tracks'], not both");
        tracks = v.cast<std::shared_ptr<rover::TrackLayer>>();
        continue;
      }
      if (!py::isinstance<py::dict>(v))
        throw InvalidArgument(std::string(kOp) + ": effects['" + name + "'] is a " + typeName(v) +
                              ", expected None, True, False or a dict of parameters" +
                              (name == "tracks" ? " (or a TrackLayer)" : ""));
      addParameters(out, name, v.cast<py::dict>());
    }
  } else if (py::isinstance<py::list>(effects) || py::isinstance<py::tuple>(effects)) {
    for (const auto& item : effects) {
      if (!py::isinstance<py::str>(item))
        throw InvalidArgument(std::string(kOp) + ": effects holds a " + typeName(item) +
                              ", expected effect names (str)");
      clod::addEffectName(out.request, item.cast<std::string>(), kOp, sp);
    }
  } else {
    throw InvalidArgument(std::string(kOp) + ": effects is a " + typeName(effects) +
                          ", expected None, a list of effect names, a comma-separated str or a "
                          "dict name -> parameters");
  }
  if (heightRange) {
    if (out.request.heightRange)
      throw InvalidArgument(std::string(kOp) +
                            ": give height_range or effects['height-colours']['range'], not both");
    out.request.heightRange = *heightRange;
  }
  if (tracks && !out.request.tracks) {
    throw InvalidArgument(std::string(kOp) +
                          ": tracks sets the layer of tracks, which effects does not name");
  }
  if (out.request.tracks && !tracks) {
    throw InvalidArgument(std::string(kOp) +
                          ": effect 'tracks' needs a TrackLayer (the ruts a traverse pressed): "
                          "tracks=layer or effects={'tracks': layer}");
  }
  out.tracks = std::move(tracks);
  return out;
}

/// The checked clod::Effects of `e` on terrain `t` drawn as `pyramid`.
clod::Effects effectsOf(const PyEffects& e, const Terrain& t, const clod::HeightPyramid& pyramid) {
  const bool planet = pyramid.kind() == clod::SurfaceKind::Planet;
  if (e.request.tracks && planet) {
    throw InvalidArgument(std::string(kOp) +
                          ": effect 'tracks' needs a DEM (ruts are in metres), "
                          "and grid '" +
                          t.grid + "' is a planet");
  }
  if (e.request.latLon && !planet && !pyramid.placement()) {
    throw InvalidArgument(std::string(kOp) +
                          ": effect 'latlon' needs a planet or a DEM placed "
                          "on one, and grid '" +
                          t.grid + "' has no placement (no latitude or longitude)");
  }
  clod::EffectDefaults d;
  const store::GridInfo& info = t.store->grid(t.grid);
  d.heightRange = [&info, &pyramid]() -> std::optional<std::array<double, 2>> {
    if (info.statistics && info.statistics->validSamples > 0)
      return std::array<double, 2>{info.statistics->min, info.statistics->max};
    return clod::heightRangeOf(pyramid);
  };
  d.gridSpacing = std::abs(pyramid.level(0).grid.spacingY());
  d.metresPerGridUnit =
      planet ? pyramid.body()->equatorialRadius() * std::numbers::pi / 180.0 : 1.0;
  clod::Effects out = clod::effectsOf(e.request, d, kOp, e.spelling);
  out.tracks = e.tracks;
  return out;
}

py::array_t<std::uint8_t> render(const Terrain& t, const std::array<double, 3>& position,
                                 const std::optional<std::array<double, 3>>& lookAt,
                                 std::optional<double> heading, std::optional<double> pitch,
                                 double fov, int width, int height, double near, int clipmapSize,
                                 const std::array<float, 4>& background,
                                 std::shared_ptr<rover::TrackLayer> tracks,
                                 const py::object& effects,
                                 const std::optional<std::array<double, 2>>& heightRange,
                                 bool legend, bool farField) {
  const char* op = kOp;
  if (lookAt.has_value() == (heading.has_value() || pitch.has_value())) {
    throw InvalidArgument(std::string(op) +
                          ": give either look_at or heading_deg and pitch_deg, not both or none");
  }
  if (width <= 0 || height <= 0 || width > 8192 || height > 8192) {
    throw InvalidArgument(std::string(op) + ": image size " + std::to_string(width) + "x" +
                          std::to_string(height) + ", expected 1 to 8192 pixels a side");
  }
  const PyEffects named = parseEffects(effects, heightRange, std::move(tracks));
  // One loader thread for the render: the pyramid's hints and the clipmap's reads.
  auto loader = std::make_shared<core::ThreadPool>(1);
  auto pyramid = pyramidOf(t, named.request.latLon, loader);
  clod::RenderRequest req;
  req.clipmap.executor = loader;
  req.clipmap.size = clipmapSize;
  req.clipmap.effects = effectsOf(named, t, *pyramid);
  req.legendInImage = legend;
  if (pyramid->placement()) {  // a DEM drawn placed (lat/lon lines): lit as in its grid frame
    const glm::dvec2 g =
        lookAt ? glm::dvec2((*lookAt)[0], (*lookAt)[1]) : glm::dvec2(position[0], position[1]);
    req.clipmap.lightDirection = clod::gridLightInScene(*pyramid, g, req.clipmap.lightDirection);
  }
  req.background = {background[0], background[1], background[2], background[3]};
  // A DEM drawn placed (lat/lon lines): the camera is still given in its grid frame.
  const auto scene = [&](const std::array<double, 3>& p) {
    return pyramid->placement() ? pyramid->position(p[0], p[1], p[2]) : vec3(p);
  };
  const glm::dvec3 eye = scene(position);
  if (lookAt) {
    req.camera.position = eye;
    req.camera.target = scene(*lookAt);
    req.camera.up = pyramid->up(eye);
    req.camera.fovYDegrees = fov;
    req.camera.width = width;
    req.camera.height = height;
  } else {
    req.camera = clod::cameraFromHeadingPitch(*pyramid, eye, heading.value_or(0.0),
                                              pitch.value_or(0.0), fov, width, height);
  }
  req.camera.near = near;
  // A planet, as `regolith render` draws it: the clipmap's levels whose window spans at most
  // 180°, the far field beyond them (docs/far-field.md).
  std::optional<render::TerrainFarField> far;
  if (farField && pyramid->kind() == clod::SurfaceKind::Planet) {
    far = render::TerrainFarField{scene::farFieldLayers(*pyramid, nullptr),
                                  scene::planetFarFieldOptions(req.clipmap.albedo)};
    req.clipmap.levels = scene::planetLevelsWithFarField(*pyramid, req.clipmap.size);
  }
  gl::RgbaImage img;
  {
    const py::gil_scoped_release release;
    img = render::renderTerrain(pyramid, req, far).image;
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
      "(InvalidArgument on a planet). effects: what to draw on the terrain (docs/overlays.md): "
      "a list of names or a comma-separated str of 'tracks', 'height-colours', 'latlon', "
      "'noise', or a dict name -> None/True (defaults), False (left out) or parameters: "
      "{'height-colours': {'range': (low, high)}, 'latlon': {'spacing': deg (0 adapts)}, "
      "'noise': {'amplitude': m, 'wavelength': grid units, 'octaves': 1..8}, 'tracks': "
      "TrackLayer}. Only the named effects are built. height_range: (low, high) metres of the "
      "height colours (default: the grid's lowest and highest height). legend: draw the "
      "legend of height colours and lat/lon lines into the top-right corner. far_field: on a "
      "planet, draw the clipmap's levels that span at most 180 degrees and the far field "
      "(projective grid mapping, or the ray-cast globe from far away) beyond them, as "
      "`regolith render` does (docs/far-field.md); False draws the clipmap alone, every "
      "level (a DEM has no far field). Drawn by the scene renderer (render::renderTerrain). "
      "Raises "
      "InvalidArgument for an unknown effect, a parameter out of range or of an effect not "
      "named, GlError if no GL 4.5 context can be made.";
  const auto def = [&](auto& cls) {
    cls.def(
        "render",
        [](const typename std::decay_t<decltype(cls)>::type& t,
           const std::array<double, 3>& position,
           const std::optional<std::array<double, 3>>& lookAt, std::optional<double> heading,
           std::optional<double> pitch, double fov, int width, int height, double near,
           int clipmapSize, const std::array<float, 4>& background,
           std::shared_ptr<rover::TrackLayer> tracks, const py::object& effects,
           const std::optional<std::array<double, 2>>& heightRange, bool legend, bool farField) {
          return render(t, position, lookAt, heading, pitch, fov, width, height, near, clipmapSize,
                        background, std::move(tracks), effects, heightRange, legend, farField);
        },
        py::arg("position"), py::arg("look_at") = py::none(), py::arg("heading_deg") = py::none(),
        py::arg("pitch_deg") = py::none(), py::arg("fov_deg") = 45.0, py::arg("width") = 640,
        py::arg("height") = 480, py::arg("near") = 0.1, py::arg("clipmap_size") = 255,
        py::arg("background") = std::array<float, 4>{0.02F, 0.02F, 0.04F, 1.0F},
        py::arg("tracks") = py::none(), py::arg("effects") = py::none(),
        py::arg("height_range") = py::none(), py::arg("legend") = true, py::arg("far_field") = true,
        doc);
  };
  def(dem);
  def(planet);
}

}  // namespace regolith::python
