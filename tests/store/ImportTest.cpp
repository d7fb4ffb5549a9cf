// GDAL import (importRaster, importTiles, describeRaster), with GDAL itself as the oracle:
// every real fixture (tests/data/dem) and a PDS4 copy of it is imported, read back
// with Store::readWindow and compared sample by sample with GDAL's pixel reads after
// scale/offset, nodata and special pixels; sample centres are compared with GDAL's
// geotransform and, through the placement, with PROJ (OGR) inverse projections. Tiles cut
// with GDAL must import as one grid equal to the single import. Bad inputs made with GDAL in
// the test must fail with messages naming the file and the reason.
#include <regolith/store/Import.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Placement.hpp>

#include "RasterOracle.hpp"
#include "support/Fixtures.hpp"
#include "support/StoreScratch.hpp"

#include <cpl_conv.h>
#include <cpl_json.h>
#include <gdal.h>
#include <gdal_utils.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;
using regolith::test::fixture;

namespace {

fs::path scratch(const std::string& name) { return test::scratchFile("import", name); }

struct DatasetCloser {
  void operator()(void* ds) const noexcept {
    if (ds != nullptr) GDALClose(ds);
  }
};
using DatasetPtr = std::unique_ptr<void, DatasetCloser>;

/// Sets a thread-local GDAL config option for a scope.
class ScopedConfig {
 public:
  ScopedConfig(const char* key, const char* value) : key_(key) {
    CPLSetThreadLocalConfigOption(key, value);
  }
  ~ScopedConfig() { CPLSetThreadLocalConfigOption(key_, nullptr); }
  ScopedConfig(const ScopedConfig&) = delete;
  ScopedConfig& operator=(const ScopedConfig&) = delete;

