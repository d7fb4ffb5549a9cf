#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/FromStore.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/FileIdentity.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Projection.hpp>

#include <EGL/egl.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

namespace regolith::demo {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

using scene::planetHeightAt;

std::shared_ptr<const clod::HeightPyramid> demPyramid(const store::VictoriaGenerator& gen) {
  const store::GridInfo info = gen.gridInfo();
  return std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      store::topoGridOf(info), gen.samples(), clod::SurfaceKind::Plane));
}

// The second, smaller Victoria-like DEM (another seed), generated in memory.
std::shared_ptr<const clod::HeightPyramid> secondDemPyramid(const MarsVictoriaOptions& options,
                                                            double originHeight) {
  store::VictoriaOptions so;
  so.size = options.secondDemSize;
  so.spacing = options.secondDemSpacing;
  so.seed = options.seed + 1;
  so.gridName = "victoria2";
  so.originHeight = originHeight;
  return demPyramid(store::VictoriaGenerator(so));
}

/// Every number of a scene view: finite, and the field of view and near plane in range.
void refuseBadView(const SceneViewOptions& o) {
  const char* op = "renderSceneView()";
  const glm::dvec3& t = o.camera.translation;
  const glm::dquat& q = o.camera.rotation;
  if (!(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z) && std::isfinite(q.w) &&
        std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z))) {
    throw InvalidArgument(core::format(
        {op,
         {},
         "camera pose",
         "(" + core::number(t.x) + ", " + core::number(t.y) + ", " + core::number(t.z) + ") m",
         "finite (eye, look-at point and up all finite)"}));
  }
  if (!(o.fovYDegrees > 0.0 && o.fovYDegrees < 180.0)) {
    throw InvalidArgument(core::format(
        {op, {}, "field of view", core::number(o.fovYDegrees) + " deg", "inside (0, 180)"}));
  }
  if (!(o.near > 0.0 && std::isfinite(o.near))) {
    throw InvalidArgument(
        core::format({op, {}, "near plane", core::number(o.near) + " m", "finite and > 0"}));
  }
  if (!(std::isfinite(o.roverX) && std::isfinite(o.roverY) && std::isfinite(o.roverHeadingDeg))) {
    throw InvalidArgument(core::format({op,
                                        {},
                                        "rover",
                                        core::number(o.roverX) + ", " + core::number(o.roverY) +
                                            ", " + core::number(o.roverHeadingDeg) + " deg",
                                        "a finite grid x, y and heading"}));
  }
}

/// The file of fly-over frame i in `dir`: frame_NNNN.png.
std::filesystem::path framePath(const std::filesystem::path& dir, int i) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04d.png", i);
  return dir / name;
}

/// No frame may be written over one of the scene's stores (core::refuseOverwritingInput()).
void refuseOverwritingStores(const FlyoverOptions& o) {
  if (o.scene.marsStore.empty()) return;
  const std::vector<std::filesystem::path> stores{o.scene.marsStore, o.scene.victoriaStore};
  for (int i = 0; i < o.frames; ++i) {
    core::refuseOverwritingInput(framePath(o.outputDir, i), stores, "renderFlyover()");
  }
  core::refuseOverwritingInput(o.outputDir / "multiview.png", stores, "renderFlyover()");
}

}  // namespace

MarsVictoriaScene::MarsVictoriaScene(const MarsVictoriaOptions& options) : options_(options) {
  if (options.marsStore.empty() != options.victoriaStore.empty())
    throw InvalidArgument("MarsVictoriaScene: marsStore and victoriaStore go together (got " +
                          (options.marsStore.empty() ? std::string("only victoriaStore")
                                                     : std::string("only marsStore")) +
                          ")");
  if (!options.marsStore.empty()) {
    fromStores(options);
    return;
  }
  store::MarsPlanetOptions po;
  po.rows = options.planetRows;
  po.seed = options.seed;
  po.ellipsoid = true;
  const store::MarsPlanetGenerator planet(po);
  const store::GridInfo pinfo = planet.gridInfo();
  mars_ = std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      store::topoGridOf(pinfo), planet.samples(), clod::SurfaceKind::Planet, store::bodyOf(pinfo),
      pinfo.latitudeType));

  layout_.mars = store::bodyOf(pinfo);
  layout_.victoriaOrigin = {store::VictoriaGenerator::kOriginLatDeg,
                            store::VictoriaGenerator::kOriginLonDeg, 0.0};
  layout_.victoriaOrigin.height = planetHeightAt(*mars_, layout_.victoriaOrigin);
  layout_.secondDem = options.secondDem;
  layout_.secondDemOrigin.height = planetHeightAt(*mars_, layout_.secondDemOrigin);

  store::VictoriaOptions vo;
  vo.size = options.demSize;
  vo.spacing = options.demSpacing;
  vo.seed = options.seed;
  vo.originHeight = layout_.victoriaOrigin.height;
  victoria_ = demPyramid(store::VictoriaGenerator(vo));
  if (options.secondDem) second_ = secondDemPyramid(options, layout_.secondDemOrigin.height);
  if (options.composition) compose();
  finish();
}

