#include "MainDemo.hpp"

#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneDescription.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Body.hpp>

#include "CancelOnSignal.hpp"
#include "Commands.hpp"
#include "OutputFolder.hpp"
#include "TerminalProgress.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace regolith::tools {

namespace {

namespace fs = std::filesystem;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// True if `path` opens as a store holding grid `grid` with `levels` pyramid levels (a
/// corrupt, foreign or differently made file does not count, and is regenerated).
bool hasGrid(const fs::path& path, const std::string& grid, std::size_t levels) {
  if (!fs::exists(path)) return false;
  try {
    const store::Store s = store::Store::open(path);
    for (const std::string& n : s.gridNames())
      if (n == grid) return s.grid(n).levels == levels;
  } catch (const Error&) {
  }
  return false;
}

store::WriteOptions writeOptions(TerminalProgress& progress) {
  store::WriteOptions w;
  w.deflate = 4;
  w.progress = progress.callback();
  w.cancel = CancelOnSignal::flag();
  return w;
}

/// The default stores: generated when absent, reused when present.
struct DefaultData {
  fs::path mars, victoria;
  std::string marsNote, victoriaNote;
  /// The composition's further datasets: north and south polar caps and an inclined strip
  /// east of Victoria, and the catalogue file listing every dataset.
  fs::path northCap, southCap, strip, catalogue;
  std::string extraNote;
};

/// Mars's surface height at the Victoria site (bilinear in the stored planet's level 0), so
/// the DEM's plains meet the planet where the scene draws both.
double marsHeightAtVictoria(const fs::path& mars, const std::string& grid) {
  auto s = std::make_shared<const store::Store>(store::Store::open(mars));
  const store::Pager pager(s, std::make_shared<store::PatchCache>(std::size_t{16} << 20));
  const topo::TopoPlanet planet = pager.planet(grid);
  const double latC =
      planet.body().planetocentricFromPlanetodetic(store::VictoriaGenerator::kOriginLatDeg);
  const topo::HeightSample h =
      planet.height(topo::LatLon{latC, store::VictoriaGenerator::kOriginLonDeg});
  if (!h.valid()) throw Error("demo: " + mars.string() + " has no height at the Victoria site");
  return h.height;
}

DefaultData ensureData(const MainDemoOptions& o, const fs::path& dir, std::ostream& out) {
  fs::create_directories(dir);
  DefaultData d;
  d.mars = dir / "mars.h5";
  d.victoria = dir / "victoria.h5";
  const CancelOnSignal cancel;
  const auto note = [](Clock::time_point t0) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(1) << "generated in " << secondsSince(t0) << " s";
    return s.str();
  };
  store::MarsPlanetOptions m;
  m.rows = o.quick ? 256 : 1024;
  m.ellipsoid = true;  // the IAU ellipsoid, as the Victoria DEM's placement uses
  // Levels down to 16 × 32 samples: the clipmap's coarsest level then spans the globe.
  m.write.levels = o.quick ? 5 : 7;
  bool marsNew = false;
  if (hasGrid(d.mars, m.gridName, m.write.levels)) {
    d.marsNote = "reused";
  } else {
    out << "  generating " << d.mars.string() << " (procedural Mars, " << m.rows << " x "
        << 2 * m.rows << " samples)..." << std::endl;
    const auto t0 = Clock::now();
    TerminalProgress progress = TerminalProgress::forStderr();
    const std::size_t levels = m.write.levels;
    m.write = writeOptions(progress);
    m.write.levels = levels;
    store::MarsPlanetGenerator(m).write(d.mars);
    d.marsNote = note(t0);
    marsNew = true;
  }
  store::VictoriaOptions v;
  if (o.quick) {  // the same 1.2 km square at 3 m
    v.size = 401;
    v.spacing = 3.0;
  }
  // Levels down to under 40 samples a side, so the clipmap's coarsest level covers the DEM.
  const std::size_t demLevels = o.quick ? 5 : 6;
  if (!marsNew && hasGrid(d.victoria, v.gridName, demLevels)) {
    d.victoriaNote = "reused";
  } else {
    v.originHeight = marsHeightAtVictoria(d.mars, m.gridName);
    out << "  generating " << d.victoria.string() << " (Victoria-like crater, " << v.size << " x "
        << v.size << " samples at " << v.spacing << " m, placed on the planet's surface at "
        << std::setprecision(6) << v.originHeight << " m)..." << std::endl;
    const auto t0 = Clock::now();
    TerminalProgress progress = TerminalProgress::forStderr();
    v.write = writeOptions(progress);
    v.write.levels = demLevels;
    store::VictoriaGenerator(v).write(d.victoria);
    d.victoriaNote = note(t0);
  }
  // The composition's further datasets, refining the same planet (seed, ellipsoid, craters):
  // polar caps at a finer spacing with the layered deposits the global grid lacks, and a
  // strip along an inclined ground track, 30 km east of Victoria.
  d.northCap = dir / "north_cap.h5";
  d.southCap = dir / "south_cap.h5";
  d.strip = dir / "strip.h5";
  const auto t0 = Clock::now();
  std::vector<std::string> made;
  for (const auto pole :
       {store::PolarCapOptions::Pole::North, store::PolarCapOptions::Pole::South}) {
    store::PolarCapOptions c;
    c.pole = pole;
    c.planet = {m.seed, m.ellipsoid, m.craterDensity};
    c.spacing = o.quick ? 6000.0 : 2000.0;
    const bool north = pole == store::PolarCapOptions::Pole::North;
    const fs::path path = north ? d.northCap : d.southCap;
    const std::string grid = north ? "north_cap" : "south_cap";
    if (!marsNew && fs::exists(path)) {
      try {
        const store::Store s = store::Store::open(path);
        if (s.grid(grid).spacingX == c.spacing) continue;
      } catch (const Error&) {  // NOLINT(bugprone-empty-catch): regenerate it below
      }
    }
    out << "  generating " << path.string() << " (" << (north ? "north" : "south") << " polar cap, "
        << c.spacing << " m)..." << std::endl;
    TerminalProgress progress = TerminalProgress::forStderr();
    c.write = writeOptions(progress);
    store::PolarCapGenerator(c).write(path);
    made.push_back(grid);
  }
  store::StripOptions st;
  st.centreLatDeg = -2.0;
  st.centreLonDeg = -5.0;
  st.inclinationDeg = 60.0;
  st.length = 200000.0;
  st.width = 8000.0;
  st.spacing = o.quick ? 400.0 : 100.0;
  st.planet = {m.seed, m.ellipsoid, m.craterDensity};
  bool stripOk = false;
  if (!marsNew && fs::exists(d.strip)) {
    try {
      const store::Store s = store::Store::open(d.strip);
      stripOk = s.grid(st.gridName).spacingX == st.spacing;
    } catch (const Error&) {  // NOLINT(bugprone-empty-catch): regenerate it below
    }
  }
  if (!stripOk) {
    out << "  generating " << d.strip.string() << " (a strip along an inclined ground track, "
        << st.length / 1e3 << " x " << st.width / 1e3 << " km at " << st.spacing << " m)..."
        << std::endl;
    TerminalProgress progress = TerminalProgress::forStderr();
    st.write = writeOptions(progress);
    store::StripGenerator(st).write(d.strip);
    made.push_back("strip");
  }
  d.extraNote = made.empty() ? "reused" : note(t0);
  // The catalogue of all five: `regolith render`, `query` and `info` read it too.
  d.catalogue = dir / "mars_catalogue.json";
  std::ostringstream json;
  json << "{\"policy\": \"weighted\", \"datasets\": [\n"
       << "  {\"store\": \"mars.h5\", \"grid\": \"" << m.gridName << "\"},\n"
       << "  {\"store\": \"north_cap.h5\", \"grid\": \"north_cap\", \"feather_m\": 60000},\n"
       << "  {\"store\": \"south_cap.h5\", \"grid\": \"south_cap\", \"feather_m\": 60000},\n"
       << "  {\"store\": \"strip.h5\", \"grid\": \"strip\", \"feather_nodata_samples\": 8},\n"
       << "  {\"store\": \"victoria.h5\", \"grid\": \"" << v.gridName
       << "\", \"feather_m\": 60}]}\n";
  const std::string text = json.str();
  core::writeStreamAtomically(
      d.catalogue, [&](std::ostream& os) { os << text; }, "demo");
  return d;
}

