// The cost of colour composition by surface-map accumulation (docs/colour-composition.md).
// Headless: Mesa llvmpipe through EGL surfaceless, 1280 × 720, a clipmap of a 1025² region
// of the Mars ellipsoid (0.59 m samples) seen from 150 m, and a catalogue of colour
// datasets in four placements over it:
//   base     a latitude/longitude albedo grid over the whole view (1.2 m, patterned)
//   strip    a tangent-plane strip of 0.5 m with a wavy nodata border and a feathered mask
//   polar    a polar stereographic albedo map of 0.5 m, 20 m feather
//   equirect an equirectangular (planetocentric) albedo map of 0.6 m, 15 m feather
//   overlay  a tangent-plane overlay of 0.8 m through the colour ramp
//
//   accumulation/<n>   each iteration draws one bare frame (clear, terrain, glFinish) and
//       one composed frame (clear, terrain, accumulate() with the first n datasets,
//       normalise(), glFinish), each phase timed on its own. Counters (means, ms): bare_ms,
//       accumulate_ms, normalise_ms, and ratio = composed / bare. Frames alternate side by
//       side so a drift of the shared machine hits both.
//
// Run: build/bench/accumulation_bench --benchmark_min_time=20x
// With ACCUMULATION_BENCH_PNG=<file.png> the composed frame with all five datasets is
// written there (docs/images/colour-composition.png).
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SurfaceAccumulator.hpp>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace regolith;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kLat0 = 18.4, kLon0 = 77.5;

const topo::Body& mars() {
  static const topo::Body body = topo::Body::marsEllipsoid();
  return body;
}

double terrainHeight(double lat, double lon) {
  return -2500.0 + 2.0 * std::sin(3000.0 * lat * kDeg) * std::cos(2500.0 * lon * kDeg) +
         0.8 * std::sin(90000.0 * lat * kDeg + 1.0) * std::cos(70000.0 * lon * kDeg);
}

std::shared_ptr<const clod::HeightPyramid> terrainPyramid() {
  const double d = 1e-5;
  const topo::TopoGrid grid(1025, 1025, kLon0 - 512 * d, kLat0 + 512 * d, d, d);
  auto samples = topo::InMemorySamples::fromFunction(1025, 1025, [&](std::size_t r, std::size_t c) {
    return static_cast<float>(terrainHeight(kLat0 + (512.0 - static_cast<double>(r)) * d,
                                            kLon0 + (static_cast<double>(c) - 512.0) * d));
  });
  return std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      grid, samples, clod::SurfaceKind::Planet, mars(), topo::LatitudeType::Planetodetic));
}

clod::Camera camera() {
  const glm::dmat3 enu = mars().enuFrame(kLat0, kLon0);
  clod::Camera cam;
  cam.target = mars().toBodyFixed({kLat0, kLon0, terrainHeight(kLat0, kLon0)});
  cam.position = cam.target + 120.0 * enu[2] - 100.0 * enu[1] + 20.0 * enu[0];
  cam.up = enu[2];
  cam.fovYDegrees = 60.0;
  cam.width = 1280;
  cam.height = 720;
  cam.near = 0.5;
  return cam;
}

compose::DatasetOptions colour(const char* name, double feather, compose::Role role,
                               std::shared_ptr<const topo::SampleSource> mask = nullptr) {
  compose::DatasetOptions o;
  o.name = name;
  o.featherMetres = feather;
  o.role = role;
  o.heightRange = std::array<double, 2>{-2510.0, -2490.0};
  o.mask = std::move(mask);
  return o;
}

/// A planar pyramid (1 level) of f(x, y) centred on (cx, cy).
topo::GridPyramid planar(double spacing, std::size_t rows, std::size_t cols, double cx, double cy,
                         const std::function<float(double, double)>& f) {
  const double x0 = cx - 0.5 * spacing * static_cast<double>(cols - 1);
  const double y0 = cy + 0.5 * spacing * static_cast<double>(rows - 1);
  topo::GridPyramid p;
  p.levels.push_back(
      {topo::TopoGrid(rows, cols, x0, y0, spacing, spacing),
       topo::InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
         return f(x0 + spacing * static_cast<double>(c), y0 - spacing * static_cast<double>(r));
       })});
  return p;
}

