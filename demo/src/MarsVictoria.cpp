#include <regolith/core/Error.hpp>
#include <regolith/core/FileIdentity.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/demo/PaperScene.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/Generate.hpp>
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

}  // namespace

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

/// What renderFlyover(scene) needs and the scene lacks: InvalidArgument.
[[noreturn]] void missing(const char* op, const std::string& name, const char* what) {
  throw InvalidArgument(core::format({op,
                                      {},
                                      "the scene's " + std::string(what) + " '" + name + "'",
                                      "missing",
                                      "the demo scene's body \"mars\", DEM \"victoria\" and "
                                      "object \"rover\" (demo::sceneDescription())"}));
}

scenegraph::NodeId needNode(const char* op, const scene::Scene& s, const std::string& name,
                            const char* what) {
  if (const auto id = s.graph().find(name)) return *id;
  missing(op, name, what);
}

/// How many datasets of a composition a camera sees: its frustum (the node `camera` of the
/// graph, with the vertical field of view and aspect ratio of its image) against each
/// dataset's bounds in the body-fixed frame of `body` (Snapshot::visible()).
std::size_t datasetsSeen(const compose::ComposedSurface& composed, const scenegraph::SceneGraph& g,
                         scenegraph::NodeId body, scenegraph::NodeId camera, double fovYDegrees,
                         double aspect, double near) {
  const scenegraph::Pose pose = g.relative(body, camera);
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
  composed.snapshot().visible(planes, seen);
  return seen.size();
}

/// The stores a scene reads (resolved), which no frame may overwrite.
std::vector<std::filesystem::path> storesOf(const scene::SceneDescription& d) {
  std::vector<std::filesystem::path> out;
  const auto add = [&](const scene::DataSource& s) {
    if (!s.store.empty()) out.push_back(d.resolve(s.store));
  };
  const auto addEffects = [&](const scene::EffectsDescription& e) {
    if (e.albedo) add(e.albedo->data);
    if (e.overlay) add(e.overlay->data);
  };
  for (const scene::Body& b : d.bodies) {
    for (const scene::DataSource& s : b.heights) add(s);
    addEffects(b.look.effects);
  }
  for (const scene::Dem& m : d.dems) {
    add(m.heights);
    addEffects(m.look.effects);
  }
  return out;
}

void checkFlyover(const FlyoverOptions& options) {
  if (options.frames < 2)
    throw InvalidArgument("renderFlyover(): " + std::to_string(options.frames) +
                          " frames, expected at least 2");
  if (!(options.approachFrom >= 0.0) || !std::isfinite(options.approachFrom))
    throw InvalidArgument("renderFlyover(): approachFrom " + std::to_string(options.approachFrom) +
                          " m, expected 0 (no approach) or a finite distance");
  if (options.width < 1 || options.height < 1)
    throw InvalidArgument("renderFlyover(): image " + std::to_string(options.width) + "×" +
                          std::to_string(options.height) + ", expected a non-empty image");
}

}  // namespace

std::vector<scene::Camera> paperCameras() {
  // As demo::buildPaperScene() places them (the orbit camera there in Mars's frame, from the
  // same tangent plane).
  const auto camera = [](const char* name, const char* frame, const glm::dvec3& eye,
                         const glm::dvec3& at, const glm::dvec3& up, double near) {
    scene::Camera c;
    c.name = name;
    c.frame = frame;
    c.eye = {eye.x, eye.y, eye.z};
    c.lookAt = {at.x, at.y, at.z};
    c.up = {up.x, up.y, up.z};
    c.fovY = 45.0;
    c.near = near;
    c.width = 960;
    c.height = 540;
    return c;
  };
  const glm::dvec3 mastEye{0.85, 0.0, 2.1};
  return {
      camera("orbit_camera", "victoria", {0.0, 0.0, 20e3}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 100.0),
      camera("mast_camera", "rover", mastEye,
             mastEye + glm::dvec3(std::cos(15.0 * kDeg), 0.0, -std::sin(15.0 * kDeg)),
             {0.0, 0.0, 1.0}, 0.05),
      camera("chase_camera", "rover", {-8.0, 0.0, 3.0}, {0.0, 0.0, 0.5}, {0.0, 0.0, 1.0}, 0.05)};
}