void MarsVictoriaScene::fromStores(const MarsVictoriaOptions& options) {
  // Both grids through one pager: the stores are opened once and read patch by patch.
  auto cache = std::make_shared<store::PatchCache>(options.cacheBytes);
  auto marsStore = std::make_shared<const store::Store>(store::Store::open(options.marsStore));
  auto demStore = std::make_shared<const store::Store>(store::Store::open(options.victoriaStore));
  const store::GridInfo& pinfo = marsStore->grid(options.marsGrid);
  const store::GridInfo& dinfo = demStore->grid(options.victoriaGrid);
  if (pinfo.kind != store::GridKind::Planet)
    throw InvalidArgument("MarsVictoriaScene: " + options.marsStore.string() + " grid '" +
                          options.marsGrid + "' is not a planet grid");
  if (dinfo.kind != store::GridKind::Dem ||
      dinfo.placement.kind != store::PlacementInfo::Kind::LocalTangentPlane)
    throw InvalidArgument("MarsVictoriaScene: " + options.victoriaStore.string() + " grid '" +
                          options.victoriaGrid +
                          "' is not a DEM on a local tangent plane (placement)");
  auto marsPager = std::make_shared<store::Pager>(marsStore, cache);
  auto demPager = std::make_shared<store::Pager>(demStore, cache);
  // The kinds were checked above: store::Pager::pyramid() makes a planet grid on its body and a
  // DEM as a plane.
  mars_ = std::make_shared<const clod::HeightPyramid>(marsPager->pyramid(options.marsGrid));
  victoria_ = std::make_shared<const clod::HeightPyramid>(demPager->pyramid(options.victoriaGrid));
  pager_ =
      std::make_shared<std::pair<std::shared_ptr<store::Pager>, std::shared_ptr<store::Pager>>>(
          marsPager, demPager);

  layout_.mars = store::bodyOf(pinfo);
  layout_.victoriaOrigin = {dinfo.placement.originLatDeg, dinfo.placement.originLonDeg,
                            dinfo.placement.originHeight};
  layout_.victoriaHeadingDeg = dinfo.placement.headingDeg;
  layout_.secondDem = options.secondDem;
  layout_.secondDemOrigin.height = planetHeightAt(*mars_, layout_.secondDemOrigin);
  if (options.secondDem) second_ = secondDemPyramid(options, layout_.secondDemOrigin.height);
  if (options.composition) compose();
  finish();
}

using scene::levelsOf;

