#include "TopoDemo.hpp"

#include <regolith/core/AtomicFile.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/topo/Mesh.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <ostream>
#include <random>
#include <string>
#include <vector>

namespace regolith::tools {
namespace {

using namespace regolith::topo;
using Clock = std::chrono::steady_clock;
constexpr double kPi = std::numbers::pi;

// The analytic Victoria-like crater of `regolith generate victoria` (store::VictoriaShape,
// seed 1): being analytic it also serves as the truth for the accuracy table.
double craterHeight(double x, double y) {
  static const store::VictoriaShape shape = store::VictoriaShape::fromSeed(1);
  return shape.height(x, y);
}

std::string fmt(const char* f, double a) {
  char b[64];
  std::snprintf(b, sizeof b, f, a);
  return b;
}

// "2.050000°S 5.500000°W" style.
std::string latLon(double lat, double lon, int decimals) {
  char b[96];
  std::snprintf(b, sizeof b, "%.*f°%c %.*f°%c", decimals, std::abs(lat), lat < 0 ? 'S' : 'N',
                decimals, std::abs(lon), lon < 0 ? 'W' : 'E');
  return b;
}

double seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

int runTopoDemo(const TopoDemoOptions& o, std::ostream& out) {
  const auto start = Clock::now();
  out << "Regolith topo demo: a Victoria-like crater DEM on Mars, queried like a rover would\n\n";

  // ---- 1. Build the DEM and place it on Mars ------------------------------------------
  const Body mars = Body::marsEllipsoid();
  // Where `regolith generate victoria` puts it: near Victoria crater, Meridiani Planum.
  const Geodetic origin{store::VictoriaGenerator::kOriginLatDeg,
                        store::VictoriaGenerator::kOriginLonDeg,
                        store::VictoriaOptions{}.originHeight};
  const LocalTangentPlane plane(mars, origin, 0.0);
  const double half = 0.5 * static_cast<double>(o.size - 1) * o.spacing;
  const TopoGrid grid(o.size, o.size, -half, half, o.spacing, o.spacing);
  auto t0 = Clock::now();
  const auto samples =
      InMemorySamples::fromFunction(o.size, o.size, [&](std::size_t r, std::size_t c) {
        const glm::dvec2 p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
        return static_cast<float>(craterHeight(p.x, p.y));
      });
  const TopoDem dem(grid, Placement(plane), samples);
  out << "[1/6] DEM: " << o.size << " x " << o.size << " samples at " << o.spacing << " m spacing ("
      << fmt("%.1f", static_cast<double>(o.size * o.size * 4) / 1e6) << " MB), built in "
      << fmt("%.2f", seconds(t0)) << " s\n";
  out << "      body: " << mars.name()
      << " IAU ellipsoid, a = " << fmt("%.0f", mars.equatorialRadius())
      << " m, b = " << fmt("%.0f", mars.polarRadius()) << " m\n";
  out << "      placement: local tangent plane at " << latLon(origin.latDeg, origin.lonDeg, 2)
      << ", " << fmt("%.0f", origin.height) << " m above the ellipsoid, heading 0 (y north)\n";
  const glm::dvec3 c0 = dem.toBodyFixed(0.0, 0.0, 0.0);
  out << "      DEM centre body-fixed: (" << fmt("%.3f", c0.x / 1e3) << ", "
      << fmt("%.3f", c0.y / 1e3) << ", " << fmt("%.3f", c0.z / 1e3) << ") km\n";
  for (auto [name, x, y] : {std::tuple{"NW corner", -half, half}, {"SE corner", half, -half}}) {
    const Geodetic g = dem.placement().toGeodetic(x, y, dem.height(x, y).height);
    out << "      " << name << ": " << latLon(g.latDeg, g.lonDeg, 6) << ", ground "
        << fmt("%.2f", g.height) << " m above the ellipsoid\n";
  }

  // ---- 2. Crater metrics, from queries -----------------------------------------------
  double rimMax = -1e9, floorMin = 1e9, steepest = 0.0;
  for (int i = 0; i < 720; ++i) {
    const double th = 2.0 * kPi * i / 720.0;
    for (double r = 0.0; r < std::min(half, 500.0); r += 2.0) {
      const SurfaceSample s =
          dem.surface(r * std::cos(th), r * std::sin(th), Interpolation::Bicubic);
      if (!s.normalValid()) continue;
      rimMax = std::max(rimMax, s.height);
      floorMin = std::min(floorMin, s.height);
      steepest = std::max(steepest, std::acos(std::clamp(s.normal.z, -1.0, 1.0)) * 180.0 / kPi);
    }
  }
  out << "\n[2/6] Crater from 180,000 bicubic surface queries: rim crest " << fmt("%.1f", rimMax)
      << " m, floor " << fmt("%.1f", floorMin) << " m, depth " << fmt("%.1f", rimMax - floorMin)
      << " m, steepest wall " << fmt("%.1f", steepest) << " deg\n";

  // ---- 3. A rover drives from the plains to the rim ----------------------------------
  out << "\n[3/6] Rover traverse from the western plains to the rim (bilinear, grid frame)\n";
  out << "      x [m]    y [m]    lat [deg N]   lon [deg E]   height [m]  slope [deg]  body-fixed "
         "normal\n";
  const double xStart = -std::min(0.95 * half, 560.0);
  const double xEnd = half > 420.0 ? -384.0 : 0.95 * half;  // the rim, or across a small DEM
  const double step = (xEnd - xStart) / 8.0;
  for (int i = 0; i <= 8; ++i) {
    const double x = xStart + step * i, y = std::clamp(-40.0 + 2.0 * i, -half, half);
    const SurfaceSample s = dem.surface(x, y, Interpolation::Bilinear, NormalFrame::Grid);
    const SurfaceSample b = dem.surface(x, y, Interpolation::Bilinear, NormalFrame::BodyFixed);
    char line[200];
    if (!s.normalValid() || !b.normalValid()) {
      std::snprintf(line, sizeof line, "      %7.1f %7.1f  (no valid terrain here)\n", x, y);
    } else {
      const Geodetic g = dem.placement().toGeodetic(x, y, s.height);
      std::snprintf(line, sizeof line,
                    "      %7.1f %7.1f  %12.7f  %12.7f  %10.3f  %10.2f   (%.4f, %.4f, %.4f)\n", x,
                    y, g.latDeg, g.lonDeg, s.height, std::acos(s.normal.z) * 180.0 / kPi,
                    b.normal.x, b.normal.y, b.normal.z);
    }
    out << line;
  }

  // ---- 4. Accuracy against the analytic crater, per kernel ---------------------------
  out << "\n[4/6] Accuracy vs. the analytic crater at 20,000 random points (r < 600 m)\n";
  out << "      kernel     max |dh| [m]   RMS dh [m]   ns/query\n";
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ang(0.0, 2.0 * kPi), rad(0.0, 1.0);
  const double rmax = std::min(600.0, half - 2.0);
  std::vector<double> xs(20000), ys(20000);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const double r = rmax * std::sqrt(rad(rng)), th = ang(rng);
    xs[i] = r * std::cos(th);
    ys[i] = r * std::sin(th);
  }
  for (auto [name, k] : {std::pair{"nearest ", Interpolation::Nearest},
                         {"bilinear", Interpolation::Bilinear},
                         {"bicubic ", Interpolation::Bicubic}}) {
    double maxErr = 0.0, sum2 = 0.0;
    t0 = Clock::now();
    double sink = 0.0;
    for (int rep = 0; rep < 20; ++rep) {
      for (std::size_t i = 0; i < xs.size(); ++i) sink += dem.height(xs[i], ys[i], k).height;
    }
    const double ns = seconds(t0) * 1e9 / (20.0 * static_cast<double>(xs.size()));
    for (std::size_t i = 0; i < xs.size(); ++i) {
      const double e = dem.height(xs[i], ys[i], k).height - craterHeight(xs[i], ys[i]);
      maxErr = std::max(maxErr, std::abs(e));
      sum2 += e * e;
    }
    char line[160];
    std::snprintf(line, sizeof line, "      %s   %10.4f   %10.4f   %8.1f%s\n", name, maxErr,
                  std::sqrt(sum2 / static_cast<double>(xs.size())), ns, sink == 0.123 ? " " : "");
    out << line;
  }