DemoCameras paperCameraNodes(const scene::Scene& s) {
  const auto node = [&](const std::string& name) {
    if (s.description().camera(name) == nullptr) {
      throw InvalidArgument(core::format({"demo::paperCameraNodes()",
                                          {},
                                          "the scene's camera '" + name + "'",
                                          "missing",
                                          "the paper's cameras (demo::paperCameras(), declared "
                                          "by demo::sceneDescription())"}));
    }
    return s.cameraNode(name);
  };
  return {node("orbit_camera"), node("mast_camera"), node("chase_camera")};
}

scene::Scene buildScene(const MarsVictoriaOptions& options, const SceneRover& rover) {
  scene::SceneOptions so;
  so.cacheBytes = options.cacheBytes;
  if (options.victoriaEffects.tracks) so.tracks["victoria"] = options.victoriaEffects.tracks;
  return scene::Scene(sceneDescription(options, rover), so);
}

gl::RgbaImage renderSceneView(const SceneViewOptions& options) {
  if (options.width < 1 || options.height < 1)
    throw InvalidArgument("renderSceneView(): image " + std::to_string(options.width) + "×" +
                          std::to_string(options.height) + ", expected a non-empty image");
  refuseBadView(options);
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  scene::Scene s =
      buildScene(options.scene, {options.roverX, options.roverY, options.roverHeadingDeg, {}});
  scenegraph::SceneGraph& g = s.graph();
  const scenegraph::NodeId victoria = g.at("victoria");
  const scenegraph::NodeId cam =
      g.add(victoria, "view_camera", options.camera, scenegraph::NodeKind::Camera);
  render::SceneView view;
  view.fovYDegrees = options.fovYDegrees;
  view.near = options.near;
  view.width = options.width;
  view.height = options.height;
  return s.render(cam, victoria, view, options.width, options.height);
}