/// The traverse and what the renders need from it: the wheel tracks it left.
struct TraverseRun {
  rover::TraverseResult result;
  /// The paged store's cache and reads after the traverse.
  store::CacheStats cache;
  store::ReadCounters reads;
  std::size_t budgetBytes = 0;
  /// The overlay the rover presses its six wheels into as it drives (every 5 cm of travel).
  std::shared_ptr<rover::TrackLayer> tracks =
      std::make_shared<rover::TrackLayer>(rover::RoverRuts::kTexelMetres);
  std::size_t imprints = 0;
  rover::ChassisPose last;  // where the rover stopped
  rover::GroundPose lastGround;
};

TraverseRun runTraverse(const MainDemoOptions& o, const fs::path& victoria, std::ostream& out) {
  // The rover drives on the DEM paged from its store through a cache of --cache-mb.
  auto file = std::make_shared<const store::Store>(store::Store::open(victoria));
  auto cache = std::make_shared<store::PatchCache>(o.cacheMb << 20U);
  const topo::TopoDem dem = store::Pager(file, cache).dem("victoria");
  rover::TraverseOptions t;
  t.path = rover::defaultVictoriaPath();
  TraverseRun run;
  run.budgetBytes = cache->stats().capacityBytes;
  double nextReport = 0.0;
  // The six wheels pressed into the tracks every 5 cm (scene::driveAndPress(), as a scene
  // file's traverse presses them).
  const scene::TraverseEnd end =
      scene::driveAndPress(dem, t, run.tracks.get(), [&](const rover::StepState& s) {
        if (s.distance >= nextReport) {
          out << "  " << std::fixed << std::setprecision(0) << std::setw(4) << s.distance
              << " m  x " << std::setw(6) << std::setprecision(1) << s.chassis.x << "  y "
              << std::setw(6) << s.chassis.y << "  height " << std::setw(7) << std::setprecision(2)
              << s.chassis.height << " m  pitch " << std::setw(5) << std::setprecision(1)
              << s.chassis.pitch * 180.0 / M_PI << "°  roll " << std::setw(5)
              << s.chassis.roll * 180.0 / M_PI << "°  cache " << cache->stats().residentBytes / 1024
              << " KiB\n";
          nextReport = s.distance + 100.0;
        }
        run.lastGround = s.ground;
        return true;
      });
  run.result = end.result;
  run.imprints = end.imprints;
  run.last = end.last;
  run.cache = cache->stats();
  run.reads = file->counters();
  return run;
}