void MarsVictoriaScene::compose() {
  // The catalogue: the planet, the DEMs on their tangent planes, and the extra store grids.
  const topo::Body& body = layout_.mars;
  auto catalogue = std::make_shared<compose::Catalogue>(body);
  compose::DatasetOptions po;
  po.name = "mars";
  catalogue->add(compose::Dataset::planet(levelsOf(*mars_), po));
  const topo::Placement victoriaPlacement(
      topo::LocalTangentPlane(body, layout_.victoriaOrigin, layout_.victoriaHeadingDeg));
  compose::DatasetOptions vo;
  vo.name = "victoria";
  vo.featherMetres = options_.demFeatherMetres;
  const auto victoriaData = compose::Dataset::dem(levelsOf(*victoria_), victoriaPlacement, vo);
  catalogue->add(victoriaData);
  std::optional<topo::Placement> secondPlacement;
  std::shared_ptr<const compose::Dataset> secondData;
  if (second_) {
    secondPlacement.emplace(topo::LocalTangentPlane(body, layout_.secondDemOrigin, 0.0));
    compose::DatasetOptions so = vo;
    so.name = "victoria2";
    secondData = compose::Dataset::dem(levelsOf(*second_), *secondPlacement, so);
    catalogue->add(secondData);
  }
  if (!options_.extraDatasets.empty()) {
    auto cache = std::make_shared<store::PatchCache>(options_.cacheBytes);
    auto pagers = std::make_shared<std::vector<std::shared_ptr<const store::Pager>>>();
    for (const auto& d : options_.extraDatasets) {
      auto pager = std::make_shared<const store::Pager>(
          std::make_shared<const store::Store>(store::Store::open(d.store)), cache);
      compose::DatasetOptions eo;
      eo.featherMetres = d.featherMetres;
      if (d.featherNodataSamples > 0.0) {
        eo.mask = compose::featherMask(store::topoGridOf(pager->grid(d.grid)),
                                       *pager->source(d.grid), d.featherNodataSamples);
      }
      catalogue->add(compose::datasetFromStore(*pager, d.grid, eo));
      pagers->push_back(std::move(pager));
    }
    extraPager_ = pagers;
  }
  composed_ = std::make_shared<const compose::ComposedSurface>(catalogue->snapshot());
  // Every terrain keeps its lattice and levels; its samples become the composed heights.
  mars_ = std::make_shared<const clod::HeightPyramid>(compose::composedPlanetPyramid(
      composed_, mars_->level(0).grid, mars_->latitudeType(), mars_->levelCount()));
  // A DEM's own lattice reads its own samples where it alone is the surface.
  const auto plane = [&](const clod::HeightPyramid& p, const topo::Placement& placement,
                         const std::shared_ptr<const compose::Dataset>& own) {
    return std::make_shared<const clod::HeightPyramid>(
        compose::composedDemPyramid(composed_, p.level(0).grid, placement, p.levelCount(), own)
            .levels,
        clod::SurfaceKind::Plane);
  };
  victoria_ = plane(*victoria_, victoriaPlacement, victoriaData);
  if (second_) second_ = plane(*second_, *secondPlacement, secondData);
}

std::size_t MarsVictoriaScene::datasetsSeen(scenegraph::NodeId camera, double fovYDegrees,
                                            double aspect, double near) const {
  if (!composed_) return 0;
  // The camera's frustum in the body-fixed frame of Mars (GL eye: it looks along −z).
  const scenegraph::Pose pose = graph_.relative(nodes_.mars, camera);
  const double ty = std::tan(0.5 * fovYDegrees * kDeg), tx = ty * aspect;
  const glm::dvec3 eyePlanes[] = {
      {1.0, 0.0, -tx}, {-1.0, 0.0, -tx}, {0.0, 1.0, -ty}, {0.0, -1.0, -ty}};
  std::vector<glm::dvec4> planes;
  for (const glm::dvec3& e : eyePlanes) {
    const glm::dvec3 n = pose.applyVector(e);
    planes.emplace_back(n, -glm::dot(n, pose.translation));
  }
  const glm::dvec3 forward = pose.applyVector({0.0, 0.0, -1.0});
  planes.emplace_back(forward, -glm::dot(forward, pose.translation) - near);
  std::vector<std::uint32_t> seen;
  composed_->snapshot().visible(planes, seen);
  return seen.size();
}

void MarsVictoriaScene::finish() {
  // Earth: a WGS84 ellipsoid with no relief, 3° samples (it is a dot from Mars).
  const topo::Body earth = topo::Body::earthWgs84();
  const topo::TopoGrid eg(60, 120, -178.5, 88.5, 3.0, 3.0);
  earth_ = std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      eg, std::make_shared<topo::InMemorySamples>(60, 120, std::vector<float>(7200, 0.0F)),
      clod::SurfaceKind::Planet, earth));

  layout_.roverInDem = {0.0, -395.0, 0.0};
  nodes_ = demo::buildPaperScene(graph_, layout_);
  placeRover(0.0, -395.0, 0.0);
}

double MarsVictoriaScene::demHeight(double x, double y) const {
  return scene::demHeightAt(*victoria_, x, y);
}

