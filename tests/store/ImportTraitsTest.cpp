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

namespace {

constexpr double kMoon = 1737400.0;
constexpr double kMetresPerDegree = kMoon * 3.14159265358979323846 / 180.0;

fs::path scratch(const std::string& name) { return test::scratchFile("import-traits", name); }

struct Closer {
  void operator()(void* ds) const noexcept {
    if (ds != nullptr) GDALClose(ds);
  }
};
using Dataset = std::unique_ptr<void, Closer>;

struct SrsCloser {
  void operator()(OGRSpatialReferenceH s) const noexcept { OSRDestroySpatialReference(s); }
};
using Srs = std::unique_ptr<std::remove_pointer_t<OGRSpatialReferenceH>, SrsCloser>;

/// A single-band float32 raster to be written with GDAL.
struct Spec {
  std::size_t rows = 0, cols = 0;
  std::array<double, 6> gt{};
  std::string crs;  // PROJ string
  std::vector<float> values;
  std::optional<double> nodata;
  std::string driver = "GTiff";
  std::optional<double> isisScale;  // ISIS3: the label's Scale (px/deg), instead of GDAL's
};

/// Writes `spec` with GDAL: into a MEM dataset, then CreateCopy with the spec's driver (an
/// ISIS3 label's Scale is set through GDAL's USE_SRC_MAPPING, the rest of its Mapping group
/// is what GDAL's writer computes).
fs::path write(const std::string& name, const Spec& spec) {
  GDALAllRegister();
  const auto w = static_cast<int>(spec.cols), h = static_cast<int>(spec.rows);
  Dataset mem(GDALCreate(GDALGetDriverByName("MEM"), "", w, h, 1, GDT_Float32, nullptr));
  EXPECT_TRUE(mem);
  std::vector<float> v = spec.values;
  GDALRasterBandH b = GDALGetRasterBand(mem.get(), 1);
  EXPECT_EQ(GDALRasterIO(b, GF_Write, 0, 0, w, h, v.data(), w, h, GDT_Float32, 0, 0), CE_None);
  if (spec.nodata) GDALSetRasterNoDataValue(b, *spec.nodata);
  std::array<double, 6> gt = spec.gt;
  GDALSetGeoTransform(mem.get(), gt.data());
  const Srs srs(OSRNewSpatialReference(nullptr));
  EXPECT_EQ(OSRSetFromUserInput(srs.get(), spec.crs.c_str()), OGRERR_NONE) << spec.crs;
  GDALSetSpatialRef(mem.get(), srs.get());
  const fs::path p = scratch(name);
  GDALDriverH drv = GDALGetDriverByName(spec.driver.c_str());
  if (!spec.isisScale) {
    Dataset out(GDALCreateCopy(drv, p.c_str(), mem.get(), FALSE, nullptr, nullptr, nullptr));
    EXPECT_TRUE(out) << p;
    return p;
  }
  // ISIS3 with the label's own Scale: GDAL's label as a template, Scale replaced.
  const fs::path first = scratch("template_" + name);
  {
    Dataset out(GDALCreateCopy(drv, first.c_str(), mem.get(), FALSE, nullptr, nullptr, nullptr));
    EXPECT_TRUE(out);
  }
  Dataset tmpl(GDALOpen(first.c_str(), GA_ReadOnly));
  char** md = GDALGetMetadata(tmpl.get(), "json:ISIS3");
  EXPECT_TRUE(md != nullptr && md[0] != nullptr);
  CPLJSONDocument doc;
  EXPECT_TRUE(doc.LoadMemory(std::string(md[0])));
  CPLJSONObject mapping = doc.GetRoot().GetObj("IsisCube/Mapping");
  mapping.Delete("Scale");
  CPLJSONObject scale;
  scale.Add("value", *spec.isisScale);
  scale.Add("unit", "pixels/degree");
  mapping.Add("Scale", scale);
  const std::string label = doc.SaveAsString();
  char* labels[] = {const_cast<char*>(label.c_str()), nullptr};
  GDALSetMetadata(mem.get(), labels, "json:ISIS3");
  char* opts[] = {const_cast<char*>("USE_SRC_MAPPING=YES"), nullptr};
  Dataset out(GDALCreateCopy(drv, p.c_str(), mem.get(), FALSE, opts, nullptr, nullptr));
  EXPECT_TRUE(out) << p;
  return p;
}

/// r·1000 + c: a nearest-sample query that lands on another sample shows which.
std::vector<float> indexValues(std::size_t rows, std::size_t cols) {
  std::vector<float> v(rows * cols);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      v[r * cols + c] = static_cast<float>(r * 1000 + c);
    }
  }
  return v;
}