struct RoverViews {
  fs::path mast, chase;
  std::size_t imprints = 0, trackTiles = 0;
};

/// The cameras of the rover views, as scene.json records them: from the rover's mast
/// (looking back along its tracks) and a chase camera ahead of the rover (looking back at it),
/// where the traverse stopped.
std::vector<scene::Camera> roverCameras(const MainDemoOptions& o, const TraverseRun& trav) {
  const glm::dvec3 p{trav.last.x, trav.last.y, trav.last.height};
  const glm::dvec3 fwd{std::sin(trav.last.heading), std::cos(trav.last.heading), 0.0};
  const glm::dvec3 up{0.0, 0.0, 1.0};
  std::vector<scene::Camera> cameras;
  const auto add = [&](const std::string& name, const glm::dvec3& eye, const glm::dvec3& target,
                       double near) {
    scene::Camera c;
    c.name = name;
    c.frame = "victoria";
    c.eye = {eye.x, eye.y, eye.z};
    c.lookAt = {target.x, target.y, target.z};
    c.up = {up.x, up.y, up.z};
    c.fovY = 45.0;
    c.near = near;
    c.width = o.width;
    c.height = o.height;
    cameras.push_back(c);
  };
  // Mast: 2.1 m up, looking back along the tracks and down at the ground 15 m behind.
  add("mast", p + 2.1 * up + 0.4 * fwd, p - 15.0 * fwd, 0.05);
  // Chase: 9 m ahead and 3.5 m up, looking back at the rover.
  add("chase", p + 9.0 * fwd + 3.5 * up, p - 4.0 * fwd + 0.5 * up, 0.1);
  return cameras;
}

}  // namespace

