// The far field's costs and accuracy (docs/far-field.md), headless on Mesa llvmpipe through
// EGL surfaceless, on a generated Mars (the IAU ellipsoid with relief at several scales, to
// ±8 km) composed into height layers:
//
//   pgm/<view>/grid:<G>/screen:<S>   one PGM frame (draw + glFinish) with a G × G grid on an
//       S × S screen: the paper's Figure 8 on this machine, for its three views:
//         global     the whole planet from 3 R (layers 4096 wide)
//         low        400 km up, looking at the horizon, low-resolution layers (1024 wide)
//         victoria   2 km above Victoria crater (2.05° S, 5.5° W), at the horizon (4096)
//       Counters: error_px_median and error_px_p99, the screen-space error of the drawn
//       surface against the layers' exact surface in double (the height error of each
//       pixel's point, over its distance, times the focal length), measured once per case.
//   cull/<view>/on|off   the same frame (grid 256, screen 1024) with and without culling the
//       mesh's folded, clockwise triangles (PgmOptions::cullFolds), side by side.
//   thin/<view>/grid:256/screen:<S>/cell:<C>   the same frame with PgmOptions::minCellPixels
//       = C (0: the full grid): the grid is halved while its cells span fewer than C pixels.
//       Counters: grid_drawn (the side of the grid drawn), cell_px (the full grid's largest
//       cell on the screen).
//   compare/<view>/pgm/grid:<G>, compare/<view>/clipmap/size:<N>   PGM (layers 4096 wide,
//       the even-error spread of its rays on; pgm-paper: off, the paper's even grid)
//       against the clipmap-only planet (a global 4096 × 2048 pyramid of the same relief,
//       every level, focused below the eye) for the same view on a 1024² screen. Counters:
//       the screen-space error against the relief function itself, in double, on every
//       other pixel (error_px_median, _p99, _max: the height error of the pixel's point over
//       its distance, times the focal length) and holes_fraction (pixels whose ray meets the
//       lowest sphere left empty). PNGs into $REGOLITH_BENCH_PNG_DIR if set.
//   reduction/tree|columns/screen:<S>   the minimum-radius reduction alone on an S × S
//       buffer: the first shader (a 16 × 16 tree of 8 barriers) against PgmRenderer's (one
//       barrier per 64 × 64 tile), side by side; each checks its minimum.
//   readback/<mode>   the primary sphere's minimum-radius reduction: none (Fixed), read at
//       once (Stall), or a frame later through a fence (Lagged); global view, grid 512,
//       screen 1024.
//   sampling/<view>   the per-frame CPU set-up of §4–§5 (reference spheres and sampling
//       camera), timed; counters (no GPU): of the sampling camera's grid rays, the fraction in
//       the behind-the-horizon band (ω > b, what the occluded-area sampling costs) and the
//       fraction whose surface point lands outside the view (not pertinent); of a plain grid
//       over the view frustum, the fraction of rays that miss the body (wasted) and of the
//       sampling camera's, the same. These are the paper's even grid; spread_*: the first two
//       for the grid with the even-error spread of its rays; spread_us: the spread's table
//       for the view's spheres (computed when they change), in microseconds.
//
// Run: build/bench/farfield_bench --benchmark_min_time=5x
#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmMath.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include "PgmShaders.hpp"

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace regolith;

constexpr double kDeg = std::numbers::pi / 180.0;

const topo::Body& mars() {
  static const topo::Body body = topo::Body::marsEllipsoid();
  return body;
}

/// Relief at several scales: continents, ridges and a few craters (metres).
double relief(double lat, double lon, double) {
  const double la = lat * kDeg, lo = lon * kDeg;
  double h = 3000.0 * std::sin(2.0 * la + 0.5) * std::cos(3.0 * lo) +
             1500.0 * std::sin(9.0 * lo + 1.0) * std::cos(7.0 * la) +
             400.0 * std::sin(41.0 * la) * std::sin(37.0 * lo + 0.2);
  const double craters[][4] = {{-2.05, -5.5, 6000.0, 3000.0},  // lat, lon, depth, radius km
                               {20.0, 100.0, 5000.0, 150.0},
                               {-45.0, -160.0, 4000.0, 300.0},
                               {75.0, 30.0, 3000.0, 200.0}};
  for (const auto& c : craters) {
    const double cl = c[0] * kDeg, cn = c[1] * kDeg;
    const double cosd =
        std::sin(la) * std::sin(cl) + std::cos(la) * std::cos(cl) * std::cos(lo - cn);
    const double km = std::acos(std::clamp(cosd, -1.0, 1.0)) * 3396.19;
    const double q = km / c[3];
    h += -c[2] * std::exp(-q * q * 2.0) + 0.3 * c[2] * std::exp(-(q - 1.0) * (q - 1.0) * 20.0);
  }
  return h;
}