  // ---- 5. Throughput along a rover-like path ------------------------------------------
  const std::size_t n = o.queries;
  std::vector<double> px(n), py(n), ph(n);
  for (std::size_t i = 0; i < n; ++i) {  // a gentle curve with 1 cm steps
    const double s = 0.01 * static_cast<double>(i % 100000);
    px[i] = -450.0 + s;
    py[i] = 30.0 * std::sin(s / 200.0);
  }
  t0 = Clock::now();
  double acc = 0.0;
  for (std::size_t i = 0; i < n; ++i) acc += dem.height(px[i], py[i]).height;
  const double single = seconds(t0) * 1e9 / static_cast<double>(n);
  t0 = Clock::now();
  dem.heights(px, py, ph, {});
  const double batch = seconds(t0) * 1e9 / static_cast<double>(n);
  t0 = Clock::now();
  for (std::size_t i = 0; i < n; ++i) acc += dem.surface(px[i], py[i]).normal.z;
  const double normals = seconds(t0) * 1e9 / static_cast<double>(n);
  out << "\n[5/6] Throughput on one core, " << n << " queries along a rover path (1 cm steps):\n"
      << "      bilinear height " << fmt("%.1f", single) << " ns/query, batch "
      << fmt("%.1f", batch) << " ns/query, height+normal " << fmt("%.1f", normals) << " ns/query"
      << (acc == 0.123 ? " " : "") << "\n"
      << "      (a 6-wheel rover at 1 kHz needs 6,000 queries/s: "
      << fmt("%.4f", 6000.0 * normals * 1e-9 * 100.0) << " % of one core)\n";

  // ---- 6. Export the rim region as a mesh for a physics engine ------------------------
  const std::size_t win = std::min<std::size_t>(o.size, 201);
  const std::size_t row0 = (o.size - win) / 2;
  const TriangleMesh mesh = buildMesh(dem, {row0, 0, win, win}, MeshFrame::Grid);
  const auto path = o.outDir / "crater_west_rim.ply";
  std::filesystem::create_directories(o.outDir);  // --out names a folder of its own
  core::writeStreamAtomically(
      path, [&](std::ostream& s) { writePly(s, mesh); }, "regolith walkthrough");
  out << "\n[6/6] Wrote " << path.string() << ": " << mesh.vertices.size() << " vertices, "
      << mesh.triangles.size() << " triangles (binary PLY, grid frame, metres)\n";

  out << "\nDone in " << fmt("%.1f", seconds(start)) << " s.\n";
  return 0;
}

}  // namespace regolith::tools
