// The pixel-centre convention and the placements checked against GDAL itself, on real
// fixtures: GDAL's geotransform, GDAL's pixel reads, and PROJ (through OGR) for positions.
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "support/Fixtures.hpp"

#include <gdal.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>

#include <array>
#include <memory>
#include <vector>

using namespace regolith;
using namespace regolith::topo;

namespace {
struct Raster {
  std::array<double, 6> gt{};
  std::size_t rows = 0, cols = 0;
  std::vector<float> data;
  std::string wkt;
  std::optional<float> nodata;
};

Raster readWithGdal(const std::string& path) {
  GDALAllRegister();
  std::unique_ptr<void, decltype(&GDALClose)> ds(GDALOpen(path.c_str(), GA_ReadOnly), &GDALClose);
  if (!ds) throw std::runtime_error("GDAL cannot open " + path);
  Raster r;
  GDALGetGeoTransform(ds.get(), r.gt.data());
  r.cols = static_cast<std::size_t>(GDALGetRasterXSize(ds.get()));
  r.rows = static_cast<std::size_t>(GDALGetRasterYSize(ds.get()));
  r.wkt = GDALGetProjectionRef(ds.get());
  GDALRasterBandH band = GDALGetRasterBand(ds.get(), 1);
  int has = 0;
  const double nd = GDALGetRasterNoDataValue(band, &has);
  if (has) r.nodata = static_cast<float>(nd);
  r.data.resize(r.rows * r.cols);
  const CPLErr err = GDALRasterIO(band, GF_Read, 0, 0, static_cast<int>(r.cols),
                                  static_cast<int>(r.rows), r.data.data(), static_cast<int>(r.cols),
                                  static_cast<int>(r.rows), GDT_Float32, 0, 0);
  if (err != CE_None) throw std::runtime_error("GDAL cannot read " + path);
  return r;
}
}  // namespace

TEST(GdalConvention, ShoemakerSampleCentresAndHeightsMatchGdal) {
  const Raster ras = readWithGdal(test::fixture("Shoemaker_1k.tif"));
  const TopoGrid grid = TopoGrid::fromGeoTransform(ras.gt, ras.rows, ras.cols, ras.nodata);
  EXPECT_EQ(grid.geoTransform(), ras.gt);

  // Placement from the file's CRS: south polar stereographic on the 1737400 m sphere.
  OGRSpatialReferenceH srs = OSRNewSpatialReference(ras.wkt.c_str());
  ASSERT_NE(srs, nullptr);
  OSRSetAxisMappingStrategy(srs, OAMS_TRADITIONAL_GIS_ORDER);
  OGRErr e = OGRERR_NONE;
  const double a = OSRGetSemiMajor(srs, &e);
  ASSERT_EQ(e, OGRERR_NONE);
  EXPECT_DOUBLE_EQ(a, 1737400.0);
  const double lat0 = OSRGetProjParm(srs, SRS_PP_LATITUDE_OF_ORIGIN, 0.0, nullptr);
  const double lon0 = OSRGetProjParm(srs, SRS_PP_CENTRAL_MERIDIAN, 0.0, nullptr);
  const double k0 = OSRGetProjParm(srs, SRS_PP_SCALE_FACTOR, 1.0, nullptr);
  ASSERT_EQ(lat0, -90.0);
  const Body moon = Body::sphere("Moon", a);
  const auto ps =
      PolarStereographic::withScaleFactor(moon, PolarStereographic::Pole::South, k0, lon0);
  const TopoDem dem(grid, Placement(moon, ps),
                    std::make_shared<InMemorySamples>(ras.rows, ras.cols, ras.data));

  // PROJ (through OGR) is the oracle for geographic positions of GDAL's pixel centres.
  OGRSpatialReferenceH geo = OSRCloneGeogCS(srs);
  OSRSetAxisMappingStrategy(geo, OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(srs, geo);
  ASSERT_NE(ct, nullptr);
  std::size_t checked = 0, nodata = 0;
  for (std::size_t r = 0; r < ras.rows; r += 17) {
    for (std::size_t c = 0; c < ras.cols; c += 13) {
      double x = ras.gt[0] + (static_cast<double>(c) + 0.5) * ras.gt[1];
      double y = ras.gt[3] + (static_cast<double>(r) + 0.5) * ras.gt[5];
      const glm::dvec2 mine = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      EXPECT_NEAR(mine.x, x, 1e-9);
      EXPECT_NEAR(mine.y, y, 1e-9);
      double z = 0.0;
      ASSERT_TRUE(OCTTransform(ct, 1, &x, &y, &z));
      const Geodetic g = dem.placement().toGeodetic(mine.x, mine.y, 0.0);
      EXPECT_NEAR(g.latDeg, y, 1e-9);
      EXPECT_NEAR(wrapLongitude180(g.lonDeg - x), 0.0, 1e-9);
      // Every kernel returns GDAL's pixel value at the pixel centre.
      const float want = ras.data[r * ras.cols + c];
      const HeightSample h = dem.height(mine.x, mine.y, Interpolation::Nearest);
      if (grid.isNodata(want)) {
        EXPECT_FALSE(h.valid());
        ++nodata;
      } else {
        ASSERT_TRUE(h.valid());
        EXPECT_EQ(h.height, static_cast<double>(want));
        EXPECT_NEAR(dem.height(mine.x, mine.y, Interpolation::Bilinear).height, want, 1e-6);
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 200u);
  OCTDestroyCoordinateTransformation(ct);
  OSRDestroySpatialReference(geo);
  OSRDestroySpatialReference(srs);
}

TEST(GdalConvention, SrtmSampleCentresFallOnWholeDegreesAtTheTileCorners) {
  // SRTM .hgt samples are points on the integer-degree lattice: S11E119 spans 11°S…10°S and
  // 119°E…120°E with samples exactly at the corners; GDAL's geotransform is half a pixel
  // beyond them, so the pixel-centre convention must put sample (0,0) at (119°E, 10°S).
  const Raster ras = readWithGdal(test::fixture("S11E119.hgt"));
  const TopoGrid grid = TopoGrid::fromGeoTransform(ras.gt, ras.rows, ras.cols, ras.nodata);
  ASSERT_EQ(ras.rows, 1201u);
  EXPECT_NEAR(grid.sampleCentre(0, 0).x, 119.0, 1e-12);
  EXPECT_NEAR(grid.sampleCentre(0, 0).y, -10.0, 1e-12);
  EXPECT_NEAR(grid.sampleCentre(1200, 1200).x, 120.0, 1e-12);
  EXPECT_NEAR(grid.sampleCentre(1200, 1200).y, -11.0, 1e-12);
  const TopoPlanet p(grid, Body::earthWgs84(), LatitudeType::Planetodetic,
                     std::make_shared<InMemorySamples>(ras.rows, ras.cols, ras.data));
  // Row 600, col 900 sits at 10.5°S, 119.75°E.
  const float want = ras.data[600 * ras.cols + 900];
  EXPECT_EQ(p.height({-10.5, 119.75}, Interpolation::Nearest).height, static_cast<double>(want));
  EXPECT_EQ(p.height({-10.5, 119.75}, Interpolation::Bicubic).height, static_cast<double>(want));
  EXPECT_EQ(p.height({-9.0, 119.5}).status, QueryStatus::OutsideGrid);
}
