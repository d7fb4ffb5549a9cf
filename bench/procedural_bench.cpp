// The procedural Mars paged like a store (store::proceduralPager(), docs/scale.md): a
// 2^20-row planet (2^20 × 2^21 samples, 10.2 m apart) in 256 × 256 patches through a 64 MiB
// cache, with nothing on disk.
//
//   procedural/patch/{equator,pole}      one patch computed (the cost of every miss)
//   procedural/traverse/{heights,surfaces}_{cold,warm}   six wheels, 1 cm steps, along a
//       20 km S-curve at 10°N 30°E (12 M wheel queries): cold starts with an empty cache, so
//       the patches the path needs are computed inside the timing; warm runs the same path
//       again with them resident
//   procedural/random/cold               random points anywhere on the planet: every query
//       computes its patch (a miss), with evictions once the budget is full
//   procedural/random/resident           random points in a 12 × 12-patch region (36 MiB,
//       within the budget), warmed first: hits only
//
// With REGOLITH_SCALE_STORE=<store file> (scripts/scale-store.sh), the same traverses also run
// on that store's planet grid REGOLITH_SCALE_GRID (default mars), read from disk through a
// 64 MiB cache: store/traverse/{heights,surfaces}_{cold,warm}. A cold run drops the cache,
// not the kernel's page cache, and not the patch the thread read last (the thread's block
// keeps it alive, and the pager finds it again): a path within one patch loads nothing.
//
// Counters: patch loads and evictions, the peak resident bytes against the budget, the
// bytes the cache loaded (decoded patches) and the bytes read from the disk (read_bytes of
// /proc/self/io: 0 for the procedural planet, and for a store in a warm page cache;
// scripts/scale-store.sh drops the page cache before each cold run where it may).
#include <regolith/store/Procedural.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "ProcStats.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::store;
using namespace regolith::topo;

constexpr std::size_t kRows = std::size_t{1} << 20;
constexpr std::size_t kBudget = std::size_t{64} << 20;  // 64 MiB

ProceduralMarsOptions planetOptions() {
  ProceduralMarsOptions o;
  o.planet.rows = kRows;
  o.planet.seed = 1;
  return o;
}

/// One pager and planet over a fresh 64 MiB cache: the procedural Mars (its pole heights are
/// computed here, outside the timing: seconds at this size), or a store's planet grid.
struct Planet {
  std::shared_ptr<PatchCache> cache = std::make_shared<PatchCache>(kBudget);
  Pager pager;
  TopoPlanet planet;
  Planet() : pager(proceduralPager(planetOptions(), cache)), planet(pager.planet("mars")) {}
  Planet(const std::string& path, const std::string& grid)
      : pager(std::make_shared<const Store>(Store::open(path)), cache),
        planet(pager.planet(grid)) {}
};

Planet& shared() {
  static Planet p;
  return p;
}

/// The store of REGOLITH_SCALE_STORE (only asked for when it is set).
Planet& scaleStore() {
  static Planet p = [] {
    const char* grid = std::getenv("REGOLITH_SCALE_GRID");
    return Planet(std::getenv("REGOLITH_SCALE_STORE"), grid != nullptr ? grid : "mars");
  }();
  return p;
}

/// The cache's counters, and the bytes read from the disk since `diskBefore`
/// (bench::diskReadBytes()).
void reportCache(benchmark::State& state, const PatchCache& cache, double diskBefore) {
  const CacheStats s = cache.stats();
  state.counters["disk_MiB_read"] = (bench::diskReadBytes() - diskBefore) / 1048576.0;
  state.counters["MiB_loaded"] = static_cast<double>(s.bytesLoaded) / 1048576.0;
  state.counters["patch_loads"] = static_cast<double>(s.loads);
  state.counters["evictions"] = static_cast<double>(s.evictions);
  state.counters["peak_resident_MiB"] = static_cast<double>(s.peakResidentBytes) / 1048576.0;
  state.counters["budget_MiB"] = static_cast<double>(kBudget) / 1048576.0;
}

void patchCompute(benchmark::State& state, std::size_t row) {
  const auto src = proceduralMars(planetOptions());
  std::vector<float> out(256 * 256);
  std::size_t col = 0;
  for (auto _ : state) {
    src->readWindow("mars", 0, row, col, 256, 256, out);
    col = (col + 256 * 97) % (2 * kRows);  // a different patch each time
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * 256 * 256);
}

