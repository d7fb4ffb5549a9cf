// Height maps without georeferencing (ImportOptions::heightMap): 8- and 16-bit PNGs and a
// GeoTIFF without a CRS, made here with GDAL's drivers, import on the local tangent plane the
// options describe; every stored sample is GDAL's value × scale + offset, the store re-opens
// and its queries return the samples. Without the options the refusal names them.
#include <regolith/core/Error.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/TopoDem.hpp>

#include "RasterOracle.hpp"
#include "support/StoreScratch.hpp"

#include <gdal.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) { return test::scratchFile("height-map", name); }

/// A rows × cols raster of `type` through GDAL's `driver` (CreateCopy from MEM), without any
/// georeferencing; values (r·7 + c·13) mod `modulo`.
fs::path writePlain(const std::string& name, const char* driver, GDALDataType type,
                    std::size_t rows, std::size_t cols, int modulo) {
  GDALAllRegister();
  const auto w = static_cast<int>(cols), h = static_cast<int>(rows);
  test::Dataset mem(GDALCreate(GDALGetDriverByName("MEM"), "", w, h, 1, type, nullptr));
  EXPECT_TRUE(mem);
  std::vector<double> v(rows * cols);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      v[r * cols + c] = static_cast<double>(static_cast<int>(r * 7 + c * 13) % modulo);
    }
  }
  EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(mem.get(), 1), GF_Write, 0, 0, w, h, v.data(), w, h,
                         GDT_Float64, 0, 0),
            CE_None);
  const fs::path p = scratch(name);
  test::Dataset out(GDALCreateCopy(GDALGetDriverByName(driver), p.c_str(), mem.get(), FALSE,
                                   nullptr, nullptr, nullptr));
  EXPECT_TRUE(out) << p;
  return p;
}

/// GDAL's values of band 1, read as doubles.
std::vector<double> gdalValues(const fs::path& p, std::size_t rows, std::size_t cols) {
  test::Dataset ds(GDALOpen(p.c_str(), GA_ReadOnly));
  EXPECT_TRUE(ds);
  std::vector<double> v(rows * cols);
  const auto w = static_cast<int>(cols), h = static_cast<int>(rows);
  EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(ds.get(), 1), GF_Read, 0, 0, w, h, v.data(), w, h,
                         GDT_Float64, 0, 0),
            CE_None);
  return v;
}

ImportOptions heightMapOptions() {
  ImportOptions o;
  o.body = "Mars";
  HeightMapOptions h;
  h.spacingX = 2.0;
  h.spacingY = 3.0;
  h.heightScale = 0.25;
  h.heightOffset = -1400.0;
  h.originLatDeg = -2.05;
  h.originLonDeg = -5.5;
  h.headingDeg = 30.0;
  o.heightMap = h;
  return o;
}

/// Imports `p` with heightMapOptions(), re-opens the store and checks every sample and a
/// nearest query at every sample centre against GDAL's value × scale + offset, and that the
/// centre sample sits at the origin.
void expectHeightMap(const fs::path& p, std::size_t rows, std::size_t cols) {
  const ImportOptions o = heightMapOptions();
  const fs::path store = scratch(p.stem().string() + ".h5");
  const ImportReport rep = importRaster(p, store, o);
  const GridInfo& g = rep.info;
  ASSERT_EQ(g.rows, rows);
  ASSERT_EQ(g.cols, cols);
  EXPECT_EQ(g.kind, GridKind::Dem);
  EXPECT_EQ(g.placement.kind, PlacementInfo::Kind::LocalTangentPlane);
  EXPECT_EQ(g.bodyName, "Mars");
  EXPECT_EQ(g.polarRadius, 3376200.0);
  const std::vector<double> raw = gdalValues(p, rows, cols);
  const auto s = std::make_shared<const Store>(Store::open(store));
  std::vector<float> got(rows * cols);
  s->readWindow(g.name, 0, 0, 0, rows, cols, got);
  const topo::TopoDem dem =
      Pager(s, std::make_shared<PatchCache>(std::size_t{8} << 20)).dem(g.name);
  std::size_t bad = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const auto want = static_cast<float>(raw[r * cols + c] * 0.25 + -1400.0);
      const double x = g.x0 + static_cast<double>(c) * g.spacingX;
      const double y = g.y0 - static_cast<double>(r) * g.spacingY;
      const topo::HeightSample q = dem.height(x, y, topo::Interpolation::Nearest);
      if (got[r * cols + c] != want || !q.valid() || q.height != static_cast<double>(want)) ++bad;
    }
  }
  EXPECT_EQ(bad, 0U);
  // The centre sample (odd sizes) at the origin, on the reference surface at height 0.
  const topo::Placement pl = placementOf(g);
  const double cx = g.x0 + 0.5 * static_cast<double>(cols - 1) * g.spacingX;
  const double cy = g.y0 - 0.5 * static_cast<double>(rows - 1) * g.spacingY;
  const topo::Geodetic at = pl.toGeodetic(cx, cy, 0.0);
  EXPECT_NEAR(at.latDeg, -2.05, 1e-12);
  EXPECT_NEAR(at.lonDeg, -5.5, 1e-12);
  EXPECT_NEAR(at.height, 0.0, 1e-6);
  // The y axis at azimuth 30°: a step up the rows moves north-east.
  const topo::Geodetic up = pl.toGeodetic(cx, cy + 1000.0, 0.0);
  EXPECT_GT(up.latDeg, at.latDeg);
  EXPECT_GT(up.lonDeg, at.lonDeg);
}

}  // namespace

