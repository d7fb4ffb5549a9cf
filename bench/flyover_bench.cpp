// A fly-over of a paged planet through a 256 MiB patch cache (docs/scale.md, "A fly-over
// within 256 MiB"): the frames a viewer draws while descending from two radii above Mars to
// 500 m over 10°N 30°E, headless (Mesa llvmpipe through EGL), 1280 × 720.
//
//   procedural/flyover   the procedural 2^20-row Mars (2^20 × 2^21 samples, 10.2 m apart;
//                        store::proceduralPager(), nothing on disk): every patch the clipmap
//                        asks for is computed on its loader thread
//   store/flyover        with REGOLITH_SCALE_STORE=<store file> (scripts/scale-store.sh),
//                        the same path over that store's planet grid REGOLITH_SCALE_GRID
//                        (default mars), read from disk
//
// Each frame moves the clipmap's focus (requestFocus(), the loader reading on its own thread),
// uploads what is ready (update(false): a frame never waits for I/O), draws the clipmap, then
// the far field (PGM, or the impostor from far away) where the clipmap left the image empty,
// and waits for the GPU (glFinish). The camera's altitude falls geometrically, its elevation
// from 90° (straight down) to 30°, and the look-at point slides east by 5 % of the altitude
// per frame, so the descent pages new ground at every level. The ground height under the
// path is read before the timing (from the pager at level 0), then the cache is emptied: the
// fly-over starts cold.
//
// Counters: frame times (median, 90th percentile, largest), frames drawn with their finest
// level still loading (frames_coarser: the clipmap drew a coarser level's centre instead),
// the far field's PGM and impostor frames; the cache's patch loads, evictions, MiB loaded
// and peak resident bytes against its budget; and the process's resident set when the
// fly-over starts (the GL driver, the far field's layers, the empty cache) and at its peak
// (VmHWM: that, the cache, the clipmap's textures and the far field's buffers); the bytes
// read from the disk during the fly-over (read_bytes of /proc/self/io: 0 from a warm page
// cache; scripts/scale-store.sh drops it first where it may).
//
// REGOLITH_FLYOVER_PNG=<folder> writes frames 0, the middle one and the last as PNGs to look at.
#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/scene/SceneParts.hpp>
#include <regolith/store/Procedural.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "ProcStats.hpp"

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace regolith;

constexpr std::size_t kRows = std::size_t{1} << 20;
constexpr std::size_t kBudget = std::size_t{256} << 20;  // 256 MiB
constexpr std::size_t kFrames = 90;
constexpr int kWidth = 1280, kHeight = 720;
constexpr double kLat = 10.0, kLon = 30.0;  // where the descent ends
constexpr double kEndAltitude = 500.0;      // metres above the ground at the last frame

store::Pager openPager(bool procedural, const std::shared_ptr<store::PatchCache>& cache,
                       std::string& grid) {
  if (procedural) {
    store::ProceduralMarsOptions o;
    o.planet.rows = kRows;
    o.planet.seed = 1;
    grid = o.planet.gridName;
    return store::proceduralPager(o, cache);
  }
  const char* g = std::getenv("REGOLITH_SCALE_GRID");
  grid = g != nullptr ? g : "mars";
  return {
      std::make_shared<const store::Store>(store::Store::open(std::getenv("REGOLITH_SCALE_STORE"))),
      cache};
}

/// One camera of the descent.
struct Shot {
  double lon = 0.0, altitude = 0.0, elevation = 0.0, ground = 0.0;
};