void MarsVictoriaScene::placeRover(double x, double y, double headingDeg) {
  graph_.setLocal(nodes_.rover, scenegraph::roverPose({x, y, demHeight(x, y)}, headingDeg));
}

std::shared_ptr<const farfield::HeightLayers> MarsVictoriaScene::farFieldLayers() const {
  return scene::farFieldLayers(*mars_, composed_.get());
}

std::size_t MarsVictoriaScene::planetClipmapLevels() const {
  if (!options_.farField) return 0;
  return scene::planetLevelsWithFarField(*mars_, options_.clipmapSize);
}

void MarsVictoriaScene::registerWith(clod::SceneRenderer& renderer) const {
  clod::ClipmapOptions planet;
  planet.size = options_.clipmapSize;
  planet.levels = planetClipmapLevels();
  planet.albedo = kPlanetAlbedo;
  clod::ClipmapOptions dem = planet;
  dem.levels = 0;
  dem.albedo = options_.demAlbedo.value_or(kDemAlbedo);
  renderer.addTerrain(demo::kDrawMars, mars_, planet);
  clod::ClipmapOptions victoria = dem;
  victoria.effects = options_.victoriaEffects;
  renderer.addTerrain(demo::kDrawVictoria, victoria_, victoria);
  renderer.addCutOut(demo::kDrawMars, demo::kDrawVictoria);
  if (second_) {
    renderer.addTerrain(demo::kDrawSecondDem, second_, dem);
    renderer.addCutOut(demo::kDrawMars, demo::kDrawSecondDem);
  }
  clod::ClipmapOptions earth = planet;
  earth.levels = 0;
  earth.size = 31;
  earth.albedo = {0.3F, 0.45F, 0.8F};
  renderer.addTerrain(demo::kDrawEarth, earth_, earth);
  renderer.addMesh(demo::kDrawRover, clod::roverMesh(), {0.85F, 0.85F, 0.8F});
}

glm::dvec3 MarsVictoriaScene::lightInFocus(scenegraph::NodeId focus) const {
  // Victoria frame: x east, y north, z up.
  const glm::dvec3 local{std::cos(35.0 * kDeg), -0.3, std::sin(35.0 * kDeg)};
  return graph_.relative(focus, nodes_.victoria).applyVector(glm::normalize(local));
}

scenegraph::Pose flyoverCamera(double t, const glm::dvec3& rover, double startDistance) {
  // Smoothstep in t, logarithmic in distance: startDistance (8000 km) out to 6 m from the
  // rover. The view direction turns from straight down (north up in the image) to a low look
  // along +y.
  const double s = t * t * (3.0 - 2.0 * t);
  const double dist =
      std::exp(std::log(startDistance) + s * (std::log(6.0) - std::log(startDistance)));
  const double tilt = std::pow(s, 3.0);  // stays near nadir until close
  const glm::dvec3 dir =
      glm::normalize(glm::mix(glm::dvec3(0.0, -0.02, 1.0), glm::dvec3(0.0, -1.0, 0.35), tilt));
  const glm::dvec3 target = rover + glm::dvec3(0.0, 0.0, 0.8);
  const glm::dvec3 up =
      glm::normalize(glm::mix(glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(0.0, 0.0, 1.0), tilt));
  return scenegraph::Pose::lookAt(target + dist * dir, target, up);
}

namespace {

/// The far field of Mars for a scene's renderer (null when options.farField is off): PGM in
/// the planet clipmap's albedo and light, so the two look alike where they meet.
std::unique_ptr<farfield::FarField> marsFarField(const MarsVictoriaScene& scene,
                                                 const MarsVictoriaOptions& options) {
  if (!options.farField) return nullptr;
  return scene::planetFarField(scene.farFieldLayers(), MarsVictoriaScene::kPlanetAlbedo);
}

}  // namespace

