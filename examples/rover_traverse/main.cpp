// rover_traverse: a six-wheel rover drives a path across the Victoria-like DEM placed on Mars,
// querying height and normal under every wheel at every 1 ms step through the pager, with a
// cache budget set on the command line. As it drives it presses its wheels into a track
// overlay (rover::TrackLayer) every few centimetres; --image renders the DEM with those tracks
// from behind the rover's last position. Writes the wheel contacts as CSV if asked.
//
//   rover_traverse --cache-mb 4 --path "-560,-90 -430,-20 -300,250" --tracks tracks.csv
//                  --image tracks.png
//
// Public API only (regolith::rover, regolith::store, regolith::clod).
#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/rover/TrackPresser.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace regolith;

/// "x,y x,y ..." (grid metres) → waypoints. Throws InvalidArgument naming the bad item.
std::vector<glm::dvec2> parsePath(const std::string& text) {
  std::vector<glm::dvec2> path;
  std::istringstream in(text);
  std::string item;
  while (in >> item) {
    const auto comma = item.find(',');
    std::size_t used1 = 0, used2 = 0;
    glm::dvec2 p{};
    bool ok = comma != std::string::npos;
    try {
      if (ok) {
        p.x = std::stod(item.substr(0, comma), &used1);
        p.y = std::stod(item.substr(comma + 1), &used2);
        ok = used1 == comma && used2 == item.size() - comma - 1;
      }
    } catch (const std::exception&) {
      ok = false;
    }
    if (!ok) {
      throw InvalidArgument("rover_traverse: --path item '" + item +
                            "' is not 'x,y' (grid metres, e.g. -560,-90)");
    }
    path.push_back(p);
  }
  return path;
}

store::CachePolicy parsePolicy(const std::string& name) {
  if (name == "lru") return store::CachePolicy::Lru;
  if (name == "hitcount") return store::CachePolicy::HitCount;
  return store::CachePolicy::DecayingHitCount;
}

double mib(double bytes) { return bytes / 1048576.0; }

