// What a longitude/latitude query costs through each placement: topo's analytic projections
// against the same CRS through PROJ (store::projPlacement()), and projections only PROJ has
// (docs/import.md).
//
// Each iteration answers kChunk queries from a fixed list of 4096 planetodetic points inside
// a 1024 × 1024 DEM of 25 m samples (in-memory, so the projection's cost is what differs):
//   <projection>/<placement>/from_geodetic   Placement::fromGeodetic() alone (lat/lon -> x, y)
//   <projection>/<placement>/lonlat_height   fromGeodetic() then a bilinear TopoDem::height()
//   <projection>/<placement>/to_geodetic     Placement::toGeodetic() (x, y -> lat/lon; through
//                                            PROJ an inverse and the forward that checks it)
// per_query is CPU time per query. Run once, all rows side by side:
//   build/bench/placement_bench --benchmark_min_time=0.3

#include <regolith/store/ProjPlacement.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using regolith::topo::Body;
using regolith::topo::Geodetic;
using regolith::topo::Placement;
using regolith::topo::TopoDem;
using regolith::topo::TopoGrid;

constexpr std::size_t kSize = 1024, kChunk = 4096;
constexpr double kSpacing = 25.0;

struct Case {
  std::string name;
  Body body;
  Placement placement;
  double cx, cy;  // map point of the DEM's centre
};

/// The DEM of a case, centred on (cx, cy), and kChunk points inside it (through the
/// placement's own inverse, so every query lands on the grid).
struct Fixture {
  std::unique_ptr<TopoDem> dem;
  std::vector<Geodetic> points;
  std::vector<glm::dvec2> xy;
};

Fixture fixtureOf(const Case& c) {
  std::vector<float> samples(kSize * kSize);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i] = static_cast<float>(std::sin(static_cast<double>(i % 977) * 0.01) * 50.0);
  }
  const double half = 0.5 * kSpacing * static_cast<double>(kSize - 1);
  const TopoGrid grid(kSize, kSize, c.cx - half, c.cy + half, kSpacing, kSpacing);
  Fixture f;
  f.dem = std::make_unique<TopoDem>(
      grid, c.placement,
      std::make_shared<regolith::topo::InMemorySamples>(kSize, kSize, std::move(samples)));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.9 * half, 0.9 * half);
  for (std::size_t i = 0; i < kChunk; ++i) {
    const glm::dvec2 p{c.cx + u(rng), c.cy + u(rng)};
    f.xy.push_back(p);
    f.points.push_back(c.placement.toGeodetic(p.x, p.y, 0.0));
  }
  return f;
}

void perQuery(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations() * static_cast<long long>(kChunk));
  state.counters["per_query"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(kChunk),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void fromGeodetic(benchmark::State& state, const Case& c) {
  const Fixture f = fixtureOf(c);
  for (auto _ : state) {
    for (const Geodetic& g : f.points) benchmark::DoNotOptimize(c.placement.fromGeodetic(g));
  }
  perQuery(state);
}

void toGeodetic(benchmark::State& state, const Case& c) {
  const Fixture f = fixtureOf(c);
  for (auto _ : state) {
    for (const glm::dvec2& p : f.xy)
      benchmark::DoNotOptimize(c.placement.toGeodetic(p.x, p.y, 0.0));
  }
  perQuery(state);
}

void lonLatHeight(benchmark::State& state, const Case& c) {
  const Fixture f = fixtureOf(c);
  for (auto _ : state) {
    for (const Geodetic& g : f.points) {
      const glm::dvec3 xy = c.placement.fromGeodetic(g);
      benchmark::DoNotOptimize(
          f.dem->height(xy.x, xy.y, regolith::topo::Interpolation::Bilinear).height);
    }
  }
  perQuery(state);
}

std::vector<Case> cases() {
  using regolith::store::projPlacement;
  using PS = regolith::topo::PolarStereographic;
  const Body sphere = Body::marsSphere(), ellipsoid = Body::marsEllipsoid();
  const std::string mars = " +a=3396190 +b=3376200 +units=m +no_defs +type=crs";
  return {
      {"equirectangular/analytic", sphere,
       Placement(sphere, regolith::topo::Equirectangular(3396190.0, 0.0, 137.0)), 2.4e4, -2.7e5},
      {"equirectangular/proj", sphere,
       projPlacement(sphere, "+proj=eqc +lon_0=137 +R=3396190 +units=m +no_defs +type=crs"), 2.4e4,
       -2.7e5},
      {"polar_stereographic/analytic", ellipsoid,
       Placement(ellipsoid, PS::withScaleFactor(ellipsoid, PS::Pole::North, 1.0, 0.0)), 1e5, 2e5},
      {"polar_stereographic/proj", ellipsoid,
       projPlacement(ellipsoid, "+proj=stere +lat_0=90 +k_0=1 +lon_0=0" + mars), 1e5, 2e5},
      {"transverse_mercator/analytic", ellipsoid,
       Placement(ellipsoid,
                 regolith::topo::TransverseMercator(ellipsoid, 137.0, 0.0, 0.9996, 5e5, 0.0)),
       5.2e5, -2.7e5},
      {"transverse_mercator/proj", ellipsoid,
       projPlacement(ellipsoid, "+proj=tmerc +lon_0=137 +k_0=0.9996 +x_0=500000" + mars), 5.2e5,
       -2.7e5},
      {"sinusoidal/proj", sphere,
       projPlacement(sphere, "+proj=sinu +lon_0=137 +R=3396190 +units=m +no_defs +type=crs"), 2.4e4,
       -2.7e5},
      {"lambert_conformal_conic/proj", sphere,
       projPlacement(sphere,
                     "+proj=lcc +lat_1=-20 +lat_2=-40 +lat_0=-30 +lon_0=30 +R=3396190 +units=m "
                     "+no_defs +type=crs"),
       0.0, 0.0},
  };
}

const std::vector<Case>& allCases() {
  static const std::vector<Case> c = cases();
  return c;
}

const bool registered = [] {
  for (const Case& c : allCases()) {
    benchmark::RegisterBenchmark((c.name + "/from_geodetic").c_str(),
                                 [&c](benchmark::State& s) { fromGeodetic(s, c); });
    benchmark::RegisterBenchmark((c.name + "/lonlat_height").c_str(),
                                 [&c](benchmark::State& s) { lonLatHeight(s, c); });
    benchmark::RegisterBenchmark((c.name + "/to_geodetic").c_str(),
                                 [&c](benchmark::State& s) { toGeodetic(s, c); });
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