gl::RgbaImage renderSceneView(const SceneViewOptions& options) {
  if (options.width < 1 || options.height < 1)
    throw InvalidArgument("renderSceneView(): image " + std::to_string(options.width) + "×" +
                          std::to_string(options.height) + ", expected a non-empty image");
  refuseBadView(options);
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  gl::RgbaImage image;
  {
    MarsVictoriaScene scene(options.scene);
    scene.placeRover(options.roverX, options.roverY, options.roverHeadingDeg);
    scenegraph::SceneGraph& g = scene.graph();
    const demo::PaperSceneNodes& n = scene.nodes();
    const scenegraph::NodeId cam =
        g.add(n.victoria, "view_camera", options.camera, scenegraph::NodeKind::Camera);
    clod::SceneRenderer renderer;
    scene.registerWith(renderer);
    gl::RenderTarget target(options.width, options.height);
    clod::SceneView view;
    view.fovYDegrees = options.fovYDegrees;
    view.near = options.near;
    view.width = options.width;
    view.height = options.height;
    view.lightInFocus = scene.lightInFocus(n.victoria);
    target.clear({0.02F, 0.02F, 0.04F, 1.0F});
    renderer.draw(g.renderList(n.victoria, cam), view);
    if (const auto farField = marsFarField(scene, options.scene)) {
      (void)scene::drawFarField(*farField, g, n.mars, cam, n.victoria, view, target);
    }
    image = target.readColor();
  }  // GL objects go before the context
  return image;
}