 private:
  const char* key_;
};

DatasetPtr openGdal(const fs::path& p, bool pdsShift = false) {
  GDALAllRegister();
  std::optional<ScopedConfig> s1, s2;
  if (pdsShift) {
    // GDAL's documented correction for PDS3 labels in the other offset convention (MOLA).
    s1.emplace("PDS_SampleProjOffset_Shift", "-0.5");
    s2.emplace("PDS_LineProjOffset_Shift", "-0.5");
  }
  DatasetPtr ds(GDALOpen(p.c_str(), GA_ReadOnly));
  if (!ds) throw std::runtime_error("GDAL cannot open " + p.string());
  return ds;
}

/// GDAL's view of a raster: raw values, mask, nodata, scale/offset, geotransform.
struct Oracle {
  std::size_t rows = 0, cols = 0;
  std::vector<double> raw;
  std::vector<unsigned char> mask;
  std::optional<double> nodata;
  double scale = 1.0, offset = 0.0;
  std::array<double, 6> gt{};
  bool declaresNothing = false;  // no nodata value, every sample valid per GDAL's mask
};

Oracle readGdal(const fs::path& p, bool pdsShift = false) {
  const DatasetPtr ds = openGdal(p, pdsShift);
  GDALRasterBandH b = GDALGetRasterBand(ds.get(), 1);
  Oracle o;
  o.cols = static_cast<std::size_t>(GDALGetRasterXSize(ds.get()));
  o.rows = static_cast<std::size_t>(GDALGetRasterYSize(ds.get()));
  o.raw.resize(o.rows * o.cols);
  o.mask.resize(o.rows * o.cols);
  const int w = static_cast<int>(o.cols), h = static_cast<int>(o.rows);
  EXPECT_EQ(GDALRasterIO(b, GF_Read, 0, 0, w, h, o.raw.data(), w, h, GDT_Float64, 0, 0), CE_None);
  EXPECT_EQ(
      GDALRasterIO(GDALGetMaskBand(b), GF_Read, 0, 0, w, h, o.mask.data(), w, h, GDT_Byte, 0, 0),
      CE_None);
  int has = 0;
  const double nd = GDALGetRasterNoDataValue(b, &has);
  if (has != 0) o.nodata = nd;
  o.declaresNothing = has == 0 && (GDALGetMaskFlags(b) & GMF_ALL_VALID) != 0;
  int ok = 0;
  const double s = GDALGetRasterScale(b, &ok);
  if (ok != 0) o.scale = s;
  const double off = GDALGetRasterOffset(b, &ok);
  if (ok != 0) o.offset = off;
  EXPECT_EQ(GDALGetGeoTransform(ds.get(), o.gt.data()), CE_None);
  return o;
}

/// What an import of a fixture must give, decided from the fixture's documentation.
struct Expect {
  GridKind kind;
  std::optional<PlacementInfo::Kind> placement;
  double radiusReference = 0.0;  // the values are radii of this sphere
  bool pdsShift = false;         // GDAL's default georeferencing is known off (MOLA)
  double pixelsPerDegree = 0.0;  // global grids: the label's exact resolution
  bool someMissing = true;
};

std::vector<float> readLevel(const Store& s, const std::string& grid, std::size_t level = 0) {
  const GridInfo& g = s.grid(grid);
  std::vector<float> v(g.levelRows(level) * g.levelCols(level));
  s.readWindow(grid, level, 0, 0, g.levelRows(level), g.levelCols(level), v);
  return v;
}

/// Stored samples equal GDAL's values after scale/offset (minus the radius reference), and
/// are missing exactly where GDAL's mask, nodata or NaN, ISIS's special pixels below
/// VALID_MIN4, or the −32768 void marker of a file declaring no nodata say so.
std::size_t expectSamplesMatch(const Store& s, const std::string& grid, const Oracle& o,
                               double radiusReference, const std::string& what) {
  const std::vector<float> got = readLevel(s, grid);
  EXPECT_EQ(got.size(), o.raw.size()) << what;
  std::size_t missing = 0, bad = 0;
  for (std::size_t i = 0; i < got.size() && i < o.raw.size(); ++i) {
    const double raw = o.raw[i];
    const bool isMissing = o.mask[i] == 0 || std::isnan(raw) || (o.nodata && raw == *o.nodata) ||
                           raw < -3.40282255e38 || (o.declaresNothing && raw == -32768.0);
    if (isMissing) {
      ++missing;
      if (!std::isnan(got[i]) && ++bad <= 5) {
        ADD_FAILURE() << what << ": sample " << i / o.cols << "," << i % o.cols << " is " << got[i]
                      << ", GDAL says missing (" << raw << ")";
      }
    } else {
      const auto want = static_cast<float>((o.offset - radiusReference) + o.scale * raw);
      if (!(got[i] == want) && ++bad <= 5) {
        ADD_FAILURE() << what << ": sample " << i / o.cols << "," << i % o.cols << " is " << got[i]
                      << ", GDAL gives " << want << " (raw " << raw << ")";
      }
    }
  }
  EXPECT_EQ(bad, 0U) << what;
  return missing;
}

/// lon/lat (degrees) of projected point (x, y) by OGR/PROJ, in the CRS's own geographic CRS.
std::array<double, 2> projInverse(OGRSpatialReferenceH srs, double x, double y) {
  OGRSpatialReferenceH geo = OSRCloneGeogCS(srs);
  OSRSetAxisMappingStrategy(geo, OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReferenceH src = OSRClone(srs);
  OSRSetAxisMappingStrategy(src, OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(src, geo);
  double px = x, py = y;
  EXPECT_TRUE(ct != nullptr && OCTTransform(ct, 1, &px, &py, nullptr) != 0);
  OCTDestroyCoordinateTransformation(ct);
  OSRDestroySpatialReference(src);
  OSRDestroySpatialReference(geo);
  return {px, py};
}

double lonDiff(double a, double b) { return std::remainder(a - b, 360.0); }

/// Sample centres: against GDAL's geotransform (metres or degrees), against the label's exact
/// resolution for a global grid, and through the placement against PROJ's inverse.
void expectGeoreferencing(const GridInfo& g, const fs::path& p, const Oracle& o, const Expect& e,
                          const std::string& what) {
  const DatasetPtr ds = openGdal(p, e.pdsShift);
  OGRSpatialReferenceH srs = GDALGetSpatialRef(ds.get());
  ASSERT_NE(srs, nullptr);
  OGRErr err = OGRERR_NONE;
  EXPECT_EQ(g.equatorialRadius, OSRGetSemiMajor(srs, &err)) << what;
  EXPECT_EQ(g.polarRadius, OSRGetSemiMinor(srs, &err)) << what;
  const std::vector<std::size_t> rows{0, o.rows / 2, o.rows - 1}, cols{0, o.cols / 3, o.cols - 1};
  for (const std::size_t r : rows) {
    for (const std::size_t c : cols) {
      const double gx = o.gt[0] + (static_cast<double>(c) + 0.5) * o.gt[1];
      const double gy = o.gt[3] + (static_cast<double>(r) + 0.5) * o.gt[5];
      const double x = g.x0 + static_cast<double>(c) * g.spacingX;
      const double y = g.y0 - static_cast<double>(r) * g.spacingY;
      const std::string at = what + " sample " + std::to_string(r) + "," + std::to_string(c);
      if (g.kind == GridKind::Dem) {
        EXPECT_NEAR(x, gx, 1e-3) << at;  // 1 mm
        EXPECT_NEAR(y, gy, 1e-3) << at;
        const auto ll = projInverse(srs, gx, gy);
        const topo::Geodetic geo = placementOf(g).toGeodetic(x, y, 0.0);
        EXPECT_NEAR(lonDiff(geo.lonDeg, ll[0]), 0.0, 1e-9) << at;
        EXPECT_NEAR(geo.latDeg, ll[1], 1e-9) << at;
      } else if (OSRIsGeographic(srs) != 0) {
        EXPECT_NEAR(x, gx, 1e-9) << at;
        EXPECT_NEAR(y, gy, 1e-9) << at;
      } else {
        // A global projected grid: GDAL's pixel offsets from the projection origin at the
        // label's exact resolution (the label's map scale in metres is rounded).
        ASSERT_GT(e.pixelsPerDegree, 0.0) << at;
        const double lon0 = OSRGetProjParm(srs, SRS_PP_CENTRAL_MERIDIAN, 0.0, nullptr);
        const double wantLon = lon0 + (gx / o.gt[1]) / e.pixelsPerDegree;
        const double wantLat = (gy / -o.gt[5]) / e.pixelsPerDegree;
        EXPECT_NEAR(x, wantLon, 1e-9) << at;
        EXPECT_NEAR(y, wantLat, 1e-9) << at;
        // PROJ on the rounded metres agrees within the rounding's drift (< 0.01°).
        const auto ll = projInverse(srs, gx, gy);
        EXPECT_NEAR(lonDiff(x, ll[0]), 0.0, 0.01) << at;
        EXPECT_NEAR(y, ll[1], 0.01) << at;
      }
    }
  }
}

ImportOptions smallPatches() {
  ImportOptions o;
  o.patchRows = 64;
  o.patchCols = 48;  // not square, not a divisor of any fixture's size
  o.threads = 2;
  return o;
}

/// Imports `raster` and checks it against GDAL; returns the report.
ImportReport checkImport(const fs::path& raster, const Expect& e, const std::string& storeName,
                         bool pdsShiftOracle) {
  const fs::path store = scratch(storeName);
  const ImportReport rep = importRaster(raster, store, smallPatches());
  const std::string what = raster.filename().string();
  const GridInfo& g = rep.info;
  EXPECT_EQ(g.kind, e.kind) << what;
  if (e.placement) {
    EXPECT_EQ(g.placement.kind, *e.placement) << what;
  }
  EXPECT_EQ(rep.radiusReference, e.radiusReference) << what;
  const Oracle o = readGdal(raster, pdsShiftOracle);
  EXPECT_EQ(g.rows, o.rows) << what;
  EXPECT_EQ(g.cols, o.cols) << what;
  const Store s = Store::open(store);
  const std::size_t missing = expectSamplesMatch(s, g.name, o, e.radiusReference, what);
  EXPECT_EQ(rep.missingSamples, missing) << what;
  EXPECT_EQ(missing > 0, e.someMissing) << what << ": " << missing << " missing";
  Expect e2 = e;
  e2.pdsShift = pdsShiftOracle;
  expectGeoreferencing(g, raster, o, e2, what);
  // describeRaster() agrees with the import, levels aside.
  const GridInfo d = describeRaster(raster, smallPatches());
  EXPECT_EQ(d.kind, g.kind);
  EXPECT_EQ(d.x0, g.x0);
  EXPECT_EQ(d.y0, g.y0);
  EXPECT_EQ(d.spacingX, g.spacingX);
  EXPECT_EQ(d.rows, g.rows);
  return rep;
}

void translate(const fs::path& src, const fs::path& dst, std::vector<std::string> args,
               bool pdsShift = false) {
  const DatasetPtr in = openGdal(src, pdsShift);
  CPLPushErrorHandler(CPLQuietErrorHandler);  // the PDS4 template's warnings
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  GDALTranslateOptions* opts = GDALTranslateOptionsNew(argv.data(), nullptr);
  if (opts == nullptr) CPLPopErrorHandler();
  ASSERT_NE(opts, nullptr);
  int usageError = 0;
  const DatasetPtr out(GDALTranslate(dst.c_str(), in.get(), opts, &usageError));
  GDALTranslateOptionsFree(opts);
  CPLPopErrorHandler();
  ASSERT_TRUE(out) << "gdal_translate " << src << " -> " << dst;
}

/// The fixture, imported, and its PDS4 copy made with GDAL's PDS4 driver, imported too: same
/// grid, and the copy's samples equal GDAL's reads of the copy.
void checkFixture(const std::string& name, const Expect& e) {
  const fs::path src = fixture(name);
  const ImportReport rep = checkImport(src, e, fs::path(name).stem().string() + ".h5", e.pdsShift);
  const fs::path copy = scratch(fs::path(name).stem().string() + "_pds4.xml");
  // GDAL's PDS4 writer labels latitudes planetocentric by default, and its reader then takes
  // the body for a sphere; an ellipsoidal transverse Mercator source is copied as
  // planetographic so that the copy keeps its ellipsoid.
  const bool tm = rep.info.kind == GridKind::Dem &&
                  rep.info.placement.kind == PlacementInfo::Kind::TransverseMercator;
  std::vector<std::string> args{"-of", "PDS4"};
  if (tm) args.insert(args.end(), {"-co", "LATITUDE_TYPE=Planetographic"});
  translate(src, copy, args, e.pdsShift);
  Expect e4 = e;
  if (OSRIsGeographic(GDALGetSpatialRef(openGdal(src).get())) != 0) {
    e4.kind = GridKind::Dem;  // see below
    e4.placement = PlacementInfo::Kind::Equirectangular;
  }
  const ImportReport rep4 =
      checkImport(copy, e4, fs::path(name).stem().string() + "_pds4.h5", false);
  EXPECT_EQ(rep4.driver, "PDS4");
  const GridInfo &a = rep.info, &b = rep4.info;
  if (a.kind == GridKind::Planet && b.kind == GridKind::Dem) {
    // A geographic source: GDAL's PDS4 writer has no geographic CRS and writes equirectangular
    // metres on a sphere of the semi-major radius instead. The copy then is an equirectangular
    // DEM whose samples still sit at the original's longitudes and latitudes.
    EXPECT_EQ(b.placement.kind, PlacementInfo::Kind::Equirectangular) << name;
    for (const std::size_t r : {std::size_t{0}, a.rows - 1}) {
      for (const std::size_t c : {std::size_t{0}, a.cols / 2, a.cols - 1}) {
        const double rr = static_cast<double>(r), cc = static_cast<double>(c);
        const topo::Geodetic g =
            placementOf(b).toGeodetic(b.x0 + cc * b.spacingX, b.y0 - rr * b.spacingY, 0.0);
        EXPECT_NEAR(lonDiff(g.lonDeg, a.x0 + cc * a.spacingX), 0.0, 1e-9) << name;
        EXPECT_NEAR(g.latDeg, a.y0 - rr * a.spacingY, 1e-9) << name;
      }
    }
    return;
  }
  EXPECT_EQ(a.kind, b.kind) << name;
  if (tm) {
    // GDAL's PDS4 writer has no false easting/northing for transverse Mercator: it moves the
    // geotransform by them instead. The samples still sit at the same places on the body.
    ASSERT_EQ(b.placement.kind, PlacementInfo::Kind::TransverseMercator) << name;
    EXPECT_EQ(a.equatorialRadius, b.equatorialRadius) << name;
    EXPECT_NEAR(a.polarRadius, b.polarRadius, 1e-6) << name;
    EXPECT_NEAR(a.x0 - a.placement.falseEasting, b.x0 - b.placement.falseEasting, 1e-6) << name;
    EXPECT_NEAR(a.y0 - a.placement.falseNorthing, b.y0 - b.placement.falseNorthing, 1e-6) << name;
    for (const std::size_t r : {std::size_t{0}, a.rows - 1}) {
      for (const std::size_t c : {std::size_t{0}, a.cols - 1}) {
        const double rr = static_cast<double>(r), cc = static_cast<double>(c);
        const topo::Geodetic ga =
            placementOf(a).toGeodetic(a.x0 + cc * a.spacingX, a.y0 - rr * a.spacingY, 0.0);
        const topo::Geodetic gb =
            placementOf(b).toGeodetic(b.x0 + cc * b.spacingX, b.y0 - rr * b.spacingY, 0.0);
        EXPECT_NEAR(ga.latDeg, gb.latDeg, 1e-9) << name;
        EXPECT_NEAR(lonDiff(ga.lonDeg, gb.lonDeg), 0.0, 1e-9) << name;
      }
    }
  } else {
    EXPECT_NEAR(a.x0, b.x0, 1e-9 * std::max(1.0, std::abs(a.x0))) << name;
    EXPECT_NEAR(a.y0, b.y0, 1e-9 * std::max(1.0, std::abs(a.y0))) << name;
  }
  EXPECT_NEAR(a.spacingX, b.spacingX, 1e-12 * a.spacingX) << name;
  EXPECT_NEAR(a.spacingY, b.spacingY, 1e-12 * a.spacingY) << name;
  EXPECT_EQ(a.latitudeType, b.latitudeType) << name;
}

using regolith::test::errorOf;  // tests/store/RasterOracle.hpp

}  // namespace

// ---- every fixture, and its PDS4 copy ------------------------------------------------------

TEST(Import, MolaMegdrPds3IsAGlobalPlanetGridCorrectedByOnePixelAndSnappedToQuarterDegrees) {
  Expect e{GridKind::Planet, std::nullopt, 0.0, true, 4.0, false};
  checkFixture("megt90n000cb.lbl", e);
  const ImportReport rep = importRaster(fixture("megt90n000cb.lbl"), scratch("mola2.h5"));
  EXPECT_EQ(rep.driver, "PDS");
  EXPECT_TRUE(rep.offsetCorrected);
  const ImportReport seen = inspectRaster(fixture("megt90n000cb.lbl"));
  EXPECT_EQ(seen.driver, "PDS");
  EXPECT_TRUE(seen.offsetCorrected);
  EXPECT_TRUE(seen.spacingSnapped);
  EXPECT_EQ(seen.info.x0, rep.info.x0);
  EXPECT_NE(seen.projection.find("Equirectangular"), std::string::npos) << seen.projection;
  EXPECT_TRUE(rep.spacingSnapped);
  // The README's placement: 0°…360°E, 90°S…90°N, centres at 0.125° + k·0.25°.
  EXPECT_EQ(rep.info.spacingX, 0.25);
  EXPECT_EQ(rep.info.spacingY, 0.25);
  EXPECT_NEAR(rep.info.x0, 0.125, 1e-12);
  EXPECT_NEAR(rep.info.y0, 89.875, 1e-12);
  EXPECT_EQ(rep.info.equatorialRadius, 3396000.0);  // the label's sphere
  EXPECT_EQ(rep.info.latitudeType, topo::LatitudeType::Planetocentric);
  // The trap itself: GDAL's default reading is one pixel west and north of that.
  const Oracle o = readGdal(fixture("megt90n000cb.lbl"), false);
  EXPECT_DOUBLE_EQ(o.gt[0], -721.0 * 14818.0);
  EXPECT_DOUBLE_EQ(o.gt[3], 361.0 * 14818.0);
}

TEST(Import, LolaIsis3ScaledRadiiBecomeHeightsOnAGlobalMoonGrid) {
  Expect e{GridKind::Planet, std::nullopt, 1737400.0, false, 4.0 / 3.0, false};
  checkFixture("ldem_4_reduced.cub", e);
  const GridInfo g = describeRaster(fixture("ldem_4_reduced.cub"));
  EXPECT_EQ(g.spacingX, 0.75);
  EXPECT_EQ(g.bodyName, "Moon");
}

TEST(Import, Ulcn2005PartialTilesRegionalSimpleCylindricalBecomesAnEquirectangularDem) {
  Expect e{GridKind::Dem, PlacementInfo::Kind::Equirectangular, 1737400.0, false, 0.0, false};
  checkFixture("ulcn2005_lpo_npole.cub", e);
}

TEST(Import, VestaSpecialPixelsAreMissingAndRadiiBecomeHeights) {
  Expect e{GridKind::Dem, PlacementInfo::Kind::Equirectangular, 289000.0, false, 0.0, true};
  checkFixture("vest64_dtm_specialpixels_downsampled.cub", e);
  // The special pixels that are not GDAL's nodata value (HRS, 0xFF7FFFFF) are missing too.
  const Oracle o = readGdal(fixture("vest64_dtm_specialpixels_downsampled.cub"));
  std::size_t hrs = 0;
  for (const double v : o.raw) hrs += v < -3.40282255e38 && v != *o.nodata ? 1U : 0U;
  EXPECT_GT(hrs, 0U);
}

namespace {

/// Gives a GDAL raster made by a test its geotransform, a geographic CRS on Mars's sphere
/// and nodata -32768.
void placeOnMarsSphere(GDALDatasetH ds, std::array<double, 6> gt) {
  GDALSetGeoTransform(ds, gt.data());
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRSetFromUserInput(srs, "+proj=longlat +R=3396190 +no_defs");
  GDALSetSpatialRef(ds, srs);
  OSRDestroySpatialReference(srs);
  GDALSetRasterNoDataValue(GDALGetRasterBand(ds, 1), -32768.0);
}

/// Bytes this process has read through read() and pread() so far (/proc/self/io, rchar).
std::uint64_t bytesRead() {
  std::ifstream in("/proc/self/io");
  std::string key;
  std::uint64_t value = 0;
  while (in >> key >> value) {
    if (key == "rchar:") return value;
  }
  return 0;
}

}  // namespace

TEST(Import, TheLookForRadiiReadsAFewTilesOfATiledRaster) {
  // A 2048² float GeoTIFF in 64² tiles (16 KiB each) holding radii of Mars's sphere, with
  // nodata in its first tile row. The look for radii used to read a tile per sample of its
  // 16×16 look (256 tiles, 4 MiB; 64 MiB of an 8192² file in 256² tiles, 0.3 s at each open);
  // it now reads at most 16 tiles and still finds the radii.
  GDALAllRegister();
  const fs::path p = scratch("tiled_radii.tif");
  constexpr int kSide = 2048, kTile = 64;
  {
    const char* opts[] = {"TILED=YES", "BLOCKXSIZE=64", "BLOCKYSIZE=64", nullptr};
    DatasetPtr ds(GDALCreate(GDALGetDriverByName("GTiff"), p.c_str(), kSide, kSide, 1, GDT_Float32,
                             const_cast<char**>(opts)));  // NOLINT
    ASSERT_TRUE(ds);
    std::vector<float> v(std::size_t{kSide} * kSide);
    for (std::size_t i = 0; i < v.size(); ++i) {
      v[i] = i < std::size_t{kSide} * kTile ? -32768.0F
                                            : 3396190.0F + static_cast<float>(i % 4093) * 0.5F;
    }
    ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds.get(), 1), GF_Write, 0, 0, kSide, kSide, v.data(),
                           kSide, kSide, GDT_Float32, 0, 0),
              CE_None);
    placeOnMarsSphere(ds.get(), {10.0, 0.001, 0.0, 5.0, 0.0, -0.001});
  }
  const std::uint64_t before = bytesRead();
  const ImportReport rep = inspectRaster(p);
  const std::uint64_t read = bytesRead() - before;
  std::cout << "[ measured ] the look for radii of a 2048² raster in 64² tiles read " << read
            << " bytes\n";
  EXPECT_EQ(rep.radiusReference, 3396190.0);  // found below the nodata tile row
  // 16 tiles of 16 KiB and the file's header and tile index (8 KiB each way); 256 tiles
  // were 4 MiB.
  EXPECT_LT(read, std::uint64_t{1} << 20);
  // The heights: the radii less the sphere's, as GDAL reads them.
  const ImportReport imported = importRaster(p, scratch("tiled_radii.h5"), smallPatches());
  const Store s = Store::open(scratch("tiled_radii.h5"));
  EXPECT_EQ(imported.radiusReference, 3396190.0);
  float h = 0.0F;
  s.readWindow(imported.info.name, 0, 100, 7, 1, 1, std::span<float>(&h, 1));
  const float radius = 3396190.0F + static_cast<float>((100 * kSide + 7) % 4093) * 0.5F;
  EXPECT_EQ(h, static_cast<float>(static_cast<double>(radius) - 3396190.0));
}

