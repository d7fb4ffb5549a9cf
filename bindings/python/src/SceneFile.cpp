// Scene files from Python (docs/scene-format.md): regolith.load_scene(path) and
// scene.render(camera=...) into a numpy image.
#include <regolith/gl/Image.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneDescription.hpp>

#include "Common.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::python {

void bindSceneFile(py::module_& m) {
  py::class_<scene::Scene, std::shared_ptr<scene::Scene>>(
      m, "SceneFile",
      "A scene file, built (docs/scene-format.md): stores opened and paged, generators run, "
      "traverses driven. render() draws one of its cameras headless.")
      .def_property_readonly(
          "cameras",
          [](const scene::Scene& s) {
            std::vector<std::string> names;
            for (const scene::Camera& c : s.description().cameras) names.push_back(c.name);
            return names;
          },
          "The scene's camera names, in file order.")
      .def_property_readonly(
          "info", [](const scene::Scene& s) { return scene::sceneInfoJson(s.description()); },
          "What the scene declares, as `regolith info --json` prints it (JSON text).")
      .def(
          "render",
          [](const scene::Scene& s, const std::optional<std::string>& camera) {
            std::string name;
            if (camera) {
              name = *camera;
            } else if (s.description().cameras.size() == 1) {
              name = s.description().cameras.front().name;
            } else {
              throw InvalidArgument("SceneFile.render(): camera=NAME is needed, the scene has " +
                                    std::to_string(s.description().cameras.size()) +
                                    " cameras (SceneFile.cameras)");
            }
            gl::RgbaImage image;
            {
              py::gil_scoped_release release;
              image = s.render(name);
            }
            return imageArray(image);
          },
          py::arg("camera") = py::none(),
          "Renders a camera (its size, viewport and field of view) headless: a (height, "
          "width, 4) uint8 RGBA array, top row first. ValueError for an unknown camera (the "
          "message lists the cameras).");
  m.def(
      "load_scene",
      [](const std::filesystem::path& path) {
        return std::make_shared<scene::Scene>(scene::Scene::load(path));
      },
      py::arg("path"),
      "Reads, checks and builds a scene file (docs/scene-format.md). ValueError naming the "
      "file and the key for a bad file (`scene.json: /cameras/1/fovY: 190 is not in (0, "
      "180)`).");
}

}  // namespace regolith::python
