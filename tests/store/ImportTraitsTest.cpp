// Import of the traits that made real global and polar products fail (issue 21): rounded map
// scales at the poles, one tolerance for "at the pole" shared with TopoPlanet, padding rows
// beyond a pole, grids that wrap past ±180° or span more than 360°. Every raster is made here
// with GDAL (GeoTIFF, or ISIS3 through GDAL's writer); every store an import writes is opened
// and queried in the same test. Oracles: GDAL's pixel reads after scale/offset for the
// samples, and OSR (PROJ) for the longitude/latitude of GDAL's pixel centres, where a
// nearest-sample query must return that very sample.
#include <regolith/core/Error.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "RasterOracle.hpp"
#include "support/Fixtures.hpp"
#include "support/StoreScratch.hpp"

#include <cpl_json.h>
#include <gdal.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;
using test::Dataset;
using test::errorOf;
using test::expectExact;
using test::indexValues;
using test::labelCentres;
using test::Oracle;
using test::readGdal;
using test::Spec;

namespace {

constexpr double kMoon = 1737400.0;
constexpr double kMetresPerDegree = kMoon * 3.14159265358979323846 / 180.0;

fs::path scratch(const std::string& name) { return test::scratchFile("import-traits", name); }

/// Writes `spec` with GDAL under this test's scratch folder.
fs::path write(const std::string& name, const test::Spec& spec) {
  return test::writeRaster(scratch(name), spec);
}

std::string moonEqc(double lon0) {
  return "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=" + std::to_string(static_cast<int>(lon0)) +
         " +R=1737400 +units=m +no_defs";
}

const std::string kMoonGeographic = "+proj=longlat +R=1737400 +no_defs";

}  // namespace

// ---- rounded map scales: the label's resolution is the truth --------------------------------

TEST(ImportTraits, AGlobalIsis3CubeWithARoundedMapScaleSnapsToTheLabelsScaleOntoThePoles) {
  // 0.4°/px on the Moon is 12129.44 m; the label says 12125 m and Scale = 2.5 px/deg, its
  // corner at 90°N in metres. Through the rounded metres the north edge lies 0.08 px beyond
  // the pole (the old snap to 180/rows kept it there and refused the file).
  const double res = 12125.0;
  Spec s;
  s.rows = 450;
  s.cols = 900;
  s.gt = {-450.0 * res, res, 0.0, 90.0 * kMetresPerDegree, 0.0, -res};
  s.crs = moonEqc(180.0);
  s.values = indexValues(s.rows, s.cols);
  s.driver = "ISIS3";
  s.isisScale = 2.5;
  const fs::path cube = write("rounded_scale.cub", s);
  const Oracle o = readGdal(cube);
  const double overhang = o.gt[3] / res - 225.0;  // pixels beyond the pole, by the metres
  ASSERT_GT(overhang, topo::kPoleOverhangPixels);
  ASSERT_LT(overhang, 0.9);

  const fs::path store = scratch("rounded_scale.h5");
  const ImportReport rep = importRaster(cube, store);
  EXPECT_EQ(rep.info.kind, GridKind::Planet);
  EXPECT_EQ(rep.info.spacingX, 0.4);
  EXPECT_EQ(rep.info.spacingY, 0.4);
  EXPECT_NEAR(rep.info.x0, 0.2, 1e-12);
  EXPECT_EQ(rep.info.y0, 90.0 - 0.2);
  EXPECT_NEAR(rep.poleShiftPixels, overhang, 1e-9);
  EXPECT_TRUE(rep.spacingSnapped);
  expectExact(store, rep, o);
}

TEST(ImportTraits, ALabelScaleThatContradicts180OverRowsIsKeptAndAPaddingRowDropped) {
  // 451 rows; the label says 2.5 px/deg (0.4°) and 12115 m/px (0.3995°), its offsets in
  // whole pixels (as PDS3 labels give them). Through the metres 451 rows span 180.19°,
  // within half a pixel of 180°, and the old snap stretched them to 180/451°, which the label
  // contradicts. The label's 0.4° is kept, and the last row, centred at 90.2°S and wholly
  // missing, is dropped.
  const double res = 12115.0;
  Spec s;
  s.rows = 451;
  s.cols = 900;
  s.gt = {-450.0 * res, res, 0.0, 225.0 * res, 0.0, -res};
  s.crs = moonEqc(180.0);
  s.values = indexValues(s.rows, s.cols);
  for (std::size_t c = 0; c < s.cols; ++c) s.values[450 * s.cols + c] = -1e30F;
  s.nodata = -1e30;
  s.driver = "ISIS3";
  s.isisScale = 2.5;
  const fs::path cube = write("extra_row.cub", s);
  const fs::path store = scratch("extra_row.h5");
  const ImportReport rep = importRaster(cube, store);
  EXPECT_EQ(rep.info.kind, GridKind::Planet);
  EXPECT_EQ(rep.info.spacingY, 0.4);
  EXPECT_EQ(rep.info.rows, 450U);
  EXPECT_EQ(rep.droppedSouthRows, 1U);
  EXPECT_EQ(rep.droppedNorthRows, 0U);
  EXPECT_EQ(rep.poleShiftPixels, 0.0);
  EXPECT_NEAR(rep.info.y0, 89.8, 1e-9);
  // OSR's centres, through the rounded metres, drift more than half a pixel from the label's
  // across 450 columns (any product of this kind does): the label's centres are the oracle.
  Oracle o = readGdal(cube);
  labelCentres(o, 180.0, 0.4);
  expectExact(store, rep, o);
}

