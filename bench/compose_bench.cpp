// Composition costs (docs/composition.md), Google Benchmark, ratios read side by side in one
// run:
//   build/bench/compose_bench --benchmark_min_time=0.3
// - Covering/N: one catalogue point query among N scattered DEMs (O(log N)).
// - PlainPaged vs Composed/k: a height at random points of a paged planet grid, straight
//   through TopoPlanet and through the composition with k covering datasets; PlainEach/k, the
//   k plain heights at each point that Composed/k reads, without the composition;
//   SoleHeight, the one dataset's own query that Composed/1 makes after its cell look-up.
//   Composed/3 blends two 0.01° twins over the global grid; ComposedMixed blends a 0.01° and
//   a 0.015° grid (weights with the projection quality), against PlainEachMixed.
// - PlainBatch vs ComposedBatch: the same per point through the batch calls (64 points a
//   call, items_per_second), where the processor may overlap one point's work with the next.
// - ComposedWindow/N: composing one clipmap level window (255 × 255 samples, what a frame's
//   loader reads when the focus jumps) with the same 5 covering datasets among N registered.
// - Traverse/plain and Traverse/composed: the rover across a feathered border, on the DEM
//   alone and on the composed surface baked into the DEM's lattice.

#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/compose/FromStore.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace {

using namespace regolith;

const topo::Body kMars = topo::Body::marsSphere();

topo::GridPyramid demPyramid(double spacing, std::size_t n, double h0) {
  const double half = 0.5 * spacing * static_cast<double>(n - 1);
  topo::TopoGrid grid(n, n, -half, half, spacing, spacing);
  auto src = topo::InMemorySamples::fromFunction(n, n, [&](std::size_t r, std::size_t c) {
    return static_cast<float>(h0 + 3.0 * std::sin(0.05 * static_cast<double>(r)) *
                                       std::cos(0.03 * static_cast<double>(c)));
  });
  topo::GridPyramid p;
  p.levels.push_back({grid, src});
  return p;
}

/// N tangent-plane DEMs (2 km, 50 m spacing) scattered over Mars; the first `near` of them
/// around (0, 0).
std::vector<std::shared_ptr<const compose::Dataset>> scattered(std::size_t n, std::size_t near) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> lat(-80.0, 80.0), lon(-180.0, 180.0), jitter(-0.01, 0.01);
  const auto pyr = demPyramid(50.0, 41, 0.0);
  std::vector<std::shared_ptr<const compose::Dataset>> out;
  for (std::size_t i = 0; i < n; ++i) {
    compose::DatasetOptions o;
    o.name = "dem";
    o.heightRange = std::array<double, 2>{-10.0, 10.0};
    const double la = i < near ? jitter(rng) : lat(rng), lo = i < near ? jitter(rng) : lon(rng);
    out.push_back(compose::Dataset::dem(
        pyr, topo::Placement(topo::LocalTangentPlane(kMars, {la, lo, 0.0})), o));
  }
  return out;
}

void Covering(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  compose::Catalogue cat(kMars);
  cat.add(scattered(n, 0));
  const auto snap = cat.snapshot();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> lat(-80.0, 80.0), lon(-180.0, 180.0);
  std::vector<double> la(4096), lo(4096);
  for (std::size_t i = 0; i < la.size(); ++i) {
    la[i] = lat(rng);
    lo[i] = lon(rng);
  }
  std::vector<std::uint32_t> found;
  std::size_t i = 0;
  std::size_t visited = 0;
  for (auto _ : state) {
    found.clear();
    visited += snap->covering(la[i], lo[i], found);
    benchmark::DoNotOptimize(found.data());
    i = (i + 1) % la.size();
  }
  state.counters["nodes/query"] =
      static_cast<double>(visited) / static_cast<double>(state.iterations());
}
BENCHMARK(Covering)->Arg(10)->Arg(100)->Arg(1000)->Arg(10000);

/// A store on Mars with a 0.05° global grid and two regional 0.01° grids over 0…10°N,
/// 0…10°E, paged through one cache holding them all.
struct PagedPlanet {
  std::filesystem::path path;
  std::shared_ptr<store::Pager> pager;
  PagedPlanet() {
    path = std::filesystem::temp_directory_path() /
           ("regolith-compose-bench-" + std::to_string(::getpid()) + ".h5");
    auto grid = [](const std::string& name, double step, double lon0, double lat0, std::size_t rows,
                   std::size_t cols, double h0) {
      store::GridSource g;
      g.info.name = name;
      g.info.kind = store::GridKind::Planet;
      g.info.rows = rows;
      g.info.cols = cols;
      g.info.x0 = lon0;
      g.info.y0 = lat0;
      g.info.spacingX = g.info.spacingY = step;
      g.info.equatorialRadius = g.info.polarRadius = kMars.equatorialRadius();
      g.samples =
          topo::InMemorySamples::fromFunction(rows, cols, [=](std::size_t r, std::size_t c) {
            return static_cast<float>(h0 + 100.0 * std::sin(0.01 * static_cast<double>(r + c)));
          });
      return g;
    };
    const store::GridSource grids[] = {grid("global", 0.05, -179.975, 89.975, 3600, 7200, 0.0),
                                       grid("regional1", 0.01, 0.005, 9.995, 1000, 1000, 10.0),
                                       grid("regional2", 0.01, 0.005, 9.995, 1000, 1000, 20.0),
                                       grid("regional3", 0.015, 0.0075, 9.9925, 667, 667, 30.0)};
    store::WriteOptions w;
    w.patchRows = w.patchCols = 256;
    store::writeStore(path, grids, w);
    pager = std::make_shared<store::Pager>(
        std::make_shared<const store::Store>(store::Store::open(path)),
        std::make_shared<store::PatchCache>(std::size_t{1} << 30));
  }
  ~PagedPlanet() { std::filesystem::remove(path); }
  PagedPlanet(const PagedPlanet&) = delete;
  PagedPlanet& operator=(const PagedPlanet&) = delete;
};

