// Clipmap rendering cost against accuracy, and against a brute-force full-resolution mesh
// (docs/clod.md). Headless: Mesa llvmpipe through EGL surfaceless, 1280 × 720.
//
//   clod/clipmap/dem:D/size:N   one frame of the clipmap (levels of N × N vertices, all
//       pyramid levels) over a D × D DEM of 1 m samples: draw + glFinish. Counters:
//       vertices per frame, and the screen-space error against the full-resolution mesh:
//       the height difference of the two surface points seen through each pixel,
//       projected at their distance (f · Δh / d, pixels): p99 and max over the frame
//   clod/mesh/dem:D/level:L   the brute-force mesh of pyramid level L (L = 0: every
//       sample) of the same DEM, with the same error counters (level 0: 0 by definition)
//   clod/pan/dem:D/size:N   60 frames of a fast pan (the focus leaps 40 m per frame)
//       with background loading: mean and worst frame time (update without waiting +
//       draw + glFinish), and how many frames drew from a coarser level while loading
//
// Run: build/bench/clod_bench   (about 4 minutes: the 8192² mesh takes half a minute a
// frame).
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/MeshRenderer.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::clod;

double hills(double x, double y) {
  const double r = std::hypot(x, y);
  const double crater = r < 400.0 ? 30.0 - 120.0 * (1.0 - (r / 400.0) * (r / 400.0))
                                  : 30.0 * std::exp(-((r - 400.0) / 120.0) * ((r - 400.0) / 120.0));
  return -1400.0 + crater + 25.0 * std::sin(x / 170.0) * std::cos(y / 230.0) +
         6.0 * std::sin((x + 2.0 * y) / 23.0) + 1.5 * std::cos((3.0 * x - y) / 7.0);
}

std::shared_ptr<const HeightPyramid> dem(std::size_t side) {
  static std::map<std::size_t, std::shared_ptr<const HeightPyramid>> cache;
  auto& p = cache[side];
  if (!p) {
    const double half = 0.5 * static_cast<double>(side - 1);
    const topo::TopoGrid grid(side, side, -half, half, 1.0, 1.0);
    auto samples =
        topo::InMemorySamples::fromFunction(side, side, [&](std::size_t r, std::size_t c) {
          return static_cast<float>(
              hills(static_cast<double>(c) - half, half - static_cast<double>(r)));
        });
    p = std::make_shared<const HeightPyramid>(
        HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane));
  }
  return p;
}

Camera camera(const glm::dvec3& target) {
  Camera cam;
  cam.target = target;
  cam.position = target + glm::dvec3(-500.0, -900.0, 450.0);
  cam.fovYDegrees = 50.0;
  cam.width = 1280;
  cam.height = 720;
  cam.near = 1.0;
  return cam;
}

const glm::dvec3 kTarget{0.0, 0.0, -1400.0};

gl::DepthImage referenceDepth(std::size_t side) {
  static std::map<std::size_t, gl::DepthImage> cache;
  auto it = cache.find(side);
  if (it != cache.end()) return it->second;
  const auto p = dem(side);
  const Camera cam = camera(kTarget);
  MeshRenderer mesh(p->level(0).grid, *p->level(0).source);
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0, 0, 0, 1});
  mesh.draw(cam);
  return cache[side] = target.readDepth();
}

/// Screen-space error in pixels: distance between the surface points seen through each
/// pixel in `a` and in the reference, times focal length over distance. Pixels that one of
/// the two leaves empty, or at depth discontinuities of the reference, are skipped.
void errorCounters(benchmark::State& state, const gl::DepthImage& a, const gl::DepthImage& ref) {
  const Camera cam = camera(kTarget);
  std::vector<double> e;
  for (int y = 1; y + 1 < ref.height; ++y)
    for (int x = 1; x + 1 < ref.width; ++x) {
      const float r = ref.at(x, y), c = a.at(x, y);
      if (r <= 0.0F || c <= 0.0F) continue;
      if (!ref.smoothAt(x, y, cam.near, 0.02)) continue;
      const double dr = cam.viewDistance(r);
      // The two points lie on one ray: their height difference is the geometric error.
      const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
      const double along = glm::dot(d, cam.forward());
      const double metres = std::abs(cam.viewDistance(c) - dr) / along * std::abs(d.z);
      e.push_back(metres * cam.focalPixels() / dr);
    }
  std::sort(e.begin(), e.end());
  state.counters["err_px_p99"] = e.empty() ? 0.0 : e[e.size() * 99 / 100];
  state.counters["err_px_max"] = e.empty() ? 0.0 : e.back();
}

