// `regolith render scene.json --camera NAME -o x.png`: one camera of a scene file, headless.
#include <regolith/core/Error.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneDescription.hpp>

#include "OutputFolder.hpp"
#include "SceneFiles.hpp"

#include <chrono>
#include <iomanip>
#include <sstream>

namespace regolith::tools {

void renderSceneFile(const std::filesystem::path& path, const std::string& camera,
                     const std::filesystem::path& png, std::ostream& report) {
  const auto start = std::chrono::steady_clock::now();
  scene::SceneDescription d = scene::readScene(path);
  std::ostringstream names;
  for (std::size_t i = 0; i < d.cameras.size(); ++i)
    names << (i == 0 ? "" : ", ") << d.cameras[i].name;
  const std::string cameras = d.cameras.empty() ? "none" : names.str();
  std::string name = camera;
  if (name.empty()) {
    if (d.cameras.size() != 1)
      throw InvalidArgument("render: " + path.string() +
                            ": --camera NAME is needed, the scene's cameras: " + cameras);
    name = d.cameras.front().name;
  }
  if (!d.camera(name))
    throw InvalidArgument("render: " + path.string() + ": no camera '" + name +
                          "', the scene's cameras: " + cameras);
  // Neither the scene nor any of its stores may be overwritten by the image.
  std::vector<std::filesystem::path> inputs{path};
  const auto add = [&](const scene::DataSource& s) {
    if (!s.store.empty()) inputs.push_back(d.resolve(s.store));
  };
  for (const scene::Body& b : d.bodies) {
    for (const scene::DataSource& s : b.heights) add(s);
    if (b.look.effects.albedo) add(b.look.effects.albedo->data);
    if (b.look.effects.overlay) add(b.look.effects.overlay->data);
  }
  for (const scene::Dem& m : d.dems) {
    add(m.heights);
    if (m.look.effects.albedo) add(m.look.effects.albedo->data);
    if (m.look.effects.overlay) add(m.look.effects.overlay->data);
  }
  for (const std::filesystem::path& input : inputs)
    refuseOverwritingInputs("render", {png}, {input});
  const scene::Scene built(std::move(d));
  const gl::RgbaImage image = built.render(name);
  gl::writePng(png.string(), image);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report << "Wrote " << png.string() << " (" << image.width << "×" << image.height << "): camera "
         << name << " of " << path.string() << ", focus " << built.focusOf(name) << "\n"
         << std::setprecision(3) << "  " << seconds << " s\n";
}

}  // namespace regolith::tools