TEST(ImportTraits, AnIsis3CopyMadeByGdalWhoseScaleComesFromRoundedMetresImportsAsTheOriginal) {
  // GDAL's ISIS3 writer derives Scale from PixelResolution (LOLA: 1.33333291 px/deg, not
  // 4/3): still the global 0.75° grid of the original, every sample and position the same.
  GDALAllRegister();
  const fs::path copy = scratch("lola_copy.cub");
  {
    Dataset in(GDALOpen(test::fixture("ldem_4_reduced.cub").c_str(), GA_ReadOnly));
    ASSERT_TRUE(in);
    Dataset out(GDALCreateCopy(GDALGetDriverByName("ISIS3"), copy.c_str(), in.get(), FALSE, nullptr,
                               nullptr, nullptr));
    ASSERT_TRUE(out);
  }
  const ImportReport a = importRaster(test::fixture("ldem_4_reduced.cub"), scratch("lola.h5"));
  const ImportReport b = importRaster(copy, scratch("lola_copy.h5"));
  EXPECT_EQ(b.info.kind, GridKind::Planet);
  EXPECT_EQ(b.info.spacingX, a.info.spacingX);
  EXPECT_EQ(b.info.spacingY, a.info.spacingY);
  EXPECT_NEAR(b.info.x0, a.info.x0, 1e-9);
  EXPECT_NEAR(b.info.y0, a.info.y0, 1e-9);
  std::vector<float> va(a.info.rows * a.info.cols), vb(va.size());
  Store::open(scratch("lola.h5")).readWindow(a.info.name, 0, 0, 0, a.info.rows, a.info.cols, va);
  Store::open(scratch("lola_copy.h5"))
      .readWindow(b.info.name, 0, 0, 0, b.info.rows, b.info.cols, vb);
  EXPECT_EQ(va, vb);
}

// ---- one tolerance for "at the pole" -----------------------------------------------------------

TEST(ImportTraits, AOneRowCropAtThePoleWithinTheSharedToleranceImportsAndOpens) {
  // The edge 0.5 kPoleOverhangPixels beyond the pole: both the importer and TopoPlanet accept.
  const double d = 0.5;
  Spec s;
  s.rows = 1;
  s.cols = 8;
  s.gt = {10.0, d, 0.0, 90.0 + 0.5 * topo::kPoleOverhangPixels * d, 0.0, -d};
  s.crs = kMoonGeographic;
  s.values = indexValues(s.rows, s.cols);
  const fs::path tif = write("crop_at_pole.tif", s);
  const fs::path store = scratch("crop_at_pole.h5");
  const ImportReport rep = importRaster(tif, store);
  EXPECT_EQ(rep.info.kind, GridKind::Planet);
  EXPECT_EQ(rep.info.rows, 1U);
  expectExact(store, rep, readGdal(tif));
}

TEST(ImportTraits, ACropBeyondTheSharedToleranceIsRefusedByTheImporterAsByTopoPlanet) {
  // The edge 2 kPoleOverhangPixels beyond the pole, its one row centred inside: TopoPlanet
  // refuses such a grid, so the import must not write it.
  const double d = 0.5, north = 90.0 + 2.0 * topo::kPoleOverhangPixels * d;
  Spec s;
  s.rows = 1;
  s.cols = 8;
  s.gt = {10.0, d, 0.0, north, 0.0, -d};
  s.crs = kMoonGeographic;
  s.values = indexValues(s.rows, s.cols);
  const fs::path tif = write("crop_beyond.tif", s);
  const fs::path store = scratch("crop_beyond.h5");
  EXPECT_EQ(errorOf([&] { (void)importRaster(tif, store); }),
            "store::importRaster(): " + tif.string() +
                ": georeferencing places the grid's edges at latitudes 90.01 to 89.51 deg, "
                "beyond a pole; expected within -90 to 90");
  EXPECT_FALSE(fs::exists(store));
  const topo::TopoGrid grid(1, 8, 10.25, north - 0.5 * d, d, d);
  EXPECT_THROW(
      topo::TopoPlanet(grid, topo::Body::moon(), topo::LatitudeType::Planetocentric,
                       std::make_shared<topo::InMemorySamples>(1, 8, std::vector<float>(8, 0.0F))),
      regolith::InvalidArgument);
}