std::vector<std::shared_ptr<const compose::Dataset>> datasets() {
  const topo::Body& body = mars();
  const glm::dmat3 enu = body.enuFrame(kLat0, kLon0);
  const glm::dvec3 centre = body.toBodyFixed({kLat0, kLon0, 0.0});
  auto at = [&](double east, double north) {
    const topo::Geodetic g = body.toGeodetic(centre + east * enu[0] + north * enu[1]);
    return topo::Geodetic{g.latDeg, g.lonDeg, 0.0};
  };
  std::vector<std::shared_ptr<const compose::Dataset>> out;
  {  // base: 2e-5° (1.2 m), 601², patterned
    const double step = 2e-5;
    const std::size_t n = 601;
    const double lat0 = kLat0 + 300 * step, lon0 = kLon0 - 300 * step;
    topo::GridPyramid p;
    p.levels.push_back(
        {topo::TopoGrid(n, n, lon0, lat0, step, step),
         topo::InMemorySamples::fromFunction(n, n, [&](std::size_t r, std::size_t c) {
           const double x = static_cast<double>(c), y = static_cast<double>(r);
           return static_cast<float>(0.7 + 0.15 * std::sin(x / 23.0) * std::cos(y / 37.0) +
                                     0.1 * std::sin((x + y) / 61.0));
         })});
    p.planetBody = body;
    p.latitudeType = topo::LatitudeType::Planetodetic;
    out.push_back(compose::Dataset::planet(p, colour("base", 0.0, compose::Role::Albedo)));
  }
  {  // strip
    const double sp = 0.5, a = 25.0 * kDeg;
    topo::GridPyramid p = planar(sp, 481, 481, 0.0, 0.0, [&](double x, double y) {
      const double along = x * std::cos(a) + y * std::sin(a);
      const double across = -x * std::sin(a) + y * std::cos(a);
      const double half = 22.0 + 6.0 * std::sin(along / 9.0);
      return std::abs(across) <= half
                 ? static_cast<float>(1.15 + 0.25 * std::sin(along / 4.0) * std::cos(across / 5.0))
                 : std::numeric_limits<float>::quiet_NaN();
    });
    auto mask = compose::featherMask(p.levels[0].grid, *p.levels[0].source, 20.0, true);
    out.push_back(
        compose::Dataset::dem(p, topo::Placement(topo::LocalTangentPlane(body, at(0.0, 10.0), 0.0)),
                              colour("strip", 0.0, compose::Role::Albedo, mask)));
  }
  {  // polar
    const auto ps = topo::PolarStereographic::withTrueScaleLatitude(
        body, topo::PolarStereographic::Pole::North, 90.0, 0.0);
    const topo::Placement pl(body, ps);
    const glm::dvec3 xy = pl.fromGeodetic(at(-45.0, 45.0));
    out.push_back(compose::Dataset::dem(planar(0.5, 161, 161, xy.x, xy.y,
                                               [](double x, double y) {
                                                 return static_cast<float>(0.45 +
                                                                           0.1 * std::sin(x / 3.0) +
                                                                           0.1 * std::cos(y / 5.0));
                                               }),
                                        pl, colour("polar", 20.0, compose::Role::Albedo)));
  }
  {  // equirect
    const topo::Equirectangular eq(body.equatorialRadius(), 0.0, 0.0);
    const topo::Placement pl(body, eq, topo::LatitudeType::Planetocentric);
    const glm::dvec3 xy = pl.fromGeodetic(at(45.0, 40.0));
    out.push_back(compose::Dataset::dem(
        planar(0.6, 121, 101, xy.x, xy.y,
               [](double x, double) { return static_cast<float>(0.9 + 0.3 * std::sin(x / 4.0)); }),
        pl, colour("equirect", 15.0, compose::Role::Albedo)));
  }
  out.push_back(compose::Dataset::dem(  // overlay
      planar(0.8, 61, 81, 0.0, 0.0,
             [](double x, double y) { return static_cast<float>(0.5 + 0.012 * x - 0.01 * y); }),
      topo::Placement(topo::LocalTangentPlane(body, at(-15.0, -20.0), -15.0)),
      colour("overlay", 8.0, compose::Role::Overlay)));
  return out;
}

double ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void accumulation(benchmark::State& state, std::size_t count) {
  const clod::Camera cam = camera();
  clod::ClipmapOptions options;
  const glm::dmat3 enu = mars().enuFrame(kLat0, kLon0);
  options.lightDirection = glm::vec3(glm::normalize(0.4 * enu[0] + 0.3 * enu[1] + 0.85 * enu[2]));
  clod::ClipmapTerrain terrain(terrainPyramid(), options);
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  const auto all = datasets();
  compose::Catalogue cat(mars());
  for (std::size_t i = 0; i < count; ++i) cat.add(all[i]);
  const auto snap = cat.snapshot();
  render::SurfaceAccumulator acc;
  const gl::RenderTarget target(cam.width, cam.height);
  auto bare = [&] {
    const auto t0 = std::chrono::steady_clock::now();
    target.clear({0.05F, 0.05F, 0.1F, 1.0F});
    (void)terrain.draw(cam);
    glFinish();
    return ms(t0);
  };
  std::size_t drawn = 0;
  auto composed = [&](double& accMs, double& normMs) {
    const double b = bare();
    auto t0 = std::chrono::steady_clock::now();
    drawn = acc.accumulate(target, cam, *snap).drawn;
    glFinish();
    accMs += ms(t0);
    t0 = std::chrono::steady_clock::now();
    acc.normalise(target);
    glFinish();
    normMs += ms(t0);
    return b;
  };
  double warmA = 0.0, warmN = 0.0;
  (void)bare();  // first frames: shader JIT, window uploads
  (void)composed(warmA, warmN);
  if (const char* png = std::getenv("ACCUMULATION_BENCH_PNG");
      png != nullptr && count == all.size())
    gl::writePng(png, target.readColor());
  double bareMs = 0.0, baseMs = 0.0, accMs = 0.0, normMs = 0.0;
  for (auto _ : state) {
    bareMs += bare();
    baseMs += composed(accMs, normMs);
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["datasets_drawn"] = static_cast<double>(drawn);
  state.counters["bare_ms"] = bareMs / n;
  state.counters["accumulate_ms"] = accMs / n;
  state.counters["normalise_ms"] = normMs / n;
  state.counters["ratio"] = (baseMs + accMs + normMs) / bareMs;
}

}  // namespace

int main(int argc, char** argv) {
  const gl::HeadlessContext context;  // one GL context for every case
  for (std::size_t n : {1U, 3U, 5U})
    benchmark::RegisterBenchmark(("accumulation/" + std::to_string(n)).c_str(),
                                 [n](benchmark::State& s) { accumulation(s, n); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()  // llvmpipe draws on its own threads: CPU time of this one undercounts
        ->MinWarmUpTime(0.0);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
