// `regolith render STORE`: one headless clipmap image of a store's grid, as a PNG.
#include <regolith/clod/Render.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Error.hpp>

#include "Commands.hpp"
#include "StoreGrid.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
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
  std::vector<double> target;  // a, b: x, y (DEM) or lon, lat (planet)
  std::optional<double> distance;
  double heading = 0.0;
  std::optional<double> elevation;
  double fov = 45.0;
  int clipmapSize = 255;
  std::size_t cacheMb = 256;
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

void runRender(const Args& a) {
  const auto start = std::chrono::steady_clock::now();
  auto store = std::make_shared<const store::Store>(store::Store::open(a.store));
  const std::string gridName = chooseGrid(*store, a.grid, "render");
  const store::GridInfo& info = store->grid(gridName);
  const bool planet = info.kind == store::GridKind::Planet;
  auto cache = std::make_shared<store::PatchCache>(a.cacheMb << 20U);
  const store::Pager pager(store, cache);
  const auto pyramid = pyramidFromStore(pager, gridName);

  // The look-at point: --target, else the grid's centre; on the surface where it has data.
  const topo::TopoGrid g0 = store::topoGridOf(info, 0);
  double ta = 0.5 * (g0.west() + g0.east()), tb = 0.5 * (g0.north() + g0.south());
  if (!a.target.empty()) {
    ta = a.target[0];
    tb = a.target[1];
    if (!std::isfinite(ta) || !std::isfinite(tb))
      throw InvalidArgument("render: --target must be two finite numbers");
    if (planet ? std::abs(tb) > 90.0 : !g0.contains(ta, tb)) {
      std::ostringstream msg;
      msg << "render: --target " << ta << "," << tb << " is outside grid '" << gridName << "' ("
          << (planet ? "latitude must be within [-90, 90]"
                     : "x in [" + std::to_string(g0.west()) + ", " + std::to_string(g0.east()) +
                           "], y in [" + std::to_string(g0.south()) + ", " +
                           std::to_string(g0.north()) + "]")
          << ")";
      throw InvalidArgument(msg.str());
    }
  }
  const double th = surfaceHeight(pager, gridName, info, ta, tb).value_or(0.0);
  const glm::dvec3 target = pyramid->position(ta, tb, th);

  // Defaults: a planet seen whole from straight above; a DEM at 35° from 1.2 × its extent.
  const double extent = planet ? store::bodyOf(info).equatorialRadius()
                               : std::max(g0.east() - g0.west(), g0.north() - g0.south());
  const double distance = a.distance.value_or(planet ? 2.0 * extent : 1.2 * extent);
  const double elevation = a.elevation.value_or(planet ? 90.0 : 35.0);
  clod::RenderRequest request;
  request.camera = clod::cameraLookingAt(*pyramid, target, a.heading, elevation, distance, a.fov,
                                         a.width, a.height);
  request.clipmap.size = a.clipmapSize;
  if (planet) {
    // On a coarse planet, shrink the levels to the largest odd size whose finest window
    // spans at most 180°: a wider window reaches over a pole onto ground it already covers,
    // and the two copies of that ground (lit from different neighbours) fight in the depth
    // test, which shows as a shading step (docs/clod.md, "Not done yet").
    const double dy = g0.spacingY();
    const int fit = static_cast<int>(std::floor(180.0 / dy)) / 2 * 2 + 1;
    if (fit < request.clipmap.size && fit >= 15) {
      std::cout << "Clipmap size " << request.clipmap.size << " spans more than 180° at " << dy
                << "° spacing; using " << fit << "\n";
      request.clipmap.size = fit;
    }
  }
  clod::renderToPng(pyramid, request, a.out);

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const store::CacheStats stats = cache->stats();
  std::cout << std::setprecision(10) << "Wrote " << a.out << " (" << a.width << "×" << a.height
            << "): grid '" << gridName << "' of " << a.store << ", looking at "
            << (planet ? "lon,lat " : "x,y ") << ta << "," << tb << " (height " << th << " m) from "
            << distance << " m, heading " << a.heading << "°, elevation " << elevation << "°\n"
            << std::setprecision(3) << "  " << seconds << " s; " << stats.loads
            << " patches loaded, " << static_cast<double>(stats.bytesLoaded) / 1048576.0
            << " MiB loaded\n";
}

}  // namespace

void addRenderCommand(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "render",
      "Renders a store's grid headless (EGL, no display or GPU needed) with the geometry-"
      "clipmap renderer and writes a PNG. The camera looks at a target point on the surface "
      "from a distance, a heading and an elevation above the target's horizon");
  cmd->add_option("store", a->store, "Store file (HDF5)")->required();
  cmd->add_option("--grid", a->grid, "Grid to render (default: the store's only grid)");
  cmd->add_option("-o,--out", a->out, "PNG file to write (replaced atomically)")
      ->capture_default_str();
  cmd->add_option("--width", a->width, "Image width in pixels")
      ->check(CLI::Range(16, 8192))
      ->capture_default_str();
  cmd->add_option("--height", a->height, "Image height in pixels")
      ->check(CLI::Range(16, 8192))
      ->capture_default_str();
  cmd->add_option("--target", a->target,
                  "Look-at point 'a,b': x,y in metres for a DEM, lon,lat in degrees for a "
                  "planet (default: the grid's centre); the camera aims at the surface there")
      ->delimiter(',')
      ->expected(2);
  cmd->add_option("--distance", a->distance,
                  "Camera distance from the target in metres (default: a DEM's larger extent "
                  "× 1.2; a planet's equatorial radius × 2)")
      ->check(CLI::Range(1e-3, 1e13));
  cmd->add_option("--heading", a->heading,
                  "Direction the camera looks in, degrees clockwise from north")
      ->check(CLI::Range(-360.0, 360.0))
      ->capture_default_str();
  cmd->add_option("--elevation", a->elevation,
                  "Camera elevation above the target's horizon in degrees, (0, 90]; 90 looks "
                  "straight down with north up (default: 35 for a DEM, 90 for a planet)")
      ->check(CLI::Range(1e-3, 90.0));
  cmd->add_option("--fov", a->fov, "Vertical field of view in degrees")
      ->check(CLI::Range(1.0, 170.0))
      ->capture_default_str();
  cmd->add_option("--clipmap-size", a->clipmapSize,
                  "Vertices per clipmap level side (odd, 15 to 2047)")
      ->check(CLI::Range(15, 2047))
      ->capture_default_str();
  cmd->add_option("--cache-mb", a->cacheMb, "Patch cache budget in MiB")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20U))
      ->capture_default_str();
  cmd->footer(
      "Examples:\n"
      "  regolith render victoria.h5 -o victoria.png\n"
      "  regolith render victoria.h5 --target 0,-300 --distance 900 --heading 20 --elevation 25\n"
      "  regolith render mars.h5 --target -5.5,-2 --distance 2e6 --elevation 60\n"
      "Exit status: 0 on success; non-zero with 'regolith: error: ...' on stderr otherwise "
      "(including when no OpenGL 4.5 context can be made).");
  cmd->callback([a] { runRender(*a); });
}

}  // namespace regolith::tools