void runMainDemo(const MainDemoOptions& o, std::ostream& out) {
  const auto start = Clock::now();
  fs::create_directories(o.outDir);
  const fs::path dataDir = o.dataDir.empty() ? o.outDir / "data" : o.dataDir;

  out << "[1/5] Default data in " << dataDir.string() << "\n";
  const DefaultData data = ensureData(o, dataDir, out);
  refuseOverwritingInputs(
      "demo",
      {o.outDir / "rover_view.png", o.outDir / "rover_chase.png", o.outDir / "north_pole.png",
       o.outDir / "south_pole.png", o.outDir / "scene.json"},
      {data.mars, data.victoria, data.northCap, data.southCap, data.strip, data.catalogue});
  out << "  " << data.mars.string() << ": " << data.marsNote << "\n  " << data.victoria.string()
      << ": " << data.victoriaNote << "\n";

  out << "[2/5] Rover traverse across the crater (6 wheels, 1 ms steps, cache budget " << o.cacheMb
      << " MiB)\n";
  const auto t1 = Clock::now();
  const TraverseRun trav = runTraverse(o, data.victoria, out);
  const double traverseSeconds = secondsSince(t1);
  const rover::TraverseResult& r = trav.result;

  out << "[3/5] Fly-over from orbit down to the rover on the crater rim (" << o.frames
      << " frames, " << o.width << "x" << o.height << ")" << std::endl;
  // The demo scene as data (docs/scene-format.md): Mars and Victoria from the stores, one
  // composed surface (docs/composition.md) with the polar caps and the strip, the rover where
  // the traverse of rover::defaultVictoriaPath() stops (scene.json replays it; this scene
  // takes the run above and its tracks), and the rover views' cameras. Every image below is drawn
  // from the scene::Scene built from this description, and it is written as scene.json.
  demo::MarsVictoriaOptions demoScene;
  demoScene.marsStore = data.mars;
  demoScene.victoriaStore = data.victoria;
  demoScene.clipmapSize = 127;
  // Mars and the DEMs blend over the DEMs' feathers: drawn in the planet's colour, the DEM's
  // border is invisible.
  demoScene.composition = true;
  demoScene.demAlbedo = demo::kPlanetAlbedo;
  demoScene.extraDatasets = {{data.northCap, "north_cap", 60000.0, 0.0},
                             {data.southCap, "south_cap", 60000.0, 0.0},
                             {data.strip, "strip", 0.0, 8.0}};
  scene::SceneDescription sceneFile =
      demo::sceneDescription(demoScene, {0.0, 0.0, 0.0, rover::defaultVictoriaPath()});
  for (const scene::Camera& c : roverCameras(o, trav)) sceneFile.cameras.push_back(c);
  // The traverse ran once, above: the scene takes where it stopped and the tracks it
  // pressed instead of driving it again (scene.json still replays it when read alone).
  scene::SceneOptions demoOptions;
  demoOptions.tracks["victoria"] = trav.tracks;
  demoOptions.driven["rover"] = trav.last;
  scene::Scene demoBuilt(sceneFile, demoOptions);

  demo::FlyoverOptions fly;
  fly.outputDir = o.outDir / "flyover";
  fly.frames = static_cast<int>(o.frames);
  fly.width = o.width;
  fly.height = o.height;
  // The flight starts beyond the north pole and passes over it, and ends where the traverse
  // stopped, with the tracks it left.
  fly.overPole = true;
  // It begins with an approach from 16 Mars radii, where the far field draws Mars as the
  // ray-cast impostor, so the flight passes through impostor, PGM and clipmaps.
  fly.approachFrom = 16.0 * topo::Body::marsEllipsoid().equatorialRadius();
  fly.progress = [&out, every = std::max<std::size_t>(1, o.frames / 6)](int done, int all,
                                                                        const fs::path& path) {
    if (static_cast<std::size_t>(done) % every == 0 || done == all)
      out << "  frame " << done << "/" << all << ": " << path.string() << std::endl;
  };
  const demo::FlyoverSummary flyover = demo::renderFlyover(demoBuilt, fly);

  out << "[4/5] The rover's view back along its tracks, and a chase view" << std::endl;
  const auto t4 = Clock::now();
  RoverViews views;
  views.imprints = trav.imprints;
  views.trackTiles = trav.tracks->tiles();
  views.mast = o.outDir / "rover_view.png";
  views.chase = o.outDir / "rover_chase.png";
  for (const auto& [camera, png] : {std::pair{"mast", views.mast}, {"chase", views.chase}}) {
    gl::writePng(png.string(), demoBuilt.render(camera));
    out << "  " << png.string() << std::endl;
  }
  const double viewSeconds = secondsSince(t4);
  // The scene of these images as a file: `regolith render OUT/scene.json --camera mast`
  // draws rover_view.png again, replaying the traverse.
  const fs::path scenePath = o.outDir / "scene.json";
  // Stores inside the output folder are named relative to it, so the folder can move.
  const fs::path outAbs = fs::absolute(o.outDir).lexically_normal();
  const auto relative = [&](scene::DataSource& s) {
    if (s.store.empty()) return;
    const fs::path rel = fs::absolute(s.store).lexically_normal().lexically_relative(outAbs);
    if (!rel.empty() && *rel.begin() != "..") s.store = rel.string();
  };
  for (scene::Body& b : sceneFile.bodies)
    for (scene::DataSource& s : b.heights) relative(s);
  for (scene::Dem& m : sceneFile.dems) relative(m.heights);
  sceneFile.folder = outAbs;
  scene::writeScene(sceneFile, scenePath);
  out << "  " << scenePath.string() << " (the scene of these views)" << std::endl;

  out << "[5/5] The poles from 2000 km: each cap composed over the global grid ("
      << data.catalogue.string() << ")" << std::endl;
  const auto t5 = Clock::now();
  const fs::path northPole = o.outDir / "north_pole.png", southPole = o.outDir / "south_pole.png";
  std::ostringstream renderReport;
  renderCatalogueView(data.catalogue, 0.0, 88.0, 2.0e6, 65.0, 0.0, northPole, o.width, o.height,
                      renderReport);
  renderCatalogueView(data.catalogue, 180.0, -88.0, 2.0e6, 65.0, 180.0, southPole, o.width,
                      o.height, renderReport);
  out << "  " << northPole.string() << "\n  " << southPole.string() << std::endl;
  const double poleSeconds = secondsSince(t5);

  out << "\n==== Summary (" << std::fixed << std::setprecision(1) << secondsSince(start) << " s)\n";
  out << "Traverse: " << r.steps << " steps, " << std::setprecision(0) << r.distance
      << " m driven, " << r.queries << " wheel queries at " << std::setprecision(1)
      << r.queriesPerSecond / 1e6 << " M/s (queries only; whole loop " << traverseSeconds
      << " s)\n";
  out << "  cache: " << trav.cache.hits << " hits, " << trav.cache.misses << " misses, "
      << trav.cache.loads << " patch loads, " << trav.reads.bytesRead / 1024
      << " KiB read; resident " << trav.cache.peakResidentBytes / 1024 << " KiB at most, budget "
      << trav.budgetBytes / 1024 << " KiB\n";
  out << "  chassis: largest tilt " << std::setprecision(1) << r.maxTilt * 180.0 / M_PI
      << "°, largest contact residual " << std::setprecision(3) << r.maxResidual << " m\n";
  out << "  driven once: every image shows this run's end and tracks (traverses the scene drove "
         "again: "
      << demoBuilt.traversesDriven() << ")\n";
  out << "Fly-over: " << flyover.files.size() << " images in " << (o.outDir / "flyover").string()
      << " (" << std::setprecision(1) << flyover.renderSeconds << " s drawing, " << flyover.seconds
      << " s in all; " << std::setprecision(0) << flyover.startDistance / 1e3 << " km to "
      << std::setprecision(1) << flyover.endDistance
      << " m from the rover, focus Mars → Victoria at frame " << flyover.focusSwitchFrame << ")\n";
  out << "  far field: PGM drew Mars beyond the clipmaps in " << flyover.farFieldFrames
      << " frames, the impostor in " << flyover.impostorFrames << "; the clipmaps filled "
      << flyover.coveredFrames << " (docs/far-field.md)\n";
  if (!flyover.datasetsPerFrame.empty()) {
    const auto [lo, hi] =
        std::minmax_element(flyover.datasetsPerFrame.begin(), flyover.datasetsPerFrame.end());
    out << "  composition: " << *lo << " to " << *hi << " datasets in view per frame (";
    for (std::size_t i = 0; i < flyover.datasetsPerFrame.size(); ++i) {
      out << (i == 0 ? "" : " ") << flyover.datasetsPerFrame[i];
    }
    out << "); over the north pole at frame " << flyover.poleFrame << " (latitude "
        << std::setprecision(2) << flyover.poleLatitude << "°)\n";
  }
  out << "Poles: " << northPole.string() << " and " << southPole.string() << " ("
      << std::setprecision(1) << poleSeconds << " s; caps and strip " << data.extraNote << ")\n";
  out << "Rover views: " << views.mast.string() << " and " << views.chase.string() << " ("
      << views.imprints << " six-wheel imprints pressed into " << views.trackTiles
      << " track tiles, " << std::setprecision(1) << viewSeconds << " s)\n";
}

}  // namespace regolith::tools
