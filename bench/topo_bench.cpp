// Speed of TopoDem and TopoPlanet queries (docs/accuracy-vs-time.md).
//
// Every benchmark iteration answers kChunk queries taken in order from a precomputed point
// list, so the figures are per query:
//   items_per_second  queries per CPU-second
//   per_query         CPU time per query (the inverse), e.g. "5.3ns"
//
// Point lists:
//   rover   a smooth curve walked in 1 cm steps (65,536 points, 655 m): consecutive
//           queries fall in the same or a neighbouring cell, so the samples are cache-hot.
//   random  uniform over the whole grid (262,144 points): nearly every query misses L1/L2.
//
// Benchmark names: <object>/<query>/<kernel>/<points>, e.g. dem/height/bilinear/rover.
//   dem/height, dem/surface_grid, dem/surface_bodyfixed     one call per query
//   dem/heights_batch, dem/surfaces_batch_grid, ..._bodyfixed  one batch call per chunk
//   dem/handwritten/bilinear   a plain interior bilinear loop over the same float array and
//                              the same points: the baseline for dem/heights_batch/bilinear
//   planet/height, planet/heights_batch   TopoPlanet on a 1440x720 global grid (MOLA MEGDR
//                                         size, 0.25 deg)
//   planet/surfaces_batch      heights and body-fixed normals, bilinear, on that sphere
//   planet_ellipsoid/heights_batch, planet_ellipsoid/surfaces_batch   the same samples on
//                              Body::marsEllipsoid(), planetocentric (the latitude conversion
//                              and both radii of curvature per normal): surfaces / heights

#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoGrid.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <benchmark/benchmark.h>
#include <glm/vec3.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace {

using regolith::topo::Body;
using regolith::topo::Geodetic;
using regolith::topo::InMemorySamples;
using regolith::topo::Interpolation;
using regolith::topo::LatitudeType;
using regolith::topo::LatLon;
using regolith::topo::LocalTangentPlane;
using regolith::topo::NormalFrame;
using regolith::topo::Placement;
using regolith::topo::QueryStatus;
using regolith::topo::TopoDem;
using regolith::topo::TopoGrid;
using regolith::topo::TopoPlanet;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

constexpr std::size_t kChunk = 4096;             // queries per benchmark iteration
constexpr std::size_t kRoverPoints = 1U << 16U;  // 655 m of path at 1 cm
constexpr std::size_t kRandomPoints = 1U << 18U;
constexpr double kRoverStep = 0.01;  // metres

constexpr std::size_t kDemSize = 2048;  // rows = cols
constexpr double kDemSpacing = 1.0;     // metres (a HiRISE-class DTM)

constexpr std::size_t kPlanetCols = 1440;  // 0.25 deg, like MOLA MEGDR 4 px/deg
constexpr std::size_t kPlanetRows = 720;

// A smooth synthetic terrain (metres); the values only matter in that they are finite.
double terrain(double x, double y) {
  return 40.0 * std::sin(x / 310.0) * std::cos(y / 270.0) + 6.0 * std::sin((x + 2.0 * y) / 53.0) +
         0.8 * std::sin((3.0 * x - y) / 7.1);
}

struct Points {
  std::vector<double> xs, ys;  // DEM: x, y in metres; planet: xs = latitude, ys = longitude
};

// Arc-length parametrised curve with a slowly varying heading: turns on a ~150 m radius,
// so 655 m of path stays within a few hundred metres of the start.
template <class Step>
Points roverPath(std::size_t n, Step&& step) {
  Points p;
  p.xs.reserve(n);
  p.ys.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) * kRoverStep;
    const double heading = s / 150.0 + 0.6 * std::sin(s / 37.0);
    const auto [a, b] = step(i, heading);
    p.xs.push_back(a);
    p.ys.push_back(b);
  }
  return p;
}

Points uniformPoints(std::size_t n, double loA, double hiA, double loB, double hiB,
                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> da(loA, hiA), db(loB, hiB);
  Points p;
  p.xs.reserve(n);
  p.ys.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.xs.push_back(da(rng));
    p.ys.push_back(db(rng));
  }
  return p;
}

struct DemFixture {
  std::shared_ptr<InMemorySamples> samples;
  TopoDem dem;
  Points rover, random;
};

struct PlanetFixture {
  TopoPlanet planet;
  TopoPlanet ellipsoid;  // the same samples on Body::marsEllipsoid()
  Points rover, random;  // xs = latitude (deg), ys = longitude (deg)
};