void flyover(benchmark::State& state, bool procedural) {
  auto cache = std::make_shared<store::PatchCache>(kBudget);
  std::string grid;
  const store::Pager pager = openPager(procedural, cache, grid);
  auto pyramid = std::make_shared<const clod::HeightPyramid>(pager.pyramid(grid));
  const topo::Body& body = *pyramid->body();
  const double radius = body.equatorialRadius();

  // The descent: altitude from two radii to kEndAltitude, geometric; elevation 90° → 30°;
  // the look-at point ends at kLon and slides east by 5 % of the altitude per frame.
  std::vector<Shot> shots(kFrames);
  const double metresPerDegree =
      radius * std::numbers::pi / 180.0 * std::cos(kLat * std::numbers::pi / 180.0);
  for (std::size_t f = 0; f < kFrames; ++f) {
    const double s = static_cast<double>(f) / static_cast<double>(kFrames - 1);
    shots[f].altitude = std::exp(std::log(2.0 * radius) * (1.0 - s) + std::log(kEndAltitude) * s);
    shots[f].elevation = 90.0 - 60.0 * s;
  }
  double lon = kLon;
  for (std::size_t f = kFrames; f-- > 0;) {
    shots[f].lon = lon;
    lon -= 0.05 * shots[f].altitude / metresPerDegree;
  }
  {
    const topo::TopoPlanet level0 = pager.planet(grid);
    for (Shot& s : shots) {
      const topo::HeightSample h = level0.height({kLat, s.lon});
      s.ground = h.valid() ? h.height : 0.0;
    }
  }

  // The clipmap keeps its levels whose window spans at most 180°, the far field draws the
  // rest of the planet (as `regolith render` and a scene do: scene/SceneParts.hpp); its
  // layers are read whole, through the cache, before the timing.
  clod::ClipmapOptions co;
  co.levels = scene::planetLevelsWithFarField(*pyramid, co.size);
  const glm::dmat3 enu = body.enuFrame(kLat, kLon);
  const glm::dvec3 sun = glm::normalize(
      std::cos(0.61) * glm::normalize(-0.92 * enu[0] + 0.38 * enu[1]) + std::sin(0.61) * enu[2]);
  co.lightDirection = glm::vec3(sun);
  const auto setup0 = std::chrono::steady_clock::now();
  const auto layers = scene::farFieldLayers(*pyramid, nullptr);
  const double layerSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - setup0).count();
  const farfield::PgmOptions po = scene::planetFarFieldOptions(co.albedo);

  const char* pngDir = std::getenv("REGOLITH_FLYOVER_PNG");
  std::vector<double> ms;
  double coarser = 0.0, pgmFrames = 0.0, impostorFrames = 0.0;
  double rssBefore = 0.0, diskBefore = 0.0, diskAfter = 0.0;
  for (auto _ : state) {
    cache->clear();
    cache->resetStats();
    rssBefore = bench::statusMiB("VmRSS:");
    diskBefore = bench::diskReadBytes();
    clod::ClipmapTerrain terrain(pyramid, co);
    farfield::FarField farField(layers, po);
    gl::RenderTarget target(kWidth, kHeight);
    ms.clear();
    coarser = pgmFrames = impostorFrames = 0.0;
    for (std::size_t f = 0; f < kFrames; ++f) {
      const Shot& s = shots[f];
      const glm::dvec3 look = pyramid->position(s.lon, kLat, s.ground);
      const double e = s.elevation * std::numbers::pi / 180.0;
      const clod::Camera cam = clod::cameraLookingAt(
          *pyramid, look, 0.0, s.elevation, s.altitude / std::sin(e), 45.0, kWidth, kHeight);
      const auto t0 = std::chrono::steady_clock::now();
      terrain.requestFocus(look);
      terrain.update(false);
      target.clear({0.02F, 0.02F, 0.04F, 1.0F});
      const clod::ClipmapFrame frame = terrain.draw(cam);
      const farfield::FarFieldFrame far = farField.draw(target, cam, sun, true);
      glFinish();
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (frame.firstLevel > 0) coarser += 1.0;
      if (far.mode == farfield::FarFieldMode::Pgm) pgmFrames += 1.0;
      if (far.mode == farfield::FarFieldMode::Impostor) impostorFrames += 1.0;
      if (pngDir != nullptr && (f == 0 || f == kFrames / 2 || f == kFrames - 1)) {
        std::filesystem::create_directories(pngDir);
        gl::writePng(
            (std::filesystem::path(pngDir) / ((procedural ? "procedural" : "store") +
                                              std::string("_frame_") + std::to_string(f) + ".png"))
                .string(),
            target.readColor());
      }
    }
    terrain.finishLoading();
    diskAfter = bench::diskReadBytes();
  }
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  const auto at = [&sorted](double q) {
    return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))];
  };
  const store::CacheStats c = cache->stats();
  state.counters["frames"] = static_cast<double>(kFrames);
  state.counters["frame_ms_median"] = at(0.5);
  state.counters["frame_ms_p90"] = at(0.9);
  state.counters["frame_ms_max"] = sorted.back();
  state.counters["frames_coarser"] = coarser;
  state.counters["pgm_frames"] = pgmFrames;
  state.counters["impostor_frames"] = impostorFrames;
  state.counters["patch_loads"] = static_cast<double>(c.loads);
  state.counters["evictions"] = static_cast<double>(c.evictions);
  state.counters["MiB_loaded"] = static_cast<double>(c.bytesLoaded) / 1048576.0;
  state.counters["peak_resident_MiB"] = static_cast<double>(c.peakResidentBytes) / 1048576.0;
  state.counters["budget_MiB"] = static_cast<double>(kBudget) / 1048576.0;
  state.counters["rss_before_MiB"] = rssBefore;
  state.counters["disk_MiB_read"] = (diskAfter - diskBefore) / 1048576.0;
  state.counters["peak_rss_MiB"] = bench::statusMiB("VmHWM:");
  state.counters["layers_s"] = layerSeconds;
}

}  // namespace

int main(int argc, char** argv) {
  const gl::HeadlessContext context;
  benchmark::AddCustomContext("gl_renderer", gl::glRenderer());
  std::vector<std::pair<std::string, bool>> runs{{"procedural/flyover", true}};
  if (std::getenv("REGOLITH_SCALE_STORE") != nullptr) runs.emplace_back("store/flyover", false);
  for (const auto& [name, procedural] : runs) {
    benchmark::RegisterBenchmark(name.c_str(), flyover, procedural)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