TEST(Import, HiriseDtmIsAnEquirectangularDemInMetres) {
  Expect e{GridKind::Dem, PlacementInfo::Kind::Equirectangular, 0.0, false, 0.0, true};
  checkFixture("Ares4_Marth_Crater_3557E_126N_ngate_03_lowres.cub", e);
  const GridInfo g = describeRaster(fixture("Ares4_Marth_Crater_3557E_126N_ngate_03_lowres.cub"));
  EXPECT_EQ(g.placement.projectionRadius, 3396190.0);
  EXPECT_EQ(g.placement.lonCentreDeg, 180.0);
  EXPECT_EQ(g.bodyName, "Mars");
}

TEST(Import, TheLabelsLatitudeTypeIsCarriedOver) {
  // The HiRISE cube with its label's LatitudeType changed in place (same length, so the cube
  // stays valid): Planetocentric -> Planetographic.
  const fs::path src = fixture("Ares4_Marth_Crater_3557E_126N_ngate_03_lowres.cub");
  std::ifstream in(src, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t n = 0;
  for (std::size_t at = bytes.find("Planetocentric"); at != std::string::npos;
       at = bytes.find("Planetocentric", at)) {
    bytes.replace(at, 14, "Planetographic");
    ++n;
  }
  ASSERT_GT(n, 0U);
  const fs::path copy = scratch("marth_planetographic.cub");
  std::ofstream(copy, std::ios::binary) << bytes;
  EXPECT_EQ(describeRaster(src).latitudeType, topo::LatitudeType::Planetocentric);
  EXPECT_EQ(describeRaster(copy).latitudeType, topo::LatitudeType::Planetodetic);
}

TEST(Import, PolarStereographicIsis3LabelAllNullIsAnAllMissingDem) {
  Expect e{GridKind::Dem, PlacementInfo::Kind::PolarStereographic, 0.0, false, 0.0, true};
  checkFixture("Polar_Crater_1_1m_ngate_edited2_forPDS_lowres.cub", e);
  const ImportReport rep = importRaster(
      fixture("Polar_Crater_1_1m_ngate_edited2_forPDS_lowres.cub"), scratch("polar2.h5"));
  EXPECT_EQ(rep.missingSamples, rep.info.rows * rep.info.cols);
  EXPECT_EQ(rep.info.placement.pole, 1);
  ASSERT_TRUE(rep.info.placement.scaleFactor.has_value());
  EXPECT_EQ(*rep.info.placement.scaleFactor, 1.0);
}

TEST(Import, LolaSouthPolarGeotiffIsAPolarStereographicDemWithNanNodata) {
  Expect e{GridKind::Dem, PlacementInfo::Kind::PolarStereographic, 0.0, false, 0.0, false};
  checkFixture("Shoemaker_1k.tif", e);
  EXPECT_EQ(describeRaster(fixture("Shoemaker_1k.tif")).placement.pole, -1);
}

TEST(Import, SrtmHgtIsAGeographicPlanetGridOnWgs84) {
  Expect e{GridKind::Planet, std::nullopt, 0.0, false, 0.0, false};
  checkFixture("S11E119.hgt", e);
  const GridInfo g = describeRaster(fixture("S11E119.hgt"));
  EXPECT_NEAR(g.x0, 119.0, 1e-12);  // SRTM samples sit on whole arc-seconds
  EXPECT_NEAR(g.y0, -10.0, 1e-12);
  EXPECT_EQ(g.bodyName, "Earth");
  EXPECT_EQ(g.latitudeType, topo::LatitudeType::Planetodetic);
  EXPECT_NE(g.equatorialRadius, g.polarRadius);
}

TEST(Import, VoidsOfAFileDeclaringNoNodataAreMissingNotHeights) {
  const fs::path src = fixture("dem_unfinished.tif");
  const ImportReport rep = importRaster(src, scratch("unfinished.h5"), smallPatches());
  EXPECT_TRUE(rep.voidMarkerAssumed);
  const Oracle o = readGdal(src);
  ASSERT_TRUE(o.declaresNothing);
  std::size_t voids = 0;
  for (const double v : o.raw) voids += v == -32768.0 ? 1 : 0;
  EXPECT_GT(voids, 0U);
  EXPECT_EQ(rep.missingSamples, voids);
  Expect e{GridKind::Planet, std::nullopt, 0.0, false, 0.0, true};
  checkFixture("dem_unfinished.tif", e);
}

TEST(Import, Nad27UtmGeotiffIsATransverseMercatorDemOnClarke1866WithNodataMissing) {
  // dem_nodata.dem: a 65×65 int16 GeoTIFF (despite its name), NAD27 / UTM zone 10N, nodata
  // −32767 (fixtures README). Its PDS4 copy made with GDAL imports to the same grid.
  Expect e{GridKind::Dem, PlacementInfo::Kind::TransverseMercator, 0.0, false, 0.0, true};
  checkFixture("dem_nodata.dem", e);
  const ImportReport rep = importRaster(fixture("dem_nodata.dem"), scratch("utm.h5"));
  const GridInfo& g = rep.info;
  EXPECT_EQ(rep.driver, "GTiff");
  EXPECT_NE(rep.projection.find("NAD27 / UTM zone 10N (Transverse_Mercator)"), std::string::npos)
      << rep.projection;
  EXPECT_EQ(g.bodyName, "Earth");
  EXPECT_EQ(g.equatorialRadius, 6378206.4);  // Clarke 1866, from the CRS
  EXPECT_NEAR(g.polarRadius, 6356583.8, 1e-3);
  EXPECT_EQ(g.latitudeType, topo::LatitudeType::Planetodetic);
  EXPECT_EQ(g.placement.lonCentreDeg, -123.0);
  EXPECT_EQ(g.placement.latOriginDeg, 0.0);
  EXPECT_EQ(g.placement.scaleFactor, std::optional<double>(0.9996));
  EXPECT_EQ(g.placement.falseEasting, 500000.0);
  EXPECT_EQ(g.placement.falseNorthing, 0.0);
  // Every −32767 sample is missing, and only those (GDAL's count of them, independently).
  const Oracle o = readGdal(fixture("dem_nodata.dem"));
  ASSERT_EQ(o.nodata, std::optional<double>(-32767.0));
  std::size_t nodata = 0;
  for (const double v : o.raw) nodata += v == -32767.0 ? 1U : 0U;
  EXPECT_GT(nodata, 0U);
  EXPECT_EQ(rep.missingSamples, nodata);
  // Transverse Mercator needs 1.2; the import's height statistics make it 1.3.
  EXPECT_EQ(Store::open(scratch("utm.h5")).formatVersion(), (std::array<int, 2>{1, 4}));
}

namespace {

/// Runs a shell command; returns its standard output.
std::string run(const std::string& command) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  if (!pipe) return {};
  std::string out;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe.get())) > 0) out.append(buf.data(), n);
  return out;
}

}  // namespace

