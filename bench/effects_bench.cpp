// The cost of the scene-declared effects (docs/overlays.md). Headless: Mesa llvmpipe through
// EGL surfaceless, 1280 × 720, a 2049² DEM of 1 m samples placed on Mars (so lat/lon lines
// apply), clipmap levels of 255².
//
//   effects/<name>   each iteration draws one frame of the bare pipeline (ClipmapOptions{}
//       as before effects existed) and one frame with only <name> declared, each timed on
//       its own (draw + glFinish), the bare one first in even iterations and second in odd
//       ones. Counters: bare_ms and effect_ms (medians over the iterations), ratio (the
//       median of the iterations' effect/bare ratios), ratio_q1 and ratio_q3 (their
//       quartiles). A pair of frames side by side shares the machine's drift, the order
//       alternates so that neither frame always follows the other (caches, the clock), and
//       the median ignores the frames another process preempted: a mean of sums let one such
//       frame move the noise floor (none) to 1.5 in a quick run.
//   <name> = none: a terrain built from a scene that declares no effect (Effects{}), which
//       is the noise floor (it builds the identical program, EffectsGLTest).
//
// Run: build/bench/effects_bench --pairs=40   (about a minute on a quiet machine)
//   --pairs=N fixes the number of frame pairs per case (Google Benchmark 1.7, Debian 12's,
//   has no iteration count on its command line: its --benchmark_min_time=40x is 1.8's).
//   Without it, --benchmark_min_time decides, and a slow frame can leave a single pair.
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/topo/Placement.hpp>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::clod;

double hills(double x, double y) {
  const double r = std::hypot(x, y);
  const double crater = r < 400.0 ? 30.0 - 120.0 * (1.0 - (r / 400.0) * (r / 400.0))
                                  : 30.0 * std::exp(-((r - 400.0) / 120.0) * ((r - 400.0) / 120.0));
  return crater + 25.0 * std::sin(x / 170.0) * std::cos(y / 230.0) +
         6.0 * std::sin((x + 2.0 * y) / 23.0) + 1.5 * std::cos((3.0 * x - y) / 7.0);
}

const topo::Placement& placement() {
  static const topo::Placement p(
      topo::LocalTangentPlane(topo::Body::marsSphere(), {-4.6, 137.4, -4400.0}, 0.0));
  return p;
}

topo::TopoGrid centred(std::size_t side, double spacing) {
  const double half = 0.5 * static_cast<double>(side - 1) * spacing;
  return {side, side, -half, half, spacing, spacing};
}

std::shared_ptr<const HeightPyramid> planePyramid(std::size_t side, double spacing,
                                                  double (*f)(double, double), bool placed) {
  const topo::TopoGrid grid = centred(side, spacing);
  auto samples = topo::InMemorySamples::fromFunction(side, side, [&](std::size_t r, std::size_t c) {
    const auto p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return static_cast<float>(f(p.x, p.y));
  });
  if (placed)
    return std::make_shared<const HeightPyramid>(
        HeightPyramid::fromSamples(grid, samples, placement()));
  return std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane));
}

const std::shared_ptr<const HeightPyramid>& terrainPyramid() {
  static const auto p = planePyramid(2049, 1.0, hills, true);
  return p;
}

DrapedTexture texture(std::size_t channels, std::size_t side, double spacing) {
  DrapedTexture t;
  static double (*const fs[3])(double, double) = {
      [](double x, double y) { return 0.5 + 0.3 * std::sin(x / 3.0) * std::cos(y / 5.0); },
      [](double x, double) { return 0.5 + 0.4 * std::sin(x / 40.0); },
      [](double, double y) { return 0.5 + 0.4 * std::cos(y / 60.0); }};
  for (std::size_t c = 0; c < channels; ++c)
    t.channels.push_back(planePyramid(side, spacing, fs[c], false));
  t.window = 512;
  t.opacity = 0.5F;
  return t;
}

Effects effects(const std::string& name) {
  Effects e;
  if (name == "albedo") e.albedo = texture(1, 4097, 0.5);
  if (name == "overlay") e.overlay = texture(3, 1025, 2.0);
  if (name == "noise") e.noise = StructuredNoise{0.1, 2.0, 4, 0.15F, std::nullopt};
  if (name == "heightColours") e.heightColours = HeightColours{-90.0F, 60.0F, true};
  if (name == "latLon") e.latLon = LatLonLines{};
  if (name == "tracks") {
    auto layer = std::make_shared<rover::TrackLayer>(0.02);
    for (int s = 0; s < 400; ++s) {  // 100 m of traverse through the view
      std::vector<rover::WheelImprint> wheels;
      for (double y : {-0.6, 0.6})
        for (double dx : {-0.5, 0.0, 0.5})
          wheels.push_back({{-50.0 + 0.25 * s + dx, 20.0 + y}, 0.3, 0.03});
      layer->step(wheels);
    }
    e.tracks = layer;
  }
  return e;
}