/// GDAL's reading of a raster: values after scale/offset (NaN where GDAL's mask or nodata say
/// missing), geotransform, and the lon/lat of every pixel centre through OSR (PROJ), in the
/// CRS's own geographic CRS.
struct Oracle {
  std::size_t rows = 0, cols = 0;
  std::vector<double> heights, lon, lat;
  std::array<double, 6> gt{};
};

Oracle readGdal(const fs::path& p) {
  Dataset ds(GDALOpen(p.c_str(), GA_ReadOnly));
  EXPECT_TRUE(ds) << p;
  Oracle o;
  o.rows = static_cast<std::size_t>(GDALGetRasterYSize(ds.get()));
  o.cols = static_cast<std::size_t>(GDALGetRasterXSize(ds.get()));
  const std::size_t n = o.rows * o.cols;
  const auto w = static_cast<int>(o.cols), h = static_cast<int>(o.rows);
  GDALRasterBandH b = GDALGetRasterBand(ds.get(), 1);
  std::vector<double> raw(n);
  std::vector<unsigned char> mask(n);
  EXPECT_EQ(GDALRasterIO(b, GF_Read, 0, 0, w, h, raw.data(), w, h, GDT_Float64, 0, 0), CE_None);
  EXPECT_EQ(
      GDALRasterIO(GDALGetMaskBand(b), GF_Read, 0, 0, w, h, mask.data(), w, h, GDT_Byte, 0, 0),
      CE_None);
  int ok = 0;
  double scale = GDALGetRasterScale(b, &ok);
  if (ok == 0) scale = 1.0;
  double offset = GDALGetRasterOffset(b, &ok);
  if (ok == 0) offset = 0.0;
  int has = 0;
  const double nd = GDALGetRasterNoDataValue(b, &has);
  o.heights.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const bool missing = mask[i] == 0 || std::isnan(raw[i]) || (has != 0 && raw[i] == nd);
    o.heights[i] = missing ? std::nan("") : offset + scale * raw[i];
  }
  EXPECT_EQ(GDALGetGeoTransform(ds.get(), o.gt.data()), CE_None);
  OGRSpatialReferenceH srs = GDALGetSpatialRef(ds.get());
  const Srs src(OSRClone(srs)), geo(OSRCloneGeogCS(srs));
  OSRSetAxisMappingStrategy(src.get(), OAMS_TRADITIONAL_GIS_ORDER);
  OSRSetAxisMappingStrategy(geo.get(), OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(src.get(), geo.get());
  EXPECT_NE(ct, nullptr);
  o.lon.resize(n);
  o.lat.resize(n);
  for (std::size_t r = 0; r < o.rows; ++r) {
    for (std::size_t c = 0; c < o.cols; ++c) {
      o.lon[r * o.cols + c] = o.gt[0] + (static_cast<double>(c) + 0.5) * o.gt[1];
      o.lat[r * o.cols + c] = o.gt[3] + (static_cast<double>(r) + 0.5) * o.gt[5];
    }
  }
  EXPECT_NE(OCTTransform(ct, static_cast<int>(n), o.lon.data(), o.lat.data(), nullptr), 0);
  OCTDestroyCoordinateTransformation(ct);
  return o;
}

/// The pixel centres of a global grid as its label places them: pixel offsets from the
/// projection's origin at the label's resolution (degrees per pixel), not through the
/// label's rounded metres.
void labelCentres(Oracle& o, double lon0, double degreesPerPixel) {
  for (std::size_t r = 0; r < o.rows; ++r) {
    for (std::size_t c = 0; c < o.cols; ++c) {
      const double x = o.gt[0] / o.gt[1] + static_cast<double>(c) + 0.5;
      const double y = o.gt[3] / -o.gt[5] - static_cast<double>(r) - 0.5;
      o.lon[r * o.cols + c] = lon0 + x * degreesPerPixel;
      o.lat[r * o.cols + c] = y * degreesPerPixel;
    }
  }
}