const farfield::HeightLayers& layers(int width) {
  static std::map<int, std::unique_ptr<farfield::HeightLayers>> cache;
  auto& slot = cache[width];
  if (!slot) {
    farfield::LayerOptions o;
    o.equirectWidth = width;
    o.capSize = width / 4;
    slot =
        std::make_unique<farfield::HeightLayers>(farfield::HeightLayers::build(mars(), relief, o));
  }
  return *slot;
}

struct View {
  const char* name = "";
  int layerWidth = 0;
  clod::Camera camera;
};

View view(const std::string& name, int screen) {
  clod::Camera cam;
  cam.width = cam.height = screen;
  cam.fovYDegrees = 45.0;
  cam.near = 1.0;
  cam.up = {0.0, 0.0, 1.0};
  if (name == "global") {
    cam.position = glm::dvec3(3.0 * mars().equatorialRadius(), 0.0, 0.0);
    cam.target = glm::dvec3(0.0);
    return {"global", 4096, cam};
  }
  const bool low = name == "low";
  const double lat = low ? 10.0 : -2.05, lon = low ? 60.0 : -5.5;
  const double alt = low ? 400e3 : 2000.0 + relief(lat, lon, 0.0);
  cam.position = mars().toBodyFixed({lat, lon, alt});
  const glm::dmat3 enu = mars().enuFrame(lat, lon);
  cam.target = cam.position + enu[1] - (low ? 0.35 : 0.05) * enu[2];
  cam.up = enu[2];
  return {low ? "low" : "victoria", low ? 1024 : 4096, cam};
}

