// `regolith info scene.json`: what a scene file declares.
#include <regolith/core/Message.hpp>
#include <regolith/scene/SceneDescription.hpp>
#include <regolith/store/Store.hpp>

#include "SceneFiles.hpp"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace regolith::tools {

bool isSceneFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec) || store::Store::isHdf5(path)) return false;
  std::ifstream in(path, std::ios::binary);
  const nlohmann::json doc = nlohmann::json::parse(in, nullptr, false);
  return doc.is_object() && doc.contains("bodies");
}

void printSceneInfo(const std::filesystem::path& path, bool json, std::ostream& out) {
  const scene::SceneDescription s = scene::readScene(path);
  if (json) {
    out << scene::sceneInfoJson(s);
    return;
  }
  const auto effects = [](const scene::EffectsDescription& e) {
    std::ostringstream text;
    const auto names = e.declared();
    for (std::size_t i = 0; i < names.size(); ++i) text << (i == 0 ? "" : ", ") << names[i];
    return names.empty() ? std::string("none") : text.str();
  };
  const auto source = [&](const scene::DataSource& d) {
    return d.store.empty() ? "generated " + d.generate + " (seed " + std::to_string(d.seed) + ")"
                           : s.resolve(d.store).string() + " grid " + d.grid;
  };
  out << path.string() << ": scene, version " << s.version << "\n";
  for (const scene::Body& b : s.bodies) {
    out << "  body " << b.name << (b.farField ? " (far field)" : "")
        << ", effects: " << effects(b.look.effects) << "\n";
    for (const scene::DataSource& d : b.heights) out << "    heights: " << source(d) << "\n";
    if (b.heights.empty()) out << "    heights: none (its ellipsoid, without relief)\n";
    if (b.pose) {
      out << "    at [" << core::number(b.pose->position[0]) << ", "
          << core::number(b.pose->position[1]) << ", " << core::number(b.pose->position[2])
          << "] m in the root frame\n";
    }
  }
  for (const scene::Dem& d : s.dems) {
    out << "  DEM " << d.name << " on " << d.body << ": " << source(d.heights)
        << ", effects: " << effects(d.look.effects) << "\n";
  }
  for (const scene::Object& o : s.objects) {
    out << "  " << o.type << " " << o.name << " on " << o.dem
        << (o.traverse ? ", replaying a traverse" : "") << "\n";
  }
  for (const scene::Camera& c : s.cameras) {
    out << "  camera " << c.name << " in " << c.frame << ", " << c.width << "x" << c.height
        << ", fovY " << c.fovY << "°\n";
  }
}

}  // namespace regolith::tools
