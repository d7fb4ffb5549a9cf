// Writes a store with known analytic content for tests/store/test_store_h5py.py, which reads
// it back with h5py and numpy only, following docs/store-format.md. The formulas here and in
// the script must agree; they are evaluated at pixel centres (x0 + col·dx, y0 − row·dy).
//
//   write_fixture_store <output.h5>
//
// Beside it, in the same directory, it writes a tiled grid (docs/store-format.md, "Tiled
// grids"): tiled.h5 with grid "mosaic", 150 × 130 samples, from two internal tiles and one
// external tile (grid "ext" of tiled_ext.h5, referenced by relative path); rows 130–149 are
// covered by no tile. And utm.h5 with grid "utm" (format 1.2): a transverse Mercator DEM
// whose heights are a function of each sample centre's latitude/longitude, which the script
// recomputes with PROJ (GDAL's osr) from the documented attributes.
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::store;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

/// "victoria": a DEM on a local tangent plane at Victoria crater, 301 × 203 samples at
/// dx = 1 m, dy = 2 m (unequal, so a transpose cannot pass), nodata −32768 inside a disc.
GridSource victoria() {
  GridInfo g;
  g.name = "victoria";
  g.kind = GridKind::Dem;
  g.rows = 301;
  g.cols = 203;
  g.x0 = -101.0;
  g.y0 = 300.0;
  g.spacingX = 1.0;
  g.spacingY = 2.0;
  g.nodata = -32768.0f;
  g.bodyName = "Mars";
  g.equatorialRadius = 3396190.0;
  g.polarRadius = 3376200.0;
  g.latitudeType = topo::LatitudeType::Planetodetic;
  g.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  g.placement.originLatDeg = -2.05;
  g.placement.originLonDeg = -5.5;
  g.placement.originHeight = -1400.0;
  g.placement.headingDeg = 0.0;
  auto samples =
      topo::InMemorySamples::fromFunction(g.rows, g.cols, [g](std::size_t r, std::size_t c) {
        const double x = g.x0 + static_cast<double>(c) * g.spacingX;
        const double y = g.y0 - static_cast<double>(r) * g.spacingY;
        if ((x - 20.0) * (x - 20.0) + (y - 100.0) * (y - 100.0) < 30.0 * 30.0) return kNan;
        return static_cast<float>(20.0 + 0.25 * x - 0.5 * y +
                                  15.0 * std::sin(x / 23.0) * std::cos(y / 31.0));
      });
  return {g, samples};
}

/// "mars": a global 0.5° planet grid (longitude −180…180, latitude 90…−90), no nodata value:
/// missing samples (north of 85°N, and a box 10–20°E, 10°S–0°) are stored as NaN.
GridSource mars() {
  GridInfo g;
  g.name = "mars";
  g.kind = GridKind::Planet;
  g.rows = 360;
  g.cols = 720;
  g.x0 = -179.75;
  g.y0 = 89.75;
  g.spacingX = g.spacingY = 0.5;
  g.bodyName = "Mars";
  g.equatorialRadius = 3396190.0;
  g.polarRadius = 3376200.0;
  g.latitudeType = topo::LatitudeType::Planetocentric;
  auto samples =
      topo::InMemorySamples::fromFunction(g.rows, g.cols, [g](std::size_t r, std::size_t c) {
        const double lon = g.x0 + static_cast<double>(c) * g.spacingX;
        const double lat = g.y0 - static_cast<double>(r) * g.spacingY;
        if (lat > 85.0 || (lon > 10.0 && lon < 20.0 && lat > -10.0 && lat < 0.0)) return kNan;
        const double d = std::acos(-1.0) / 180.0;
        return static_cast<float>(1000.0 * std::cos(lat * d) * std::sin(2.0 * lon * d) +
                                  10.0 * lat);
      });
  return {g, samples};
}

/// "tilt": a plane h = 3 + 0.125·x − 0.0625·y on a south polar stereographic DEM, 97 × 131
/// samples at 5 m. The 2×2 mean of a plane is the plane at the mean position, so every
/// coarse level shows where its sample centres are.
GridSource tilt() {
  GridInfo g;
  g.name = "tilt";
  g.kind = GridKind::Dem;
  g.rows = 97;
  g.cols = 131;
  g.x0 = 1000.0;
  g.y0 = -2000.0;
  g.spacingX = g.spacingY = 5.0;
  g.bodyName = "Moon";
  g.equatorialRadius = g.polarRadius = 1737400.0;
  g.placement.kind = PlacementInfo::Kind::PolarStereographic;
  g.placement.pole = -1;
  g.placement.latTrueScaleDeg = -90.0;
  g.placement.lonCentreDeg = 0.0;
  auto samples =
      topo::InMemorySamples::fromFunction(g.rows, g.cols, [g](std::size_t r, std::size_t c) {
        const double x = g.x0 + static_cast<double>(c) * g.spacingX;
        const double y = g.y0 - static_cast<double>(r) * g.spacingY;
        return static_cast<float>(3.0 + 0.125 * x - 0.0625 * y);
      });
  return {g, samples};
}

