// The beyond-a-pole rule and the snap onto the poles of a mosaic (importTiles()) apply to the
// mosaic's extent, not tile by tile: tiles of a global grid whose edge overhangs a pole by a
// fraction of a pixel import as the whole file does, and a mosaic that lies beyond a pole is
// refused naming it. Rasters made here with GDAL; every store written is opened and queried.
#include <regolith/store/Import.hpp>
#include <regolith/store/Store.hpp>

#include "RasterOracle.hpp"
#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

constexpr double kMoon = 1737400.0;
constexpr double kMetresPerDegree = kMoon * 3.14159265358979323846 / 180.0;

fs::path scratch(const std::string& name) { return test::scratchFile("mosaic-poles", name); }

/// Rows r0 … r1 − 1 of `full`, its geotransform moved to them.
test::Spec rowsOf(const test::Spec& full, std::size_t r0, std::size_t r1) {
  test::Spec t = full;
  t.rows = r1 - r0;
  t.gt[3] = full.gt[3] + static_cast<double>(r0) * full.gt[5];
  t.values.assign(full.values.begin() + static_cast<std::ptrdiff_t>(r0 * full.cols),
                  full.values.begin() + static_cast<std::ptrdiff_t>(r1 * full.cols));
  return t;
}

/// Imports `full` as one file and as its north and south halves (a mosaic of two tiles);
/// both give the same grid and samples. Returns the mosaic's report.
ImportReport importBothWays(const std::string& name, const test::Spec& full) {
  const fs::path whole = test::writeRaster(scratch(name + ".tif"), full);
  const std::size_t half = full.rows / 2;
  const std::vector<fs::path> tiles{
      test::writeRaster(scratch(name + "_north.tif"), rowsOf(full, 0, half)),
      test::writeRaster(scratch(name + "_south.tif"), rowsOf(full, half, full.rows))};
  ImportOptions o;
  o.gridName = name;
  const ImportReport one = importRaster(whole, scratch(name + ".h5"), o);
  const ImportReport two = importTiles(tiles, scratch(name + "_tiles.h5"), o);
  EXPECT_EQ(two.info.kind, one.info.kind);
  EXPECT_EQ(two.info.rows, one.info.rows);
  EXPECT_EQ(two.info.cols, one.info.cols);
  EXPECT_EQ(two.info.spacingY, one.info.spacingY);
  EXPECT_EQ(two.info.spacingX, one.info.spacingX);
  EXPECT_NEAR(two.info.y0, one.info.y0, 1e-12);
  EXPECT_NEAR(two.info.x0, one.info.x0, 1e-12);
  EXPECT_NEAR(two.poleShiftPixels, one.poleShiftPixels, 1e-12);
  EXPECT_EQ(test::readLevel0(scratch(name + "_tiles.h5"), name),
            test::readLevel0(scratch(name + ".h5"), name));
  return two;
}

}  // namespace

TEST(MosaicPoles, GeographicTilesOfAGridOverhangingThePoleSnapOntoItAsAWhole) {
  // 0.5° pixels, the north edge 0.3 px beyond 90°N. The north tile alone is no pole-to-pole
  // grid (it was refused tile by tile); the mosaic is, and moves onto the poles.
  test::Spec full;
  full.rows = 360;
  full.cols = 720;
  full.gt = {-180.0, 0.5, 0.0, 90.15, 0.0, -0.5};
  full.crs = "+proj=longlat +R=1737400 +no_defs";
  full.values = test::indexValues(full.rows, full.cols);
  const ImportReport rep = importBothWays("geographic", full);
  EXPECT_EQ(rep.info.kind, GridKind::Planet);
  EXPECT_EQ(rep.tiles, 2U);
  EXPECT_NEAR(rep.poleShiftPixels, 0.3, 1e-9);
  EXPECT_EQ(rep.info.y0, 89.75);
  test::expectExact(scratch("geographic_tiles.h5"), rep, test::readGdal(scratch("geographic.tif")));
}

