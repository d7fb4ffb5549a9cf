// `regolith render STORE|CATALOGUE`: one headless image of a store's grid, or of the
// composed surface of a catalogue file, as a PNG: drawn by the scene-rendering layer
// (render::renderTerrain(): the clipmap, and a planet's far field beyond it).
#include <regolith/clod/EffectList.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/FromStore.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/render/TerrainImage.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include "CatalogueInfo.hpp"
#include "Commands.hpp"
#include "EffectsOption.hpp"
#include "FiniteRange.hpp"
#include "OutputFolder.hpp"
#include "SceneFiles.hpp"
#include "StoreGrid.hpp"

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace regolith::tools {

namespace {

struct Args {
  std::string store;
  std::string grid;
  std::string out = "render.png";
  int width = 1280, height = 720;
  std::vector<double> target;    // a, b: x, y (DEM) or lon, lat (planet)
  std::vector<double> position;  // a, b, altitude above the surface there
  std::optional<double> pitch;
  std::optional<double> distance;
  double heading = 0.0;
  std::optional<double> elevation;
  double fov = 45.0;
  int clipmapSize = 255;
  std::size_t cacheMb = 256;
  std::optional<double> spacing;  // catalogue: the composed grid's spacing, degrees
  bool noFarField = false;
  EffectOptions effects;
  std::string camera;  // scene files (SceneRenderCommand.cpp)
};

/// What a render draws: a store's grid, or a catalogue's composed surface over a global
/// latitude/longitude grid.
struct Terrain {
  /// The render's one loader thread: the pyramid's (or the datasets') hints and loads, and
  /// the clipmap's reads.
  std::shared_ptr<core::Executor> loader = std::make_shared<core::ThreadPool>(1);
  std::shared_ptr<const clod::HeightPyramid> pyramid;
  bool planet = false;
  topo::TopoGrid g0{1, 1, 0.0, 0.0, 1.0, 1.0};
  double radius = 0.0;                                          // the body's equatorial radius
  std::function<std::optional<double>(double, double)> height;  // at grid point (a, b)
  /// Scene position of command-line point (a, b) at height h (the pyramid's, unless the
  /// pyramid's grid is not the command line's: a catalogue drawn in a polar frame).
  std::function<glm::dvec3(double, double, double)> position;
  bool latLonGrid = false;  // the pyramid's grid is latitude/longitude (degrees)
  std::string what;         // for messages and the summary
  std::shared_ptr<store::PatchCache> cache;
  std::shared_ptr<const void> keepAlive;                    // pagers, stores, catalogue
  std::shared_ptr<const compose::ComposedSurface> surface;  // a catalogue's
  /// Effects: the height range (a store's level-0 statistics, else the pyramid's samples)
  /// and the DEM a traverse drives on (a store's DEM grid only).
  std::function<std::optional<std::array<double, 2>>()> heightRange;
  std::function<topo::TopoDem()> dem;
};

/// Height at grid point (a, b) from the finest level that has a sample there, or nullopt.
std::optional<double> surfaceHeight(const store::Pager& pager, const std::string& grid,
                                    const store::GridInfo& info, double a, double b) {
  for (std::size_t l = 0; l < info.levels; ++l) {
    const topo::HeightSample s = info.kind == store::GridKind::Dem
                                     ? pager.dem(grid, l).height(a, b)
                                     : pager.planet(grid, l).height(topo::LatLon{b, a});
    if (s.valid()) return s.height;
  }
  return std::nullopt;
}

Terrain storeTerrain(const Args& a) {
  Terrain t;
  auto store = std::make_shared<const store::Store>(store::Store::open(a.store));
  const std::string gridName = chooseGrid(*store, a.grid, "render");
  const store::GridInfo& info = store->grid(gridName);
  t.planet = info.kind == store::GridKind::Planet;
  t.cache = std::make_shared<store::PatchCache>(a.cacheMb << 20U);
  auto pager = std::make_shared<const store::Pager>(store, t.cache);
  // Lat/lon lines need a DEM on its body: then it is drawn through its placement
  // (body-fixed), else in its grid frame.
  t.pyramid = !t.planet && namesLatLon(a.effects)
                  ? std::make_shared<const clod::HeightPyramid>(
                        pager->pyramid(gridName, t.loader).levels, store::placementOf(info))
                  : std::make_shared<const clod::HeightPyramid>(pager->pyramid(gridName, t.loader));
  t.g0 = store::topoGridOf(info, 0);
  t.radius = store::bodyOf(info).equatorialRadius();
  t.height = [pager, gridName, &info](double pa, double pb) {
    return surfaceHeight(*pager, gridName, info, pa, pb);
  };
  t.position = [p = t.pyramid](double pa, double pb, double h) { return p->position(pa, pb, h); };
  t.latLonGrid = t.planet;
  t.what = "grid '" + gridName + "' of " + a.store;
  t.keepAlive = pager;
  t.heightRange = [&info, p = t.pyramid]() -> std::optional<std::array<double, 2>> {
    if (info.statistics && info.statistics->validSamples > 0)
      return std::array<double, 2>{info.statistics->min, info.statistics->max};
    return clod::heightRangeOf(*p);
  };
  if (!t.planet) t.dem = [pager, gridName] { return pager->dem(gridName); };
  return t;
}

/// A catalogue's composed surface drawn over a global planet grid at --spacing degrees
/// (default: the finest height dataset's ground spacing, at least 1e-6°).
Terrain catalogueTerrain(const Args& a) {
  Terrain t;
  auto file = std::make_shared<compose::CatalogueFile>(
      compose::readCatalogueFile(a.store, a.cacheMb << 20U, t.loader));
  const auto snapshot = file->catalogue->snapshot();
  const topo::Body& body = snapshot->body();
  t.radius = body.equatorialRadius();
  const double metresPerDegree = t.radius * std::numbers::pi / 180.0;
  auto surface = std::make_shared<const compose::ComposedSurface>(snapshot, file->rules);
  const double lookLat = a.target.size() == 2 ? a.target[1] : 0.0;
  const compose::DrawingFrame f =
      compose::drawingFrame(surface, lookLat, a.spacing ? *a.spacing * metresPerDegree : 0.0);
  std::ostringstream frame;
  if (!f.polar) {
    t.pyramid = std::make_shared<const clod::HeightPyramid>(f.pyramid);
    t.g0 = f.pyramid.levels[0].grid;
    t.position = [p = t.pyramid](double lon, double lat, double h) {
      return p->position(lon, lat, h);
    };
    t.latLonGrid = true;
    frame << "a latitude/longitude grid at " << t.g0.spacingY() << "°";
  } else {
    t.pyramid = std::make_shared<const clod::HeightPyramid>(f.pyramid.levels, *f.placement);
    t.g0 = f.pyramid.levels[0].grid;
    t.position = [body](double lon, double lat, double hh) {
      return body.toBodyFixed({lat, lon, hh});
    };
    t.latLonGrid = false;
    frame << "a polar stereographic grid at " << f.spacingMetres << " m";
  }
  t.planet = true;  // the command line speaks longitude, latitude
  t.surface = surface;
  t.height = [surface](double lon, double lat) -> std::optional<double> {
    const topo::HeightSample hs = surface->height(lat, lon);
    return hs.valid() ? std::optional<double>(hs.height) : std::nullopt;
  };
  std::ostringstream what;
  what << "the composed surface of " << snapshot->size() << " datasets of " << a.store << " ("
       << compose::policyName(file->rules.policy) << ", drawn on " << frame.str() << ")";
  t.what = what.str();
  t.cache = file->pagers.empty() ? nullptr
                                 : std::shared_ptr<store::PatchCache>(
                                       file->pagers.front(), &file->pagers.front()->cache());
  t.keepAlive = std::shared_ptr<const void>(file, file.get());
  t.heightRange = [p = t.pyramid] { return clod::heightRangeOf(*p); };
  return t;
}

void runRender(const Args& a, std::ostream& report) {
  const auto start = std::chrono::steady_clock::now();
  refuseOverwritingInputs("render", {a.out, a.out + ".legend.json"}, {a.store});
  refuseStdoutOverInput("render", a.store);
  const bool catalogue = isCatalogueFile(a.store);
  if (!catalogue && a.spacing) {
    throw InvalidArgument("render: --spacing applies to a catalogue file only; " + a.store +
                          " is a store");
  }
  const Terrain terrain = catalogue ? catalogueTerrain(a) : storeTerrain(a);
  const bool planet = terrain.planet;
  const auto& pyramid = terrain.pyramid;
  const topo::TopoGrid& g0 = terrain.g0;

  // A grid point given on the command line: checked, and lifted to the surface (the finest
  // level with data there; 0 m over nodata everywhere).
  struct Ground {
    double a, b, h;
  };
  const auto ground = [&](double pa, double pb, const char* option) {
    if (!std::isfinite(pa) || !std::isfinite(pb))
      throw InvalidArgument(std::string("render: ") + option + " must be finite numbers");
    if (planet ? std::abs(pb) > 90.0 : !g0.contains(pa, pb)) {
      std::ostringstream msg;
      msg << "render: " << option << " " << pa << "," << pb << " is outside " << terrain.what
          << " (";
      msg << (planet ? "latitude must be within [-90, 90]"
                     : "x in [" + std::to_string(g0.west()) + ", " + std::to_string(g0.east()) +
                           "], y in [" + std::to_string(g0.south()) + ", " +
                           std::to_string(g0.north()) + "]")
          << ")";
      throw InvalidArgument(msg.str());
    }
    return Ground{pa, pb, terrain.height(pa, pb).value_or(0.0)};
  };
  // The look-at point: --look-at, else the grid's centre.
  const Ground t = a.target.empty() ? ground(0.5 * (g0.west() + g0.east()),
                                             0.5 * (g0.north() + g0.south()), "--look-at")
                                    : ground(a.target[0], a.target[1], "--look-at");
  const double ta = t.a, tb = t.b, th = t.h;
  const glm::dvec3 target = terrain.position(ta, tb, th);

  // Defaults: a planet seen whole from straight above; a DEM at 35° from 1.2 × its extent.
  const double extent =
      planet ? terrain.radius : std::max(g0.east() - g0.west(), g0.north() - g0.south());
  const double distance = a.distance.value_or(planet ? 2.0 * extent : 1.2 * extent);
  const double elevation = a.elevation.value_or(planet ? 90.0 : 35.0);
  clod::RenderRequest request;
  std::ostringstream view;
  view << std::setprecision(10);
  if (a.position.empty()) {
    request.camera = clod::cameraLookingAt(*pyramid, target, a.heading, elevation, distance, a.fov,
                                           a.width, a.height);
    view << "looking at " << (planet ? "lon,lat " : "x,y ") << ta << "," << tb << " (height " << th
         << " m) from " << distance << " m, heading " << a.heading << "°, elevation " << elevation
         << "°";
  } else {
    // A camera at a position: --look-at aims it at a surface point, else heading and pitch.
    const Ground p = ground(a.position[0], a.position[1], "--position");
    if (!(a.position[2] >= 0.0 && std::isfinite(a.position[2]))) {
      throw InvalidArgument(core::format(
          {"render",
           {},
           "--position altitude",
           core::number(a.position[2]) + " m",
           "finite and >= 0 (below the surface the camera is inside the body and sees no "
           "terrain)"}));
    }
    const glm::dvec3 eye = terrain.position(p.a, p.b, p.h + a.position[2]);
    view << "from " << (planet ? "lon,lat " : "x,y ") << p.a << "," << p.b << " at "
         << a.position[2] << " m above the surface (height " << p.h << " m), ";
    if (!a.target.empty()) {
      const glm::dvec3 dir = target - eye;
      if (glm::length(dir) < 1e-6)
        throw InvalidArgument("render: --position and --look-at are the same point");
      request.camera.position = eye;
      request.camera.target = target;
      // Up: the local vertical, or north when looking straight down.
      glm::dvec3 up = pyramid->up(eye);
      if (glm::length(glm::cross(glm::normalize(dir), up)) < 1e-9)
        up = clod::cameraLookingAt(*pyramid, target, 0.0, 90.0, 1.0, a.fov, 2, 2).up;
      request.camera.up = up;
      request.camera.fovYDegrees = a.fov;
      request.camera.width = a.width;
      request.camera.height = a.height;
      request.camera.near = std::max(0.05, 1e-3 * glm::length(dir));
      view << "looking at " << ta << "," << tb << " (height " << th << " m)";
    } else {
      const double pitch = a.pitch.value_or(-20.0);
      request.camera =
          clod::cameraFromHeadingPitch(*pyramid, eye, a.heading, pitch, a.fov, a.width, a.height);
      request.camera.near = std::max(0.05, 1e-3 * std::abs(a.position[2]));
      view << "heading " << a.heading << "°, pitch " << pitch << "°";
    }
  }
  request.clipmap.size = a.clipmapSize;
  request.clipmap.executor = terrain.loader;
  // Effects (docs/overlays.md): only those --effects names are built.
  EffectTerrain effectTerrain{
      pyramid.get(), terrain.heightRange,
      terrain.dem,   terrain.what,
      {ta, tb},      terrain.latLonGrid ? terrain.radius * std::numbers::pi / 180.0 : 1.0};
  const DeclaredEffects effects = declareEffects(a.effects, effectTerrain);
  request.clipmap.effects = effects.effects;
  request.clipmap.trackWindow = effects.trackWindow;
  if (!catalogue && pyramid->placement()) {  // a DEM drawn placed: lit as in its grid frame
    request.clipmap.lightDirection =
        clod::gridLightInScene(*pyramid, {ta, tb}, request.clipmap.lightDirection);
  }
  if (catalogue) {
    // The sun 35° above the look-at point's horizon, from the west-north-west, wherever on
    // the body that is (the default light is fixed in body-fixed axes: from below at a
    // south pole).
    const glm::dmat3 enu = terrain.pyramid->body()->enuFrame(tb, ta);
    const glm::dvec3 horizontal = glm::normalize(-0.92 * enu[0] + 0.38 * enu[1]);
    const double el = 35.0 * std::numbers::pi / 180.0;
    request.clipmap.lightDirection = glm::vec3(std::cos(el) * horizontal + std::sin(el) * enu[2]);
  }
  // A planet: the far field (docs/far-field.md) draws it beyond the clipmap, so the clipmap
  // keeps only its levels whose window spans at most 180° (a wider one reaches over a pole
  // onto ground it already covers, and the two copies fight in the depth test). Its heights
  // and look are a scene's (scene::farFieldLayers(), planetFarFieldOptions()).
  std::optional<render::TerrainFarField> farField;
  if (planet && !a.noFarField) {
    farField = render::TerrainFarField{scene::farFieldLayers(*pyramid, terrain.surface.get()),
                                       scene::planetFarFieldOptions(request.clipmap.albedo)};
    if (terrain.latLonGrid)
      request.clipmap.levels = scene::planetLevelsWithFarField(*pyramid, request.clipmap.size);
  }
  if (terrain.latLonGrid) {
    // On a coarse planet whose finest window alone spans more than 180°, shrink the levels
    // to the largest odd size within 180° (docs/clod.md, "Not done yet").
    const double dy = g0.spacingY();
    const int fit = static_cast<int>(std::floor(180.0 / dy)) / 2 * 2 + 1;
    if (fit < request.clipmap.size && fit >= 15) {
      report << "Clipmap size " << request.clipmap.size << " spans more than 180° at " << dy
             << "° spacing; using " << fit << "\n";
      request.clipmap.size = fit;
    }
  }
  render::renderTerrainToPng(pyramid, request, farField, a.out);
  // A legend beside the PNG describes this image only: one an earlier render left there
  // goes when this one has none (no height colours or lat/lon lines).
  if (!effects.effects.heightColours && !effects.effects.latLon) {
    std::error_code ignored;
    std::filesystem::remove(a.out + ".legend.json", ignored);
  }

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report << "Wrote " << a.out << " (" << a.width << "×" << a.height << "): " << terrain.what << ", "
         << view.str() << "\n"
         << std::setprecision(3) << "  " << seconds << " s";
  if (terrain.cache) {
    const store::CacheStats stats = terrain.cache->stats();
    report << "; " << stats.loads << " patches loaded, "
           << static_cast<double>(stats.bytesLoaded) / 1048576.0 << " MiB loaded";
  }
  report << "\n";
  if (!effects.summary.empty()) report << effects.summary << "\n";
}

}  // namespace

void renderCatalogueView(const std::filesystem::path& catalogue, double lonDeg, double latDeg,
                         double distance, double elevationDeg, double headingDeg,
                         const std::filesystem::path& png, int width, int height,
                         std::ostream& report) {
  Args a;
  a.store = catalogue.string();
  a.out = png.string();
  a.width = width;
  a.height = height;
  a.target = {lonDeg, latDeg};
  a.distance = distance;
  a.elevation = elevationDeg;
  a.heading = headingDeg;
  runRender(a, report);
}

void addRenderCommand(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "render",
      "Renders a store's grid, or the composed surface of a catalogue file (JSON, "
      "docs/composition.md), headless (EGL, no display or GPU needed) with the geometry-"
      "clipmap renderer and writes a PNG. The camera orbits a look-at point on the surface "
      "(distance, heading, elevation), or stands at --position and looks at --look-at or "
      "along --heading and --pitch");
  addStoreGridOptions(*cmd, a->store, a->grid, a->cacheMb, "render");
  cmd->add_option("-o,--out", a->out, "PNG file to write (replaced atomically)")
      ->capture_default_str();
  cmd->add_option("--width", a->width, "Image width in pixels")
      ->check(CLI::Range(16, 8192))
      ->capture_default_str();
  cmd->add_option("--height", a->height, "Image height in pixels")
      ->check(CLI::Range(16, 8192))
      ->capture_default_str();
  cmd->add_option("--look-at,--target", a->target,
                  "Look-at point 'a,b' on the surface: x,y in metres for a DEM, lon,lat in "
                  "degrees for a planet (default: the grid's centre)")
      ->delimiter(',')
      ->expected(2)
      ->check(FiniteRange());
  cmd->add_option("--position", a->position,
                  "Camera position 'a,b,altitude': a grid point as for --look-at and the "
                  "height above the surface there, in metres. The camera then looks at "
                  "--look-at if given, else along --heading and --pitch (without "
                  "--position it orbits the look-at point)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--distance", a->distance,
                  "Orbit: camera distance from the look-at point in metres (default: a DEM's "
                  "larger extent × 1.2; a planet's equatorial radius × 2)")
      ->check(FiniteRange(1e-3, 1e13));
  cmd->add_option("--heading", a->heading,
                  "Direction the camera looks in, degrees clockwise from north")
      ->check(FiniteRange(-360.0, 360.0))
      ->capture_default_str();
  cmd->add_option("--elevation", a->elevation,
                  "Orbit: camera elevation above the look-at point's horizon in degrees, "
                  "(0, 90]; 90 looks straight down with north up (default: 35 for a DEM, 90 "
                  "for a planet)")
      ->check(FiniteRange(1e-3, 90.0));
  cmd->add_option("--pitch", a->pitch,
                  "With --position and no --look-at: view pitch in degrees, (-90, 90), "
                  "negative looks down (default: -20)")
      ->check(FiniteRange(-89.999, 89.999));
  cmd->add_option("--fov", a->fov, "Vertical field of view in degrees")
      ->check(FiniteRange(1.0, 170.0))
      ->capture_default_str();
  cmd->add_option("--spacing", a->spacing,
                  "Catalogue files: spacing of the global latitude/longitude grid the composed "
                  "surface is drawn on, degrees (default: the finest height dataset's, at least "
                  "1e-6)")
      ->check(FiniteRange(1e-7, 10.0));
  cmd->add_flag("--no-far-field", a->noFarField,
                "Planets: draw only the clipmap, every level, instead of its levels within 180° "
                "and the far field (projective grid mapping, docs/far-field.md) beyond them");
  addEffectOptions(*cmd, a->effects);
  cmd->add_option("--clipmap-size", a->clipmapSize,
                  "Vertices per clipmap level side (odd, 15 to 2047)")
      ->check(CLI::Range(15, 2047))
      ->capture_default_str();
  cmd->footer(
      "Examples:\n"
      "  regolith render victoria.h5 -o victoria.png\n"
      "  regolith render victoria.h5 --look-at 0,-300 --distance 900 --heading 20 --elevation 25\n"
      "  regolith render victoria.h5 --position -450,0,2 --look-at 0,0\n"
      "  regolith render victoria.h5 --position -450,0,2 --heading 90 --pitch -10\n"
      "  regolith render mars.h5 --look-at -5.5,-2 --distance 2e6 --elevation 60\n"
      "  regolith render moon.json --look-at 0,-88 --distance 1e6 --elevation 60\n"
      "  regolith render victoria.h5 --effects height-colours,noise --height-range -80,20\n"
      "  regolith render mars.h5 --effects latlon --latlon-spacing 15\n"
      "Exit status: 0 on success; non-zero with 'regolith: error: ...' on stderr otherwise "
      "(including when no OpenGL 4.5 context can be made).");
  cmd->add_option("--camera", a->camera,
                  "Scene files (docs/scene-format.md): the camera to render (its size, "
                  "viewport and field of view are the scene's)");
  cmd->callback([a] {
    if (isSceneFile(a->store)) {
      renderSceneFile(a->store, a->camera, a->out, std::cout);
    } else {
      runRender(*a, std::cout);
    }
  });
}

}  // namespace regolith::tools