/// Screen-space error of the drawn surface against the layers' surface, per drawn pixel.
std::vector<double> screenErrors(const clod::Camera& cam, const gl::DepthImage& depth,
                                 const farfield::HeightLayers& l) {
  std::vector<double> out;
  for (int y = 0; y < cam.height; y += 2) {
    for (int x = 0; x < cam.width; x += 2) {
      const float z = depth.at(x, y);
      if (!(z > 0.0F)) continue;
      const glm::dvec3 r = cam.ray(x + 0.5, y + 0.5);
      const double t = cam.viewDistance(z) / glm::dot(r, cam.forward());
      const topo::Geodetic g = mars().toGeodetic(cam.position + t * r);
      out.push_back(std::abs(g.height - l.heightAt(g.latDeg, g.lonDeg)) / t * cam.focalPixels());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

double quantile(const std::vector<double>& v, double q) {
  return v.empty() ? 0.0 : v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

void pgmFrame(benchmark::State& state, const std::string& name, int grid, int screen,
              bool cullFolds = true, double minCellPixels = 0.0) {
  const View v = view(name, screen);
  const farfield::HeightLayers& l = layers(v.layerWidth);
  farfield::PgmOptions o;
  o.gridWidth = o.gridHeight = grid;
  o.timePasses = true;
  o.cullFolds = cullFolds;
  o.minCellPixels = minCellPixels;
  farfield::PgmRenderer pgm(l, o);
  gl::RenderTarget target(screen, screen);
  const glm::dvec3 sun = glm::normalize(glm::dvec3(1.0, 0.5, 0.6));
  for (int i = 0; i < 3; ++i) {  // settle the primary sphere
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    pgm.draw(target, v.camera, sun);
  }
  glFinish();
  const std::vector<double> err = screenErrors(v.camera, target.readDepth(), l);
  // The mesh's triangles as the rasteriser sees them (the grid read back and projected in
  // double): how many face the eye with a vertex on the screen, and their summed screen
  // area against the pixels drawn (overdraw, before the depth test).
  {
    const std::vector<glm::vec4> pos = pgm.readGridPositions();
    const glm::dmat4 vp = v.camera.viewProjection();
    std::vector<glm::dvec3> win(pos.size());
    for (std::size_t i = 0; i < pos.size(); ++i) {
      const glm::dvec4 c = vp * glm::dvec4(glm::dvec3(pos[i]), 1.0);
      win[i] = c.w > 0.0 ? glm::dvec3((c.x / c.w * 0.5 + 0.5) * screen,
                                      (c.y / c.w * 0.5 + 0.5) * screen, 1.0)
                         : glm::dvec3(0.0);
    }
    double front = 0.0, area = 0.0;
    const auto tri = [&](std::size_t i0, std::size_t i1, std::size_t i2) {
      const glm::dvec3 &a = win[i0], &b = win[i1], &c = win[i2];
      if (a.z == 0.0 || b.z == 0.0 || c.z == 0.0) return;
      const auto on = [&](const glm::dvec3& p) {
        return p.x >= 0 && p.y >= 0 && p.x <= screen && p.y <= screen;
      };
      if (!on(a) && !on(b) && !on(c)) return;
      const double s2 = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
      if (s2 <= 0.0) return;  // clockwise or degenerate: culled
      front += 1.0;
      area += 0.5 * s2;
    };
    const auto gw = static_cast<std::size_t>(grid);
    for (std::size_t j = 0; j + 1 < gw; ++j) {
      for (std::size_t i = 0; i + 1 < gw; ++i) {
        const std::size_t p00 = j * gw + i, p10 = p00 + 1, p01 = p00 + gw, p11 = p01 + 1;
        tri(p00, p10, p01);  // the strip's winding: (j+1,i), (j,i), (j+1,i+1), ...
        tri(p10, p11, p01);
      }
    }
    const gl::DepthImage depth = target.readDepth();
    double drawn = 0.0;
    for (int y = 0; y < screen; ++y) {
      for (int x = 0; x < screen; ++x) drawn += depth.at(x, y) > 0.0F ? 1.0 : 0.0;
    }
    state.counters["front_triangles_on_screen"] = front;
    state.counters["front_area_per_drawn_pixel"] = drawn > 0.0 ? area / drawn : 0.0;
    state.counters["drawn_pixels"] = drawn;
  }
  double gridMs = 0.0, meshMs = 0.0, reduceMs = 0.0;
  for (auto _ : state) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    const farfield::PgmFrame f = pgm.draw(target, v.camera, sun);
    glFinish();
    state.counters["grid_drawn"] = f.gridWidth;
    state.counters["cell_px"] = f.cellPixels;
    gridMs += f.gridMs;
    meshMs += f.meshMs;
    reduceMs += f.reduceMs;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["grid_ms"] = gridMs / n;
  state.counters["mesh_ms"] = meshMs / n;
  state.counters["reduce_ms"] = reduceMs / n;
  state.counters["error_px_median"] = quantile(err, 0.5);
  state.counters["error_px_p99"] = quantile(err, 0.99);
  state.counters["grid_points"] = static_cast<double>(grid) * grid;
}

void readback(benchmark::State& state, farfield::PrimaryReadback mode) {
  const View v = view("global", 1024);
  farfield::PgmOptions o;
  o.gridWidth = o.gridHeight = 512;
  o.minCellPixels = 0.0;
  o.readback = mode;
  farfield::PgmRenderer pgm(layers(v.layerWidth), o);
  gl::RenderTarget target(1024, 1024);
  for (int i = 0; i < 3; ++i) pgm.draw(target, v.camera, {1.0, 0.0, 0.0});  // JIT, first frames
  glFinish();
  for (auto _ : state) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    pgm.draw(target, v.camera, {1.0, 0.0, 0.0});
    glFinish();
  }
}

void sampling(benchmark::State& state, const std::string& name) {
  const View v = view(name, 512);
  const farfield::HeightLayers& l = layers(v.layerWidth);
  const double minR = mars().polarRadius() + l.minHeight();
  const double maxR = mars().equatorialRadius() + l.maxHeight();
  const clod::Camera& cam = v.camera;
  const double d = glm::length(cam.position);
  const glm::dvec3 nadir = -cam.position / d;
  const glm::dmat3 rot = cam.rotation();
  const glm::dvec3 right(rot[0][0], rot[1][0], rot[2][0]), up(rot[0][1], rot[1][1], rot[2][1]);
  const farfield::Frustum frustum =
      farfield::viewFrustum(cam.forward(), right, up, cam.fovYDegrees * kDeg, 1.0);
  farfield::ReferenceSpheres s;
  farfield::SamplingCamera sc;
  for (auto _ : state) {
    s = farfield::referenceSpheres(d, minR, maxR, 0.9);
    sc = farfield::samplingCamera(frustum, nadir, s.tauTop);
    benchmark::DoNotOptimize(sc);
  }
  // The even-error spread's table for these spheres: what a frame pays when they change.
  {
    const auto t0 = std::chrono::steady_clock::now();
    constexpr int kSpreads = 200;
    for (int i = 0; i < kSpreads; ++i) {
      benchmark::DoNotOptimize(farfield::evenErrorSpread(s, 256));
    }
    state.counters["spread_us"] =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
        kSpreads;
  }
  // Counters on a 128² grid of each kind: the paper's even grid, and the same spread.
  const farfield::RaySpread spread = farfield::evenErrorSpread(s, 256);
  const int n = 128;
  int behind = 0, offScreen = 0, plainMiss = 0, samplingMiss = 0;
  int spreadBehind = 0, spreadOffScreen = 0;
  // Whether grid ray r's surface point (on the primary sphere at its blended γ) is off the
  // screen, and whether r is in the behind-the-horizon band.
  const auto offTheScreen = [&](const glm::dvec3& r, int& inBand) {
    const double omega = std::acos(std::clamp(glm::dot(r, nadir), -1.0, 1.0));
    inBand += omega > s.begin ? 1 : 0;
    const double gamma = farfield::blendedNormalAngle(s, omega);
    glm::dvec3 k = r - glm::dot(r, nadir) * nadir;
    k = glm::length(k) > 1e-12 ? glm::normalize(k) : glm::dvec3(0.0);
    const glm::dvec3 p = cam.position + farfield::eyeSpacePoint(gamma, d, s.primary, nadir, k);
    const glm::dvec3 q = cam.project(p);
    return (q.z <= 0.0 || q.x < 0 || q.y < 0 || q.x > cam.width || q.y > cam.height) ? 1 : 0;
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double u = i / (n - 1.0), w = j / (n - 1.0);
      const glm::dvec3 r = sc.ray(u, w);
      const double omega = std::acos(std::clamp(glm::dot(r, nadir), -1.0, 1.0));
      samplingMiss += omega > s.tauTop ? 1 : 0;
      offScreen += offTheScreen(r, behind);
      spreadOffScreen += offTheScreen(spread.ray(r, nadir), spreadBehind);
      // A plain grid over the view frustum.
      const glm::dvec3 pr = cam.ray(u * cam.width, w * cam.height);
      const double om = std::acos(std::clamp(glm::dot(pr, nadir), -1.0, 1.0));
      plainMiss += om > s.tauTop ? 1 : 0;
    }
  }
  const double total = static_cast<double>(n) * n;
  state.counters["behind_horizon_fraction"] = behind / total;
  state.counters["sampling_offscreen_fraction"] = offScreen / total;
  state.counters["sampling_miss_fraction"] = samplingMiss / total;
  state.counters["plain_grid_miss_fraction"] = plainMiss / total;
  state.counters["spread_behind_horizon_fraction"] = spreadBehind / total;
  state.counters["spread_offscreen_fraction"] = spreadOffScreen / total;
}

// ---- PGM against the clipmap-only planet at equal screen-space error ----------------------

/// The clipmap-only planet: a global latitude/longitude pyramid of the same relief, at the
/// resolution of the PGM layers (4096 × 2048, 5.2 km on Mars), every level.
std::shared_ptr<const clod::HeightPyramid> planetPyramid() {
  static const std::shared_ptr<const clod::HeightPyramid> p = [] {
    constexpr std::size_t cols = 4096, rows = 2048;
    const double step = 360.0 / cols;
    const topo::TopoGrid grid(rows, cols, -180.0 + 0.5 * step, 90.0 - 0.5 * step, step, step);
    auto samples =
        topo::InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
          const glm::dvec2 xy = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
          return static_cast<float>(relief(xy.y, xy.x, 0.0));
        });
    return std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
        grid, samples, clod::SurfaceKind::Planet, mars(), topo::LatitudeType::Planetodetic));
  }();
  return p;
}

