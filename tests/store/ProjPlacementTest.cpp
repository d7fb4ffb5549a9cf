// Placements through PROJ (store::projPlacement()): the same positions as topo's analytic
// projections where both exist, and DEMs in projections topo has no formula for (sinusoidal
// on Mars, Lambert conformal conic on the Moon) made here with GDAL, imported, re-opened from
// the store and queried at the longitude/latitude OSR gives each of GDAL's pixel centres.
#include <regolith/core/Error.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/ProjPlacement.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>

#include "RasterOracle.hpp"
#include "support/StoreScratch.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

constexpr double kMarsA = 3396190.0, kMoonR = 1737400.0;

fs::path scratch(const std::string& name) { return test::scratchFile("proj-placement", name); }

/// The analytic placement and the PROJ one of the same CRS put every grid point at the same
/// body-fixed position, and every geodetic position at the same grid point, to 1e-9 of the
/// body's radius (3 mm on Mars), over a square of ±half metres around (cx, cy).
void expectSamePlacement(const topo::Placement& analytic, const topo::Placement& proj, double cx,
                         double cy, double half) {
  ASSERT_EQ(proj.kind(), topo::Placement::Kind::Projected);
  const double tol = 1e-9 * analytic.body().equatorialRadius();
  double worstP = 0.0, worstXy = 0.0;
  constexpr int kSteps = 12;
  for (int i = 0; i <= kSteps; ++i) {
    for (int j = 0; j <= kSteps; ++j) {
      const double x = cx - half + 2.0 * half * i / kSteps;
      const double y = cy - half + 2.0 * half * j / kSteps;
      const double h = 250.0 * (i - j);
      const glm::dvec3 a = analytic.toBodyFixed(x, y, h), b = proj.toBodyFixed(x, y, h);
      worstP = std::max(worstP, glm::length(a - b));
      const topo::Geodetic g = analytic.toGeodetic(x, y, h);
      const glm::dvec3 back = proj.fromGeodetic(g);
      worstXy = std::max(worstXy, std::hypot(back.x - x, back.y - y));
      EXPECT_EQ(back.z, h);
    }
  }
  EXPECT_LE(worstP, tol);
  EXPECT_LE(worstXy, tol);
}

std::string marsEllipsoid() { return " +a=3396190 +b=3376200 +units=m +no_defs +type=crs"; }

}  // namespace

TEST(ProjPlacement, EquirectangularAsAProjCrsPlacesAsTheAnalyticProjection) {
  const topo::Body mars = topo::Body::marsSphere();
  const topo::Placement analytic(mars, topo::Equirectangular(kMarsA, 10.0, 137.0, 0.0));
  const topo::Placement proj = projPlacement(
      mars, "+proj=eqc +lat_ts=10 +lat_0=0 +lon_0=137 +R=3396190 +units=m +no_defs +type=crs");
  expectSamePlacement(analytic, proj, 0.0, -3e5, 2e6);
}

TEST(ProjPlacement, PolarStereographicAsAProjCrsPlacesAsTheAnalyticProjection) {
  const topo::Body mars = topo::Body::marsEllipsoid();
  using PS = topo::PolarStereographic;
  const topo::Placement north(mars,
                              PS::withScaleFactor(mars, PS::Pole::North, 0.97, 45.0, 1e5, 2e5));
  expectSamePlacement(
      north,
      projPlacement(mars, "+proj=stere +lat_0=90 +k_0=0.97 +lon_0=45 +x_0=100000 +y_0=200000" +
                              marsEllipsoid()),
      1e5, 2e5, 8e5);
  const topo::Placement south(mars, PS::withTrueScaleLatitude(mars, PS::Pole::South, -71.0, 0.0));
  expectSamePlacement(
      south, projPlacement(mars, "+proj=stere +lat_0=-90 +lat_ts=-71 +lon_0=0" + marsEllipsoid()),
      0.0, 0.0, 8e5);
}

TEST(ProjPlacement, TransverseMercatorAsAProjCrsPlacesAsTheAnalyticProjection) {
  const topo::Body mars = topo::Body::marsEllipsoid();
  const topo::Placement analytic(mars, topo::TransverseMercator(mars, 137.0, -5.0, 0.9996, 5e5, 0));
  const topo::Placement proj = projPlacement(
      mars, "+proj=tmerc +lat_0=-5 +lon_0=137 +k_0=0.9996 +x_0=500000 +y_0=0" + marsEllipsoid());
  expectSamePlacement(analytic, proj, 5e5, 1e5, 6e5);
}

TEST(ProjPlacement, RecordsItsCrsAsWkt2AndRefusesWhatIsNoProjectedCrsOnTheBody) {
  const auto p = projProjection("+proj=sinu +lon_0=137 +R=3396190 +units=m +no_defs +type=crs");
  EXPECT_EQ(p->definition().rfind("PROJCRS[", 0), 0U) << p->definition();
  // The WKT2 reads back as the same projection.
  const auto again = projProjection(p->definition());
  const glm::dvec2 a = p->forward({-4.5, 137.4}), b = again->forward({-4.5, 137.4});
  EXPECT_EQ(a, b);
  EXPECT_NE(projString(p->definition()).find("+proj=sinu"), std::string::npos);
  EXPECT_THROW((void)projProjection("+proj=longlat +R=3396190 +type=crs"), InvalidArgument);
  EXPECT_THROW((void)projProjection("not a CRS"), InvalidArgument);
  EXPECT_THROW((void)projPlacement(topo::Body::moon(), p->definition()), InvalidArgument);
  // Off the map: a DomainError, as the analytic projections give.
  EXPECT_THROW((void)p->inverse({1e8, 0.0}), DomainError);
}