/// Height of mosaic sample (r, c) of the tiled fixture; NaN on a diagonal pattern.
float mosaicHeight(std::size_t r, std::size_t c) {
  if ((r + c) % 37 == 0) return kNan;
  return static_cast<float>(5.0 + 0.5 * static_cast<double>(r) - 0.25 * static_cast<double>(c) +
                            3.0 * std::sin(static_cast<double>(c) / 7.0));
}

std::shared_ptr<const topo::SampleSource> mosaicPart(std::size_t row0, std::size_t col0,
                                                     std::size_t rows, std::size_t cols) {
  return topo::InMemorySamples::fromFunction(
      rows, cols, [=](std::size_t r, std::size_t c) { return mosaicHeight(row0 + r, col0 + c); });
}

GridInfo mosaicInfo(const char* name, std::size_t rows, std::size_t cols) {
  GridInfo g;
  g.name = name;
  g.kind = GridKind::Dem;
  g.rows = rows;
  g.cols = cols;
  g.x0 = 0.0;
  g.y0 = 0.0;
  g.nodata = -32768.0f;
  g.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  return g;
}

void writeTiled(const std::filesystem::path& dir, const WriteOptions& o) {
  const GridSource ext{mosaicInfo("ext", 60, 130), mosaicPart(70, 0, 60, 130)};
  writeStore(dir / "tiled_ext.h5", std::span<const GridSource>(&ext, 1), o);
  GridSource mosaic{mosaicInfo("mosaic", 150, 130), nullptr};
  mosaic.tiles.push_back({0, 0, mosaicPart(0, 0, 70, 50), {}, {}});
  mosaic.tiles.push_back({0, 50, mosaicPart(0, 50, 70, 80), {}, {}});
  mosaic.tiles.push_back({70, 0, nullptr, "tiled_ext.h5", "ext"});
  writeStore(dir / "tiled.h5", std::span<const GridSource>(&mosaic, 1), o);
}

/// "utm": 40 × 50 samples of 250 × 200 m in a UTM-like zone south of the equator on Clarke
/// 1866 (λ0 = 123°W, φ0 = −10°, k0 = 0.9996, false easting 500 km, false northing 10,000 km),
/// about 1.3° west of the central meridian near 43°S. Height = 1e6 m per degree of latitude
/// and of longitude (scaled by cos 43°) from 43°S 124.5°W: a 1e-8° error in a sample's
/// position moves its height by 0.01 m, above float32's rounding (at most 0.004 m here).
void writeUtm(const std::filesystem::path& dir, const WriteOptions& o) {
  GridInfo g;
  g.name = "utm";
  g.kind = GridKind::Dem;
  g.rows = 40;
  g.cols = 50;
  g.x0 = 393000.0;
  g.y0 = 6345000.0;
  g.spacingX = 250.0;
  g.spacingY = 200.0;
  g.bodyName = "Earth";
  g.equatorialRadius = 6378206.4;
  g.polarRadius = 6356583.8;
  g.latitudeType = topo::LatitudeType::Planetodetic;
  g.placement.kind = PlacementInfo::Kind::TransverseMercator;
  g.placement.lonCentreDeg = -123.0;
  g.placement.latOriginDeg = -10.0;
  g.placement.scaleFactor = 0.9996;
  g.placement.falseEasting = 500000.0;
  g.placement.falseNorthing = 10000000.0;
  const topo::Placement pl = placementOf(g);
  auto samples =
      topo::InMemorySamples::fromFunction(g.rows, g.cols, [&](std::size_t r, std::size_t c) {
        const double x = g.x0 + static_cast<double>(c) * g.spacingX;
        const double y = g.y0 - static_cast<double>(r) * g.spacingY;
        const topo::Geodetic p = pl.toGeodetic(x, y, 0.0);
        return static_cast<float>(1e6 * (p.latDeg + 43.0) +
                                  1e6 * std::cos(43.0 * std::acos(-1.0) / 180.0) *
                                      (p.lonDeg + 124.5));
      });
  const GridSource src{g, samples};
  writeStore(dir / "utm.h5", std::span<const GridSource>(&src, 1), o);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: write_fixture_store <output.h5> [deflate|zfp]\n");
    return 2;
  }
  try {
    const std::vector<GridSource> grids{victoria(), mars(), tilt()};
    WriteOptions o;
    o.patchRows = 64;
    o.patchCols = 48;
    if (argc == 3) o.codec = codecNamed(argv[2]);  // deflate: level 0, i.e. uncompressed
    writeStore(argv[1], grids, o);
    std::filesystem::path dir = std::filesystem::path(argv[1]).parent_path();
    if (dir.empty()) dir = ".";
    writeTiled(dir, o);
    writeUtm(dir, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "write_fixture_store: %s\n", e.what());
    return 1;
  }
  return 0;
}
