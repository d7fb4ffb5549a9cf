#include "ViewScene.hpp"

#include <regolith/core/Executor.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include "StoreGrid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace regolith::tools::viewer {

namespace {

/// The height range of a pyramid: min and max of its coarsest level of at least 64 samples
/// a side (or its finest), read whole.
std::pair<float, float> heightRange(const clod::HeightPyramid& p) {
  std::size_t k = p.levelCount() - 1;
  while (k > 0 && std::min(p.level(k).grid.rows(), p.level(k).grid.cols()) < 64) --k;
  const auto& level = p.level(k);
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (std::size_t r = 0; r < level.grid.rows(); ++r) {
    for (std::size_t c = 0; c < level.grid.cols(); ++c) {
      const float h = level.source->sample(r, c);
      if (!std::isfinite(h)) continue;
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
  }
  if (lo > hi) return {0.0F, 1.0F};
  return {lo, std::max(hi, lo + 1.0F)};
}

clod::Effects declaredEffects(const clod::HeightPyramid& p, bool latLon) {
  clod::Effects e;
  const auto [lo, hi] = heightRange(p);
  e.heightColours = clod::HeightColours{lo, hi, true};
  if (latLon) e.latLon = clod::LatLonLines{};
  return e;
}

}  // namespace

ViewScene storeScene(const std::string& path, const std::string& grid, std::size_t cacheBytes,
                     int clipmapSize) {
  ViewScene v;
  auto store = std::make_shared<const store::Store>(store::Store::open(path));
  const std::string name = chooseGrid(*store, grid, "view");
  auto cache = std::make_shared<store::PatchCache>(cacheBytes);
  auto pager = std::make_shared<const store::Pager>(store, cache);
  // One loader for the pyramid's hints and loads and the clipmap's windows, not a thread each.
  auto loader = std::make_shared<core::ThreadPool>(1);
  auto pyramid = std::make_shared<const clod::HeightPyramid>(pager->pyramid(name, loader));
  const bool planet = pyramid->kind() == clod::SurfaceKind::Planet;
  v.title = name + " of " + path;
  v.graph = std::make_shared<scenegraph::SceneGraph>(planet ? "body" : "map");
  ViewTerrain t;
  t.name = name;
  t.node = v.graph->add(v.graph->root(), name, scenegraph::Pose::identity(),
                        scenegraph::NodeKind::Terrain, 0);
  t.pyramid = pyramid;
  t.options.size = clipmapSize;
  t.options.executor = loader;
  t.options.effects = declaredEffects(*pyramid, planet || pyramid->placement().has_value());
  ViewObject o{name, t.node, pyramid, 1.0};
  OpeningView open;
  if (planet) {
    // The far field draws the planet beyond the clipmap's levels within 180°; a planet
    // coarse enough that one window spans more than 180° gets smaller windows.
    const double dy = std::abs(pyramid->level(0).grid.spacingY());
    const int fit = static_cast<int>(std::floor(180.0 / dy)) / 2 * 2 + 1;
    if (fit < t.options.size && fit >= 15) t.options.size = fit;
    t.options.levels = scene::planetLevelsWithFarField(*pyramid, t.options.size);
    t.farField = scene::farFieldLayers(*pyramid, nullptr);
    const double radius = pyramid->body()->equatorialRadius();
    o.size = 2.0 * radius;
    // The whole planet, seen from 3.2 radii out, looking at (0°E, 0°N) from 70° above its
    // horizon, so the limb shows its relief.
    open.target = pyramid->position(0.0, 0.0, 0.0);
    open.headingDeg = 0.0;
    open.elevationDeg = 70.0;
    open.distance = 3.2 * radius;
    v.bodyGrid = pyramid;
    v.bodyNode = t.node;
    ViewCamera overview{"overview", 0, 30.0, 1000.0};
    const glm::dvec3 eye = pyramid->position(-60.0, 30.0, 4.0 * radius);
    overview.node = v.graph->add(v.graph->root(), "overview",
                                 scenegraph::Pose::lookAt(eye, glm::dvec3(0.0), {0.0, 0.0, 1.0}),
                                 scenegraph::NodeKind::Camera);
    v.cameras.push_back(overview);
  } else {
    // The renderer centres the clipmap on the camera's position clamped onto the grid (an
    // edge, when the camera stands off to the side): the coarsest level must reach across
    // the whole grid from there.
    const auto& coarsest = pyramid->level(pyramid->levelCount() - 1).grid;
    const std::size_t across = 2 * std::max(coarsest.rows(), coarsest.cols()) + 1;
    t.options.size =
        std::max(t.options.size, static_cast<int>(std::min<std::size_t>(across, 2047)));
    const auto& g = pyramid->level(0).grid;
    const double extent = std::max(g.east() - g.west(), g.north() - g.south());
    o.size = extent;
    const double cx = 0.5 * (g.west() + g.east()), cy = 0.5 * (g.south() + g.north());
    const auto [lo, hi] = heightRange(*pyramid);
    open.target = pyramid->position(cx, cy, 0.5 * static_cast<double>(lo + hi));
    open.headingDeg = 20.0;
    open.elevationDeg = 35.0;
    open.distance = 1.2 * extent;
  }
  v.terrains.push_back(std::move(t));
  v.objects.push_back(std::move(o));
  v.openings.push_back(open);
  v.cache = cache;
  v.keepAlive = pager;
  return v;
}

namespace {

/// A built scene as the viewer shows it: its bodies (with their far fields) and DEMs with
/// the effects each declares, its objects and cameras; opens on the first body whole and, if
/// there is a DEM, split with the first DEM from above at 35°.
ViewScene fromScene(const std::shared_ptr<scene::Scene>& built, const std::string& title) {
  ViewScene v;
  v.title = title;
  v.graph = std::shared_ptr<scenegraph::SceneGraph>(built, &built->graph());
  const std::vector<scene::SceneTerrain> terrains = built->terrains();
  const scene::SceneTerrain* firstBody = nullptr;
  const scene::SceneTerrain* firstDem = nullptr;
  for (const scene::SceneTerrain& t : terrains) {
    ViewTerrain vt;
    vt.name = t.name;
    vt.node = t.node;
    vt.drawable = t.drawable;
    vt.pyramid = t.pyramid;
    vt.options = t.options;
    vt.farField = t.farField;
    vt.pickPriority = t.planet ? 0 : 1;
    if (t.planet) {
      for (const scene::SceneTerrain& d : terrains)
        if (!d.planet && d.body == t.name) vt.cutOuts.push_back(d.drawable);
    }
    v.terrains.push_back(std::move(vt));
    const auto& g = t.pyramid->level(0).grid;
    const double size = t.planet ? 2.0 * t.pyramid->body()->equatorialRadius()
                                 : std::max(g.east() - g.west(), g.north() - g.south());
    v.objects.push_back({t.name, t.node, t.pyramid, size});
    if (t.planet && firstBody == nullptr) firstBody = &t;
    if (!t.planet && firstDem == nullptr) firstDem = &t;
  }
  for (const scene::SceneObject& o : built->objects()) {
    v.meshes.push_back({o.drawable, render::roverMesh(), o.colour});
    v.objects.push_back({o.name, o.node, nullptr, 4.0});
  }
  for (const scene::Camera& c : built->description().cameras) {
    v.cameras.push_back({c.name, built->cameraNode(c.name), c.fovY, c.near});
  }
  const auto indexOf = [&](const scene::SceneTerrain* t) {
    return static_cast<std::size_t>(t - terrains.data());  // objects begin with the terrains
  };
  if (firstBody != nullptr) {
    // The body whole from 3.2 radii, looking at its first DEM's site (or 0°E, 0°N).
    const clod::HeightPyramid& p = *firstBody->pyramid;
    double lon = 0.0, lat = 0.0;
    for (const scene::Dem& d : built->description().dems) {
      if (d.body == firstBody->name && d.placement) {
        lon = d.placement->lon;
        lat = d.placement->lat;
        break;
      }
    }
    OpeningView whole;
    whole.object = indexOf(firstBody);
    whole.target = p.position(lon, lat, 0.0);
    whole.elevationDeg = 75.0;
    whole.distance = 3.2 * p.body()->equatorialRadius();
    v.openings.push_back(whole);
    v.bodyGrid = firstBody->pyramid;
    v.bodyNode = firstBody->node;
  }
  if (firstDem != nullptr) {
    const auto& g = firstDem->pyramid->level(0).grid;
    const double cx = 0.5 * (g.west() + g.east()), cy = 0.5 * (g.south() + g.north());
    OpeningView crater;
    crater.object = indexOf(firstDem);
    crater.target = {cx, cy, built->demHeight(firstDem->name, cx, cy)};
    crater.headingDeg = 20.0;
    crater.elevationDeg = 35.0;
    crater.distance = 1.2 * std::max(g.east() - g.west(), g.north() - g.south());
    v.openings.push_back(crater);
  }
  if (v.openings.empty())
    throw InvalidArgument("view: " + title + ": the scene has no body or DEM");
  v.cache = built->cache();
  v.keepAlive = built;
  return v;
}

}  // namespace

ViewScene demoScene() {
  // The demo scene as data (demo::sceneDescription(): generated Mars, the Victoria-like DEM
  // and a second DEM, the rover), with what the viewer shows on top: lat/lon lines on Mars
  // and structured noise on Victoria.
  scene::SceneDescription d = demo::sceneDescription({});
  d.bodies.front().look.effects.latLon = scene::EffectsDescription::LatLon{};
  for (scene::Dem& dem : d.dems) {
    if (dem.name == "victoria")
      dem.look.effects.noise = scene::EffectsDescription::Noise{0.3, 8.0, 4, 0.15};
  }
  auto built = std::make_shared<scene::Scene>(std::move(d));
  const demo::DemoCameras cameras = demo::paperCameraNodes(*built);
  ViewScene v = fromScene(built, "Mars/Victoria demo scene");
  // Height colours over each terrain's height range (known once the data is built): Mars's
  // from its far-field layers, Victoria's from its grid (with lat/lon lines, as a bare store).
  for (ViewTerrain& t : v.terrains) {
    if (t.farField) {
      t.options.effects.heightColours =
          clod::HeightColours{static_cast<float>(t.farField->minHeight()),
                              static_cast<float>(t.farField->maxHeight()), true};
    } else if (t.name == "victoria") {
      const clod::Effects e = declaredEffects(*t.pyramid, true);
      t.options.effects.heightColours = e.heightColours;
      t.options.effects.latLon = e.latLon;
    }
  }
  v.cameras = {{"orbit", cameras.orbit, 45.0, 100.0},
               {"mast", cameras.mast, 45.0, 0.05},
               {"chase", cameras.chase, 45.0, 0.05}};
  return v;
}

ViewScene sceneFileScene(const std::string& path, std::size_t cacheBytes) {
  scene::SceneOptions options;
  options.cacheBytes = cacheBytes;
  return fromScene(std::make_shared<scene::Scene>(scene::Scene::load(path, options)), path);
}

}  // namespace regolith::tools::viewer