DemFixture makeDemFixture() {
  // Centred on the tangent-plane origin: x, y from −1024 m to +1024 m.
  const double half = 0.5 * static_cast<double>(kDemSize - 1) * kDemSpacing;
  TopoGrid grid(kDemSize, kDemSize, -half, half, kDemSpacing, kDemSpacing);
  auto samples =
      InMemorySamples::fromFunction(kDemSize, kDemSize, [&](std::size_t r, std::size_t c) {
        const glm::dvec2 xy = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
        return static_cast<float>(terrain(xy.x, xy.y));
      });
  const Body mars = Body::marsSphere();
  Placement placement(LocalTangentPlane(mars, Geodetic{18.4, 77.5, -2500.0}, 0.0));
  TopoDem dem(grid, placement, samples);

  double x = 0.0, y = 0.0;
  Points rover = roverPath(kRoverPoints, [&](std::size_t, double heading) {
    x += kRoverStep * std::cos(heading);
    y += kRoverStep * std::sin(heading);
    return std::pair{x, y};
  });
  const double margin = 1.0;
  Points random = uniformPoints(kRandomPoints, grid.west() + margin, grid.east() - margin,
                                grid.south() + margin, grid.north() - margin, 12345);
  return {std::move(samples), std::move(dem), std::move(rover), std::move(random)};
}

PlanetFixture makePlanetFixture() {
  const double dLon = 360.0 / static_cast<double>(kPlanetCols);
  const double dLat = 180.0 / static_cast<double>(kPlanetRows);
  TopoGrid grid(kPlanetRows, kPlanetCols, -180.0 + 0.5 * dLon, 90.0 - 0.5 * dLat, dLon, dLat);
  auto samples =
      InMemorySamples::fromFunction(kPlanetRows, kPlanetCols, [&](std::size_t r, std::size_t c) {
        const glm::dvec2 ll = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
        return static_cast<float>(3000.0 * std::sin(3.0 * ll.x * kDeg) *
                                      std::cos(2.0 * ll.y * kDeg) +
                                  500.0 * std::sin(17.0 * ll.x * kDeg + 11.0 * ll.y * kDeg));
      });
  const Body mars = Body::marsSphere();
  TopoPlanet planet(grid, mars, LatitudeType::Planetocentric, samples);
  TopoPlanet ellipsoid(grid, Body::marsEllipsoid(), LatitudeType::Planetocentric, samples);

  const double radius = mars.equatorialRadius();
  double lat = 18.4, lon = 77.5;
  Points rover = roverPath(kRoverPoints, [&](std::size_t, double heading) {
    lat += kRoverStep * std::sin(heading) / radius / kDeg;
    lon += kRoverStep * std::cos(heading) / (radius * std::cos(lat * kDeg)) / kDeg;
    return std::pair{lat, lon};
  });
  Points random = uniformPoints(kRandomPoints, -90.0, 90.0, -180.0, 180.0, 67890);
  return {std::move(planet), std::move(ellipsoid), std::move(rover), std::move(random)};
}