TEST(Import, EverySampleCentreOfTheUtmFixtureHasTheLatLonGdaltransformGivesInNad27) {
  // `gdaltransform -t_srs EPSG:4267 dem_nodata.dem` maps pixel/line coordinates through the
  // file's geotransform and PROJ to NAD27 longitude/latitude: the pixel centres are
  // (col + 0.5, row + 0.5). The imported placement must give the same, to 1e-9°, and map them
  // back to the sample centres to 1 mm.
  const fs::path src = fixture("dem_nodata.dem");
  const ImportReport rep = importRaster(src, scratch("utm-gdaltransform.h5"));
  const GridInfo& g = rep.info;
  const fs::path in = scratch("utm-pixel-centres.txt");
  {
    std::ofstream f(in);
    f.precision(17);
    for (std::size_t r = 0; r < g.rows; ++r) {
      for (std::size_t c = 0; c < g.cols; ++c) {
        f << static_cast<double>(c) + 0.5 << ' ' << static_cast<double>(r) + 0.5 << '\n';
      }
    }
  }
  const std::string out =
      run("gdaltransform -t_srs EPSG:4267 '" + src.string() + "' < '" + in.string() + "'");
  std::istringstream lines(out);
  const topo::Placement pl = placementOf(Store::open(scratch("utm-gdaltransform.h5")).grid(g.name));
  double worstDeg = 0.0, worstM = 0.0;
  std::size_t n = 0;
  for (std::size_t r = 0; r < g.rows; ++r) {
    for (std::size_t c = 0; c < g.cols; ++c) {
      double lon = std::nan(""), lat = std::nan(""), z = 0.0;
      ASSERT_TRUE(lines >> lon >> lat >> z)
          << "gdaltransform output after " << n << " points: " << out.substr(0, 500);
      const double x = g.x0 + static_cast<double>(c) * g.spacingX;
      const double y = g.y0 - static_cast<double>(r) * g.spacingY;
      const topo::Geodetic geo = pl.toGeodetic(x, y, 0.0);
      EXPECT_NEAR(geo.latDeg, lat, 1e-9) << r << "," << c;
      EXPECT_NEAR(lonDiff(geo.lonDeg, lon), 0.0, 1e-9) << r << "," << c;
      worstDeg =
          std::max({worstDeg, std::abs(geo.latDeg - lat), std::abs(lonDiff(geo.lonDeg, lon))});
      const glm::dvec3 back = pl.fromGeodetic({lat, lon, 0.0});
      EXPECT_NEAR(back.x, x, 1e-3) << r << "," << c;
      EXPECT_NEAR(back.y, y, 1e-3) << r << "," << c;
      worstM = std::max({worstM, std::abs(back.x - x), std::abs(back.y - y)});
      ++n;
    }
  }
  EXPECT_EQ(n, 65U * 65U);
  std::cout << "[ measured ] utm fixture: lat/lon vs gdaltransform max " << worstDeg
            << " deg; gdaltransform lat/lon mapped back vs sample centres max " << worstM << " m\n";
}

// ---- imported grids answer queries: the kind decides TopoPlanet or TopoDem -----------------

TEST(Import, ImportedGridsAnswerTopoQueriesWithGdalsValuesAtGdalsPixelCentres) {
  struct Case {
    std::string file;
    bool pdsShift;
    double pixelsPerDegree;  // global projected grids: the label's resolution
  };
  for (const Case& k :
       {Case{"megt90n000cb.lbl", true, 4.0}, Case{"ldem_4_reduced.cub", false, 4.0 / 3.0},
        Case{"S11E119.hgt", false, 0.0}, Case{"Shoemaker_1k.tif", false, 0.0},
        Case{"vest64_dtm_specialpixels_downsampled.cub", false, 0.0},
        Case{"ulcn2005_lpo_npole.cub", false, 0.0}, Case{"dem_nodata.dem", false, 0.0}}) {
    SCOPED_TRACE(k.file);
    const fs::path store = scratch("query.h5");
    const ImportReport rep = importRaster(fixture(k.file), store, smallPatches());
    const Oracle o = readGdal(fixture(k.file), k.pdsShift);
    const DatasetPtr ds = openGdal(fixture(k.file), k.pdsShift);
    const bool geographic = OSRIsGeographic(GDALGetSpatialRef(ds.get())) != 0;
    const double lon0 =
        OSRGetProjParm(GDALGetSpatialRef(ds.get()), SRS_PP_CENTRAL_MERIDIAN, 0.0, nullptr);
    auto pager = std::make_shared<Pager>(std::make_shared<const Store>(Store::open(store)),
                                         std::make_shared<PatchCache>(std::size_t{8} << 20));
    std::size_t checked = 0;
    for (std::size_t r = 0; r < o.rows; r += o.rows / 7 + 1) {
      for (std::size_t c = 0; c < o.cols; c += o.cols / 9 + 1) {
        const double gx = o.gt[0] + (static_cast<double>(c) + 0.5) * o.gt[1];
        const double gy = o.gt[3] + (static_cast<double>(r) + 0.5) * o.gt[5];
        topo::HeightSample h;
        if (rep.info.kind == GridKind::Dem) {
          h = pager->dem(rep.info.name).height(gx, gy, topo::Interpolation::Nearest);
        } else if (geographic) {
          h = pager->planet(rep.info.name).height({gy, gx}, topo::Interpolation::Nearest);
        } else {
          const topo::LatLon ll{(gy / -o.gt[5]) / k.pixelsPerDegree,
                                lon0 + (gx / o.gt[1]) / k.pixelsPerDegree};
          h = pager->planet(rep.info.name).height(ll, topo::Interpolation::Nearest);
        }
        const double raw = o.raw[r * o.cols + c];
        const bool missing = o.mask[r * o.cols + c] == 0 || std::isnan(raw) ||
                             (o.nodata && raw == *o.nodata) || raw < -3.40282255e38;
        if (missing) {
          EXPECT_FALSE(h.valid()) << r << "," << c;
        } else {
          ASSERT_TRUE(h.valid()) << r << "," << c;
          EXPECT_EQ(h.height, static_cast<double>(static_cast<float>(
                                  (o.offset - rep.radiusReference) + o.scale * raw)))
              << r << "," << c;
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 5U);
  }
}

// ---- bad input ---------------------------------------------------------------------------

namespace {

/// A GeoTIFF made with GDAL: `bands` bands of `type`, a geotransform and a CRS from `crs`.
fs::path makeGeotiff(const std::string& name, int bands, GDALDataType type, const char* crs,
                     const std::array<double, 6>& gt) {
  GDALAllRegister();
  const fs::path p = scratch(name);
  GDALDriverH drv = GDALGetDriverByName("GTiff");
  char* opts[] = {const_cast<char*>("PHOTOMETRIC=RGB"), nullptr};
  DatasetPtr ds(GDALCreate(drv, p.c_str(), 16, 12, bands, type, bands == 3 ? opts : nullptr));
  if (!ds) throw std::runtime_error("cannot create " + p.string());
  std::vector<float> v(16 * 12);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(i % 200);
  for (int b = 1; b <= bands; ++b) {
    EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(ds.get(), b), GF_Write, 0, 0, 16, 12, v.data(), 16, 12,
                           GDT_Float32, 0, 0),
              CE_None);
  }
  std::array<double, 6> g = gt;
  GDALSetGeoTransform(ds.get(), g.data());
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  EXPECT_EQ(OSRSetFromUserInput(srs, crs), OGRERR_NONE);
  GDALSetSpatialRef(ds.get(), srs);
  OSRDestroySpatialReference(srs);
  return p;
}

}  // namespace

TEST(ImportErrors, AGridOffItsProjectionsMapIsRefused) {
  // Any projected CRS imports through PROJ (tests/store/ProjPlacementTest.cpp), but an
  // orthographic grid centred beyond the horizon has no position on the body.
  const fs::path p =
      makeGeotiff("ortho.tif", 1, GDT_Float32, "+proj=ortho +lat_0=0 +lon_0=0 +R=3396190 +units=m",
                  {5000000.0, 100.0, 0.0, 5000.0, 0.0, -100.0});
  const std::string msg = errorOf([&] { (void)importRaster(p, scratch("ortho.h5")); });
  EXPECT_EQ(msg, "store::importRaster(): " + p.string() +
                     ": the grid's centre (x 5000800, y 4400 m) is off the map of unknown "
                     "(Orthographic), expected a grid on the projection's map");
  EXPECT_FALSE(fs::exists(scratch("ortho.h5")));
}

TEST(ImportErrors, AnRgbImageIsNotADem) {
  const fs::path p =
      makeGeotiff("rgb.tif", 3, GDT_Byte, "EPSG:4326", {10.0, 0.1, 0.0, 50.0, 0.0, -0.1});
  const std::string msg = errorOf([&] { (void)importRaster(p, scratch("rgb.h5")); });
  EXPECT_EQ(msg, "store::importRaster(): " + p.string() +
                     ": has 3 bands (red, green, blue), expected one elevation band (an RGB "
                     "image is not a DEM)");
  EXPECT_FALSE(fs::exists(scratch("rgb.h5")));
}

TEST(ImportErrors, AFileGdalCannotOpenOrThatDoesNotExist) {
  const fs::path p = scratch("garbage.tif");
  std::ofstream(p) << "this is not a raster\n";
  std::string msg = errorOf([&] { (void)importRaster(p, scratch("garbage.h5")); });
  EXPECT_NE(msg.find("store::importRaster(): " + p.string() + ": GDAL cannot open it as a raster"),
            std::string::npos)
      << msg;
  msg = errorOf([&] { (void)describeRaster(scratch("nowhere.tif")); });
  EXPECT_EQ(msg, "store::describeRaster(): " + scratch("nowhere.tif").string() + ": no such file");
  EXPECT_FALSE(fs::exists(scratch("garbage.h5")));
}

TEST(ImportErrors, ARasterWithoutGeoreferencing) {
  GDALAllRegister();
  const fs::path p = scratch("plain.tif");
  {
    DatasetPtr ds(
        GDALCreate(GDALGetDriverByName("GTiff"), p.c_str(), 8, 8, 1, GDT_Float32, nullptr));
    ASSERT_TRUE(ds);
  }
  const std::string msg = errorOf([&] { (void)describeRaster(p); });
  EXPECT_EQ(msg, "store::describeRaster(): " + p.string() +
                     ": has no georeferencing (no coordinate reference system), expected a "
                     "georeferenced raster; a height map imports with its spacing and "
                     "placement: --spacing, --origin and --body, optionally --height-scale, "
                     "--height-offset and --heading (regolith import), or spacing=, origin=, "
                     "body=, height_scale=, height_offset=, heading= (regolith.import_raster())");
}

namespace {
/// A NOAA NGS geoid grid (GDAL's NGSGEOID driver) of nothing but its 44-byte header: south
/// latitude, west longitude, latitude and longitude steps (float64), rows, columns and kind
/// (int32, 1 = float32), little-endian. GDAL opens it from the header alone, so a few bytes
/// declare whatever geometry they like.
fs::path ngsGeoidHeader(const std::string& name, double south, double west, double step,
                        std::int32_t rows, std::int32_t cols) {
  static_assert(std::endian::native == std::endian::little);
  const fs::path p = scratch(name);
  std::ofstream f(p, std::ios::binary);
  for (const double d : {south, west, step, step}) {
    f.write(reinterpret_cast<const char*>(&d), sizeof d);  // NOLINT(*-reinterpret-cast)
  }
  for (const std::int32_t i : {rows, cols, std::int32_t{1}}) {
    f.write(reinterpret_cast<const char*>(&i), sizeof i);  // NOLINT(*-reinterpret-cast)
  }
  return p;
}
}  // namespace

TEST(ImportErrors, ABlockBeyond256MiBIsRefusedBeforeAnyRead) {
  // Found by fuzz_info_json (stop 31): 48 bytes declaring rows of 1.1e9 samples in one block
  // each made GDAL allocate 4.5 GB to read one sample. Here 2 rows of 3e8 float32 samples:
  // blocks of 1.1 GiB, from a 44-byte file.
  GDALAllRegister();
  const fs::path p = ngsGeoidHeader("huge_block.bin", 10.0, 20.0, 1e-6, 2, 300'000'000);
  ASSERT_EQ(fs::file_size(p), 44U);
  std::string msg = errorOf([&] { (void)describeRaster(p); });
  EXPECT_EQ(msg, "store::describeRaster(): " + p.string() +
                     ": band 1 is stored in blocks of 300000000 x 1 samples of Float32 "
                     "(1144.40917969 MiB), expected at most 256 MiB per block (GDAL reads "
                     "whole blocks)");
  msg = errorOf([&] { (void)importRaster(p, scratch("huge_block.h5")); });
  EXPECT_NE(msg.find("store::importRaster(): " + p.string() + ": band 1 is stored in blocks"),
            std::string::npos)
      << msg;
  EXPECT_FALSE(fs::exists(scratch("huge_block.h5")));
  // The same header with rows GDAL reads in blocks of 12 bytes is not refused for its blocks.
  const fs::path small = ngsGeoidHeader("small_block.bin", 10.0, 20.0, 1e-6, 2, 3);
  msg = errorOf([&] { (void)describeRaster(small); });
  EXPECT_EQ(msg.find("blocks"), std::string::npos) << msg;
}