/// What a drawn frame shows against the true surface: the relief function itself, evaluated
/// in double (not either renderer's data), on every other pixel.
struct TruthError {
  std::vector<double> px;  ///< screen-space error of each drawn pixel on the body, sorted
  int holes = 0;           ///< pixels whose ray meets the body's lowest sphere, left empty
  int body = 0;            ///< pixels whose ray meets the body's lowest sphere
};

TruthError truthError(const clod::Camera& cam, const gl::DepthImage& depth) {
  TruthError e;
  const double minR = mars().polarRadius() - 8000.0;  // below the relief's lowest point
  for (int y = 0; y < cam.height; y += 2) {
    for (int x = 0; x < cam.width; x += 2) {
      const glm::dvec3 r = cam.ray(x + 0.5, y + 0.5);
      const double bq = glm::dot(cam.position, r);
      const double cq = glm::dot(cam.position, cam.position) - minR * minR;
      const bool meets = bq < 0.0 && bq * bq - cq > 0.0;
      e.body += meets ? 1 : 0;
      const float z = depth.at(x, y);
      if (!(z > 0.0F)) {
        e.holes += meets ? 1 : 0;
        continue;
      }
      const double t = cam.viewDistance(z) / glm::dot(r, cam.forward());
      const topo::Geodetic g = mars().toGeodetic(cam.position + t * r);
      e.px.push_back(std::abs(g.height - relief(g.latDeg, g.lonDeg, 0.0)) / t * cam.focalPixels());
    }
  }
  std::sort(e.px.begin(), e.px.end());
  return e;
}

