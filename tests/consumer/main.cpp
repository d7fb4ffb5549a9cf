// Uses the installed Regolith package: a 5x5 DEM on a local tangent plane on the Mars
// sphere, holding the plane h(x, y) = 100 + 0.5 x - 0.25 y. Bilinear interpolation
// reproduces a plane exactly, so the query must return the analytic height.
// Exit status 0 only if every check holds.

#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/rover/Rover.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <vector>

namespace topo = regolith::topo;
namespace store = regolith::store;

namespace {

double plane(double x, double y) { return 100.0 + 0.5 * x - 0.25 * y; }

bool check(bool ok, const char* what) {
  std::printf("consumer: %-58s %s\n", what, ok ? "ok" : "FAILED");
  return ok;
}

}  // namespace

int main() {
  try {
    const topo::Body mars = topo::Body::marsSphere();
    const topo::LocalTangentPlane ltp(mars, topo::Geodetic{-4.5, 137.4, 0.0});

    // Sample (row, col) sits at x = -20 + 10 col, y = 20 - 10 row (row 0 is north).
    const topo::TopoGrid grid(5, 5, -20.0, 20.0, 10.0, 10.0);
    auto samples =
        topo::InMemorySamples::fromFunction(5, 5, [&grid](std::size_t row, std::size_t col) {
          const glm::dvec2 p =
              grid.sampleCentre(static_cast<double>(row), static_cast<double>(col));
          return static_cast<float>(plane(p.x, p.y));
        });
    const topo::TopoDem dem(grid, topo::Placement(ltp), samples);

    const double x = 3.5, y = -7.25;
    const topo::HeightSample h = dem.height(x, y);
    std::printf("consumer: height at (%g, %g) m = %.6f m, expected %.6f m\n", x, y, h.height,
                plane(x, y));

    bool ok = check(h.valid(), "query status is Ok");
    ok &= check(std::abs(h.height - plane(x, y)) < 1e-9, "height matches the analytic plane");
    // The plane's origin (0, 0, 0) lies on the sphere: |P| = R.
    ok &= check(std::abs(glm::length(dem.toBodyFixed(0.0, 0.0, 0.0)) - 3396190.0) < 1e-6,
                "tangent-plane origin lies on the Mars sphere");
    // A query outside the grid is a status, not an exception.
    ok &= check(!dem.height(1000.0, 0.0).valid(), "query outside the grid is not valid");
    // Bad input throws a regolith::Error across the library boundary.
    bool threw = false;
    try {
      (void)dem.height(std::nan(""), 0.0);
    } catch (const regolith::InvalidArgument&) {
      threw = true;
    }
    ok &= check(threw, "NaN coordinate throws regolith::InvalidArgument");

    // regolith::store through the package: write the DEM as a store, page it back.
    store::GridInfo info;
    info.name = "plane";
    info.rows = info.cols = 5;
    info.x0 = -20.0;
    info.y0 = 20.0;
    info.spacingX = info.spacingY = 10.0;
    info.equatorialRadius = info.polarRadius = 3396190.0;
    info.placement.originLatDeg = -4.5;
    info.placement.originLonDeg = 137.4;
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() / "regolith-consumer-store.h5";
    const std::vector<store::GridSource> grids{{info, samples}};
    store::writeStore(path, grids);
    auto opened = std::make_shared<const store::Store>(store::Store::open(path));
    const store::Pager pager(opened, std::make_shared<store::PatchCache>(1 << 20));
    const topo::HeightSample paged = pager.dem("plane").height(x, y);
    ok &= check(paged.valid() && paged.height == h.height, "paged store gives the same height");

    // Every other exported target: core, clod (its store-free pyramid seam), rover,
    // scenegraph and demo, linked from the package alone.
    ok &= check(regolith::core::number(1e-9) == "1e-09", "core::number() is shortest round trip");
    const regolith::clod::HeightPyramid pyramid(pager.pyramid("plane"));
    ok &= check(pyramid.levelCount() == opened->grid("plane").levels &&
                    pyramid.position(1.0, 2.0, 3.0) == glm::dvec3(1.0, 2.0, 3.0),
                "clod draws the store's pyramid export as a plane");
    const regolith::rover::Rover rover;
    const auto wheels = rover.wheelPositions({0.0, 0.0, 0.0});
    ok &= check(std::isfinite(wheels[0].x) && wheels[0] != wheels[5], "rover places its wheels");
    regolith::scenegraph::SceneGraph graph("mars");
    ok &= check(graph.add(graph.root(), "rover", regolith::scenegraph::Pose{}) != graph.root(),
                "scene graph adds a node");
    const regolith::demo::MarsVictoriaOptions demo;
    ok &= check(demo.planetRows > 0 && demo.marsGrid == "mars", "demo options link");
    std::filesystem::remove(path);
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: unexpected exception: %s\n", e.what());
    return 1;
  }
}