namespace {
// ThreadSanitizer's shadow memory (several bytes per byte the program touches) is in RSS, so
// there the peak measures TSan, not the import's allocations (1.1 GB for the same run).
#if defined(__SANITIZE_THREAD__)
constexpr bool kRssMeasuresAllocations = false;
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
constexpr bool kRssMeasuresAllocations = false;
#else
constexpr bool kRssMeasuresAllocations = true;
#endif
#else
constexpr bool kRssMeasuresAllocations = true;
#endif

/// The process's peak resident KiB since the last resetPeakRss() (VmHWM).
long peakRssKiB() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}
/// Resets VmHWM to the current RSS (Linux ≥ 4.0: "5" to clear_refs).
bool resetPeakRss() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  return static_cast<bool>(f.flush());
}
}  // namespace

TEST(ImportErrors, RowsBeyondAPoleOfAVeryWideRasterAreCheckedInBoundedMemory) {
  // Found by fuzz_import (stop 31): the check that the rows beyond a pole are wholly missing
  // read them in one piece, 4 GB for a header declaring 10^9 columns. A sparse tiled GeoTIFF
  // (nothing written, so every sample is the nodata value) of 2^27 columns whose first row's
  // centre lies beyond the north pole: that row was one read of 512 MiB (the test then fails:
  // the peak grows by more than 448 MiB); in pieces of 4 MiB it stays far below.
  GDALAllRegister();
  const fs::path p = scratch("wide_beyond_pole.tif");
  constexpr int kCols = 1 << 27, kRows = 3;
  const double dx = 360.0 / kCols;
  {
    const char* opts[] = {"TILED=YES", "BLOCKXSIZE=512", "BLOCKYSIZE=16", "SPARSE_OK=TRUE",
                          nullptr};
    DatasetPtr ds(GDALCreate(GDALGetDriverByName("GTiff"), p.c_str(), kCols, kRows, 1, GDT_Float32,
                             const_cast<char**>(opts)));  // NOLINT
    ASSERT_TRUE(ds);
    // Row 0 half a pixel beyond the pole.
    placeOnMarsSphere(ds.get(), {-180.0, dx, 0.0, 90.0 + dx, 0.0, -dx});
  }
  ASSERT_LT(fs::file_size(p), std::uintmax_t{64} << 20);
  // GDAL's own block cache (5 % of RAM by default) would fill with the sparse tiles read:
  // 64 MiB here, restored after, so that the peak is the import's own memory.
  const GIntBig cacheMax = GDALGetCacheMax64();
  GDALSetCacheMax64(GIntBig{64} << 20);
  ASSERT_TRUE(resetPeakRss());
  const long before = peakRssKiB();
  ASSERT_GT(before, 0);
  const GridInfo g = describeRaster(p);
  const long grew = peakRssKiB() - before;
  GDALSetCacheMax64(cacheMax);
  std::cout << "[ measured ] rows beyond a pole, 2^27 columns: peak RSS grew by " << grew
            << " KiB\n";
  EXPECT_EQ(g.rows, 2U);  // the row beyond the pole, wholly missing, dropped
  EXPECT_EQ(g.cols, static_cast<std::size_t>(kCols));
  // The old single read allocated (and zeroed) 512 MiB for that row alone: +705 MB in all.
  // In pieces the peak grows by GDAL's cache and buffers and a few pieces: about 200 MB in a
  // Release build, 296 MB under AddressSanitizer (its quarantine keeps freed blocks).
  // Under TSan (kRssMeasuresAllocations false) the bound is the Release and ASan builds';
  // the import must still answer.
  if (kRssMeasuresAllocations) {
    EXPECT_LT(grew, 448L * 1024) << "peak RSS grew by " << grew << " KiB";
  }
}

TEST(ImportErrors, ANonFiniteGeotransformIsRefusedNamingItsTerms) {
  // The geoid header with a NaN south edge: GDAL reports the origin's latitude as NaN.
  GDALAllRegister();
  const fs::path p =
      ngsGeoidHeader("nan_origin.bin", std::numeric_limits<double>::quiet_NaN(), 20.0, 0.25, 2, 3);
  const std::string msg = errorOf([&] { (void)describeRaster(p); });
  EXPECT_EQ(msg, "store::describeRaster(): " + p.string() +
                     ": geotransform has a non-finite term (origin 19.875, nan, pixel size 0.25 "
                     "x -0.25, rotation 0, 0), expected finite numbers");
}

// ---- tiles -----------------------------------------------------------------------------------

namespace {

/// Cuts `src` into a 2×2 set of tiles with gdal_translate -srcwin; returns their paths.
std::vector<fs::path> cutTiles(const fs::path& src, const std::string& stem, std::size_t rows,
                               std::size_t cols, const std::string& format = "GTiff") {
  const std::size_t r1 = rows / 2 + 3, c1 = cols / 2 - 5;  // unequal pieces
  std::vector<fs::path> out;
  const std::array<std::array<std::size_t, 4>, 4> wins{{{0, 0, r1, c1},
                                                        {0, c1, r1, cols - c1},
                                                        {r1, 0, rows - r1, c1},
                                                        {r1, c1, rows - r1, cols - c1}}};
  for (std::size_t i = 0; i < wins.size(); ++i) {
    const auto& w = wins[i];
    const fs::path t =
        scratch(stem + "_tile" + std::to_string(i) + (format == "GTiff" ? ".tif" : ".xml"));
    translate(src, t,
              {"-of", format, "-srcwin", std::to_string(w[1]), std::to_string(w[0]),
               std::to_string(w[3]), std::to_string(w[2])});
    out.push_back(t);
  }
  return out;
}

void expectSameGrids(const Store& a, const std::string& ga, const Store& b, const std::string& gb) {
  const GridInfo &x = a.grid(ga), &y = b.grid(gb);
  ASSERT_EQ(x.rows, y.rows);
  ASSERT_EQ(x.cols, y.cols);
  EXPECT_NEAR(x.x0, y.x0, 1e-9 * std::max(1.0, std::abs(x.x0)));
  EXPECT_NEAR(x.y0, y.y0, 1e-9 * std::max(1.0, std::abs(x.y0)));
  EXPECT_EQ(x.spacingX, y.spacingX);
  EXPECT_EQ(x.kind, y.kind);
  ASSERT_EQ(x.levels, y.levels);
  for (std::size_t k = 0; k < x.levels; ++k) {
    const std::vector<float> u = readLevel(a, ga, k), v = readLevel(b, gb, k);
    std::size_t bad = 0;
    for (std::size_t i = 0; i < u.size(); ++i) {
      if (!((std::isnan(u[i]) && std::isnan(v[i])) || u[i] == v[i])) ++bad;
    }
    EXPECT_EQ(bad, 0U) << "level " << k;
  }
}

}  // namespace

TEST(ImportTiles, TilesCutWithGdalImportAsOneGridEqualToTheSingleImport) {
  for (const std::string name :
       {"S11E119.hgt", "Shoemaker_1k.tif", "ldem_4_reduced.cub", "dem_nodata.dem"}) {
    SCOPED_TRACE(name);
    const fs::path src = fixture(name);
    const GridInfo whole = describeRaster(src);
    const std::vector<fs::path> tiles =
        cutTiles(src, fs::path(name).stem().string(), whole.rows, whole.cols);
    const ImportOptions o = smallPatches();
    const ImportReport single = importRaster(src, scratch("single.h5"), o);
    ImportOptions ot = o;
    ot.gridName = single.info.name;
    // Given in a shuffled order: placement comes from the georeferencing, not the order.
    const std::vector<fs::path> shuffled{tiles[3], tiles[0], tiles[2], tiles[1]};
    const ImportReport tiled = importTiles(shuffled, scratch("tiled.h5"), ot);
    EXPECT_EQ(tiled.tiles, 4U);
    const Store a = Store::open(scratch("single.h5")), b = Store::open(scratch("tiled.h5"));
    EXPECT_TRUE(b.tiled(single.info.name));
    expectSameGrids(a, single.info.name, b, single.info.name);
    // The mosaic's height statistics are the single import's, to the bit (chunk order).
    const std::optional<HeightStatistics> sa = a.grid(single.info.name).statistics,
                                          sb = b.grid(single.info.name).statistics;
    ASSERT_TRUE(sa && sb);
    EXPECT_EQ(sb->validSamples, sa->validSamples);
    EXPECT_EQ(sb->min, sa->min);
    EXPECT_EQ(sb->max, sa->max);
    EXPECT_EQ(sb->mean, sa->mean);
    // Its provenance lists every tile's files (a PDS4 tile is its label, its image and the
    // sidecar files GDAL lists beside them).
    CPLJSONDocument doc;
    ASSERT_TRUE(doc.LoadMemory(b.grid(single.info.name).provenance));
    const CPLJSONArray sources = doc.GetRoot().GetArray("sources");
    std::set<std::string> paths;
    for (int i = 0; i < sources.Size(); ++i) paths.insert(sources[i].GetString("path"));
    for (const fs::path& t : tiles) EXPECT_EQ(paths.count(t.string()), 1U) << t;
    // Imports store height statistics: format 1.3 (which reads tiles and transverse
    // Mercator too).
    EXPECT_EQ(b.formatVersion(), (std::array<int, 2>{1, 4}));
    EXPECT_EQ(b.grid(single.info.name).placement.kind, single.info.placement.kind);
  }
}