void clipmapFrame(benchmark::State& state) {
  const auto side = static_cast<std::size_t>(state.range(0));
  ClipmapOptions opt;
  opt.size = static_cast<int>(state.range(1));
  const auto p = dem(side);
  ClipmapTerrain terrain(p, opt);
  terrain.setFocus(kTarget);
  const Camera cam = camera(kTarget);
  gl::RenderTarget target(cam.width, cam.height);
  ClipmapFrame frame;
  for (auto _ : state) {
    target.clear({0, 0, 0, 1});
    frame = terrain.draw(cam);
    glFinish();
  }
  state.counters["vertices"] = static_cast<double>(frame.vertices);
  state.counters["levels"] = static_cast<double>(frame.levelsDrawn);
  errorCounters(state, target.readDepth(), referenceDepth(side));
}

void meshFrame(benchmark::State& state) {
  const auto side = static_cast<std::size_t>(state.range(0));
  const auto level = static_cast<std::size_t>(state.range(1));
  const auto p = dem(side);
  MeshRenderer mesh(p->level(level).grid, *p->level(level).source);
  const Camera cam = camera(kTarget);
  gl::RenderTarget target(cam.width, cam.height);
  std::size_t vertices = 0;
  for (auto _ : state) {
    target.clear({0, 0, 0, 1});
    vertices = mesh.draw(cam);
    glFinish();
  }
  state.counters["vertices"] = static_cast<double>(vertices);
  errorCounters(state, target.readDepth(), referenceDepth(side));
}

void panFrames(benchmark::State& state) {
  const auto side = static_cast<std::size_t>(state.range(0));
  ClipmapOptions opt;
  opt.size = static_cast<int>(state.range(1));
  const auto p = dem(side);
  gl::RenderTarget target(1280, 720);
  double mean = 0.0, worst = 0.0, coarser = 0.0;
  for (auto _ : state) {
    ClipmapTerrain terrain(p, opt);
    terrain.setFocus(kTarget);
    std::vector<double> ms;
    for (int f = 0; f < 60; ++f) {
      const glm::dvec3 focus = kTarget + glm::dvec3(40.0 * f, 15.0 * f, 0.0);
      const Camera cam = camera(focus);
      const auto t0 = std::chrono::steady_clock::now();
      terrain.requestFocus(focus);
      terrain.update(false);
      target.clear({0, 0, 0, 1});
      const ClipmapFrame frame = terrain.draw(cam);
      glFinish();
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (frame.firstLevel > 0) coarser += 1.0;
    }
    terrain.finishLoading();
    double sum = 0.0;
    for (double m : ms) sum += m;
    mean = sum / static_cast<double>(ms.size());
    worst = *std::max_element(ms.begin(), ms.end());
  }
  state.counters["frame_ms_mean"] = mean;
  state.counters["frame_ms_max"] = worst;
  state.counters["frames_coarser"] = coarser / static_cast<double>(state.iterations());
}

BENCHMARK(clipmapFrame)
    ->Name("clod/clipmap")
    ->ArgNames({"dem", "size"})
    ->Args({2048, 63})
    ->Args({2048, 127})
    ->Args({2048, 255})
    ->Args({8192, 63})
    ->Args({8192, 127})
    ->Args({8192, 255})
    ->Args({8192, 511})
    ->Unit(benchmark::kMillisecond)
    ->MinWarmUpTime(0.0);
BENCHMARK(meshFrame)
    ->Name("clod/mesh")
    ->ArgNames({"dem", "level"})
    ->Args({2048, 0})
    ->Args({8192, 0})
    ->Args({8192, 1})
    ->Args({8192, 2})
    ->Args({8192, 3})
    ->Unit(benchmark::kMillisecond)
    ->MinWarmUpTime(0.0);
BENCHMARK(panFrames)
    ->Name("clod/pan")
    ->ArgNames({"dem", "size"})
    ->Args({8192, 255})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  const gl::HeadlessContext context;                             // one GL context for every case
  benchmark::AddCustomContext("gl_renderer", gl::glRenderer());  // for regolith report
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