// ---- rows beyond a pole: padding dropped, data refused -----------------------------------------

TEST(ImportTraits, AWhollyNullIsis3RowCentredBeyondThePoleIsDroppedAndReported) {
  // 181 rows of 1°: row 0 is centred at 90.5°N and entirely NULL (GDAL writes the nodata
  // value as ISIS's NULL).
  const double res = kMetresPerDegree;
  Spec s;
  s.rows = 181;
  s.cols = 360;
  s.gt = {-180.0 * res, res, 0.0, 91.0 * res, 0.0, -res};
  s.crs = moonEqc(180.0);
  s.values = indexValues(s.rows, s.cols);
  for (std::size_t c = 0; c < s.cols; ++c) s.values[c] = -1e30F;
  s.nodata = -1e30;
  s.driver = "ISIS3";
  const fs::path cube = write("padding_row.cub", s);
  const fs::path store = scratch("padding_row.h5");
  const ImportReport rep = importRaster(cube, store);
  EXPECT_EQ(rep.info.kind, GridKind::Planet);
  EXPECT_EQ(rep.info.rows, 180U);
  EXPECT_EQ(rep.droppedNorthRows, 1U);
  EXPECT_EQ(rep.droppedSouthRows, 0U);
  EXPECT_NEAR(rep.info.y0, 89.5, 1e-9);
  EXPECT_EQ(rep.missingSamples, 0U);
  expectExact(store, rep, readGdal(cube), 1);
}

TEST(ImportTraits, ARowCentredBeyondThePoleHoldingDataIsRefused) {
  const double res = kMetresPerDegree;
  Spec s;
  s.rows = 181;
  s.cols = 360;
  s.gt = {-180.0 * res, res, 0.0, 91.0 * res, 0.0, -res};
  s.crs = moonEqc(180.0);
  s.values = indexValues(s.rows, s.cols);
  s.driver = "ISIS3";
  const fs::path cube = write("data_row.cub", s);
  const fs::path store = scratch("data_row.h5");
  EXPECT_EQ(errorOf([&] { (void)importRaster(cube, store); }),
            "store::importRaster(): " + cube.string() +
                ": row 0 (centre latitude 90.5 deg) lie beyond the north pole and hold valid "
                "samples; expected within -90 to 90 (wholly missing rows beyond a pole are "
                "dropped)");
  EXPECT_FALSE(fs::exists(store));
}

TEST(ImportTraits, ARegionalDemWhoseRowsLieAt98NorthIsRefusedOrTrimmedLikeAPlanet) {
  // An equirectangular DEM (regional: 40 columns) from 99°N down to 80°N in 1° rows.
  const double res = kMetresPerDegree;
  Spec s;
  s.rows = 19;
  s.cols = 40;
  s.gt = {10.0 * res, res, 0.0, 99.0 * res, 0.0, -res};
  s.crs = moonEqc(0.0);
  s.values = indexValues(s.rows, s.cols);
  s.nodata = -9999.0;
  const fs::path tif = write("dem_98n.tif", s);
  EXPECT_EQ(errorOf([&] { (void)importRaster(tif, scratch("dem_98n.h5")); }),
            "store::importRaster(): " + tif.string() +
                ": rows 0-8 (centre latitude 98.5 to 90.5 deg) lie beyond the north pole and "
                "hold valid samples; expected within -90 to 90 (wholly missing rows beyond a "
                "pole are dropped)");
  // The same rows missing: dropped, and the rest imports exactly.
  for (std::size_t i = 0; i < 9 * s.cols; ++i) s.values[i] = -9999.0F;
  const fs::path padded = write("dem_98n_padded.tif", s);
  const fs::path store = scratch("dem_98n_padded.h5");
  const ImportReport rep = importRaster(padded, store);
  EXPECT_EQ(rep.info.kind, GridKind::Dem);
  EXPECT_EQ(rep.info.rows, 10U);
  EXPECT_EQ(rep.droppedNorthRows, 9U);
  expectExact(store, rep, readGdal(padded), 9);
}

// ---- longitudes that wrap --------------------------------------------------------------------

TEST(ImportTraits, AGeographicGridCentredOn180ReachingPastMinus180Imports) {
  // Columns from 170°E to 190°E (= −170°): queries at OSR's longitudes, which stay in
  // 170…190, and at the same longitudes wrapped to −180…180, reach every column.
  Spec s;
  s.rows = 10;
  s.cols = 20;
  s.gt = {170.0, 1.0, 0.0, 5.0, 0.0, -1.0};
  s.crs = kMoonGeographic;
  s.values = indexValues(s.rows, s.cols);
  const fs::path tif = write("across_180.tif", s);
  const fs::path store = scratch("across_180.h5");
  const ImportReport rep = importRaster(tif, store);
  Oracle o = readGdal(tif);
  expectExact(store, rep, o);
  for (double& lon : o.lon) lon = std::remainder(lon, 360.0);
  expectExact(store, rep, o);
}