FlyoverSummary renderFlyover(const FlyoverOptions& options) {
  checkFlyover(options);
  if (options.rover && !(std::isfinite(options.rover->x) && std::isfinite(options.rover->y) &&
                         std::isfinite(options.rover->z)))
    throw InvalidArgument("renderFlyover(): rover (" + std::to_string(options.rover->x) + ", " +
                          std::to_string(options.rover->y) + ", " +
                          std::to_string(options.rover->z) +
                          "), expected a finite grid x, y and heading");
  const auto t0 = std::chrono::steady_clock::now();
  SceneRover rover;
  if (options.rover) rover = {options.rover->x, options.rover->y, options.rover->z, {}};
  // Refused before the scene is built (a store may be large).
  const std::vector<std::filesystem::path> stores =
      storesOf(sceneDescription(options.scene, rover));
  for (int i = 0; i < options.frames; ++i)
    core::refuseOverwritingInput(framePath(options.outputDir, i), stores, "renderFlyover()");
  core::refuseOverwritingInput(options.outputDir / "multiview.png", stores, "renderFlyover()");
  scene::Scene s = buildScene(options.scene, rover);
  FlyoverSummary summary = renderFlyover(s, options);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

FlyoverSummary renderFlyover(scene::Scene& s, const FlyoverOptions& options) {
  checkFlyover(options);
  const std::vector<std::filesystem::path> stores = storesOf(s.description());
  for (int i = 0; i < options.frames; ++i)
    core::refuseOverwritingInput(framePath(options.outputDir, i), stores, "renderFlyover()");
  core::refuseOverwritingInput(options.outputDir / "multiview.png", stores, "renderFlyover()");
  const auto t0 = std::chrono::steady_clock::now();
  FlyoverSummary summary;
  scenegraph::SceneGraph& g = s.graph();
  const char* op = "renderFlyover()";
  const scenegraph::NodeId marsNode = needNode(op, s, "mars", "body"),
                           victoriaNode = needNode(op, s, "victoria", "DEM"),
                           roverNode = needNode(op, s, "rover", "object");
  const std::vector<scene::SceneTerrain> terrains = s.terrains();
  const scene::SceneTerrain* mars = nullptr;
  const scene::SceneTerrain* victoria = nullptr;
  for (const scene::SceneTerrain& t : terrains) {
    if (t.name == "mars" && t.planet) mars = &t;
    if (t.name == "victoria" && !t.planet) victoria = &t;
  }
  if (mars == nullptr) missing(op, "mars", "body");
  if (victoria == nullptr) missing(op, "victoria", "DEM");
  std::filesystem::create_directories(options.outputDir);
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  {
    const glm::dvec3 rover = g.relative(victoriaNode, roverNode).translation;
    const scenegraph::NodeId cam = g.add(victoriaNode, "flyover_camera", flyoverCamera(0.0, rover),
                                         scenegraph::NodeKind::Camera);
    const topo::Body& body = *mars->pyramid->body();
    const DemoCameras paper = paperCameraNodes(s);
    const scenegraph::NodeId orbitCamera = paper.orbit, mastCamera = paper.mast;
    render::SceneRenderer renderer;
    s.registerWith(renderer);
    gl::RenderTarget target(options.width, options.height);
    // The far field of Mars (when the scene's Mars has one) is the renderer's, from
    // registerWith(), in the planet clipmap's albedo and light.
    const auto lightIn = [&](scenegraph::NodeId focus) {
      return s.lightIn(focus == marsNode ? "mars" : "victoria");
    };
    double renderSeconds = 0.0;
    // Over the pole: the first 40% of the frames follow the great circle through the pole
    // and Victoria's meridian at 2000 km, from 20° beyond the pole to above Victoria, looking
    // straight down with north at the top of the image; the rest descends from 2000 km.
    const double lonV = victoria->origin.lonDeg, latV = victoria->origin.latDeg;
    const scenegraph::Pose victoriaFromMars = g.relative(victoriaNode, marsNode);
    constexpr double kPoleShare = 0.4, kPoleAltitude = 2.0e6;
    const glm::dvec3 meridian(std::cos(lonV * kDeg), std::sin(lonV * kDeg), 0.0);
    double bestLat = -90.0;
    // The approach (approachFrom): the first tenth of the frames, at least one, and at least
    // two frames left for the rest.
    const int approachFrames =
        options.approachFrom > 0.0
            ? std::min(std::max(1, static_cast<int>(std::lround(0.1 * options.frames))),
                       options.frames - 2)
            : 0;
    const int restFrames = options.frames - approachFrames;
    const glm::dvec3 marsCentre = victoriaFromMars.translation;  // in Victoria's frame
    for (int i = 0; i < options.frames; ++i) {
      const double t =
          i < approachFrames ? 0.0 : static_cast<double>(i - approachFrames) / (restFrames - 1);
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
        poleLight = glm::normalize(glm::mix(sky, lightIn(marsNode), t / kPoleShare));
        if (lat > bestLat && i >= approachFrames) {
          bestLat = lat;
          summary.poleFrame = i;
          summary.poleLatitude = lat;
        }
      } else {
        const double u = options.overPole ? (t - kPoleShare) / (1.0 - kPoleShare) : t;
        pose = flyoverCamera(u, rover, options.overPole ? kPoleAltitude : 8.0e6);
      }
      if (i < approachFrames) {
        // Back along the first pose's view, to a distance from Mars's centre log-spaced from
        // approachFrom down to the first pose's: |w − k·f| = D, w = eye − centre.
        const glm::dvec3 f = pose.applyVector(glm::dvec3(0.0, 0.0, -1.0));
        const glm::dvec3 w = pose.translation - marsCentre;
        const double near = glm::length(w), far = std::max(options.approachFrom, near);
        const double a = static_cast<double>(i) / approachFrames;
        const double dist = std::exp(std::log(far) + a * (std::log(near) - std::log(far)));
        const double wf = glm::dot(w, f);
        pose.translation -=
            (wf + std::sqrt(std::max(wf * wf - glm::dot(w, w) + dist * dist, 0.0))) * f;
      }
      g.setLocal(cam, pose);
      const double dist = glm::length(pose.translation - rover);
      // Focus: Mars while the camera is far, Victoria once within 200 km of the rover.
      const scenegraph::NodeId focus = dist > 2.0e5 ? marsNode : victoriaNode;
      if (focus == victoriaNode && summary.focusSwitchFrame < 0) summary.focusSwitchFrame = i;
      if (i == 0) summary.startDistance = dist;
      summary.endDistance = dist;
      render::SceneView view;
      view.fovYDegrees = 45.0;
      view.near = std::clamp(0.01 * dist, 0.05, 1000.0);
      view.width = options.width;
      view.height = options.height;
      view.lightInFocus = poleLight && focus == marsNode ? *poleLight : lightIn(focus);
      if (mars->composed) {
        summary.datasetsPerFrame.push_back(
            datasetsSeen(*mars->composed, g, marsNode, cam, view.fovYDegrees,
                         static_cast<double>(options.width) / options.height, view.near));
      }
      const auto r0 = std::chrono::steady_clock::now();
      target.clear({0.02F, 0.02F, 0.04F, 1.0F});
      const scenegraph::RenderList list = g.renderList(focus, cam);
      renderer.prepare(list, view);
      // Beyond the clipmaps: the far field, where nothing is drawn yet.
      const render::SceneFrame frame = renderer.draw(list, view, &target);
      summary.farFieldFrames += frame.farFieldsPgm > 0 ? 1 : 0;
      summary.impostorFrames += frame.farFieldsImpostor > 0 ? 1 : 0;
      summary.coveredFrames += frame.farFieldsCovered > 0 ? 1 : 0;
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
      for (const auto& [camera, x] : {std::pair{orbitCamera, 0}, {mastCamera, half}}) {
        render::SceneView view;
        view.x = x;
        view.width = half;
        view.height = options.height;
        view.near = camera == orbitCamera ? 100.0 : 0.05;
        view.lightInFocus = lightIn(victoriaNode);
        const scenegraph::RenderList list = g.renderList(victoriaNode, camera);
        renderer.prepare(list, view);
        renderer.draw(list, view);
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
  // The root is the Sun, as in buildPaperScene(): the bodies' poses are heliocentric. The
  // light stays Victoria's morning sun below (a direction chosen for the pictures), not
  // `"from": "sun"`, the Sun's direction in this layout.
  d.root = "sun";
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
  mars.look.colour = rgb(kPlanetAlbedo);
  mars.look.clipmapSize = options.clipmapSize;
  // The paper's layout (PaperScene.hpp): heliocentric, the ecliptic the x-y plane.
  const demo::PaperSceneLayout layout;
  const auto array = [](const glm::dvec3& v) { return std::array<double, 3>{v.x, v.y, v.z}; };
  mars.pose = scene::Body::Pose{array(heliocentric(layout.marsDistance, layout.marsLongitudeDeg)),
                                layout.marsObliquityDeg, layout.marsSpinDeg};
  d.bodies.push_back(mars);
  // Earth as the paper's scene draws it: WGS84 without relief (3° cells: a dot from Mars),
  // blue, a small clipmap, no far field.
  scene::Body earth;
  earth.name = "earth";
  const topo::Body wgs84 = topo::Body::earthWgs84();
  earth.radii = std::array<double, 2>{wgs84.equatorialRadius(), wgs84.polarRadius()};
  earth.pose =
      scene::Body::Pose{array(heliocentric(layout.earthDistance, layout.earthLongitudeDeg)),
                        layout.earthObliquityDeg, 0.0};
  earth.look.colour = {0.3, 0.45, 0.8};
  earth.look.clipmapSize = 31;
  earth.farField = false;
  d.bodies.push_back(earth);

  const glm::vec3 demAlbedo = options.demAlbedo.value_or(kDemAlbedo);
  scene::Dem victoria;
  victoria.name = "victoria";
  victoria.body = "mars";
  if (options.victoriaStore.empty()) {
    victoria.heights.generate = "victoria";
    victoria.heights.size = options.demSize;
    victoria.heights.spacing = options.demSpacing;
    victoria.heights.seed = options.seed;
    victoria.placement =
        scene::Dem::Placement{layout.victoriaOrigin.latDeg, layout.victoriaOrigin.lonDeg, 0.0, true,
                              layout.victoriaHeadingDeg};
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
  d.cameras = paperCameras();
  // lightInFocus(): morning sun over Victoria, 35° up from the east (x east, y north, z up).
  d.light.frame = "victoria";
  d.light.direction = std::array<double, 3>{std::cos(35.0 * kDeg), -0.3, std::sin(35.0 * kDeg)};
  return d;
}

}  // namespace regolith::demo