// Six wheel contact points per 1 cm step along a 20 km S-curve at 10°N 30°E: wheels at
// ±0.9 m across and −1, 0, +1 m along the heading.
struct Path {
  std::vector<LatLon> points;
};
const Path& path() {
  static const Path p = [] {
    Path x;
    const double radius = 3396190.0, degPerMetre = 180.0 / (std::numbers::pi * radius);
    const double lat0 = 10.0, lon0 = 30.0;
    const double lonScale = 1.0 / std::cos(lat0 * std::numbers::pi / 180.0);
    const std::size_t steps = 2000000;  // 20 km in 1 cm steps
    x.points.reserve(6 * steps);
    for (std::size_t i = 0; i < steps; ++i) {
      const double s = 1e-2 * static_cast<double>(i);  // metres along
      const double cx = 0.7 * s, cy = 0.7 * s + 800.0 * std::sin(s / 1200.0);
      const double dx = 0.7, dy = 0.7 + 800.0 / 1200.0 * std::cos(s / 1200.0);
      const double n = std::hypot(dx, dy), hx = dx / n, hy = dy / n;
      for (const double along : {-1.0, 0.0, 1.0}) {
        for (const double across : {-0.9, 0.9}) {
          const double east = cx + along * hx - across * hy;
          const double north = cy + along * hy + across * hx;
          x.points.push_back({lat0 + north * degPerMetre, lon0 + east * degPerMetre * lonScale});
        }
      }
    }
    return x;
  }();
  return p;
}

double drive(const TopoPlanet& planet, bool surfaces) {
  double sink = 0.0;
  for (const LatLon& ll : path().points) {
    sink += surfaces ? planet.surface(ll).normal.z : planet.height(ll).height;
  }
  return sink;
}

void traverseCold(benchmark::State& state, Planet& (*planet)(), bool surfaces) {
  (void)path();
  (void)planet();  // opened (the store's metadata read) before the disk is counted
  const double disk = bench::diskReadBytes();
  for (auto _ : state) {
    state.PauseTiming();
    Planet& p = planet();
    p.cache->clear();
    p.cache->resetStats();
    state.ResumeTiming();
    benchmark::DoNotOptimize(drive(p.planet, surfaces));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(path().points.size()));
  reportCache(state, *planet().cache, disk);
}

void traverseWarm(benchmark::State& state, Planet& (*planet)(), bool surfaces) {
  Planet& p = planet();
  (void)drive(p.planet, surfaces);  // the path's patches resident
  p.cache->resetStats();
  const double disk = bench::diskReadBytes();
  for (auto _ : state) benchmark::DoNotOptimize(drive(p.planet, surfaces));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(path().points.size()));
  reportCache(state, *p.cache, disk);
}

void randomCold(benchmark::State& state) {
  Planet& p = shared();
  p.cache->clear();
  p.cache->resetStats();
  const double disk = bench::diskReadBytes();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> z(-1.0, 1.0), lon(-180.0, 180.0);
  for (auto _ : state) {
    // Uniform over the sphere's area.
    const double lat = std::asin(z(rng)) * 180.0 / std::numbers::pi;
    benchmark::DoNotOptimize(p.planet.height({lat, lon(rng)}).height);
  }
  state.SetItemsProcessed(state.iterations());
  reportCache(state, *p.cache, disk);
}

void randomResident(benchmark::State& state) {
  Planet& p = shared();
  p.cache->clear();
  const GridInfo& info = p.pager.grid("mars");
  // A 12 × 12-patch region at 20°S 100°W: 3072 samples a side, 36 MiB of patches.
  const double side = 12.0 * 256.0 * info.spacingX - 2.0 * info.spacingX;
  const double lat0 = -20.0, lon0 = -100.0;
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(0.0, side);
  std::vector<LatLon> points(1 << 20);
  for (LatLon& ll : points) ll = {lat0 + u(rng), lon0 + u(rng)};
  for (const LatLon& ll : points) benchmark::DoNotOptimize(p.planet.height(ll).height);
  p.cache->resetStats();
  const double disk = bench::diskReadBytes();
  for (auto _ : state) {
    double sink = 0.0;
    for (const LatLon& ll : points) sink += p.planet.height(ll).height;
    benchmark::DoNotOptimize(sink);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size()));
  reportCache(state, *p.cache, disk);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("procedural/patch/equator", patchCompute, kRows / 2)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(8);
  benchmark::RegisterBenchmark("procedural/patch/pole", patchCompute, 0)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(8);
  std::vector<std::pair<std::string, Planet& (*)()>> planets{{"procedural", shared}};
  if (std::getenv("REGOLITH_SCALE_STORE") != nullptr) planets.emplace_back("store", scaleStore);
  for (const auto& [name, planet] : planets) {
    for (const bool surfaces : {false, true}) {
      const std::string what = name + "/traverse/" + (surfaces ? "surfaces" : "heights");
      benchmark::RegisterBenchmark((what + "_cold").c_str(), traverseCold, planet, surfaces)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(1);
      benchmark::RegisterBenchmark((what + "_warm").c_str(), traverseWarm, planet, surfaces)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(3);
    }
  }
  benchmark::RegisterBenchmark("procedural/random/cold", randomCold)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(400);
  benchmark::RegisterBenchmark("procedural/random/resident", randomResident)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(5);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
