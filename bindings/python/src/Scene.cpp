// The paper's example scene from Python: the scene graph (poses only) and headless renders
// of the Mars/Victoria scene with data (regolith::demo) into numpy images.
#include <regolith/core/Error.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/demo/PaperScene.hpp>
#include <regolith/rover/TrackLayer.hpp>

#include "Common.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::python {

namespace {

using scenegraph::SceneGraph;

/// A built paper scene: the graph and the ids of its named nodes.
struct PyScene {
  SceneGraph graph{"sun"};
  demo::PaperSceneNodes nodes;
};

const char* kindName(scenegraph::NodeKind k) {
  switch (k) {
    case scenegraph::NodeKind::Frame: return "frame";
    case scenegraph::NodeKind::Terrain: return "terrain";
    case scenegraph::NodeKind::Object: return "object";
    case scenegraph::NodeKind::Camera: return "camera";
  }
  return "frame";
}

/// {"translation": (3,), "rotation": (3, 3)}: p_to_frame = rotation · p + translation.
py::dict poseDict(const scenegraph::Pose& p) {
  py::array_t<double> t(3), r({3, 3});
  auto tm = t.mutable_unchecked<1>();
  auto rm = r.mutable_unchecked<2>();
  const glm::dmat3 m = p.matrix();
  for (py::ssize_t i = 0; i < 3; ++i) {
    tm(i) = p.translation[static_cast<glm::length_t>(i)];
    for (py::ssize_t j = 0; j < 3; ++j)
      rm(i, j) = m[static_cast<glm::length_t>(j)][static_cast<glm::length_t>(i)];  // column j
  }
  py::dict d;
  d["translation"] = t;
  d["rotation"] = r;
  return d;
}

demo::MarsVictoriaOptions sceneOptions(const std::optional<std::filesystem::path>& mars,
                                       const std::optional<std::filesystem::path>& victoria,
                                       std::size_t planetRows, std::size_t demSize,
                                       double demSpacing, int clipmapSize) {
  demo::MarsVictoriaOptions o;
  o.planetRows = planetRows;
  o.demSize = demSize;
  o.demSpacing = demSpacing;
  o.clipmapSize = clipmapSize;
  if (mars) o.marsStore = *mars;
  if (victoria) o.victoriaStore = *victoria;
  return o;
}

/// The wheels of one rover step as contacts: a (wheels, 2 or more) array of grid x, y.
std::vector<rover::WheelImprint> contactsOf(const DoubleArray& wheels, double width, double depth,
                                            const char* op) {
  if (wheels.ndim() != 2 || wheels.shape(1) < 2 || wheels.shape(0) < 1) {
    throw InvalidArgument(std::string(op) + ": wheels has shape " + shapeOf(wheels) +
                          ", expected (wheels, 2 or more): grid x, y of each wheel");
  }
  const auto a = wheels.unchecked<2>();
  std::vector<rover::WheelImprint> c(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t w = 0; w < a.shape(0); ++w)
    c[static_cast<std::size_t>(w)] = {{a(w, 0), a(w, 1)}, width, depth};
  return c;
}

/// render_scene()'s tracks: a TrackLayer as it is, or wheel contacts (steps, 6, 2 or more)
/// pressed step by step into a new layer.
std::shared_ptr<rover::TrackLayer> trackLayerOf(const py::object& tracks) {
  if (py::isinstance<rover::TrackLayer>(tracks))
    return tracks.cast<std::shared_ptr<rover::TrackLayer>>();
  const auto notContacts = [&] {
    return InvalidArgument("regolith.render_scene(): tracks is a " +
                           std::string(py::str(py::type::of(tracks).attr("__name__"))) +
                           ", expected a TrackLayer or wheel contacts (steps, 6, 2 or more)");
  };
  DoubleArray arr;
  try {
    arr = tracks.cast<DoubleArray>();
  } catch (const py::cast_error&) {
    throw notContacts();
  } catch (const py::error_already_set& e) {  // numpy could not convert it
    if (!e.matches(PyExc_TypeError) && !e.matches(PyExc_ValueError)) throw;
    throw notContacts();
  }
  if (arr.ndim() != 3 || arr.shape(1) != 6 || arr.shape(2) < 2) {
    throw InvalidArgument("regolith.render_scene(): tracks has shape " + shapeOf(arr) +
                          ", expected (steps, 6, 2 or more): wheel x, y per step, or a TrackLayer");
  }
  const auto a = arr.unchecked<3>();
  using Ruts = rover::RoverRuts;
  auto layer = std::make_shared<rover::TrackLayer>(Ruts::kTexelMetres);
  std::array<rover::WheelImprint, 6> step;
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    for (py::ssize_t w = 0; w < 6; ++w)
      step[static_cast<std::size_t>(w)] = {
          {a(i, w, 0), a(i, w, 1)}, Ruts::kWheelWidthMetres, Ruts::kDepthMetres};
    layer->step(step);
  }
  return layer;
}

}  // namespace