TEST(ProjPlacement, ThreadsUseTheirOwnProjContextsAtOnce) {
  const topo::Placement pl = projPlacement(
      topo::Body::marsSphere(), "+proj=sinu +lon_0=137 +R=3396190 +units=m +no_defs +type=crs");
  std::vector<topo::Geodetic> want(64);
  for (std::size_t i = 0; i < want.size(); ++i) {
    want[i] = pl.toGeodetic(1000.0 * static_cast<double>(i), -2000.0 * static_cast<double>(i), 0);
  }
  std::vector<int> bad(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      const topo::Placement copy = pl;  // copies share the projection
      for (int round = 0; round < 200; ++round) {
        for (std::size_t i = 0; i < want.size(); ++i) {
          const topo::Geodetic g = copy.toGeodetic(1000.0 * static_cast<double>(i),
                                                   -2000.0 * static_cast<double>(i), 0.0);
          bad[static_cast<std::size_t>(t)] +=
              g.latDeg != want[i].latDeg || g.lonDeg != want[i].lonDeg ? 1 : 0;
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(bad, std::vector<int>(4, 0));
}

// ---- DEMs in projections topo has no formula for ----------------------------------------------

TEST(ProjPlacement, ASinusoidalMarsDemImportsReopensAndLonLatQueriesHitItsSamples) {
  // HiRISE/CTX-like: sinusoidal on the Mars sphere, 137°E, 25 m pixels near 4.6°S.
  test::Spec s;
  s.rows = 40;
  s.cols = 50;
  s.gt = {24000.0, 25.0, 0.0, -272000.0, 0.0, -25.0};
  s.crs =
      R"(PROJCS["Mars_Sinusoidal_137",GEOGCS["GCS_Mars",DATUM["D_Mars",SPHEROID["Mars",3396190,0]],)"
      R"(PRIMEM["Reference_Meridian",0],UNIT["degree",0.0174532925199433]],PROJECTION["Sinusoidal"],)"
      R"(PARAMETER["longitude_of_center",137],PARAMETER["false_easting",0],)"
      R"(PARAMETER["false_northing",0],UNIT["metre",1]])";
  s.values = test::indexValues(s.rows, s.cols);
  const fs::path tif = test::writeRaster(scratch("sinusoidal.tif"), s);
  const fs::path store = scratch("sinusoidal.h5");
  const ImportReport rep = importRaster(tif, store);
  EXPECT_EQ(rep.info.kind, GridKind::Dem);
  EXPECT_EQ(rep.info.placement.kind, PlacementInfo::Kind::Projected);
  EXPECT_EQ(rep.info.bodyName, "Mars");
  EXPECT_NE(rep.projection.find("Sinusoidal"), std::string::npos) << rep.projection;
  EXPECT_EQ(Store::open(store).formatVersion(), (std::array<int, 2>{1, 4}));
  test::expectExact(store, rep, test::readGdal(tif));
}

TEST(ProjPlacement, ALambertConformalConicMoonDemImportsReopensAndLonLatQueriesHitItsSamples) {
  // A PROJ string names no body: --body says the Moon.
  test::Spec s;
  s.rows = 30;
  s.cols = 45;
  s.gt = {-12000.0, 400.0, 0.0, 9000.0, 0.0, -400.0};
  s.crs =
      "+proj=lcc +lat_1=-20 +lat_2=-40 +lat_0=-30 +lon_0=30 +x_0=0 +y_0=0 +R=1737400 "
      "+units=m +no_defs";
  s.values = test::indexValues(s.rows, s.cols);
  s.values[7] = -9999.0F;
  s.nodata = -9999.0;
  const fs::path tif = test::writeRaster(scratch("lcc.tif"), s);
  const fs::path store = scratch("lcc.h5");
  ImportOptions o;
  o.body = "Moon";
  const ImportReport rep = importRaster(tif, store, o);
  EXPECT_EQ(rep.info.placement.kind, PlacementInfo::Kind::Projected);
  EXPECT_EQ(rep.info.bodyName, "Moon");
  EXPECT_EQ(rep.info.equatorialRadius, kMoonR);
  EXPECT_EQ(rep.missingSamples, 1U);
  test::expectExact(store, rep, test::readGdal(tif));
}

TEST(ProjPlacement, AnEquirectangularDemOnAnEllipsoidImportsThroughProj) {
  // topo's equirectangular is spherical; on the Mars ellipsoid the import goes through PROJ.
  test::Spec s;
  s.rows = 20;
  s.cols = 30;
  s.gt = {-1.5e5, 1000.0, 0.0, 3.0e5, 0.0, -1000.0};
  s.crs = "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=100" + marsEllipsoid();
  s.values = test::indexValues(s.rows, s.cols);
  const fs::path tif = test::writeRaster(scratch("eqc_ellipsoid.tif"), s);
  const fs::path store = scratch("eqc_ellipsoid.h5");
  const ImportReport rep = importRaster(tif, store);
  EXPECT_EQ(rep.info.placement.kind, PlacementInfo::Kind::Projected);
  test::expectExact(store, rep, test::readGdal(tif));
}
