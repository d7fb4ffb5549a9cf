#pragma once
// A store shared by the pager and prefetcher tests: a 700×900 DEM (one NaN sample) on a
// tangent plane at Victoria crater and a 1° global planet, in 128×128 patches, written
// once per test process into a scratch folder.

#include <regolith/store/Pager.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>

namespace regolith::test {

using namespace regolith::store;
using namespace regolith::topo;
namespace fs = std::filesystem;

inline fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("regolith-pager-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

inline float terrain(std::size_t r, std::size_t c) {
  const double x = static_cast<double>(c), y = static_cast<double>(r);
  if (r == 300 && c == 301) return std::nanf("");  // one hole
  return static_cast<float>(40.0 * std::sin(x / 37.0) + 25.0 * std::cos(y / 23.0) +
                            0.01 * x * y / 10.0);
}

inline GridInfo demInfo(std::size_t rows, std::size_t cols) {
  GridInfo g;
  g.name = "dem";
  g.kind = GridKind::Dem;
  g.rows = rows;
  g.cols = cols;
  g.x0 = -500.0;
  g.y0 = 400.0;
  g.spacingX = g.spacingY = 1.0;
  g.nodata = -32768.0f;
  g.bodyName = "Mars";
  g.equatorialRadius = 3396190.0;
  g.polarRadius = 3376200.0;
  g.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  g.placement.originLatDeg = -2.05;
  g.placement.originLonDeg = -5.5;
  return g;
}

inline GridInfo planetInfo() {
  GridInfo g;
  g.name = "planet";
  g.kind = GridKind::Planet;
  g.rows = 180;
  g.cols = 360;
  g.x0 = 0.5;
  g.y0 = 89.5;
  g.spacingX = g.spacingY = 1.0;
  g.equatorialRadius = g.polarRadius = 3396190.0;
  return g;
}

struct Fixture {
  fs::path path;
  std::shared_ptr<InMemorySamples> demSamples, planetSamples;
};

// Writes one store with a 700×900 DEM and a 1° global planet, 128×128 patches.
inline const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture fx;
    fx.path = scratch("pager.h5");
    fx.demSamples = InMemorySamples::fromFunction(700, 900, terrain);
    fx.planetSamples = InMemorySamples::fromFunction(180, 360, [](std::size_t r, std::size_t c) {
      return static_cast<float>(100.0 * static_cast<double>(r) - static_cast<double>(c));
    });
    const std::vector<GridSource> grids{{demInfo(700, 900), fx.demSamples},
                                        {planetInfo(), fx.planetSamples}};
    WriteOptions o;
    o.patchRows = o.patchCols = 128;
    writeStore(fx.path, grids, o);
    return fx;
  }();
  return f;
}

struct Opened {
  std::shared_ptr<const Store> store;
  std::shared_ptr<PatchCache> cache;
  Pager pager;
};

inline Opened openFixture(std::size_t capacity = std::size_t{64} << 20) {
  auto store = std::make_shared<const Store>(Store::open(fixture().path));
  auto cache = std::make_shared<PatchCache>(capacity);
  return {store, cache, Pager(store, cache)};
}

}  // namespace regolith::test