PagedPlanet& paged() {
  static PagedPlanet p;
  return p;
}

struct Points {
  std::vector<double> lat, lon;
  explicit Points(std::size_t n) : lat(n), lon(n) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.5, 9.5);
    for (std::size_t i = 0; i < n; ++i) {
      lat[i] = u(rng);
      lon[i] = u(rng);
    }
  }
};

/// Heights at the random points straight through TopoPlanet on one paged grid.
void plainHeights(benchmark::State& state, const char* grid) {
  const topo::TopoPlanet planet = paged().pager->planet(grid);
  const Points pts(1 << 16);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(planet.height({pts.lat[i], pts.lon[i]}).height);
    i = (i + 1) & (pts.lat.size() - 1);
  }
}

void PlainPaged(benchmark::State& state) { plainHeights(state, "global"); }
BENCHMARK(PlainPaged);

// regional1 alone (0.01°, 1000², random points over all of it): PlainEach/2 − PlainPaged −
// PlainRegional is what alternating between two grids costs the plain queries.
void PlainRegional(benchmark::State& state) { plainHeights(state, "regional1"); }
BENCHMARK(PlainRegional);

// The plain queries Composed/k makes, without the composition: at each point a height from
// each of the first k grids in turn, straight through TopoPlanet (so the thread's block
// changes grid at every query, as in the composition). Composed/k − PlainEach/k is what the
// composition itself costs.
void plainEach(benchmark::State& state, std::span<const char* const> names) {
  std::vector<topo::TopoPlanet> planets;
  for (const char* name : names) planets.push_back(paged().pager->planet(name));
  const Points pts(1 << 16);
  std::size_t i = 0;
  for (auto _ : state) {
    for (const topo::TopoPlanet& p : planets)
      benchmark::DoNotOptimize(p.height({pts.lat[i], pts.lon[i]}).height);
    i = (i + 1) & (pts.lat.size() - 1);
  }
}
void PlainEach(benchmark::State& state) {
  const char* const names[] = {"global", "regional1", "regional2"};
  plainEach(state, std::span(names).first(static_cast<std::size_t>(state.range(0))));
}
BENCHMARK(PlainEach)->Arg(1)->Arg(2)->Arg(3);

void PlainEachMixed(benchmark::State& state) {
  const char* const names[] = {"global", "regional1", "regional3"};
  plainEach(state, names);
}
BENCHMARK(PlainEachMixed);

// Heights through a composition of `names`, the last one feathered over `featherLast` metres.
void composed(benchmark::State& state, std::span<const char* const> names,
              double featherLast = 0.0) {
  compose::Catalogue cat(kMars);
  for (const char* name : names) {
    compose::DatasetOptions o;
    if (name == names.back()) o.featherMetres = featherLast;
    cat.add(compose::datasetFromStore(*paged().pager, name, o));
  }
  const compose::ComposedSurface s(cat.snapshot(), compose::Rules{compose::Policy::Weighted, 2.0});
  const Points pts(1 << 16);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.height(pts.lat[i], pts.lon[i]).height);
    i = (i + 1) & (pts.lat.size() - 1);
  }
}
void Composed(benchmark::State& state) {
  const char* const names[] = {"global", "regional1", "regional2"};
  composed(state, std::span(names).first(static_cast<std::size_t>(state.range(0))));
}
BENCHMARK(Composed)->Arg(1)->Arg(2)->Arg(3);

void ComposedMixed(benchmark::State& state) {
  const char* const names[] = {"global", "regional1", "regional3"};
  composed(state, names);
}
BENCHMARK(ComposedMixed);

// Composed/2 with a 120 km (about 2°) feather on the regional grid: 56 % of the points lie
// in its band, where the two blend by coverage (ComposedSurface::featheredTopHeight()), the
// rest inside it (coverage 1). Against PlainEach/2.
void ComposedFeathered(benchmark::State& state) {
  const char* const names[] = {"global", "regional1"};
  composed(state, names, 120e3);
}
BENCHMARK(ComposedFeathered);