Camera camera() {
  const auto& pl = placement();
  Camera cam;
  cam.target = pl.toBodyFixed(0.0, 0.0, 0.0);
  cam.position = pl.toBodyFixed(-40.0, -90.0, 60.0);
  cam.up = glm::normalize(pl.toBodyFixed(0.0, 0.0, 1.0) - cam.target);
  cam.fovYDegrees = 50.0;
  cam.width = 1280;
  cam.height = 720;
  cam.near = 0.5;
  return cam;
}

/// The q-quantile of v (linear between order statistics); v is reordered.
double quantile(std::vector<double>& v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(at);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double frameMs(const ClipmapTerrain& terrain, const Camera& cam, const gl::RenderTarget& target) {
  const auto t0 = std::chrono::steady_clock::now();
  target.clear({0, 0, 0, 1});
  (void)terrain.draw(cam);
  glFinish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void effectFrame(benchmark::State& state, const std::string& name) {
  const auto& p = terrainPyramid();
  const Camera cam = camera();
  ClipmapTerrain bare(p, ClipmapOptions{});
  ClipmapOptions opt;
  opt.effects = effects(name);
  ClipmapTerrain withEffect(p, opt);
  bare.setFocus(cam.target);
  withEffect.setFocus(cam.target);
  const gl::RenderTarget target(cam.width, cam.height);
  (void)frameMs(bare, cam, target);  // first frames: shader JIT, uploads
  (void)frameMs(withEffect, cam, target);
  std::vector<double> bareMs, effectMs, ratios;
  bool bareFirst = true;
  for (auto _ : state) {
    double b = 0.0, e = 0.0;
    if (bareFirst) {
      b = frameMs(bare, cam, target);
      e = frameMs(withEffect, cam, target);
    } else {
      e = frameMs(withEffect, cam, target);
      b = frameMs(bare, cam, target);
    }
    bareFirst = !bareFirst;
    bareMs.push_back(b);
    effectMs.push_back(e);
    ratios.push_back(e / b);
  }
  state.counters["bare_ms"] = quantile(bareMs, 0.5);
  state.counters["effect_ms"] = quantile(effectMs, 0.5);
  state.counters["ratio"] = quantile(ratios, 0.5);
  state.counters["ratio_q1"] = quantile(ratios, 0.25);
  state.counters["ratio_q3"] = quantile(ratios, 0.75);
}

}  // namespace

/// Takes --pairs=N out of argv (Google Benchmark rejects flags it does not know): N > 0, or
/// 0 when absent. A bad value ends the program with a message naming the flag.
long takePairs(int& argc, char** argv) {
  long pairs = 0;
  int out = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--pairs=", 0) != 0) {
      argv[out++] = argv[i];
      continue;
    }
    char* end = nullptr;
    pairs = std::strtol(a.c_str() + 8, &end, 10);
    if (end == a.c_str() + 8 || *end != '\0' || pairs <= 0) {
      std::fprintf(stderr, "effects_bench: --pairs=%s: expected a whole number > 0\n",
                   a.c_str() + 8);
      std::exit(2);
    }
  }
  argc = out;
  return pairs;
}

int main(int argc, char** argv) {
  const long pairs = takePairs(argc, argv);
  const gl::HeadlessContext context;                             // one GL context for every case
  benchmark::AddCustomContext("gl_renderer", gl::glRenderer());  // for regolith report
  for (const char* name :
       {"none", "albedo", "tracks", "noise", "heightColours", "latLon", "overlay"}) {
    auto* b = benchmark::RegisterBenchmark(
                  (std::string("effects/") + name).c_str(),
                  [n = std::string(name)](benchmark::State& s) { effectFrame(s, n); })
                  ->Unit(benchmark::kMillisecond)
                  ->UseRealTime()  // llvmpipe draws on its own threads: CPU time undercounts
                  ->MinWarmUpTime(0.0);
    if (pairs > 0) b->Iterations(pairs);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