TEST(ImportTiles, TilesWithDifferentSpacingCrsOrAlignmentAreRefusedNamingTheTile) {
  const fs::path src = fixture("Shoemaker_1k.tif");
  const std::vector<fs::path> tiles = cutTiles(src, "shoe", 256, 256);
  // Different spacing: the same window at half resolution.
  const fs::path coarse = scratch("shoe_coarse.tif");
  translate(src, coarse, {"-srcwin", "0", "0", "128", "128", "-outsize", "64", "64"});
  std::vector<fs::path> set{tiles[0], coarse};
  std::string msg = errorOf([&] { (void)importTiles(set, scratch("bad.h5")); });
  EXPECT_NE(msg.find("store::importTiles(): " + coarse.string() + ": tile does not fit " +
                     tiles[0].string() + ": different spacing 10 x 10 (first tile: 5 x 5)"),
            std::string::npos)
      << msg;
  // Different CRS: tile 1 relabelled as north polar.
  const fs::path north = scratch("shoe_north.tif");
  translate(tiles[1], north,
            {"-a_srs", "+proj=stere +lat_0=90 +lat_ts=90 +lon_0=0 +R=1737400 +units=m"});
  set = {tiles[0], north};
  msg = errorOf([&] { (void)importTiles(set, scratch("bad.h5")); });
  EXPECT_NE(msg.find(north.string() + ": tile does not fit " + tiles[0].string() + ": different"),
            std::string::npos)
      << msg;
  // Misaligned by a third of a sample.
  const fs::path shifted = scratch("shoe_shifted.tif");
  const Oracle o = readGdal(tiles[1]);
  translate(tiles[1], shifted,
            {"-a_ullr", std::to_string(o.gt[0] + 5.0 / 3.0), std::to_string(o.gt[3]),
             std::to_string(o.gt[0] + 5.0 / 3.0 + 5.0 * static_cast<double>(o.cols)),
             std::to_string(o.gt[3] - 5.0 * static_cast<double>(o.rows))});
  set = {tiles[0], shifted};
  msg = errorOf([&] { (void)importTiles(set, scratch("bad.h5")); });
  EXPECT_NE(msg.find(shifted.string() + ": tile does not fit " + tiles[0].string() +
                     ": its samples are offset by"),
            std::string::npos)
      << msg;
  // Overlapping: the same tile twice.
  set = {tiles[0], tiles[1], tiles[1]};
  msg = errorOf([&] { (void)importTiles(set, scratch("bad.h5")); });
  EXPECT_NE(msg.find(tiles[1].string() + ": tile overlaps " + tiles[1].string()), std::string::npos)
      << msg;
  EXPECT_FALSE(fs::exists(scratch("bad.h5")));
}

// ---- interruption and progress -------------------------------------------------------------

TEST(ImportProgress, ProgressIsMonotonicAndEndsAtOne) {
  std::vector<double> seen;
  ImportOptions o = smallPatches();
  o.progress = [&](double f, std::string_view) { seen.push_back(f); };
  (void)importRaster(fixture("S11E119.hgt"), scratch("progress.h5"), o);
  ASSERT_GT(seen.size(), 10U);
  for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_GE(seen[i], seen[i - 1]) << i;
  EXPECT_EQ(seen.back(), 1.0);
  EXPECT_GE(seen.front(), 0.0);
}