// Dataset::soleHeightOrNan() alone (what Composed/1 runs after its cell look-up): the
// dataset's own locate and its grid's query, against PlainPaged.
void SoleHeight(benchmark::State& state) {
  const auto d = compose::datasetFromStore(*paged().pager, "global");
  const Points pts(1 << 16);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(d->soleHeightOrNan(pts.lat[i], pts.lon[i], 0));
    i = (i + 1) & (pts.lat.size() - 1);
  }
}
BENCHMARK(SoleHeight);

// Batches of 64 points, one dataset: the per-point cost where the processor may overlap
// queries (a rover's wheels are a batch). `query` writes the heights of a batch.
template <class Query>
void batchesOf64(benchmark::State& state, const Query& query) {
  const Points pts(1 << 16);
  std::vector<double> out(64);
  std::size_t i = 0;
  for (auto _ : state) {
    query(std::span<const double>(pts.lat).subspan(i, 64),
          std::span<const double>(pts.lon).subspan(i, 64), std::span<double>(out));
    benchmark::DoNotOptimize(out.data());
    i = (i + 64) & (pts.lat.size() - 1);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 64);
}

void PlainBatch(benchmark::State& state) {
  const topo::TopoPlanet planet = paged().pager->planet("global");
  batchesOf64(state, [&](auto lats, auto lons, auto out) { planet.heights(lats, lons, out, {}); });
}
BENCHMARK(PlainBatch);

void ComposedBatch(benchmark::State& state) {
  compose::Catalogue cat(kMars);
  cat.add(compose::datasetFromStore(*paged().pager, "global"));
  const compose::ComposedSurface s(cat.snapshot(), compose::Rules{compose::Policy::Weighted, 2.0});
  batchesOf64(state, [&](auto lats, auto lons, auto out) { s.heights(lats, lons, out, {}); });
}
BENCHMARK(ComposedBatch);

void ComposedWindow(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  compose::Catalogue cat(kMars);
  cat.add(scattered(n, 5));
  const auto surface = std::make_shared<const compose::ComposedSurface>(cat.snapshot());
  // A planet grid around (0, 0) at 5 m: its 255² window spans about 1.3 km, inside the five
  // DEMs near the origin.
  const double d = 5.0 / (kMars.equatorialRadius() * 3.141592653589793 / 180.0);
  const topo::TopoGrid grid(255, 255, -127 * d, 127 * d, d, d);
  const compose::ComposedSamples samples(surface, grid, topo::LatitudeType::Planetodetic, 5.0);
  std::vector<float> out(255 * 255);
  for (auto _ : state) {
    samples.readWindow(0, 0, 255, 255, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["samples/s"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * 255 * 255, benchmark::Counter::kIsRate);
}
BENCHMARK(ComposedWindow)->Arg(5)->Arg(1000)->Unit(benchmark::kMillisecond);

void Traverse(benchmark::State& state) {
  // A 1 m DEM (1201²) over a 0.01° planet grid; a second 1 m DEM overlapping its east half,
  // 2 m higher, feathered over 100 m: the path crosses the border and its feather.
  const bool composed = state.range(0) != 0;
  const topo::Placement placement(topo::LocalTangentPlane(kMars, {0.0, 0.0, 0.0}));
  const auto a = demPyramid(1.0, 1201, 0.0);
  compose::Catalogue cat(kMars);
  compose::DatasetOptions oa;
  oa.name = "west";
  cat.add(compose::Dataset::dem(a, placement, oa));
  compose::DatasetOptions ob;
  ob.name = "east";
  ob.featherMetres = 100.0;
  ob.priority = 1;
  cat.add(compose::Dataset::dem(
      demPyramid(1.0, 801, 2.0),
      topo::Placement(topo::LocalTangentPlane(kMars, {0.0, 400.0 / 59275.0, 0.0})), ob));
  std::shared_ptr<const topo::SampleSource> samples = a.levels[0].source;
  if (composed) {
    // The composed surface baked into the first DEM's lattice: the samples the clipmap of
    // composedDemPyramid() draws, so the rover feels what the camera shows.
    const auto surface = std::make_shared<const compose::ComposedSurface>(cat.snapshot());
    const compose::ComposedSamples cs(surface, a.levels[0].grid, placement, 1.0);
    std::vector<float> baked(1201 * 1201);
    cs.readWindow(0, 0, 1201, 1201, baked);
    samples = std::make_shared<topo::InMemorySamples>(1201, 1201, std::move(baked));
  }
  const topo::TopoDem dem(a.levels[0].grid, placement, samples);
  rover::TraverseOptions o;
  o.path = {{-500.0, 0.0}, {500.0, 0.0}};
  o.speed = 10.0;
  double queries = 0.0, seconds = 0.0;
  for (auto _ : state) {
    const rover::TraverseResult r = rover::runTraverse(dem, o);
    queries += static_cast<double>(r.queries);
    seconds += r.querySeconds;
  }
  state.counters["Mqueries/s"] = queries / seconds / 1e6;
}
BENCHMARK(Traverse)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