void savePngIfAsked(const std::string& name, const gl::RenderTarget& target) {
  const char* dir = std::getenv("REGOLITH_BENCH_PNG_DIR");
  if (dir != nullptr && *dir != '\0')
    gl::writePng(std::string(dir) + "/" + name + ".png", target.readColor());
}

void setCompareCounters(benchmark::State& state, const TruthError& e) {
  state.counters["error_px_median"] = quantile(e.px, 0.5);
  state.counters["error_px_p99"] = quantile(e.px, 0.99);
  state.counters["error_px_max"] = e.px.empty() ? 0.0 : e.px.back();
  state.counters["holes_fraction"] = e.body > 0 ? static_cast<double>(e.holes) / e.body : 0.0;
}

/// One PGM frame (FarField's way: grid, mesh, Lagged reduction) against the truth.
void comparePgm(benchmark::State& state, const std::string& name, int grid, int screen,
                bool evenError) {
  View v = view(name, screen);
  farfield::PgmOptions o;
  o.gridWidth = o.gridHeight = grid;
  o.evenError = evenError;
  o.minCellPixels = 0.0;  // the grid as given
  farfield::PgmRenderer pgm(layers(4096), o);
  gl::RenderTarget target(screen, screen);
  const glm::dvec3 sun = glm::normalize(glm::dvec3(1.0, 0.5, 0.6));
  for (int i = 0; i < 3; ++i) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    pgm.draw(target, v.camera, sun);
  }
  glFinish();
  setCompareCounters(state, truthError(v.camera, target.readDepth()));
  savePngIfAsked("compare_" + name + (evenError ? "_pgm_" : "_pgm-paper_") + std::to_string(grid),
                 target);
  for (auto _ : state) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    pgm.draw(target, v.camera, sun);
    glFinish();
  }
  state.counters["grid_points"] = static_cast<double>(grid) * grid;
}