void bindScene(py::module_& m) {
  py::class_<rover::TrackLayer, std::shared_ptr<rover::TrackLayer>>(
      m, "TrackLayer",
      "Wheel tracks a traverse leaves (rover::TrackLayer): a sparse rut-depth field in a DEM's "
      "grid frame (metres), pressed step by step and drawn by render_scene(tracks=...) and "
      "Dem.render(tracks=...) as ruts. Thread-safe.")
      .def(py::init<double>(), py::arg("texel_metres") = rover::RoverRuts::kTexelMetres,
           "texel_metres: the field's resolution (> 0).")
      .def(
          "step",
          [](rover::TrackLayer& l, const DoubleArray& wheels, double width, double depth) {
            const auto c = contactsOf(wheels, width, depth, "regolith.TrackLayer.step()");
            l.step(c);
          },
          py::arg("wheels"), py::arg("width") = rover::RoverRuts::kWheelWidthMetres,
          py::arg("depth") = rover::RoverRuts::kDepthMetres,
          "Presses one rover step: wheels is (wheels, 2 or more), each wheel's grid x, y (e.g. a "
          "run_traverse callback's state['wheels']); each wheel's rut runs from its previous "
          "contact to this one, depth·cos²(π·d/width) across, the deeper rut winning where they "
          "overlap.")
      .def(
          "depth_at",
          [](const rover::TrackLayer& l, const DoubleArray& xs, const DoubleArray& ys) {
            if (xs.size() != ys.size())
              throw InvalidArgument("regolith.TrackLayer.depth_at(): x has " +
                                    std::to_string(xs.size()) + " values and y " +
                                    std::to_string(ys.size()) + ", expected the same number");
            py::array_t<double> out(xs.request().shape);
            const double* x = xs.data();
            const double* y = ys.data();
            double* o = out.mutable_data();
            for (py::ssize_t i = 0; i < xs.size(); ++i) o[i] = l.depthAt({x[i], y[i]});
            return out;
          },
          py::arg("x"), py::arg("y"),
          "Rut depth (metres, ≥ 0) at grid points, bilinear between texel centres; the shape "
          "of x.")
      .def_property_readonly("texel_metres", &rover::TrackLayer::texelMetres)
      .def_property_readonly("tiles", &rover::TrackLayer::tiles,
                             "Tiles of 512² texels allocated so far.")
      .def("clear", &rover::TrackLayer::clear, "Forgets every track.");

  py::class_<PyScene, std::shared_ptr<PyScene>>(
      m, "SceneGraph",
      "The JPL paper's example scene as a tree of frames (poses in double, metres): Sun → "
      "Earth, Sun → Mars → Victoria (a DEM's local tangent plane at 2.05°S, 5.5°W) → rover → "
      "mast and chase cameras, Mars → orbit camera (and a second DEM if asked). No data and no "
      "GL: poses only. Build it with regolith.paper_scene().")
      .def(
          "names",
          [](const PyScene& s) {
            std::vector<std::string> names;
            for (std::size_t i = 0; i < s.graph.size(); ++i) names.push_back(s.graph.node(i).name);
            return names;
          },
          "The node names, root (the Sun) first.")
      .def(
          "parent",
          [](const PyScene& s, const std::string& name) -> std::optional<std::string> {
            const auto& n = s.graph.node(s.graph.at(name));
            if (!n.parent) return std::nullopt;
            return s.graph.node(*n.parent).name;
          },
          py::arg("name"), "The parent's name (None for the root).")
      .def(
          "kind",
          [](const PyScene& s, const std::string& name) {
            return std::string(kindName(s.graph.node(s.graph.at(name)).kind));
          },
          py::arg("name"), "'frame', 'terrain', 'object' or 'camera'.")
      .def(
          "relative",
          [](const PyScene& s, const std::string& frame, const std::string& node) {
            return poseDict(s.graph.relative(s.graph.at(frame), s.graph.at(node)));
          },
          py::arg("frame"), py::arg("node"),
          "The pose of `node` in `frame`, composed along the tree through their common "
          "ancestor: {'translation': (3,), 'rotation': (3, 3)} with p_frame = rotation @ p_node "
          "+ translation. Raises InvalidArgument for an unknown name.")
      .def(
          "place_rover",
          [](PyScene& s, double x, double y, double z, double headingDeg) {
            s.graph.setLocal(s.nodes.rover, scenegraph::roverPose({x, y, z}, headingDeg));
          },
          py::arg("x"), py::arg("y"), py::arg("z"), py::arg("heading_deg") = 0.0,
          "Puts the rover at (x, y, z) in the Victoria DEM's frame, heading clockwise from +y.");

  m.def(
      "paper_scene",
      [](bool secondDem) {
        auto s = std::make_shared<PyScene>();
        demo::PaperSceneLayout layout;
        layout.secondDem = secondDem;
        s->nodes = demo::buildPaperScene(s->graph, layout);
        return s;
      },
      py::arg("second_dem") = false,
      "Builds the paper's example scene (demo::buildPaperScene) and returns its SceneGraph.");

  m.def(
      "render_scene",
      [](std::array<double, 3> eye, std::array<double, 3> lookAt, std::array<double, 3> rover,
         std::optional<std::filesystem::path> marsStore,
         std::optional<std::filesystem::path> victoriaStore, const py::object& tracks, int width,
         int height, double fov, std::size_t planetRows, std::size_t demSize, double demSpacing,
         int clipmapSize, std::array<double, 3> up) {
        demo::SceneViewOptions v;
        v.scene =
            sceneOptions(marsStore, victoriaStore, planetRows, demSize, demSpacing, clipmapSize);
        v.roverX = rover[0];
        v.roverY = rover[1];
        v.roverHeadingDeg = rover[2];
        v.width = width;
        v.height = height;
        v.fovYDegrees = fov;
        const glm::dvec3 e{eye[0], eye[1], eye[2]}, t{lookAt[0], lookAt[1], lookAt[2]};
        v.camera = scenegraph::Pose::lookAt(e, t, {up[0], up[1], up[2]});
        if (!tracks.is_none()) v.scene.victoriaEffects.tracks = trackLayerOf(tracks);
        gl::RgbaImage img;
        {
          const py::gil_scoped_release release;
          img = demo::renderSceneView(v);
        }
        return imageArray(img);
      },
      py::arg("eye"), py::arg("look_at"),
      py::arg("rover") = std::array<double, 3>{0.0, -395.0, 0.0},
      py::arg("mars_store") = py::none(), py::arg("victoria_store") = py::none(),
      py::arg("tracks") = py::none(), py::arg("width") = 640, py::arg("height") = 360,
      py::arg("fov_deg") = 45.0, py::arg("planet_rows") = 360, py::arg("dem_size") = 601,
      py::arg("dem_spacing") = 2.0, py::arg("clipmap_size") = 127,
      py::arg("up") = std::array<double, 3>{0.0, 0.0, 1.0},
      "Builds the Mars/Victoria scene with data (generated in memory, or the given mars and "
      "victoria stores, as `regolith demo` writes them) and renders one view headless into a "
      "(height, width, 4) uint8 RGBA array. eye and look_at are in the Victoria DEM's frame "
      "(x east, y north, z up, metres), and up is the direction that is up in the image (within "
      "1e-6 rad of parallel to the view, another up is chosen: the frame axis most "
      "perpendicular to it); rover is (x, y, heading_deg) on the DEM. tracks: wheel "
      "contacts (steps, 6, 2), e.g. run_traverse(...)['record']['wheels'], pressed as ruts, or "
      "a TrackLayer a traverse stamped.");

  m.def(
      "render_flyover",
      [](const std::filesystem::path& outDir, int frames, int width, int height,
         std::optional<std::filesystem::path> marsStore,
         std::optional<std::filesystem::path> victoriaStore, std::size_t planetRows,
         std::size_t demSize, double demSpacing, int clipmapSize, bool overPole,
         double approachFrom) {
        demo::FlyoverOptions o;
        o.outputDir = outDir;
        o.frames = frames;
        o.width = width;
        o.height = height;
        o.overPole = overPole;
        o.approachFrom = approachFrom;
        o.scene =
            sceneOptions(marsStore, victoriaStore, planetRows, demSize, demSpacing, clipmapSize);
        demo::FlyoverSummary s;
        {
          const py::gil_scoped_release release;
          s = demo::renderFlyover(o);
        }
        py::dict d;
        std::vector<std::filesystem::path> files(s.files.begin(), s.files.end());
        d["files"] = files;
        d["seconds"] = s.seconds;
        d["render_seconds"] = s.renderSeconds;
        d["focus_switch_frame"] = s.focusSwitchFrame;
        d["start_distance"] = s.startDistance;
        d["end_distance"] = s.endDistance;
        d["far_field_frames"] = s.farFieldFrames;
        d["impostor_frames"] = s.impostorFrames;
        d["covered_frames"] = s.coveredFrames;
        return d;
      },
      py::arg("out_dir"), py::arg("frames") = 24, py::arg("width") = 480, py::arg("height") = 270,
      py::arg("mars_store") = py::none(), py::arg("victoria_store") = py::none(),
      py::arg("planet_rows") = 360, py::arg("dem_size") = 601, py::arg("dem_spacing") = 2.0,
      py::arg("clipmap_size") = 127, py::arg("over_pole") = false, py::arg("approach_from") = 0.0,
      "Renders the fly-over from orbit down to the rover (demo::renderFlyover) as "
      "frame_NNNN.png files and multiview.png in out_dir; returns a summary dict. over_pole: "
      "begin with the pass over the north pole at 2000 km; approach_from: begin with an "
      "approach from this many metres from Mars's centre (0: none; `regolith demo` takes both, "
      "from 16 Mars radii, where the far field draws Mars as the ray-cast impostor). The "
      "summary counts the frames the far field drew by PGM (far_field_frames), by the "
      "impostor (impostor_frames) and left to the clipmaps (covered_frames).");
}

}  // namespace regolith::python