/// Renders the DEM with the traverse's tracks, headless, from 9 m ahead of the rover's last
/// position and 3.5 m up, looking back along its tracks.
void renderTracks(const std::string& storePath, const std::string& grid,
                  const rover::ChassisPose& last, std::shared_ptr<rover::TrackLayer> tracks,
                  const std::string& png) {
  auto st = std::make_shared<const store::Store>(store::Store::open(storePath));
  const store::Pager pager(st, std::make_shared<store::PatchCache>(std::size_t{64} << 20U));
  auto pyramid = std::make_shared<const clod::HeightPyramid>(pager.pyramid(grid));
  const glm::dvec3 p{last.x, last.y, last.height};
  const glm::dvec3 fwd{std::sin(last.heading), std::cos(last.heading), 0.0}, up{0.0, 0.0, 1.0};
  clod::RenderRequest req;
  req.camera.position = p + 9.0 * fwd + 3.5 * up;
  req.camera.target = p - 12.0 * fwd;
  req.camera.up = up;
  req.camera.fovYDegrees = 50.0;
  req.camera.width = 960;
  req.camera.height = 540;
  req.camera.near = 0.1;
  req.clipmap.effects.tracks = std::move(tracks);
  clod::renderToPng(pyramid, req, png);
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"A six-wheel rover drives a path across the Victoria-like DEM on Mars at 1 kHz"};
  std::string storePath = "out/rover/victoria.h5", grid = "victoria", pathText, tracks, image;
  double cacheMb = 16.0, speed = 1.0, stepMs = 1.0, trackSpacing = rover::RoverRuts::kSpacingMetres;
  std::size_t maxSteps = 0, trackEvery = 10, size = 1201;
  std::string policy = "lru";
  app.add_option("--store", storePath,
                 "Store holding the DEM; generated (VictoriaGenerator, 1 m) if absent")
      ->capture_default_str();
  app.add_option("--grid", grid, "DEM grid of the store")->capture_default_str();
  app.add_option("--cache-mb", cacheMb, "Patch cache budget in MiB (> 0)")->capture_default_str();
  app.add_option("--policy", policy, "Cache eviction policy")
      ->check(CLI::IsMember({"lru", "hitcount", "decaying"}))
      ->capture_default_str();
  app.add_option("--path", pathText,
                 "Waypoints 'x,y x,y ...' in grid metres (default: plains, rim, along the rim)");
  app.add_option("--speed", speed, "Rover speed, m/s")->capture_default_str();
  app.add_option("--step-ms", stepMs, "Time step, ms")->capture_default_str();
  app.add_option("--max-steps", maxSteps, "Stop after this many steps (0: end of the path)");
  app.add_option("--size", size, "Samples per side when generating the DEM")->capture_default_str();
  app.add_option("--tracks", tracks, "Write the wheel contacts every --track-every steps as CSV");
  app.add_option("--track-every", trackEvery, "Steps between track rows")->capture_default_str();
  app.add_option("--track-spacing", trackSpacing,
                 "Metres driven between imprints of the six wheels in the track overlay (> 0)")
      ->capture_default_str();
  app.add_option("--image", image,
                 "Render the DEM with the tracks to this PNG (headless), looking back at them");
  CLI11_PARSE(app, argc, argv);

  try {
    rover::TraverseOptions o;
    if (!(std::isfinite(cacheMb) && cacheMb > 0.0)) {
      throw InvalidArgument("rover_traverse: --cache-mb is " + core::number(cacheMb) +
                            ", expected a finite budget > 0");
    }
    const auto cacheBytes = static_cast<std::size_t>(cacheMb * 1048576.0);
    o.path = pathText.empty() ? rover::defaultVictoriaPath() : parsePath(pathText);
    o.speed = speed;
    o.step = stepMs / 1000.0;
    o.maxSteps = maxSteps;
    if (trackEvery == 0) throw InvalidArgument("rover_traverse: --track-every is 0, expected > 0");
    if (!(std::isfinite(trackSpacing) && trackSpacing > 0.0)) {
      throw InvalidArgument("rover_traverse: --track-spacing is " + core::number(trackSpacing) +
                            ", expected a distance > 0 m");
    }

    const std::filesystem::path storeFile = storePath;
    if (!std::filesystem::exists(storeFile)) {
      std::cout << "Generating the Victoria-like DEM (" << size << " x " << size << " at 1 m) into "
                << storeFile.string() << " ...\n";
      if (storeFile.has_parent_path()) std::filesystem::create_directories(storeFile.parent_path());
      store::VictoriaOptions v;
      v.size = size;
      v.gridName = grid;
      store::VictoriaGenerator(v).write(storeFile);
    }
    // The rover drives on the DEM paged from the store through a cache of --cache-mb.
    auto file = std::make_shared<const store::Store>(store::Store::open(storeFile));
    auto cache = std::make_shared<store::PatchCache>(cacheBytes, parsePolicy(policy));
    const topo::TopoDem dem = store::Pager(file, cache).dem(grid);

    std::ofstream csv;
    if (!tracks.empty()) {
      csv.open(tracks);
      if (!csv) throw InvalidArgument("rover_traverse: cannot write --tracks " + tracks);
      csv << "step,time,wheel,x,y,height,nx,ny,nz,chassis_height,pitch_deg,roll_deg\n";
      csv.precision(10);
    }
    constexpr double kDeg = 180.0 / std::numbers::pi;
    auto overlay = std::make_shared<rover::TrackLayer>(rover::RoverRuts::kTexelMetres);
    rover::TrackPressOptions press;
    press.spacingMetres = trackSpacing;
    rover::TrackPresser presser(*overlay, press);
    rover::ChassisPose last;
    const rover::TraverseResult r = rover::runTraverse(dem, o, [&](const rover::StepState& s) {
      (void)presser.press(s);  // the wheels press their ruts into the overlay
      last = s.chassis;
      if (csv.is_open() && s.step % trackEvery == 0) {
        for (std::size_t i = 0; i < rover::kWheels; ++i) {
          const auto& w = s.wheels[i];
          csv << s.step << ',' << s.time << ',' << i << ',' << w.x << ',' << w.y << ',' << w.height
              << ',' << w.normal.x << ',' << w.normal.y << ',' << w.normal.z << ','
              << s.chassis.height << ',' << s.chassis.pitch * kDeg << ',' << s.chassis.roll * kDeg
              << '\n';
        }
      }
      return true;
    });

    const store::CacheStats c = cache->stats();
    const store::ReadCounters reads = file->counters();
    std::printf("Traverse of grid '%s' in %s\n", grid.c_str(), storeFile.string().c_str());
    std::printf("  steps            %zu (%.3f s simulated at %.3g ms, %.1f m driven)\n", r.steps,
                static_cast<double>(r.steps) * o.step, stepMs, r.distance);
    std::printf(
        "  wheel queries    %zu height+normal, %.3f s in queries: %.2f M queries/s "
        "(%.0f ns each)\n",
        r.queries, r.querySeconds, r.queriesPerSecond / 1e6, 1e9 / r.queriesPerSecond);
    std::printf("  loop             %.3f s wall for %.3f s simulated (%.0fx real time)\n",
                r.totalSeconds, static_cast<double>(r.steps) * o.step,
                static_cast<double>(r.steps) * o.step / r.totalSeconds);
    std::printf("  cache            %llu hits, %llu misses, %llu patch loads, %llu evictions\n",
                static_cast<unsigned long long>(c.hits), static_cast<unsigned long long>(c.misses),
                static_cast<unsigned long long>(c.loads),
                static_cast<unsigned long long>(c.evictions));
    std::printf("  store reads      %llu hyperslab reads, %.2f MiB read\n",
                static_cast<unsigned long long>(reads.reads),
                mib(static_cast<double>(reads.bytesRead)));
    std::printf("  resident         %.2f MiB now, %.2f MiB peak, budget %.2f MiB (%s)\n",
                mib(static_cast<double>(c.residentBytes)),
                mib(static_cast<double>(c.peakResidentBytes)),
                mib(static_cast<double>(c.capacityBytes)),
                c.peakResidentBytes <= c.capacityBytes ? "within budget" : "OVER BUDGET");
    std::printf("  chassis          max tilt %.2f deg, max contact residual %.4f m\n",
                r.maxTilt * kDeg, r.maxResidual);
    std::printf("  track overlay    %zu imprints of the six wheels (every %.3g m), %zu tiles\n",
                presser.imprints(), trackSpacing, overlay->tiles());
    if (!tracks.empty()) std::printf("  tracks           %s\n", tracks.c_str());
    if (!image.empty()) {
      renderTracks(storePath, grid, last, overlay, image);
      std::printf("  image            %s\n", image.c_str());
    }
    return 0;
  } catch (const regolith::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
} catch (const std::exception& e) {
  std::fprintf(stderr, "rover_traverse: %s\n", e.what());
  return 1;
}