/// One frame of the clipmap-only planet (every level of the global pyramid, focused below
/// the eye) against the truth.
void compareClipmap(benchmark::State& state, const std::string& name, int size, int screen) {
  View v = view(name, screen);
  clod::ClipmapOptions co;
  co.size = size;
  co.lightDirection = glm::vec3(glm::normalize(glm::dvec3(1.0, 0.5, 0.6)));
  clod::ClipmapTerrain clipmap(planetPyramid(), co);
  const topo::Geodetic below = mars().toGeodetic(v.camera.position);
  clipmap.setFocus(mars().toBodyFixed({below.latDeg, below.lonDeg, 0.0}));
  clipmap.finishLoading();
  gl::RenderTarget target(screen, screen);
  clod::ClipmapFrame f;
  for (int i = 0; i < 3; ++i) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    f = clipmap.draw(v.camera);
  }
  glFinish();
  setCompareCounters(state, truthError(v.camera, target.readDepth()));
  savePngIfAsked("compare_" + name + "_clipmap_" + std::to_string(size), target);
  for (auto _ : state) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    clipmap.draw(v.camera);
    glFinish();
  }
  state.counters["levels_drawn"] = static_cast<double>(f.levelsDrawn);
  state.counters["vertices"] = static_cast<double>(f.vertices);
}

// ---- The radius reduction alone: the first shader (a tree of barriers) against the one in
// PgmRenderer (one barrier per 64 × 64 tile), on the same 1024² R32F buffer ----------------

// The first version, as it was in farfield/src/PgmShaders.hpp (the "before").
constexpr const char* kReduceTree = R"(#version 450 core
layout(local_size_x = 16, local_size_y = 16) in;
layout(binding = 0, r32f) uniform readonly image2D uRadius;
layout(std430, binding = 1) buffer Result { uint minBits; };
shared float tile[256];
uint orderedBits(float f) {
  uint u = floatBitsToUint(f);
  return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
void main() {
  ivec2 size = imageSize(uRadius);
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  float v = 3.0e38;
  if (p.x < size.x && p.y < size.y) v = imageLoad(uRadius, p).r;
  uint i = gl_LocalInvocationIndex;
  tile[i] = v;
  barrier();
  for (uint stride = 128u; stride > 0u; stride >>= 1u) {
    if (i < stride) tile[i] = min(tile[i], tile[i + stride]);
    barrier();
  }
  if (i == 0u) atomicMin(minBits, orderedBits(tile[0]));
}
)";