TEST(ImportTraits, AnEquirectangularDemCentredOn180ReachingPastMinus180Imports) {
  // Projected metres on lon_0 = 180°: columns from 160°E to 200°E (= −160°), across ±180°.
  const double res = kMetresPerDegree;
  Spec s;
  s.rows = 10;
  s.cols = 40;
  s.gt = {-20.0 * res, res, 0.0, 10.0 * res, 0.0, -res};
  s.crs = moonEqc(180.0);
  s.values = indexValues(s.rows, s.cols);
  const fs::path tif = write("dem_across_180.tif", s);
  const fs::path store = scratch("dem_across_180.h5");
  const ImportReport rep = importRaster(tif, store);
  EXPECT_EQ(rep.info.kind, GridKind::Dem);
  EXPECT_EQ(rep.info.placement.lonCentreDeg, 180.0);
  Oracle o = readGdal(tif);
  expectExact(store, rep, o);
}

TEST(ImportTraits, AnEquirectangularDemWhoseColumnsLieAcross180FromItsMeridianImports) {
  // Projected metres on lon_0 = 0°: columns from 170°E to 190°E, x beyond πR.
  const double res = kMetresPerDegree;
  Spec s;
  s.rows = 10;
  s.cols = 20;
  s.gt = {170.0 * res, res, 0.0, 10.0 * res, 0.0, -res};
  s.crs = moonEqc(0.0);
  s.values = indexValues(s.rows, s.cols);
  const fs::path tif = write("dem_beyond_180.tif", s);
  const fs::path store = scratch("dem_beyond_180.h5");
  const ImportReport rep = importRaster(tif, store);
  EXPECT_EQ(rep.info.kind, GridKind::Dem);
  // Queried at GDAL's pixel centres in map metres: the placement's forward projection wraps
  // longitudes to −180…180 around the central meridian, so lon/lat queries beyond 180°E miss
  // until it follows PROJ's +over (issue 16, item 5).
  expectExact(store, rep, readGdal(tif), 0, true);
}

TEST(ImportTraits, AGeographicGridOfMoreThan360DegreesDropsItsRepeatedColumns) {
  // 362 columns of 1°: columns 360 and 361 repeat columns 0 and 1.
  Spec s;
  s.rows = 180;
  s.cols = 362;
  s.gt = {-180.0, 1.0, 0.0, 90.0, 0.0, -1.0};
  s.crs = kMoonGeographic;
  s.values = indexValues(s.rows, s.cols);
  for (std::size_t r = 0; r < s.rows; ++r) {
    for (std::size_t c = 360; c < s.cols; ++c)
      s.values[r * s.cols + c] = s.values[r * s.cols + c - 360];
  }
  const fs::path tif = write("wider_than_360.tif", s);
  const fs::path store = scratch("wider_than_360.h5");
  const ImportReport rep = importRaster(tif, store);
  EXPECT_EQ(rep.info.cols, 360U);
  EXPECT_EQ(rep.droppedColumns, 2U);
  Oracle o = readGdal(tif);
  expectExact(store, rep, o);
  // Queries at the dropped columns' centres return their (equal) twins.
  const topo::TopoPlanet planet = Pager(std::make_shared<const Store>(Store::open(store)),
                                        std::make_shared<PatchCache>(std::size_t{4} << 20))
                                      .planet(rep.info.name);
  for (std::size_t r = 0; r < s.rows; r += 17) {
    for (std::size_t c = 360; c < s.cols; ++c) {
      const std::size_t k = r * s.cols + c;
      const topo::HeightSample q =
          planet.height({o.lat[k], o.lon[k]}, topo::Interpolation::Nearest);
      ASSERT_TRUE(q.valid());
      EXPECT_EQ(q.height, o.heights[k]) << r << "," << c;
    }
  }
  // Repeated columns with other values are refused.
  s.values[5 * s.cols + 361] += 1.0F;
  const fs::path differs = write("wider_than_360_differs.tif", s);
  EXPECT_EQ(errorOf([&] { (void)importRaster(differs, scratch("differs.h5")); }),
            "store::importRaster(): " + differs.string() +
                ": grid spans 362 deg of longitude in 362 columns of 1 deg; column 361 repeats "
                "the longitude of column 1 with another value (row 5: 5002 vs 5001 m); expected "
                "at most 360 deg, or repeated columns equal to the first ones");
}
