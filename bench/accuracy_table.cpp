// Interpolation accuracy versus grid spacing, with a rough speed column
// (docs/accuracy-vs-time.md).
//
// A TopoDem samples an analytic surface, a sum of three plane sine waves with known height
// and gradient, at spacings of 4 m, 1 m and 0.25 m over the same 256 m x 256 m area. Each
// kernel is evaluated at the same random points (kept 8 m inside the grid, so no stencil
// touches the edge) and compared with the analytic height and unit normal (grid frame).
// The table goes to stdout as Markdown.
//
// The ns/query columns come from std::chrono around single height() / surface() calls over
// the same random points (best of several passes); they are only indicative. The
// authoritative speed figures come from topo_bench (Google Benchmark).

#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include "JsonRows.hpp"

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace {

using regolith::topo::Body;
using regolith::topo::Geodetic;
using regolith::topo::InMemorySamples;
using regolith::topo::Interpolation;
using regolith::topo::LocalTangentPlane;
using regolith::topo::NormalFrame;
using regolith::topo::Placement;
using regolith::topo::TopoDem;
using regolith::topo::TopoGrid;

constexpr double kPi = std::numbers::pi;
constexpr double kExtent = 256.0;  // metres, both axes; sample centres from 0 to kExtent
constexpr double kMargin = 8.0;    // random points stay this far from the edge
constexpr std::size_t kDefaultPoints = 200000;
constexpr int kTimingPasses = 5;

// One plane wave A·sin(kx·x + ky·y + φ).
struct Wave {
  double amplitude, kx, ky, phase;
};

Wave wave(double amplitude, double wavelength, double azimuthDeg, double phase) {
  const double k = 2.0 * kPi / wavelength;
  const double a = azimuthDeg * kPi / 180.0;
  return {amplitude, k * std::cos(a), k * std::sin(a), phase};
}

// 6 m at 120 m, 1.5 m at 37 m, 0.25 m at 11 m wavelength: slopes up to ~0.7 (35 deg);
// the shortest wave is above the Nyquist wavelength (8 m) of the coarsest grid.
const std::array<Wave, 3> kWaves = {wave(6.0, 120.0, 20.0, 0.3), wave(1.5, 37.0, 110.0, 1.1),
                                    wave(0.25, 11.0, 245.0, 2.0)};

double exactHeight(double x, double y) {
  double h = 0.0;
  for (const Wave& w : kWaves) h += w.amplitude * std::sin(w.kx * x + w.ky * y + w.phase);
  return h;
}

// Unit normal (−∂h/∂x, −∂h/∂y, 1)/‖·‖ in the grid frame.
glm::dvec3 exactNormal(double x, double y) {
  double hx = 0.0, hy = 0.0;
  for (const Wave& w : kWaves) {
    const double c = w.amplitude * std::cos(w.kx * x + w.ky * y + w.phase);
    hx += c * w.kx;
    hy += c * w.ky;
  }
  return glm::normalize(glm::dvec3(-hx, -hy, 1.0));
}

double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

TopoDem makeDem(double spacing) {
  const auto n = static_cast<std::size_t>(std::llround(kExtent / spacing)) + 1;
  // Row 0 is the north edge: y0 = kExtent, x0 = 0.
  TopoGrid grid(n, n, 0.0, kExtent, spacing, spacing);
  auto samples = InMemorySamples::fromFunction(n, n, [&](std::size_t r, std::size_t c) {
    const glm::dvec2 xy = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return static_cast<float>(exactHeight(xy.x, xy.y));
  });
  Placement placement(LocalTangentPlane(Body::marsSphere(), Geodetic{18.4, 77.5, -2500.0}));
  return TopoDem(grid, placement, samples);
}

struct Row {
  double maxDh = 0.0, sumDh2 = 0.0;
  double maxAng = 0.0, sumAng2 = 0.0;
  std::size_t failed = 0;
  double nsHeight = 0.0, nsSurface = 0.0;
};

template <class Fn>
double bestNsPerQuery(std::size_t n, Fn&& fn) {
  double best = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < kTimingPasses; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    const auto t1 = std::chrono::steady_clock::now();
    const double ns = std::chrono::duration<double, std::nano>(t1 - t0).count();
    best = std::min(best, ns / static_cast<double>(n));
  }
  return best;
}

volatile double gSink = 0.0;  // keeps the timed loops from being optimised away

