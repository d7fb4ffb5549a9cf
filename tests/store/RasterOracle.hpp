#pragma once
// Rasters made with GDAL for the import tests, and GDAL/OSR as their oracle: a Spec written
// through GDAL's drivers, GDAL's reading of it (values after scale/offset, OSR's lon/lat of
// every pixel centre), and the check that an imported store holds exactly those samples and
// that queries at those positions return them (the store opened and queried).

#include <regolith/core/Error.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

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
#include <type_traits>
#include <vector>

namespace regolith::test {

namespace fs = std::filesystem;
using namespace regolith::store;

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
inline fs::path writeRaster(const fs::path& p, const Spec& spec) {
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
  GDALDriverH drv = GDALGetDriverByName(spec.driver.c_str());
  if (!spec.isisScale) {
    Dataset out(GDALCreateCopy(drv, p.c_str(), mem.get(), FALSE, nullptr, nullptr, nullptr));
    EXPECT_TRUE(out) << p;
    return p;
  }
  // ISIS3 with the label's own Scale: GDAL's label as a template, Scale replaced.
  const fs::path first = p.parent_path() / ("template_" + p.filename().string());
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
inline std::vector<float> indexValues(std::size_t rows, std::size_t cols) {
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

inline Oracle readGdal(const fs::path& p) {
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
inline void labelCentres(Oracle& o, double lon0, double degreesPerPixel) {
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
inline void expectExact(const fs::path& store, const ImportReport& rep, const Oracle& o,
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

}  // namespace regolith::test