TEST(ImportProgress, ACancelledImportLeavesNoFile) {
  std::atomic<bool> cancel{false};
  ImportOptions o = smallPatches();
  o.cancel = &cancel;
  o.progress = [&](double f, std::string_view) {
    if (f > 0.3) cancel = true;
  };
  const fs::path p = scratch("cancelled.h5");
  try {
    (void)importRaster(fixture("S11E119.hgt"), p, o);
    ADD_FAILURE() << "no exception";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("cancelled"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(p));
  for (const auto& entry : fs::directory_iterator(p.parent_path())) {
    EXPECT_EQ(entry.path().filename().string().find("cancelled.h5.tmp"), std::string::npos)
        << entry.path();
  }
}

TEST(ImportProgress, AKilledImportLeavesNoStoreUnderTheFinalName) {
  const fs::path p = scratch("killed.h5");
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(fds[0]);
    ImportOptions o = smallPatches();
    bool told = false;
    o.progress = [&](double f, std::string_view) {
      if (!told && f >= 0.5) {
        told = true;
        const char c = 'k';
        (void)!::write(fds[1], &c, 1);
        for (;;) ::pause();  // mid-import, temporary file open, until SIGKILL
      }
    };
    try {
      (void)importRaster(fixture("S11E119.hgt"), p, o);
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  ::close(fds[1]);
  char c = 0;
  EXPECT_EQ(::read(fds[0], &c, 1), 1) << "the import ended before half way";
  ::close(fds[0]);
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_FALSE(fs::exists(p));
  EXPECT_THROW((void)Store::open(p), StoreError);
}

// ---- the pyramid is built by threads; the result does not depend on how many ---------------

TEST(ImportThreads, OneThreadAndSeveralThreadsWriteTheSameStore) {
  ImportOptions o = smallPatches();
  o.deflate = 4;
  o.threads = 1;
  const ImportReport one = importRaster(fixture("S11E119.hgt"), scratch("threads1.h5"), o);
  o.threads = 3;
  const ImportReport three = importRaster(fixture("S11E119.hgt"), scratch("threads3.h5"), o);
  EXPECT_GT(one.info.levels, 3U);
  const Store a = Store::open(scratch("threads1.h5")), b = Store::open(scratch("threads3.h5"));
  expectSameGrids(a, one.info.name, b, three.info.name);
  // Level 1 is the 2×2 mean of GDAL's samples, ignoring missing ones (an outside check of
  // the parallel pyramid, not only a comparison of two runs).
  const Oracle g = readGdal(fixture("S11E119.hgt"));
  const std::vector<float> l1 = readLevel(b, three.info.name, 1);
  const std::size_t cols1 = (g.cols + 1) / 2;
  std::size_t bad = 0;
  for (std::size_t r = 0; r < (g.rows + 1) / 2; ++r) {
    for (std::size_t c = 0; c < cols1; ++c) {
      double sum = 0.0;
      int n = 0;
      for (std::size_t dr = 0; dr < 2; ++dr) {
        for (std::size_t dc = 0; dc < 2; ++dc) {
          const std::size_t rr = 2 * r + dr, cc = 2 * c + dc;
          if (rr >= g.rows || cc >= g.cols) continue;
          const double v = g.raw[rr * g.cols + cc];
          if (v == -32768.0) continue;
          sum += static_cast<double>(static_cast<float>(v));
          ++n;
        }
      }
      const float want = n > 0 ? static_cast<float>(sum / n) : std::nanf("");
      const float got = l1[r * cols1 + c];
      if (!((std::isnan(want) && std::isnan(got)) || want == got)) ++bad;
    }
  }
  EXPECT_EQ(bad, 0U);
}

// ---- transverse Mercator beyond the fixture: south zones, other origins and ellipsoids ------

TEST(Import, TransverseMercatorGeotiffsOfAnyZoneAndOriginPlaceTheirSamplesWherePROJDoes) {
  struct Case {
    const char* file;
    const char* crs;
    std::array<double, 6> gt;
    double lon0, lat0, k0, fe, fn, a;
  };
  // WGS 84 / UTM 33S (false northing 10,000 km), the British National Grid (Airy 1830,
  // origin 49°N 2°W, k0 0.9996012717, negative false northing), and a Mars ellipsoid zone
  // 7° wide of its central meridian with a latitude of origin south of the equator.
  const std::vector<Case> cases{
      {"utm33s.tif",
       "EPSG:32733",
       {430000.0, 30.0, 0.0, 7900000.0, 0.0, -30.0},
       15.0,
       0.0,
       0.9996,
       500000.0,
       10000000.0,
       6378137.0},
      {"bng.tif",
       "EPSG:27700",
       {529000.0, 5.0, 0.0, 181000.0, 0.0, -5.0},
       -2.0,
       49.0,
       0.9996012717,
       400000.0,
       -100000.0,
       6377563.396},
      {"mars_tm.tif",
       "+proj=tmerc +lat_0=-20 +lon_0=137.4 +k=1 +x_0=250000 +y_0=0 +a=3396190 +b=3376200 "
       "+units=m",
       {650000.0, 200.0, 0.0, 300000.0, 0.0, -200.0},
       137.4,
       -20.0,
       1.0,
       250000.0,
       0.0,
       3396190.0},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.file);
    const fs::path p = makeGeotiff(k.file, 1, GDT_Float32, k.crs, k.gt);
    const ImportReport rep = importRaster(p, scratch(std::string(k.file) + ".h5"), smallPatches());
    const GridInfo& g = rep.info;
    ASSERT_EQ(g.kind, GridKind::Dem);
    ASSERT_EQ(g.placement.kind, PlacementInfo::Kind::TransverseMercator);
    EXPECT_NEAR(g.placement.lonCentreDeg, k.lon0, 1e-12);
    EXPECT_NEAR(g.placement.latOriginDeg, k.lat0, 1e-12);
    EXPECT_EQ(g.placement.scaleFactor, std::optional<double>(k.k0));
    EXPECT_EQ(g.placement.falseEasting, k.fe);
    EXPECT_EQ(g.placement.falseNorthing, k.fn);
    EXPECT_EQ(g.equatorialRadius, k.a);
    // Values, and sample centres against GDAL's geotransform and PROJ's inverse (OGR) at the
    // corners and middle, as for every fixture.
    const Oracle o = readGdal(p);
    const Store s = Store::open(scratch(std::string(k.file) + ".h5"));
    EXPECT_EQ(expectSamplesMatch(s, g.name, o, 0.0, k.file), 0U);
    expectGeoreferencing(g, p, o, Expect{GridKind::Dem, PlacementInfo::Kind::TransverseMercator},
                         k.file);
  }
}

// ---- windows, bounding boxes, the body's name ------------------------------------------------

namespace {

/// The store's level 0 equals GDAL's samples of `w` (after scale/offset), and its geometry is
/// the full grid's moved by the window.
void expectWindow(const fs::path& raster, const ImportReport& rep, const GridInfo& full,
                  const SampleWindow& w, bool pdsShift) {
  ASSERT_TRUE(rep.window);
  EXPECT_EQ(rep.window->row0, w.row0);
  EXPECT_EQ(rep.window->col0, w.col0);
  const GridInfo& g = rep.info;
  EXPECT_EQ(g.rows, w.rows);
  EXPECT_EQ(g.cols, w.cols);
  EXPECT_EQ(g.x0, full.x0 + static_cast<double>(w.col0) * full.spacingX);
  EXPECT_EQ(g.y0, full.y0 - static_cast<double>(w.row0) * full.spacingY);
  EXPECT_EQ(g.spacingX, full.spacingX);
  const Oracle o = readGdal(raster, pdsShift);
  const Store s = Store::open(scratch("window.h5"));
  const std::vector<float> got = readLevel(s, g.name);
  std::size_t bad = 0;
  for (std::size_t r = 0; r < g.rows; ++r) {
    for (std::size_t c = 0; c < g.cols; ++c) {
      const std::size_t k = (w.row0 + r) * o.cols + w.col0 + c;
      const double raw = o.raw[k];
      const bool missing = o.mask[k] == 0 || std::isnan(raw) || (o.nodata && raw == *o.nodata);
      const float want = missing ? std::nanf("") : static_cast<float>(o.offset + o.scale * raw);
      const float have = got[r * g.cols + c];
      if (!(have == want || (std::isnan(have) && std::isnan(want))) && ++bad <= 5) {
        ADD_FAILURE() << r << "," << c << ": " << have << " vs GDAL " << want;
      }
    }
  }
  EXPECT_EQ(bad, 0U);
}

}  // namespace

TEST(ImportWindow, AWindowOfTheMolaGridIsItsSamplesAndOpensAsAPlanet) {
  const fs::path src = fixture("megt90n000cb.lbl");
  const GridInfo full = describeRaster(src);
  ImportOptions o = smallPatches();
  o.window = SampleWindow{100, 200, 50, 60};
  const ImportReport rep = importRaster(src, scratch("window.h5"), o);
  EXPECT_TRUE(rep.offsetCorrected);  // decided on the whole grid, before the window
  expectWindow(src, rep, full, *o.window, true);
  // The store opens and answers at its samples' centres.
  Pager pager(std::make_shared<const Store>(Store::open(scratch("window.h5"))),
              std::make_shared<PatchCache>(std::size_t{4} << 20));
  const topo::TopoPlanet planet = pager.planet(rep.info.name);
  const std::vector<float> got = readLevel(Store::open(scratch("window.h5")), rep.info.name);
  for (std::size_t r = 0; r < rep.info.rows; r += 7) {
    for (std::size_t c = 0; c < rep.info.cols; c += 9) {
      const topo::HeightSample h =
          planet.height({rep.info.y0 - static_cast<double>(r) * rep.info.spacingY,
                         rep.info.x0 + static_cast<double>(c) * rep.info.spacingX},
                        topo::Interpolation::Nearest);
      ASSERT_TRUE(h.valid());
      EXPECT_EQ(h.height, static_cast<double>(got[r * rep.info.cols + c]));
    }
  }
  o.window = SampleWindow{700, 0, 30, 10};
  EXPECT_EQ(errorOf([&] { (void)importRaster(src, scratch("window2.h5"), o); }),
            "store::importRaster(): " + src.string() +
                ": window of 30 rows x 10 cols from row 700, col 0 is empty or leaves the grid "
                "of 720 rows x 1440 cols; expected a non-empty window inside it");
  o.bbox = std::array<double, 4>{1.0, 2.0, 3.0, 4.0};
  EXPECT_EQ(errorOf([&] { (void)importRaster(src, scratch("window2.h5"), o); }),
            "store::importRaster(): " + src.string() +
                ": both a window and a bounding box given; expected one");
}

TEST(ImportWindow, ABoundingBoxTakesTheSamplesWhoseCentresLieInside) {
  const fs::path src = fixture("megt90n000cb.lbl");
  const GridInfo full = describeRaster(src);
  ImportOptions o = smallPatches();
  const std::array<double, 4> box{137.0, -6.1, 138.3, -5.0};  // Gale crater, roughly
  o.bbox = box;
  const ImportReport rep = importRaster(src, scratch("window.h5"), o);
  ASSERT_TRUE(rep.window);
  const SampleWindow w = *rep.window;
  // Every centre inside the box, and the next row or column out on each side outside it.
  const auto lon = [&](double c) { return full.x0 + c * full.spacingX; };
  const auto lat = [&](double r) { return full.y0 - r * full.spacingY; };
  const double r0 = static_cast<double>(w.row0), c0 = static_cast<double>(w.col0);
  const double r1 = r0 + static_cast<double>(w.rows) - 1.0;
  const double c1 = c0 + static_cast<double>(w.cols) - 1.0;
  EXPECT_GE(lon(c0), box[0]);
  EXPECT_LT(lon(c0 - 1.0), box[0]);
  EXPECT_LE(lon(c1), box[2]);
  EXPECT_GT(lon(c1 + 1.0), box[2]);
  EXPECT_LE(lat(r0), box[3]);
  EXPECT_GT(lat(r0 - 1.0), box[3]);
  EXPECT_GE(lat(r1), box[1]);
  EXPECT_LT(lat(r1 + 1.0), box[1]);
  expectWindow(src, rep, full, w, true);
  // The same box given in −180…180 longitudes, and one across the grid's seam at 0°.
  o.bbox = std::array<double, 4>{137.0 - 360.0, -6.1, 138.3 - 360.0, -5.0};
  EXPECT_EQ(importRaster(src, scratch("window.h5"), o).window->col0, w.col0);
  o.bbox = std::array<double, 4>{-10.0, 0.0, 10.0, 5.0};
  EXPECT_EQ(errorOf([&] { (void)importRaster(src, scratch("window2.h5"), o); }),
            "store::importRaster(): " + src.string() +
                ": bounding box -10, 0, 10, 5 crosses the grid's seam at 0 deg longitude; "
                "expected a box within 0 to 360 (import the two sides apart)");
}

TEST(ImportWindow, ABoundingBoxOnAPolarStereographicDemHoldsTheBoxsOutline) {
  const fs::path src = fixture("Shoemaker_1k.tif");
  const GridInfo full = describeRaster(src);
  // A box around the grid's centre sample.
  const topo::Placement pl = placementOf(full);
  const double xc = full.x0 + 128.0 * full.spacingX, yc = full.y0 - 128.0 * full.spacingY;
  const topo::Geodetic centre = pl.toGeodetic(xc, yc, 0.0);
  ImportOptions o = smallPatches();
  o.bbox = std::array<double, 4>{centre.lonDeg - 0.3, centre.latDeg - 0.002, centre.lonDeg + 0.3,
                                 centre.latDeg + 0.002};
  const ImportReport rep = importRaster(src, scratch("window.h5"), o);
  ASSERT_TRUE(rep.window);
  expectWindow(src, rep, full, *rep.window, false);
  // The window's centres span the box's corners to within one sample: it takes the samples
  // whose centres lie in the rectangle around the box's outline.
  const GridInfo& g = rep.info;
  const double east = g.x0 + static_cast<double>(g.cols - 1) * g.spacingX;
  const double south = g.y0 - static_cast<double>(g.rows - 1) * g.spacingY;
  for (const double la : {(*o.bbox)[1], (*o.bbox)[3]}) {
    for (const double lo : {(*o.bbox)[0], (*o.bbox)[2]}) {
      const glm::dvec3 p = pl.fromGeodetic({la, lo, 0.0});
      EXPECT_GT(p.x, g.x0 - g.spacingX);
      EXPECT_LT(p.x, east + g.spacingX);
      EXPECT_LT(p.y, g.y0 + g.spacingY);
      EXPECT_GT(p.y, south - g.spacingY);
    }
  }
  EXPECT_LT(rep.info.rows, full.rows);
  EXPECT_LT(rep.info.cols, full.cols);
}

TEST(ImportWindow, TheBodyOptionNamesTheBodyTheCrsDoesNot) {
  const fs::path tif =
      makeGeotiff("unnamed_body.tif", 1, GDT_Float32, "+proj=longlat +R=1737400 +no_defs",
                  {10.0, 0.5, 0.0, 20.0, 0.0, -0.5});
  EXPECT_EQ(describeRaster(tif).bodyName, "unknown");
  ImportOptions o;
  o.body = "Moon";
  const ImportReport rep = importRaster(tif, scratch("body.h5"), o);
  EXPECT_EQ(rep.info.bodyName, "Moon");
  EXPECT_EQ(Store::open(scratch("body.h5")).grid(rep.info.name).bodyName, "Moon");
  EXPECT_EQ(rep.info.equatorialRadius, 1737400.0);  // the radii stay the CRS's
}

// ---- height statistics ---------------------------------------------------------------------

/// GDAL's sample i as the store holds it (metres above the reference radius, through float),
/// or nothing where the import counts it missing.
std::optional<double> oracleHeight(const Oracle& o, std::size_t i, double radiusReference) {
  const double raw = o.raw[i];
  if (o.mask[i] == 0 || std::isnan(raw) || (o.nodata && raw == *o.nodata) || raw < -3.40282255e38 ||
      (o.declaresNothing && raw == -32768.0)) {
    return std::nullopt;
  }
  return static_cast<double>(static_cast<float>((o.offset - radiusReference) + o.scale * raw));
}

TEST(ImportStatistics, TheStoreRecordsMinMaxMeanAndValidCountOfGdalsHeights) {
  for (const char* name : {"vest64_dtm_specialpixels_downsampled.cub", "dem_unfinished.tif",
                           "Polar_Crater_1_1m_ngate_edited2_forPDS_lowres.cub"}) {
    SCOPED_TRACE(name);
    const ImportReport rep = importRaster(fixture(name), scratch("stats.h5"), smallPatches());
    const Oracle o = readGdal(fixture(name));
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0;
    std::uint64_t valid = 0;
    for (std::size_t i = 0; i < o.raw.size(); ++i) {
      const std::optional<double> sample = oracleHeight(o, i, rep.radiusReference);
      if (!sample) continue;
      const double h = *sample;
      lo = std::min(lo, h);
      hi = std::max(hi, h);
      sum += h;
      ++valid;
    }
    const Store s = Store::open(scratch("stats.h5"));
    const std::optional<HeightStatistics> st = s.grid(rep.info.name).statistics;
    ASSERT_TRUE(st);
    EXPECT_EQ(st->validSamples, valid);
    EXPECT_EQ(st->validSamples, rep.info.rows * rep.info.cols - rep.missingSamples);
    if (valid == 0) {  // the all-NULL polar cube
      EXPECT_TRUE(std::isnan(st->min) && std::isnan(st->max) && std::isnan(st->mean));
      continue;
    }
    EXPECT_EQ(st->min, lo);
    EXPECT_EQ(st->max, hi);
    EXPECT_NEAR(st->mean, sum / static_cast<double>(valid),
                1e-12 * std::abs(sum / static_cast<double>(valid)));
    EXPECT_EQ(s.formatVersion(), (std::array<int, 2>{1, 4}));
  }
}

TEST(ImportStatistics, EachLevel0BlocksStatisticsReachTheCallerRowMajorAsTheWriterSumsThem) {
  // WriteOptions::blockStatistics (what regolith-mpi gathers from its parts) against GDAL's
  // samples, block by block (smallPatches(): 64 × 48, not a divisor of the sizes).
  for (const char* name : {"vest64_dtm_specialpixels_downsampled.cub", "dem_unfinished.tif",
                           "Polar_Crater_1_1m_ngate_edited2_forPDS_lowres.cub"}) {
    SCOPED_TRACE(name);
    std::vector<store::BlockStatistics> blocks;
    std::vector<std::string> grids;
    ImportOptions opts = smallPatches();
    opts.blockStatistics = [&](std::string_view grid, const store::BlockStatistics& b) {
      grids.emplace_back(grid);
      blocks.push_back(b);
    };
    const ImportReport rep = importRaster(fixture(name), scratch("blocks.h5"), opts);
    const Oracle o = readGdal(fixture(name));
    const std::size_t pr = opts.patchRows, pc = opts.patchCols;
    const std::size_t blockCols = (o.cols + pc - 1) / pc;
    ASSERT_EQ(blocks.size(), ((o.rows + pr - 1) / pr) * blockCols);
    std::uint64_t valid = 0;
    for (std::size_t k = 0; k < blocks.size(); ++k) {
      const store::BlockStatistics& b = blocks[k];
      EXPECT_EQ(grids[k], rep.info.name);
      ASSERT_EQ(b.row0, (k / blockCols) * pr) << k;  // row-major
      ASSERT_EQ(b.col0, (k % blockCols) * pc) << k;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0;
      std::uint64_t count = 0;
      for (std::size_t r = b.row0; r < std::min(b.row0 + pr, o.rows); ++r) {
        for (std::size_t c = b.col0; c < std::min(b.col0 + pc, o.cols); ++c) {
          const std::optional<double> h = oracleHeight(o, r * o.cols + c, rep.radiusReference);
          if (!h) continue;
          lo = std::min(lo, *h);
          hi = std::max(hi, *h);
          sum += *h;  // in the block's row-major order, as the writer
          ++count;
        }
      }
      EXPECT_EQ(b.count, count) << k;
      EXPECT_EQ(b.min, lo) << k;  // ±∞ in a block without a valid sample
      EXPECT_EQ(b.max, hi) << k;
      EXPECT_EQ(b.sum, sum) << k;
      valid += count;
    }
    const std::optional<HeightStatistics> st =
        Store::open(scratch("blocks.h5")).grid(rep.info.name).statistics;
    ASSERT_TRUE(st);
    EXPECT_EQ(st->validSamples, valid);
  }
}

// ---- provenance ----------------------------------------------------------------------------

TEST(ImportProvenance, TheStoreRecordsSourceFilesDigestsGdalAndTheDecidingLabelFields) {
  // The fixtures' own SHA256SUMS (made when they were collected) are the digests' oracle.
  std::map<std::string, std::string> sums;
  std::ifstream in(fixture("SHA256SUMS"));
  for (std::string hash, file; in >> hash >> file;) sums[file] = hash;
  ASSERT_FALSE(sums.empty());
  const fs::path src = fixture("megt90n000cb.lbl");
  const ImportReport rep = importRaster(src, scratch("provenance.h5"), smallPatches());
  const std::string text = Store::open(scratch("provenance.h5")).grid(rep.info.name).provenance;
  CPLJSONDocument doc;
  ASSERT_TRUE(doc.LoadMemory(text)) << text;
  const CPLJSONObject root = doc.GetRoot();
  const CPLJSONArray sources = root.GetArray("sources");
  ASSERT_EQ(sources.Size(), 2);  // the detached label and its image, as GDAL lists them
  std::set<std::string> names;
  for (int i = 0; i < sources.Size(); ++i) {
    const std::string file = sources[i].GetString("file");
    names.insert(file);
    EXPECT_EQ(sources[i].GetString("sha256"), sums.at(file)) << file;
    EXPECT_EQ(sources[i].GetLong("bytes"), static_cast<GInt64>(fs::file_size(fixture(file))));
  }
  EXPECT_EQ(names, (std::set<std::string>{"megt90n000cb.lbl", "megt90n000cb.img"}));
  EXPECT_EQ(root.GetString("gdal_driver"), "PDS");
  EXPECT_EQ(root.GetString("gdal_version"), std::string(GDALVersionInfo("RELEASE_NAME")));
  EXPECT_EQ(root.GetDouble("label/MAP_RESOLUTION/value"), 4.0);
  EXPECT_EQ(root.GetDouble("label/LINE_PROJECTION_OFFSET"), 360.5);
  const CPLJSONArray gt = root.GetArray("geotransform");
  const Oracle o = readGdal(src, true);  // the geotransform as the import read it
  ASSERT_EQ(gt.Size(), 6);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(gt[i].ToDouble(), o.gt[static_cast<std::size_t>(i)]);
  EXPECT_NE(root.GetString("crs_wkt").find("3396000"), std::string::npos);  // the sphere
  EXPECT_EQ(Store::open(scratch("provenance.h5")).formatVersion(), (std::array<int, 2>{1, 4}));
}

TEST(ImportProvenance, WithoutDigestsTheSourcesKeepTheirSizesAndRasterProvenanceAddsThem) {
  const fs::path src = fixture("megt90n000cb.lbl");
  ImportOptions o = smallPatches();
  o.digestSources = false;
  o.window = SampleWindow{10, 20, 64, 96};  // the provenance does not depend on a window
  const ImportReport rep = importRaster(src, scratch("undigested.h5"), o);
  const std::string text = Store::open(scratch("undigested.h5")).grid(rep.info.name).provenance;
  CPLJSONDocument undigested;
  ASSERT_TRUE(undigested.LoadMemory(text)) << text;
  const CPLJSONArray files = undigested.GetRoot().GetArray("sources");
  ASSERT_EQ(files.Size(), 2);
  for (int i = 0; i < files.Size(); ++i) {
    const std::string file = files[i].GetString("file");
    EXPECT_FALSE(files[i].GetObj("sha256").IsValid()) << file;
    EXPECT_EQ(files[i].GetLong("bytes"), static_cast<GInt64>(fs::file_size(fixture(file))));
  }
  // rasterProvenance(): the import's provenance to the byte, with digests or without them.
  EXPECT_EQ(rasterProvenance(src, o), text);
  const ImportReport full = importRaster(src, scratch("digested.h5"), smallPatches());
  EXPECT_EQ(rasterProvenance(src, smallPatches()),
            Store::open(scratch("digested.h5")).grid(full.info.name).provenance);
  EXPECT_NE(rasterProvenance(src, smallPatches()), text);
  EXPECT_THROW((void)rasterProvenance(fixture("no_such_file.tif")), ImportError);
}

// ---- the writer's memory budget (WriteOptions::memoryBudgetBytes) ---------------------------

namespace {

/// Every level of two grids holds the same bits (NaN payloads included), read with the store
/// reader.
void expectSameBits(const Store& a, const Store& b, const std::string& grid) {
  ASSERT_EQ(a.grid(grid).levels, b.grid(grid).levels);
  for (std::size_t k = 0; k < a.grid(grid).levels; ++k) {
    if (k == 0 && a.tiled(grid)) continue;  // level 0 of a mosaic lives in its tiles
    const std::vector<float> u = readLevel(a, grid, k), v = readLevel(b, grid, k);
    ASSERT_EQ(u.size(), v.size());
    EXPECT_EQ(std::memcmp(u.data(), v.data(), u.size() * sizeof(float)), 0) << "level " << k;
  }
  const std::optional<HeightStatistics> sa = a.grid(grid).statistics, sb = b.grid(grid).statistics;
  ASSERT_TRUE(sa && sb);
  EXPECT_EQ(sb->validSamples, sa->validSamples);
  EXPECT_EQ(sb->min, sa->min);
  EXPECT_EQ(sb->max, sa->max);
  EXPECT_EQ(sb->mean, sa->mean);
}

}  // namespace

TEST(ImportMemory, ABudgetSmallerThanTwoBandsBuildsColumnTilesAndTheSameLevels) {
  for (const std::string name : {"S11E119.hgt", "Shoemaker_1k.tif", "dem_nodata.dem"}) {
    for (const int deflate : {0, 4}) {
      SCOPED_TRACE(name + " deflate " + std::to_string(deflate));
      ImportOptions o = smallPatches();
      o.deflate = deflate;
      o.gridName = "g";
      const ImportReport whole = importRaster(fixture(name), scratch("whole.h5"), o);
      EXPECT_EQ(whole.memory.tileChunks, 0U);  // the default budget holds whole bands
      EXPECT_GT(whole.memory.untiledBytes, 0U);
      EXPECT_GT(whole.peakRssBytes, 0U);
      // The least budget: column tiles of one chunk on one thread; the scratch of both
      // threads (10 chunks each) and three tile chunks (4 read back + 5/4 encoded each):
      // tiles of three on two threads.
      const std::size_t least = writerMemoryMinimum(o);
      const std::size_t chunk = o.patchRows * o.patchCols * sizeof(float);
      const std::size_t three = 2 * 10 * chunk + 3 * (4 * chunk + chunk + chunk / 4);
      for (const std::size_t budget : {least, three}) {
        ASSERT_GT(whole.memory.untiledBytes, least);
        if (whole.memory.untiledBytes <= budget) continue;  // a small fixture: bands fit
        ImportOptions t = o;
        t.memoryBudgetBytes = budget;
        const ImportReport tiled = importRaster(fixture(name), scratch("tiles.h5"), t);
        EXPECT_EQ(tiled.memory.tileChunks, budget == least ? 1U : 3U);
        EXPECT_EQ(tiled.memory.threads, budget == least ? 1U : 2U);
        EXPECT_LE(tiled.memory.plannedBytes, budget);
        expectSameBits(Store::open(scratch("whole.h5")), Store::open(scratch("tiles.h5")), "g");
      }
    }
  }
}

TEST(ImportMemory, ATiledGridBuildsItsLevelOneFromItsTilesInColumnTiles) {
  const fs::path src = fixture("Shoemaker_1k.tif");
  const GridInfo whole = describeRaster(src);
  const std::vector<fs::path> tiles = cutTiles(src, "shoemaker-mem", whole.rows, whole.cols);
  ImportOptions o = smallPatches();
  o.gridName = "s";
  (void)importTiles(tiles, scratch("mosaic-whole.h5"), o);
  o.memoryBudgetBytes = writerMemoryMinimum(o);
  const ImportReport tiled = importTiles(tiles, scratch("mosaic-tiles.h5"), o);
  EXPECT_EQ(tiled.memory.tileChunks, 1U);
  expectSameBits(Store::open(scratch("mosaic-whole.h5")), Store::open(scratch("mosaic-tiles.h5")),
                 "s");
  // And level 1 up equal the single import's.
  (void)importRaster(src, scratch("mosaic-single.h5"), o);
  const Store single = Store::open(scratch("mosaic-single.h5"));
  const Store mosaic = Store::open(scratch("mosaic-tiles.h5"));
  for (std::size_t k = 1; k < single.grid("s").levels; ++k) {
    const std::vector<float> u = readLevel(single, "s", k), v = readLevel(mosaic, "s", k);
    ASSERT_EQ(u.size(), v.size());
    EXPECT_EQ(std::memcmp(u.data(), v.data(), u.size() * sizeof(float)), 0) << "level " << k;
  }
}

TEST(ImportMemory, ABudgetBelowOneColumnTileIsRefusedNamingTheOptionAndTheMinimum) {
  ImportOptions o = smallPatches();  // 64x48 patches, 2 threads
  // One tile of one chunk: 4 chunks read back + 5/4 chunk encoded; 10 chunks for one thread.
  const std::size_t chunk = 64 * 48 * sizeof(float);
  const std::size_t least = 4 * chunk + chunk + chunk / 4 + 10 * chunk;
  EXPECT_EQ(writerMemoryMinimum(o), least);
  o.memoryBudgetBytes = least - 1;
  const fs::path out = scratch("too-small.h5");
  std::error_code ec;
  fs::remove(out, ec);
  try {
    (void)importRaster(fixture("S11E119.hgt"), out, o);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              "store::writeStore(): " + out.string() + ": options.memoryBudgetBytes is " +
                  std::to_string(least - 1) + " bytes, below the minimum of " +
                  std::to_string(least) +
                  " bytes for patches of 64x48 (one column tile of one chunk, and one thread's "
                  "scratch); expected at least that, or 0 for no bound");
  }
  EXPECT_FALSE(fs::exists(out));
  // 0: no bound.
  o.memoryBudgetBytes = 0;
  EXPECT_EQ(importRaster(fixture("S11E119.hgt"), out, o).memory.tileChunks, 0U);
  // The default budget grows to the minimum of patches it cannot hold (8192²: 256 MiB a
  // chunk), and builds a wide grid in tiles of one chunk on one thread.
  WriteOptions big;
  big.patchRows = big.patchCols = 8192;
  big.threads = 4;
  const WriterMemoryPlan plan = writerMemoryPlan(65536, 1U << 20U, big);
  const std::size_t bigChunk = std::size_t{8192} * 8192 * sizeof(float);
  EXPECT_EQ(plan.minimumBytes, 15 * bigChunk + bigChunk / 4);
  EXPECT_GT(plan.minimumBytes, kDefaultMemoryBudget);
  EXPECT_EQ(plan.tileChunks, 1U);
  EXPECT_EQ(plan.threads, 1U);
  EXPECT_EQ(plan.plannedBytes, plan.minimumBytes);
}