FlyoverSummary renderFlyover(const FlyoverOptions& options) {
  if (options.frames < 2)
    throw InvalidArgument("renderFlyover(): " + std::to_string(options.frames) +
                          " frames, expected at least 2");
  if (options.width < 1 || options.height < 1)
    throw InvalidArgument("renderFlyover(): image " + std::to_string(options.width) + "×" +
                          std::to_string(options.height) + ", expected a non-empty image");
  if (options.rover && !(std::isfinite(options.rover->x) && std::isfinite(options.rover->y) &&
                         std::isfinite(options.rover->z)))
    throw InvalidArgument("renderFlyover(): rover (" + std::to_string(options.rover->x) + ", " +
                          std::to_string(options.rover->y) + ", " +
                          std::to_string(options.rover->z) +
                          "), expected a finite grid x, y and heading");
  refuseOverwritingStores(options);
  const auto t0 = std::chrono::steady_clock::now();
  FlyoverSummary summary;
  std::filesystem::create_directories(options.outputDir);
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  {
    MarsVictoriaScene scene(options.scene);
    if (options.rover) scene.placeRover(options.rover->x, options.rover->y, options.rover->z);
    scenegraph::SceneGraph& g = scene.graph();
    const demo::PaperSceneNodes& n = scene.nodes();
    const glm::dvec3 rover = g.relative(n.victoria, n.rover).translation;
    const scenegraph::NodeId cam = g.add(n.victoria, "flyover_camera", flyoverCamera(0.0, rover),
                                         scenegraph::NodeKind::Camera);
    clod::SceneRenderer renderer;
    scene.registerWith(renderer);
    gl::RenderTarget target(options.width, options.height);
    const std::unique_ptr<farfield::FarField> farField = marsFarField(scene, options.scene);
    double renderSeconds = 0.0;
    // Over the pole: the first 40% of the frames follow the great circle through the pole
    // and Victoria's meridian at 2000 km, from 20° beyond the pole to above Victoria, looking
    // straight down with north at the top of the image; the rest descends from 2000 km.
    const double lonV = scene.layout().victoriaOrigin.lonDeg,
                 latV = scene.layout().victoriaOrigin.latDeg;
    const scenegraph::Pose victoriaFromMars = g.relative(n.victoria, n.mars);
    const topo::Body& body = scene.layout().mars;
    constexpr double kPoleShare = 0.4, kPoleAltitude = 2.0e6;
    const glm::dvec3 meridian(std::cos(lonV * kDeg), std::sin(lonV * kDeg), 0.0);
    double bestLat = -90.0;
    for (int i = 0; i < options.frames; ++i) {
      const double t = static_cast<double>(i) / (options.frames - 1);
      scenegraph::Pose pose;
      std::optional<glm::dvec3> poleLight;  // in the Mars frame
      if (options.overPole && t < kPoleShare) {
        const double theta =
            (-20.0 + (90.0 - latV + 20.0) * t / kPoleShare) * kDeg;  // from the pole
        const double lat = 90.0 - std::abs(theta) / kDeg, lon = theta < 0.0 ? lonV + 180.0 : lonV;
        const glm::dvec3 travel =
            -std::sin(theta) * glm::dvec3(0.0, 0.0, 1.0) + std::cos(theta) * meridian;
        const scenegraph::Pose inMars =
            scenegraph::Pose::lookAt(body.toBodyFixed({lat, lon, kPoleAltitude}),
                                     body.toBodyFixed({lat, lon, 0.0}), -travel);
        pose = victoriaFromMars * inMars;
        // The sun 35° above the horizon under the camera, turning into Victoria's morning
        // sun by the end of this part (a sun fixed over Victoria would leave the pole dark).
        const glm::dmat3 enu = body.enuFrame(lat, lon);
        const glm::dvec3 sky =
            std::cos(35.0 * kDeg) * glm::normalize(-0.92 * enu[0] + 0.38 * enu[1]) +
            std::sin(35.0 * kDeg) * enu[2];
        poleLight = glm::normalize(glm::mix(sky, scene.lightInFocus(n.mars), t / kPoleShare));
        if (lat > bestLat) {
          bestLat = lat;
          summary.poleFrame = i;
          summary.poleLatitude = lat;
        }
      } else {
        const double u = options.overPole ? (t - kPoleShare) / (1.0 - kPoleShare) : t;
        pose = flyoverCamera(u, rover, options.overPole ? kPoleAltitude : 8.0e6);
      }
      g.setLocal(cam, pose);
      const double dist = glm::length(pose.translation - rover);
      // Focus: Mars while the camera is far, Victoria once within 200 km of the rover.
      const scenegraph::NodeId focus = dist > 2.0e5 ? n.mars : n.victoria;
      if (focus == n.victoria && summary.focusSwitchFrame < 0) summary.focusSwitchFrame = i;
      if (i == 0) summary.startDistance = dist;
      summary.endDistance = dist;
      clod::SceneView view;
      view.fovYDegrees = 45.0;
      view.near = std::clamp(0.01 * dist, 0.05, 1000.0);
      view.width = options.width;
      view.height = options.height;
      view.lightInFocus = poleLight && focus == n.mars ? *poleLight : scene.lightInFocus(focus);
      if (scene.composed()) {
        summary.datasetsPerFrame.push_back(scene.datasetsSeen(
            cam, view.fovYDegrees, static_cast<double>(options.width) / options.height, view.near));
      }
      const auto r0 = std::chrono::steady_clock::now();
      target.clear({0.02F, 0.02F, 0.04F, 1.0F});
      renderer.draw(g.renderList(focus, cam), view);
      if (farField) {
        // Beyond the clipmaps: the far field, in Mars's body-fixed frame, where nothing is
        // drawn yet.
        const clod::Camera marsCamera = clod::cameraInItem(g.relative(n.mars, cam), view);
        const glm::dvec3 sun =
            g.relative(n.mars, focus).applyVector(glm::normalize(view.lightInFocus));
        const farfield::FarFieldFrame ff = farField->draw(target, marsCamera, sun, true);
        summary.farFieldFrames += ff.mode == farfield::FarFieldMode::Pgm ? 1 : 0;
        summary.impostorFrames += ff.mode == farfield::FarFieldMode::Impostor ? 1 : 0;
      }
      const gl::RgbaImage image = target.readColor();
      renderSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
      const auto path = framePath(options.outputDir, i);
      gl::writePng(path.string(), image);
      summary.files.push_back(path);
      if (options.progress) options.progress(i + 1, options.frames, path);
    }
    if (options.multiView) {
      // Two viewports of one frame: the orbit camera (left) and the rover's mast camera.
      const int half = options.width / 2;
      target.clear({0.02F, 0.02F, 0.04F, 1.0F});
      for (const auto& [camera, x] : {std::pair{n.orbitCamera, 0}, {n.mastCamera, half}}) {
        clod::SceneView view;
        view.x = x;
        view.width = half;
        view.height = options.height;
        view.near = camera == n.orbitCamera ? 100.0 : 0.05;
        view.lightInFocus = scene.lightInFocus(n.victoria);
        renderer.draw(g.renderList(n.victoria, camera), view);
      }
      const auto path = options.outputDir / "multiview.png";
      gl::writePng(path.string(), target.readColor());
      summary.files.push_back(path);
    }
    summary.renderSeconds = renderSeconds;
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

scene::SceneDescription sceneDescription(const MarsVictoriaOptions& options,
                                         const SceneRover& rover) {
  const clod::Effects& fx = options.victoriaEffects;
  if (fx.albedo || fx.noise || fx.heightColours || fx.latLon || fx.overlay)
    throw InvalidArgument(
        "demo::sceneDescription(): victoriaEffects other than tracks are not carried over");
  if (options.marsStore.empty() != options.victoriaStore.empty())
    throw InvalidArgument("demo::sceneDescription(): marsStore and victoriaStore go together");
  const auto rgb = [](const glm::vec3& c) {
    return std::array<double, 3>{static_cast<double>(c.x), static_cast<double>(c.y),
                                 static_cast<double>(c.z)};
  };
  scene::SceneDescription d;
  d.folder = std::filesystem::current_path();
  scene::Body mars;
  mars.name = "mars";
  scene::DataSource planet;
  if (options.marsStore.empty()) {
    planet.generate = "mars-planet";
    planet.rows = options.planetRows;
    planet.seed = options.seed;
  } else {
    planet.store = options.marsStore.string();
    planet.grid = options.marsGrid;
  }
  mars.heights.push_back(planet);
  if (options.composition) {
    for (const MarsVictoriaOptions::StoreDataset& e : options.extraDatasets) {
      scene::DataSource s;
      s.store = e.store.string();
      s.grid = e.grid;
      s.featherMetres = e.featherMetres;
      s.featherNodataSamples = e.featherNodataSamples;
      mars.heights.push_back(s);
    }
  }
  mars.composeDems = options.composition;
  mars.farField = options.farField;
  mars.look.colour = rgb(MarsVictoriaScene::kPlanetAlbedo);
  mars.look.clipmapSize = options.clipmapSize;
  d.bodies.push_back(mars);

  const glm::vec3 demAlbedo = options.demAlbedo.value_or(MarsVictoriaScene::kDemAlbedo);
  scene::Dem victoria;
  victoria.name = "victoria";
  victoria.body = "mars";
  if (options.victoriaStore.empty()) {
    victoria.heights.generate = "victoria";
    victoria.heights.size = options.demSize;
    victoria.heights.spacing = options.demSpacing;
    victoria.heights.seed = options.seed;
    victoria.placement =
        scene::Dem::Placement{store::VictoriaGenerator::kOriginLatDeg,
                              store::VictoriaGenerator::kOriginLonDeg, 0.0, true, 0.0};
  } else {
    victoria.heights.store = options.victoriaStore.string();
    victoria.heights.grid = options.victoriaGrid;
  }
  victoria.heights.featherMetres = options.demFeatherMetres;
  victoria.look.colour = rgb(demAlbedo);
  victoria.look.clipmapSize = options.clipmapSize;
  victoria.look.effects.tracks = fx.tracks != nullptr || !rover.traverse.empty();
  d.dems.push_back(victoria);
  if (options.secondDem) {
    const demo::PaperSceneLayout layout;
    scene::Dem second = victoria;
    second.name = "second_dem";
    second.heights = {};
    second.heights.generate = "victoria";
    second.heights.size = options.secondDemSize;
    second.heights.spacing = options.secondDemSpacing;
    second.heights.seed = options.seed + 1;
    second.heights.featherMetres = options.demFeatherMetres;
    second.placement = scene::Dem::Placement{layout.secondDemOrigin.latDeg,
                                             layout.secondDemOrigin.lonDeg, 0.0, true, 0.0};
    second.look.effects = {};
    d.dems.push_back(second);
  }
  scene::Object r;
  r.name = "rover";
  r.dem = "victoria";
  if (rover.traverse.empty()) {
    r.pose = scene::Object::Pose{rover.x, rover.y, rover.headingDeg};
  } else {
    scene::Object::Traverse t;
    for (const glm::dvec2& w : rover.traverse) t.waypoints.push_back({w.x, w.y});
    r.traverse = t;
  }
  d.objects.push_back(r);
  // lightInFocus(): morning sun over Victoria, 35° up from the east (x east, y north, z up).
  d.light.frame = "victoria";
  d.light.direction = std::array<double, 3>{std::cos(35.0 * kDeg), -0.3, std::sin(35.0 * kDeg)};
  return d;
}

}  // namespace regolith::demo