/// The imported grid is GDAL's rows row0… and columns 0…cols−1: each stored sample equals
/// GDAL's value, and a nearest-sample query at the OSR longitude/latitude of GDAL's pixel
/// centre (through the placement for a DEM) returns it. Opens and queries the store.
/// Between the outermost row of a planet and its pole TopoPlanet blends towards the pole's
/// height by design (its polar cap); where OSR's latitude of an outermost centre lies in
/// the cap (a rounded map scale moves it there), that row is queried at its own latitude.
void expectExact(const fs::path& store, const ImportReport& rep, const Oracle& o,
                 std::size_t row0 = 0, bool demAtMapXy = false) {
  const GridInfo& g = rep.info;
  ASSERT_LE(row0 + g.rows, o.rows);
  ASSERT_LE(g.cols, o.cols);
  const auto s = std::make_shared<const Store>(Store::open(store));
  std::vector<float> got(g.rows * g.cols);
  s->readWindow(g.name, 0, 0, 0, g.rows, g.cols, got);
  Pager pager(s, std::make_shared<PatchCache>(std::size_t{16} << 20));
  std::optional<topo::TopoPlanet> planet;
  std::optional<topo::TopoDem> dem;
  if (g.kind == GridKind::Planet) {
    planet.emplace(pager.planet(g.name));
  } else {
    dem.emplace(pager.dem(g.name));
  }
  const std::optional<topo::Placement> placement =
      g.kind == GridKind::Dem ? std::optional<topo::Placement>(placementOf(g)) : std::nullopt;
  std::size_t bad = 0, checked = 0;
  for (std::size_t r = 0; r < g.rows; ++r) {
    for (std::size_t c = 0; c < g.cols; ++c) {
      const std::size_t k = (row0 + r) * o.cols + c;
      const double want = o.heights[k];
      const float stored = got[r * g.cols + c];
      const bool sampleOk =
          std::isnan(want) ? std::isnan(stored) : stored == static_cast<float>(want);
      topo::HeightSample q;
      bool cap = false;
      if (planet) {
        const double rowLat = g.y0 - static_cast<double>(r) * g.spacingY;
        cap = (r == 0 && o.lat[k] >= rowLat && planet->hasNorthCap()) ||
              (r + 1 == g.rows && o.lat[k] <= rowLat && planet->hasSouthCap());
        q = planet->height({cap ? rowLat : o.lat[k], o.lon[k]}, topo::Interpolation::Nearest);
      } else if (demAtMapXy) {  // GDAL's pixel centre in the DEM's own map metres
        q = dem->height(o.gt[0] + (static_cast<double>(c) + 0.5) * o.gt[1],
                        o.gt[3] + (static_cast<double>(row0 + r) + 0.5) * o.gt[5],
                        topo::Interpolation::Nearest);
      } else {
        const glm::dvec3 xy = placement->fromGeodetic({o.lat[k], o.lon[k], 0.0});
        q = dem->height(xy.x, xy.y, topo::Interpolation::Nearest);
      }
      // In a cap row the blend towards the pole may see the row's own latitude an ulp
      // poleward (TopoPlanet's rounding): 1 µm there, exact elsewhere.
      const double tol = cap ? 1e-6 : 0.0;
      const bool queryOk =
          std::isnan(want) ? !q.valid()
                           : q.valid() && std::abs(q.height - static_cast<double>(stored)) <= tol;
      if ((!sampleOk || !queryOk) && ++bad <= 5) {
        ADD_FAILURE() << "sample " << r << "," << c << ": stored " << stored << ", query "
                      << (q.valid() ? q.height : std::nan("")) << " at lon " << o.lon[k] << " lat "
                      << o.lat[k] << ", GDAL " << want;
      }
      ++checked;
    }
  }
  EXPECT_EQ(bad, 0U);
  EXPECT_EQ(checked, g.rows * g.cols);
}

template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const ImportError& e) {
    return e.what();
  }
  return "(no ImportError)";
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