void reduction(benchmark::State& state, bool tree, int screen) {
  const gl::Program program =
      gl::Program::compute(tree ? "reduce (tree)" : "reduce (columns)",
                           tree ? kReduceTree : farfield::shaders::kReduceCompute);
  gl::Texture radius;
  glTextureStorage2D(radius.id(), 1, GL_R32F, screen, screen);
  glTextureParameteri(radius.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(radius.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  std::vector<float> values(static_cast<std::size_t>(screen) * static_cast<std::size_t>(screen));
  std::uint32_t seed = 12345U;
  float expected = 3.0e38F;
  for (float& v : values) {
    seed = seed * 1664525U + 1013904223U;
    v = static_cast<float>(seed >> 8) * 1.0e-3F - 5000.0F;
    expected = std::min(expected, v);
  }
  glTextureSubImage2D(radius.id(), 0, 0, 0, screen, screen, GL_RED, GL_FLOAT, values.data());
  gl::Buffer result;
  const std::uint32_t init = 0xFFFFFFFFU;
  glNamedBufferStorage(result.id(), sizeof init, &init, GL_DYNAMIC_STORAGE_BIT);
  const auto run = [&] {
    glNamedBufferSubData(result.id(), 0, sizeof init, &init);
    if (tree) {
      glBindImageTexture(0, radius.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
    } else {
      glBindTextureUnit(3, radius.id());
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, result.id());
    program.use();
    const int tile = tree ? 16 : 64;
    glDispatchCompute(static_cast<GLuint>((screen + tile - 1) / tile),
                      static_cast<GLuint>((screen + tile - 1) / tile), 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::uint32_t bits = 0;
    glGetNamedBufferSubData(result.id(), 0, sizeof bits, &bits);  // waits for the dispatch
    return bits;
  };
  const std::uint32_t bits = run();
  const std::uint32_t raw = (bits & 0x80000000U) != 0U ? (bits & 0x7FFFFFFFU) : ~bits;
  float got = 0.0F;
  std::memcpy(&got, &raw, sizeof got);
  if (got != expected) state.SkipWithError("the reduction's minimum is wrong");
  for (auto _ : state) benchmark::DoNotOptimize(run());
  state.counters["pixels"] = static_cast<double>(values.size());
}

}  // namespace

int main(int argc, char** argv) {
  const gl::HeadlessContext context;
  benchmark::AddCustomContext("gl_renderer", gl::glRenderer());  // for regolith report
  for (const char* name : {"global", "low", "victoria"}) {
    for (const int grid : {256, 512, 1024, 2048}) {
      for (const int screen : {256, 512, 1024}) {
        const std::string label = std::string("pgm/") + name + "/grid:" + std::to_string(grid) +
                                  "/screen:" + std::to_string(screen);
        benchmark::RegisterBenchmark(label.c_str(),
                                     [=](benchmark::State& s) { pgmFrame(s, name, grid, screen); })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinWarmUpTime(0.0);
      }
    }
  }
  for (const char* name : {"global", "low", "victoria"}) {
    for (const bool cull : {false, true}) {
      const std::string label =
          std::string("cull/") + name + (cull ? "/on" : "/off") + "/grid:256/screen:1024";
      benchmark::RegisterBenchmark(label.c_str(),
                                   [=](benchmark::State& s) { pgmFrame(s, name, 256, 1024, cull); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinWarmUpTime(0.0);
    }
  }
  for (const char* name : {"global", "low"}) {
    for (const int screen : {256, 512, 1024}) {
      for (const double cell : {0.0, 1.0, 2.0, 4.0}) {
        const std::string label = std::string("thin/") + name +
                                  "/grid:256/screen:" + std::to_string(screen) +
                                  "/cell:" + std::to_string(static_cast<int>(cell));
        benchmark::RegisterBenchmark(
            label.c_str(), [=](benchmark::State& s) { pgmFrame(s, name, 256, screen, true, cell); })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinWarmUpTime(0.0);
      }
    }
  }
  // The scene's grid (512², scene/SceneParts.cpp) on a viewer-sized screen, whole planet.
  for (const double cell : {0.0, 1.0, 2.0}) {
    const std::string label =
        "thin/global/grid:512/screen:720/cell:" + std::to_string(static_cast<int>(cell));
    benchmark::RegisterBenchmark(
        label.c_str(), [=](benchmark::State& s) { pgmFrame(s, "global", 512, 720, true, cell); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MinWarmUpTime(0.0);
  }
  for (const auto& [label, mode] :
       {std::pair{"readback/fixed", farfield::PrimaryReadback::Fixed},
        std::pair{"readback/stall", farfield::PrimaryReadback::Stall},
        std::pair{"readback/lagged", farfield::PrimaryReadback::Lagged}}) {
    const farfield::PrimaryReadback m = mode;  // a structured binding cannot be captured
    benchmark::RegisterBenchmark(label, [m](benchmark::State& s) { readback(s, m); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  for (const char* name : {"global", "low", "victoria"}) {
    benchmark::RegisterBenchmark((std::string("sampling/") + name).c_str(),
                                 [name](benchmark::State& s) { sampling(s, name); })
        ->Unit(benchmark::kMicrosecond);
  }
  for (const char* name : {"global", "low"}) {
    for (const bool evenError : {true, false}) {
      for (const int grid : {40, 64, 96, 128, 256, 512}) {
        const std::string label = std::string("compare/") + name +
                                  (evenError ? "/pgm/grid:" : "/pgm-paper/grid:") +
                                  std::to_string(grid) + "/screen:1024";
        benchmark::RegisterBenchmark(
            label.c_str(), [=](benchmark::State& s) { comparePgm(s, name, grid, 1024, evenError); })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinWarmUpTime(0.0);
      }
    }
    for (const int size : {63, 127, 255}) {
      const std::string label =
          std::string("compare/") + name + "/clipmap/size:" + std::to_string(size) + "/screen:1024";
      benchmark::RegisterBenchmark(
          label.c_str(), [=](benchmark::State& s) { compareClipmap(s, name, size, 1024); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinWarmUpTime(0.0);
    }
  }
  for (const int screen : {256, 1024}) {
    for (const bool tree : {true, false}) {
      const std::string label = std::string("reduction/") + (tree ? "tree" : "columns") +
                                "/screen:" + std::to_string(screen);
      benchmark::RegisterBenchmark(label.c_str(),
                                   [=](benchmark::State& s) { reduction(s, tree, screen); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