TEST(MosaicPoles, GeographicTilesWhoseRowsSpan180WithinHalfAPixelSnapAsTheWholeFile) {
  // A pixel height of 0.5000001° (a rounded geotransform): 360 rows span 180.000036°. The
  // whole file snaps to 0.5° and onto the poles; so does the mosaic of its two halves (each
  // spans 90°, so tile by tile nothing snapped).
  test::Spec full;
  full.rows = 360;
  full.cols = 720;
  full.gt = {-180.0, 0.5, 0.0, 90.1, 0.0, -0.5000001};
  full.crs = "+proj=longlat +R=1737400 +no_defs";
  full.values = test::indexValues(full.rows, full.cols);
  const ImportReport rep = importBothWays("rounded", full);
  EXPECT_EQ(rep.info.spacingY, 0.5);
  EXPECT_EQ(rep.info.y0, 89.75);
  EXPECT_TRUE(rep.spacingSnapped);
  EXPECT_GT(rep.poleShiftPixels, 0.1);
  test::expectExact(scratch("rounded_tiles.h5"), rep, test::readGdal(scratch("rounded.tif")));
}

TEST(MosaicPoles, EquirectangularTilesWithARoundedMapScaleBecomeOneGlobalGridOnThePoles) {
  // 12125 m pixels on the Moon (0.4° is 12129.4 m), corner at 90°N in metres: 450 × 900
  // samples. Each half spans 360° of longitude but only half the latitudes: the snap to
  // 180/rows and onto the poles is the mosaic's (tile by tile, each half kept its rounded
  // spacing and the two together fell short of the poles).
  const double res = 12125.0;
  test::Spec full;
  full.rows = 450;
  full.cols = 900;
  full.gt = {-450.0 * res, res, 0.0, 90.0 * kMetresPerDegree, 0.0, -res};
  full.crs = "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=180 +R=1737400 +units=m +no_defs";
  full.values = test::indexValues(full.rows, full.cols);
  const ImportReport rep = importBothWays("eqc", full);
  EXPECT_EQ(rep.info.kind, GridKind::Planet);
  EXPECT_EQ(rep.info.spacingY, 0.4);
  EXPECT_EQ(rep.info.y0, 90.0 - 0.2);
  EXPECT_GT(rep.poleShiftPixels, topo::kPoleOverhangPixels);
  EXPECT_TRUE(rep.spacingSnapped);
  // The label's centres: pixel offsets from the projection's origin at 0.4°.
  test::Oracle o = test::readGdal(scratch("eqc.tif"));
  test::labelCentres(o, 180.0, 0.4);
  test::expectExact(scratch("eqc_tiles.h5"), rep, o);
}

TEST(MosaicPoles, AMosaicBeyondThePoleIsRefusedNamingTheMosaic) {
  // 20 rows of 0.5° from 90.15°N: no pole-to-pole grid, its edge 0.3 px beyond the pole.
  test::Spec full;
  full.rows = 20;
  full.cols = 16;
  full.gt = {10.0, 0.5, 0.0, 90.15, 0.0, -0.5};
  full.crs = "+proj=longlat +R=1737400 +no_defs";
  full.values = test::indexValues(full.rows, full.cols);
  const std::vector<fs::path> tiles{
      test::writeRaster(scratch("beyond_north.tif"), rowsOf(full, 0, 10)),
      test::writeRaster(scratch("beyond_south.tif"), rowsOf(full, 10, 20))};
  const fs::path store = scratch("beyond.h5");
  EXPECT_EQ(test::errorOf([&] { (void)importTiles(tiles, store); }),
            "store::importTiles(): " + tiles[0].string() +
                " and 1 more tile(s): georeferencing places the grid's edges at latitudes 90.15 "
                "to 80.15 deg, beyond a pole; expected within -90 to 90");
  EXPECT_FALSE(fs::exists(store));
}