TEST(HeightMap, An8BitPngImportsWithTheGivenSpacingScaleAndPlacement) {
  expectHeightMap(writePlain("h8.png", "PNG", GDT_Byte, 21, 33, 256), 21, 33);
}

TEST(HeightMap, A16BitPngImportsWithTheGivenSpacingScaleAndPlacement) {
  expectHeightMap(writePlain("h16.png", "PNG", GDT_UInt16, 17, 25, 65536), 17, 25);
}

TEST(HeightMap, AGeotiffWithoutACrsImportsWithTheGivenSpacingScaleAndPlacement) {
  expectHeightMap(writePlain("plain.tif", "GTiff", GDT_Float32, 15, 19, 1000), 15, 19);
}

TEST(HeightMap, WithoutTheOptionsThePngIsRefusedNamingThem) {
  const fs::path p = writePlain("refused.png", "PNG", GDT_Byte, 5, 5, 256);
  const std::string msg = test::errorOf([&] { (void)importRaster(p, scratch("refused.h5")); });
  EXPECT_EQ(msg, "store::importRaster(): " + p.string() +
                     ": has no georeferencing (no coordinate reference system), expected a "
                     "georeferenced raster; a height map imports with its spacing and "
                     "placement: --spacing, --origin and --body, optionally --height-scale, "
                     "--height-offset and --heading (regolith import), or spacing=, origin=, "
                     "body=, height_scale=, height_offset=, heading= (regolith.import_raster())");
  EXPECT_FALSE(fs::exists(scratch("refused.h5")));
}

TEST(HeightMap, BadOptionsAndAGeoreferencedRasterAreRefused) {
  const fs::path p = writePlain("bad.png", "PNG", GDT_Byte, 5, 5, 256);
  ImportOptions o = heightMapOptions();
  o.body = "Vesta";
  EXPECT_EQ(test::errorOf([&] { (void)importRaster(p, scratch("bad.h5"), o); }),
            "store::importRaster(): " + p.string() +
                ": height map body is 'Vesta', expected Mars, Moon or Earth (--body; Python "
                "body=)");
  o = heightMapOptions();
  o.heightMap->spacingX = -1.0;
  EXPECT_EQ(test::errorOf([&] { (void)importRaster(p, scratch("bad.h5"), o); }),
            "store::importRaster(): " + p.string() +
                ": height map spacing x is -1, expected finite and > 0 (metres)");
  o = heightMapOptions();
  o.heightMap->heightScale = 0.0;
  EXPECT_EQ(test::errorOf([&] { (void)importRaster(p, scratch("bad.h5"), o); }),
            "store::importRaster(): " + p.string() +
                ": height map height scale is 0, expected finite and non-zero");
  EXPECT_FALSE(fs::exists(scratch("bad.h5")));
  // A georeferenced raster keeps its own georeferencing: the options are refused.
  test::Spec s;
  s.rows = 4;
  s.cols = 4;
  s.gt = {0.0, 1.0, 0.0, 0.0, 0.0, -1.0};
  s.crs = "+proj=longlat +R=1737400 +no_defs";
  s.values = test::indexValues(4, 4);
  const fs::path tif = test::writeRaster(scratch("georeferenced.tif"), s);
  const std::string msg =
      test::errorOf([&] { (void)importRaster(tif, scratch("bad.h5"), heightMapOptions()); });
  EXPECT_NE(msg.find(tif.string() + ": is georeferenced (CRS '"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected the height-map options (spacing, origin) only for a raster "
                     "without a coordinate reference system"),
            std::string::npos)
      << msg;
}
