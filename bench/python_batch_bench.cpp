// python_batch_bench: the C++ side of the Python-versus-C++ batch query comparison
// (docs/python.md). bench/python_vs_cpp.py runs this program and times the same batches
// through the regolith Python module in one run, then prints the table.
//
//   python_batch_bench --store=out/bench/victoria.h5 [google benchmark flags]
//
// Points: 1 M grid points of the Victoria DEM, identical to the Python script's (a Weyl
// sequence computed with the same IEEE operations), in two patterns:
//   scattered  fractional parts of i·φ and i·ψ spread over the whole DEM (cache-unfriendly);
//   path       a meandering line crossing the DEM in order (rover-like, cache-friendly).
// The DEM is paged through a 64 MiB cache, warmed before timing, as in Python. With 1 M
// points per batch, milliseconds per batch are nanoseconds per point.
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace regolith;

constexpr std::size_t kPoints = 1'000'000;

std::string gStore;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

struct Points {
  std::vector<double> x, y;
};

/// The same formulas as points() in python_vs_cpp.py.
Points makePoints(const topo::TopoGrid& g, bool scattered) {
  Points p;
  p.x.resize(kPoints);
  p.y.resize(kPoints);
  const double w = g.west() + 2.0, e = g.east() - 2.0, s = g.south() + 2.0, n = g.north() - 2.0;
  for (std::size_t i = 0; i < kPoints; ++i) {
    const double t = static_cast<double>(i);
    double u = 0.0, v = 0.0;
    if (scattered) {
      u = std::fmod(t * 0.6180339887498949, 1.0);
      v = std::fmod(t * 0.7548776662466927, 1.0);
    } else {
      u = t / static_cast<double>(kPoints);
      v = 0.5 + 0.4 * std::sin(t * 1e-5);
    }
    p.x[i] = w + u * (e - w);
    p.y[i] = s + v * (n - s);
  }
  return p;
}

struct Fixture {
  std::shared_ptr<store::PatchCache> cache;
  std::optional<topo::TopoDem> dem;
  Points scattered, path;
};

Fixture& fixture() {
  static Fixture f = [] {
    Fixture x;
    auto file = std::make_shared<const store::Store>(store::Store::open(gStore));
    x.cache = std::make_shared<store::PatchCache>(std::size_t{64} << 20);
    const store::Pager pager(file, x.cache);
    x.dem.emplace(pager.dem("victoria"));
    x.scattered = makePoints(x.dem->grid(), true);
    x.path = makePoints(x.dem->grid(), false);
    std::vector<double> h(kPoints);
    x.dem->heights(x.scattered.x, x.scattered.y, h, {});  // warm the cache
    return x;
  }();
  return f;
}

void BM_Heights(benchmark::State& state) {
  Fixture& f = fixture();
  const Points& p = state.range(0) != 0 ? f.scattered : f.path;
  std::vector<double> h(kPoints);
  for (auto _ : state) {
    f.dem->heights(p.x, p.y, h, {});
    benchmark::DoNotOptimize(h.data());
  }
}
BENCHMARK(BM_Heights)->Arg(1)->Arg(0)->ArgName("scattered")->Unit(benchmark::kMillisecond);

void BM_Surfaces(benchmark::State& state) {
  Fixture& f = fixture();
  const Points& p = state.range(0) != 0 ? f.scattered : f.path;
  std::vector<double> h(kPoints);
  std::vector<glm::dvec3> n(kPoints);
  for (auto _ : state) {
    f.dem->surfaces(p.x, p.y, h, n, {});
    benchmark::DoNotOptimize(n.data());
  }
}
BENCHMARK(BM_Surfaces)->Arg(1)->Arg(0)->ArgName("scattered")->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--store=", 0) == 0) gStore = a.substr(8);
  }
  if (gStore.empty()) {
    std::fprintf(stderr,
                 "python_batch_bench: --store=PATH is required (a Victoria store, e.g. written "
                 "by bench/python_vs_cpp.py)\n");
    return 2;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