// Walks the point list kChunk points per iteration and reports per-query figures.
template <class Fn>
void runChunks(benchmark::State& state, const Points& pts, Fn&& body) {
  const std::size_t n = pts.xs.size();
  std::size_t off = 0;
  for (auto _ : state) {
    body(off);
    off += kChunk;
    if (off + kChunk > n) off = 0;
  }
  const auto items =
      static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kChunk);
  state.SetItemsProcessed(items);
  // (kChunk · iterations / CPU seconds)⁻¹ = CPU seconds per query, shown as e.g. "5.3ns".
  state.counters["per_query"] = benchmark::Counter(
      static_cast<double>(kChunk),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// ---- TopoDem ---------------------------------------------------------------------------

void demHeight(benchmark::State& state, const DemFixture* f, const Points* pts,
               Interpolation interp) {
  const TopoDem& dem = f->dem;
  const double* xs = pts->xs.data();
  const double* ys = pts->ys.data();
  runChunks(state, *pts, [&](std::size_t off) {
    for (std::size_t i = off; i < off + kChunk; ++i) {
      const regolith::topo::HeightSample h = dem.height(xs[i], ys[i], interp);
      benchmark::DoNotOptimize(h);
    }
  });
}

void demSurface(benchmark::State& state, const DemFixture* f, const Points* pts,
                Interpolation interp, NormalFrame frame) {
  const TopoDem& dem = f->dem;
  const double* xs = pts->xs.data();
  const double* ys = pts->ys.data();
  runChunks(state, *pts, [&](std::size_t off) {
    for (std::size_t i = off; i < off + kChunk; ++i) {
      const regolith::topo::SurfaceSample s = dem.surface(xs[i], ys[i], interp, frame);
      benchmark::DoNotOptimize(s);
    }
  });
}

void demHeightsBatch(benchmark::State& state, const DemFixture* f, const Points* pts,
                     Interpolation interp, bool withStatus) {
  const TopoDem& dem = f->dem;
  std::vector<double> out(kChunk);
  std::vector<QueryStatus> status(withStatus ? kChunk : 0);
  runChunks(state, *pts, [&](std::size_t off) {
    dem.heights(std::span(pts->xs).subspan(off, kChunk), std::span(pts->ys).subspan(off, kChunk),
                out, status, interp);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  });
}

void demSurfacesBatch(benchmark::State& state, const DemFixture* f, const Points* pts,
                      Interpolation interp, NormalFrame frame) {
  const TopoDem& dem = f->dem;
  std::vector<double> heights(kChunk);
  std::vector<glm::dvec3> normals(kChunk);
  runChunks(state, *pts, [&](std::size_t off) {
    dem.surfaces(std::span(pts->xs).subspan(off, kChunk), std::span(pts->ys).subspan(off, kChunk),
                 heights, normals, {}, interp, frame);
    benchmark::DoNotOptimize(heights.data());
    benchmark::DoNotOptimize(normals.data());
    benchmark::ClobberMemory();
  });
}

// The baseline: what a caller would write by hand over the same row-major float array.
// Interior points only (the point lists keep 1 m from the edge), no nodata or NaN checks,
// no clamping; the reciprocal spacings are hoisted out of the loop.
void handwrittenBilinear(benchmark::State& state, const DemFixture* f, const Points* pts) {
  const TopoGrid& g = f->dem.grid();
  const float* data = f->samples->data().data();
  const auto cols = static_cast<std::ptrdiff_t>(g.cols());
  const double x0 = g.x0(), y0 = g.y0();
  const double invDx = 1.0 / g.spacingX(), invDy = 1.0 / g.spacingY();
  std::vector<double> out(kChunk);
  runChunks(state, *pts, [&](std::size_t off) {
    const double* xs = pts->xs.data() + off;
    const double* ys = pts->ys.data() + off;
    double* o = out.data();
    for (std::size_t i = 0; i < kChunk; ++i) {
      const double u = (xs[i] - x0) * invDx;
      const double v = (y0 - ys[i]) * invDy;
      const auto c = static_cast<std::ptrdiff_t>(u);  // u, v > 0: truncation is floor
      const auto r = static_cast<std::ptrdiff_t>(v);
      const double tu = u - static_cast<double>(c), tv = v - static_cast<double>(r);
      const float* p = data + r * cols + c;
      const double a = static_cast<double>(p[0]), b = static_cast<double>(p[1]);
      const double cc = static_cast<double>(p[cols]), d = static_cast<double>(p[cols + 1]);
      const double top = a + tu * (b - a), bottom = cc + tu * (d - cc);
      o[i] = top + tv * (bottom - top);
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  });
}

// ---- TopoPlanet --------------------------------------------------------------------------

void planetHeight(benchmark::State& state, const PlanetFixture* f, const Points* pts,
                  Interpolation interp) {
  const TopoPlanet& planet = f->planet;
  const double* lats = pts->xs.data();
  const double* lons = pts->ys.data();
  runChunks(state, *pts, [&](std::size_t off) {
    for (std::size_t i = off; i < off + kChunk; ++i) {
      const regolith::topo::HeightSample h = planet.height(LatLon{lats[i], lons[i]}, interp);
      benchmark::DoNotOptimize(h);
    }
  });
}

void planetHeightsBatch(benchmark::State& state, const PlanetFixture* f, const Points* pts,
                        Interpolation interp) {
  const TopoPlanet& planet = f->planet;
  std::vector<double> out(kChunk);
  runChunks(state, *pts, [&](std::size_t off) {
    planet.heights(std::span(pts->xs).subspan(off, kChunk), std::span(pts->ys).subspan(off, kChunk),
                   out, {}, interp);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  });
}

void planetSurfacesBatch(benchmark::State& state, const TopoPlanet* planet, const Points* pts) {
  std::vector<double> h(kChunk);
  std::vector<glm::dvec3> n(kChunk);
  runChunks(state, *pts, [&](std::size_t off) {
    planet->surfaces(std::span(pts->xs).subspan(off, kChunk),
                     std::span(pts->ys).subspan(off, kChunk), h, n, {}, Interpolation::Bilinear,
                     NormalFrame::BodyFixed);
    benchmark::DoNotOptimize(n.data());
    benchmark::ClobberMemory();
  });
}

struct Kernel {
  const char* name;
  Interpolation interp;
};
constexpr Kernel kKernels[] = {{"nearest", Interpolation::Nearest},
                               {"bilinear", Interpolation::Bilinear},
                               {"bicubic", Interpolation::Bicubic}};

void registerAll(const DemFixture& dem, const PlanetFixture& planet) {
  struct PointSet {
    const char* name;
    const Points* dem;
    const Points* planet;
  };
  const PointSet sets[] = {{"rover", &dem.rover, &planet.rover},
                           {"random", &dem.random, &planet.random}};
  auto reg = [](const std::string& name, auto&& fn, auto&&... args) {
    benchmark::RegisterBenchmark(name.c_str(), fn, args...)->Unit(benchmark::kMicrosecond);
  };
  for (const PointSet& s : sets) {
    const std::string suffix = std::string("/") + s.name;
    // Baseline and the batch API on the same points, registered next to each other.
    reg("dem/handwritten/bilinear" + suffix, handwrittenBilinear, &dem, s.dem);
    reg("dem/heights_batch/bilinear" + suffix, demHeightsBatch, &dem, s.dem,
        Interpolation::Bilinear, false);
    reg("dem/heights_batch_status/bilinear" + suffix, demHeightsBatch, &dem, s.dem,
        Interpolation::Bilinear, true);
    for (const Kernel& k : kKernels) {
      const std::string ks = std::string("/") + k.name + suffix;
      reg("dem/height" + ks, demHeight, &dem, s.dem, k.interp);
      if (k.interp != Interpolation::Bilinear) {  // bilinear is registered above
        reg("dem/heights_batch" + ks, demHeightsBatch, &dem, s.dem, k.interp, false);
      }
      reg("dem/surface_grid" + ks, demSurface, &dem, s.dem, k.interp, NormalFrame::Grid);
      reg("dem/surface_bodyfixed" + ks, demSurface, &dem, s.dem, k.interp, NormalFrame::BodyFixed);
      reg("dem/surfaces_batch_grid" + ks, demSurfacesBatch, &dem, s.dem, k.interp,
          NormalFrame::Grid);
      reg("dem/surfaces_batch_bodyfixed" + ks, demSurfacesBatch, &dem, s.dem, k.interp,
          NormalFrame::BodyFixed);
    }
    for (const Kernel& k : kKernels) {
      const std::string ks = std::string("/") + k.name + suffix;
      reg("planet/height" + ks, planetHeight, &planet, s.planet, k.interp);
      reg("planet/heights_batch" + ks, planetHeightsBatch, &planet, s.planet, k.interp);
    }
    reg("planet/surfaces_batch/bilinear" + suffix, planetSurfacesBatch, &planet.planet, s.planet);
    reg(
        "planet_ellipsoid/heights_batch/bilinear" + suffix,
        [](benchmark::State& st, const TopoPlanet* p, const Points* pts) {
          std::vector<double> out(kChunk);
          runChunks(st, *pts, [&](std::size_t off) {
            p->heights(std::span(pts->xs).subspan(off, kChunk),
                       std::span(pts->ys).subspan(off, kChunk), out, {}, Interpolation::Bilinear);
            benchmark::DoNotOptimize(out.data());
            benchmark::ClobberMemory();
          });
        },
        &planet.ellipsoid, s.planet);
    reg("planet_ellipsoid/surfaces_batch/bilinear" + suffix, planetSurfacesBatch, &planet.ellipsoid,
        s.planet);
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  const DemFixture dem = makeDemFixture();
  const PlanetFixture planet = makePlanetFixture();
  benchmark::AddCustomContext("queries_per_iteration", std::to_string(kChunk));
  benchmark::AddCustomContext("dem", std::to_string(kDemSize) + "x" + std::to_string(kDemSize) +
                                         " float, " +
                                         std::to_string(static_cast<int>(kDemSpacing * 100.0)) +
                                         " cm spacing, LocalTangentPlane on Body::marsSphere()");
  benchmark::AddCustomContext("planet", std::to_string(kPlanetCols) + "x" +
                                            std::to_string(kPlanetRows) +
                                            " float, 0.25 deg global, Body::marsSphere()");
  benchmark::AddCustomContext("rover_path", std::to_string(kRoverPoints) + " points, 1 cm steps");
  benchmark::AddCustomContext("random_points", std::to_string(kRandomPoints));
  registerAll(dem, planet);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