Row evaluate(const TopoDem& dem, Interpolation interp, const std::vector<double>& xs,
             const std::vector<double>& ys) {
  Row row;
  const std::size_t n = xs.size();
  for (std::size_t i = 0; i < n; ++i) {
    const regolith::topo::SurfaceSample s = dem.surface(xs[i], ys[i], interp);
    if (!s.valid()) {
      ++row.failed;
      continue;
    }
    const double dh = std::abs(s.height - exactHeight(xs[i], ys[i]));
    const double ang = angleBetween(s.normal, exactNormal(xs[i], ys[i]));
    row.maxDh = std::max(row.maxDh, dh);
    row.sumDh2 += dh * dh;
    row.maxAng = std::max(row.maxAng, ang);
    row.sumAng2 += ang * ang;
  }
  row.nsHeight = bestNsPerQuery(n, [&] {
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) sum += dem.height(xs[i], ys[i], interp).height;
    gSink = sum;
  });
  row.nsSurface = bestNsPerQuery(n, [&] {
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      sum += dem.surface(xs[i], ys[i], interp, NormalFrame::Grid).normal.z;
    }
    gSink = sum;
  });
  return row;
}

const char* kernelName(Interpolation k) {
  switch (k) {
    case Interpolation::Nearest: return "Nearest";
    case Interpolation::Bilinear: return "Bilinear";
    case Interpolation::Bicubic: return "Bicubic";
  }
  return "?";
}

}  // namespace

int main(int argc, char** argv) {
  // --points N (default 200000; fewer for a quick run), --json FILE: also write the rows
  // as JSON for `regolith report` (counters in metres and radians, ns per query).
  std::size_t points = kDefaultPoints;
  std::string jsonPath;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--points" || a == "--json") && i + 1 < argc) {
      const std::string v = argv[++i];
      if (a == "--json") {
        jsonPath = v;
      } else {
        points = static_cast<std::size_t>(std::stoull(v));
      }
    } else {
      std::fprintf(stderr, "usage: accuracy_table [--points N] [--json FILE]\n");
      return 2;
    }
  }
  if (points == 0) {
    std::fprintf(stderr, "accuracy_table: --points must be > 0\n");
    return 2;
  }
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> coord(kMargin, kExtent - kMargin);
  std::vector<double> xs(points), ys(points);
  for (std::size_t i = 0; i < points; ++i) {
    xs[i] = coord(rng);
    ys[i] = coord(rng);
  }

  const double spacings[] = {4.0, 1.0, 0.25};
  const Interpolation kernels[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                   Interpolation::Bicubic};

  std::printf(
      "Analytic surface: h(x, y) = sum of 3 plane sine waves "
      "(A = 6 m / 1.5 m / 0.25 m, wavelength = 120 m / 37 m / 11 m), "
      "max slope about 0.7.\n");
  std::printf(
      "Grid: %.0f m x %.0f m, float samples; %zu random points at least %.0f m "
      "inside the edge; normals in the grid frame.\n\n",
      kExtent, kExtent, points, kMargin);
  std::printf(
      "| kernel | spacing (m) | max \\|dh\\| (m) | RMS dh (m) | max normal error (mrad) "
      "| RMS normal error (mrad) | height() ns/query | surface() ns/query |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  std::size_t failed = 0;
  std::vector<regolith::bench::JsonRow> rows;
  for (const Interpolation k : kernels) {
    for (const double spacing : spacings) {
      const TopoDem dem = makeDem(spacing);
      const Row r = evaluate(dem, k, xs, ys);
      failed += r.failed;
      const double valid = static_cast<double>(points - r.failed);
      std::printf("| %s | %g | %.3g | %.3g | %.3g | %.3g | %.1f | %.1f |\n", kernelName(k), spacing,
                  r.maxDh, std::sqrt(r.sumDh2 / valid), 1e3 * r.maxAng,
                  1e3 * std::sqrt(r.sumAng2 / valid), r.nsHeight, r.nsSurface);
      char name[64];
      std::snprintf(name, sizeof name, "accuracy/%s/spacing:%g", kernelName(k), spacing);
      rows.push_back(regolith::bench::JsonRow{name, {}, {}}
                         .label("kernel", kernelName(k))
                         .set("spacing_m", spacing)
                         .set("max_dh_m", r.maxDh)
                         .set("rms_dh_m", std::sqrt(r.sumDh2 / valid))
                         .set("max_normal_rad", r.maxAng)
                         .set("rms_normal_rad", std::sqrt(r.sumAng2 / valid))
                         .set("height_ns", r.nsHeight)
                         .set("surface_ns", r.nsSurface)
                         .set("points", static_cast<double>(points)));
    }
  }
  std::printf(
      "\nns/query: std::chrono, best of %d passes over the %zu points, single calls, "
      "one thread; indicative only (see topo_bench).\n",
      kTimingPasses, points);
  if (!jsonPath.empty()) regolith::bench::writeJsonRows(jsonPath, "accuracy_table", rows);
  if (failed != 0) {
    std::printf("\nWARNING: %zu queries did not return Ok.\n", failed);
    return 1;
  }
  return 0;
}
