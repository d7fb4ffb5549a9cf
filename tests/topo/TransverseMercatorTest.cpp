// Tests for regolith::topo::TransverseMercator (Karney 2011, Krüger series to n^6) and its
// Placement against outside oracles: PROJ's C API (`tmerc` with the Poder/Engsager
// algorithm, and `utm`), PROJ's `cct` program, and Snyder's published worked example
// (Map Projections: A Working Manual, USGS PP 1395, p. 269, Clarke 1866).
//
// The largest errors observed against PROJ are printed on stdout and recorded as test
// properties (gtest --gtest_output=xml shows them).

#include <regolith/core/Error.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>

#include "support/ProjOracle.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace {

using regolith::test::messageOf;
using regolith::test::num;
using regolith::test::Proj;
using regolith::test::projEllipsoid;
using regolith::test::report;
using regolith::topo::Body;
using regolith::topo::Geodetic;
using regolith::topo::LatLon;
using regolith::topo::Placement;
using regolith::topo::TransverseMercator;

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Clarke 1866 (NAD27's ellipsoid), as EPSG 7008 gives it: a = 6378206.4 m, b = 6356583.8 m.
Body clarke1866() { return Body::ellipsoid("Earth (Clarke 1866)", 6378206.4, 6356583.8); }

/// A projection taking (lon deg, lat deg) in and giving metres out.
std::string degreesIn(const std::string& projection) {
  return "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step " + projection;
}

double lonDiffDeg(double a, double b) { return std::remainder(a - b, 360.0); }

struct TmCase {
  std::string label;
  Body body;
  double lon0, lat0, k0, fe, fn;
  [[nodiscard]] TransverseMercator make() const { return {body, lon0, lat0, k0, fe, fn}; }
  /// On a sphere PROJ's `tmerc` uses Snyder's closed form, whose acos loses precision next
  /// to the equator (4 mm on the Moon at 1e-6° from it); it is given an ellipsoid with
  /// 1/f = 1e15 instead (within 3e-9 m of the sphere) so that Poder/Engsager's series runs.
  [[nodiscard]] std::string proj() const {
    const std::string ellps =
        body.isSphere() ? " +a=" + num(body.equatorialRadius()) + " +rf=1e15" : projEllipsoid(body);
    return degreesIn("+proj=tmerc +algo=poder_engsager +lon_0=" + num(lon0) +
                     " +lat_0=" + num(lat0) + " +k_0=" + num(k0) + " +x_0=" + num(fe) +
                     " +y_0=" + num(fn) + ellps);
  }
};

std::vector<TmCase> tmCases() {
  return {
      {"Clarke1866_UTM10N", clarke1866(), -123.0, 0.0, 0.9996, 500000.0, 0.0},
      {"WGS84_UTM33S", Body::earthWgs84(), 15.0, 0.0, 0.9996, 500000.0, 10000000.0},
      {"WGS84_k1_lat0_49_lonm2", Body::earthWgs84(), -2.0, 49.0, 0.9996012717, 400000.0,
       -100000.0},  // the British National Grid's parameters, on WGS84
      {"WGS84_lat0_m35_lon147", Body::earthWgs84(), 147.0, -35.0, 1.0, 0.0, 0.0},
      {"MarsEllipsoid_lon137_k1", Body::marsEllipsoid(), 137.4, 0.0, 1.0, 0.0, 0.0},
      {"MoonSphere_lon0_lat10", Body::moon(), 0.0, 10.0, 0.999, 100000.0, 200000.0},
      {"Clarke1866_lon180", clarke1866(), 180.0, 0.0, 0.9996, 500000.0, 0.0},
  };
}

/// Offsets from the central meridian: on it, next to it, across a 6° UTM zone, and beyond.
const std::vector<double> kDLons = {0.0,  1e-7, -1e-7, 0.001, -0.5, 1.0, -2.9,  3.0,
                                    -3.0, 3.5,  -4.5,  6.0,   -7.5, 8.0, -10.0, 10.0};
const std::vector<double> kLats = {-89.9, -84.0, -80.0, -60.0, -45.0, -30.0, -10.0,
                                   -1e-6, 0.0,   1e-6,  5.0,   20.0,  46.2,  60.0,
                                   72.0,  84.0,  89.99, 90.0,  -90.0};

TEST(TransverseMercator, ForwardAndInverseMatchProjTmercAcrossAndBeyondTheZone) {
  double worstFwd = 0.0, worstInvDeg = 0.0, worstRoundTrip = 0.0;
  std::size_t points = 0;
  for (const TmCase& c : tmCases()) {
    const TransverseMercator tm = c.make();
    const Proj proj(c.proj());
    ASSERT_TRUE(proj.ok()) << proj.error();
    for (const double lat : kLats) {
      for (const double dl : kDLons) {
        const double lon = c.lon0 + dl;
        const glm::dvec3 ref = proj.trans(PJ_FWD, lon, lat);
        ASSERT_EQ(proj.lastError(), 0) << c.label << " PROJ forward at " << lat << ", " << lon;
        const glm::dvec2 xy = tm.forward({lat, lon});
        const double d = glm::length(xy - glm::dvec2(ref.x, ref.y));
        worstFwd = std::max(worstFwd, d);
        EXPECT_LT(d, 1e-6) << c.label << " forward at lat " << lat << " lon " << lon << ": ("
                           << xy.x << ", " << xy.y << ") vs PROJ (" << ref.x << ", " << ref.y
                           << ")";
        // Our inverse of PROJ's forward, and PROJ's inverse of ours, give the point back.
        const LatLon back = tm.inverse({ref.x, ref.y});
        const glm::dvec3 pinv = proj.trans(PJ_INV, xy.x, xy.y);
        ++points;
        const bool pole = std::abs(lat) == 90.0;
        EXPECT_NEAR(back.latDeg, lat, 1e-9) << c.label << " inverse at " << lat << ", " << lon;
        EXPECT_NEAR(pinv.y, back.latDeg, 1e-9) << c.label << " vs PROJ inverse at " << lat;
        worstInvDeg = std::max(worstInvDeg, std::abs(back.latDeg - lat));
        worstInvDeg = std::max(worstInvDeg, std::abs(pinv.y - back.latDeg));
        if (!pole) {  // the longitude of a pole is anything
          EXPECT_NEAR(lonDiffDeg(back.lonDeg, lon), 0.0, 1e-9)
              << c.label << " inverse at " << lat << ", " << lon;
          EXPECT_NEAR(lonDiffDeg(pinv.x, back.lonDeg), 0.0, 1e-9)
              << c.label << " vs PROJ inverse at " << lat << ", " << lon;
          worstInvDeg = std::max(
              worstInvDeg, std::abs(lonDiffDeg(back.lonDeg, lon)) * std::cos(lat * kRadPerDeg));
          worstInvDeg = std::max(
              worstInvDeg, std::abs(lonDiffDeg(pinv.x, back.lonDeg)) * std::cos(lat * kRadPerDeg));
        }
        EXPECT_GE(back.lonDeg, -180.0);
        EXPECT_LT(back.lonDeg, 180.0);
        // Round trip through our own pair, in metres.
        const glm::dvec2 again = tm.forward(tm.inverse(xy));
        worstRoundTrip = std::max(worstRoundTrip, glm::length(again - xy));
        EXPECT_LT(glm::length(again - xy), 1e-6) << c.label << " round trip at " << lat;
      }
    }
  }
  EXPECT_EQ(points, tmCases().size() * kLats.size() * kDLons.size());
  report("tmerc.forward_vs_PROJ_max_m", worstFwd);
  report("tmerc.inverse_vs_exact_and_PROJ_max_deg", worstInvDeg);
  report("tmerc.round_trip_max_m", worstRoundTrip);
}

TEST(TransverseMercator, UtmZonesMatchProjUtmNorthAndSouth) {
  const Body wgs = Body::earthWgs84();
  double worst = 0.0;
  for (const int zone : {1, 10, 31, 33, 60}) {
    for (const bool north : {true, false}) {
      const TransverseMercator tm = TransverseMercator::utm(wgs, zone, north);
      EXPECT_EQ(tm.lonCentreDeg(), 6.0 * zone - 183.0);
      EXPECT_EQ(tm.scaleFactor(), 0.9996);
      EXPECT_EQ(tm.falseEasting(), 500000.0);
      EXPECT_EQ(tm.falseNorthing(), north ? 0.0 : 10000000.0);
      const Proj proj(degreesIn("+proj=utm +zone=" + std::to_string(zone) +
                                (north ? "" : " +south") + " +ellps=WGS84"));
      ASSERT_TRUE(proj.ok()) << proj.error();
      for (const double dl : {-3.0, -1.25, 0.0, 2.0, 3.0}) {
        for (const double lat : {0.5, 23.0, 47.0, 71.0, 84.0}) {
          const double la = north ? lat : -lat;
          const double lon = tm.lonCentreDeg() + dl;
          const glm::dvec3 ref = proj.trans(PJ_FWD, lon, la);
          const glm::dvec2 xy = tm.forward({la, lon});
          worst = std::max(worst, glm::length(xy - glm::dvec2(ref.x, ref.y)));
          EXPECT_LT(glm::length(xy - glm::dvec2(ref.x, ref.y)), 1e-4)
              << "zone " << zone << (north ? "N" : "S") << " at " << la << ", " << lon;
          // North of the equator northings are positive, south of it below 10,000 km.
          EXPECT_TRUE(north ? xy.y > 0.0 : xy.y < 1e7);
        }
      }
    }
  }
  report("utm.forward_vs_PROJ_utm_max_m", worst);
}

/// Runs a command and returns its standard output.
std::string run(const std::string& command) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  if (!pipe) return {};
  std::string out;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, pipe.get())) > 0) out.append(buf, n);
  return out;
}

TEST(TransverseMercator, InverseMatchesTheCctProgramOnNad27Utm10) {
  // PROJ's command-line program as a second oracle, on the CRS of the UTM fixture:
  // cct on (E, N) through the inverse UTM gives (lon, lat) in degrees with 12 decimals.
  const TransverseMercator tm = TransverseMercator::utm(clarke1866(), 10, true);
  std::ostringstream in;
  in.precision(17);
  std::vector<glm::dvec2> pts;
  for (const double e : {166021.0, 320000.0, 500000.0, 557880.46, 567540.0, 833978.0, 1.1e6}) {
    for (const double n : {1.0, 2.0e6, 5114985.0, 8.0e6, 9.3e6}) {
      pts.emplace_back(e, n);
      in << e << ' ' << n << " 0 0\n";
    }
  }
  const std::string out =
      run("printf '" + in.str() +
          "' | cct -d 12 +proj=pipeline +step +inv +proj=utm +zone=10 +ellps=clrk66 "
          "+step +proj=unitconvert +xy_in=rad +xy_out=deg 2>&1");
  std::istringstream lines(out);
  double worst = 0.0;
  for (const glm::dvec2& p : pts) {
    double lon = kNaN, lat = kNaN, z = 0.0, t = 0.0;
    ASSERT_TRUE(lines >> lon >> lat >> z >> t) << "cct output: " << out;
    const LatLon ll = tm.inverse(p);
    EXPECT_NEAR(ll.latDeg, lat, 1e-9) << p.x << ", " << p.y;
    EXPECT_NEAR(lonDiffDeg(ll.lonDeg, lon), 0.0, 1e-9) << p.x << ", " << p.y;
    worst = std::max({worst, std::abs(ll.latDeg - lat), std::abs(lonDiffDeg(ll.lonDeg, lon))});
  }
  report("utm10_nad27.inverse_vs_cct_max_deg", worst);
}

TEST(TransverseMercator, MatchesSnydersWorkedExampleOnClarke1866) {
  // Snyder (1987) p. 269: φ = 40°30'N, λ = 73°30'W, λ0 = 75°W, φ0 = 0, k0 = 0.9996 on
  // Clarke 1866 gives x = 127,106.5 m, y = 4,484,124.4 m (printed to 0.1 m).
  const TransverseMercator tm(clarke1866(), -75.0, 0.0, 0.9996);
  const glm::dvec2 xy = tm.forward({40.5, -73.5});
  EXPECT_NEAR(xy.x, 127106.5, 0.05);
  EXPECT_NEAR(xy.y, 4484124.4, 0.05);
  const LatLon back = tm.inverse({127106.5, 4484124.4});
  EXPECT_NEAR(back.latDeg, 40.5, 1e-6);  // 0.05 m ≈ 5e-7°
  EXPECT_NEAR(back.lonDeg, -73.5, 1e-6);
}

TEST(TransverseMercator, OnTheCentralMeridianNorthingIsTheScaledMeridianArc) {
  // On λ = λ0, y − FN = k0 (M(φ) − M(φ0)); M from PROJ's `merc`-independent oracle: a
  // numerical integral of the meridian radius of curvature (Simpson, 20000 steps).
  const Body wgs = Body::earthWgs84();
  const TransverseMercator tm(wgs, 9.0, 12.0, 0.9996, 0.0, 1000.0);
  auto arc = [&](double lat) {
    const int n = 20000;
    const double h = lat / n;
    double s = wgs.meridianRadius(0.0) + wgs.meridianRadius(lat);
    for (int i = 1; i < n; ++i) s += (i % 2 == 1 ? 4.0 : 2.0) * wgs.meridianRadius(i * h);
    return s * h / 3.0 * kRadPerDeg;
  };
  for (const double lat : {-70.0, -12.0, 0.0, 12.0, 45.0, 80.0}) {
    const glm::dvec2 xy = tm.forward({lat, 9.0});
    EXPECT_NEAR(xy.x, 0.0, 1e-9) << lat;
    EXPECT_NEAR(xy.y, 1000.0 + 0.9996 * (arc(lat) - arc(12.0)), 1e-5) << lat;
  }
  EXPECT_NEAR(tm.forward({90.0, 9.0}).y, 1000.0 + 0.9996 * (arc(90.0) - arc(12.0)), 1e-5);
  // Any longitude at the pole maps to the pole's image on the central meridian.
  EXPECT_NEAR(glm::length(tm.forward({90.0, 100.0}) - tm.forward({90.0, 9.0})), 0.0, 1e-6);
}

TEST(TransverseMercator, AccessorsReportTheConstructionParameters) {
  const TransverseMercator tm(clarke1866(), -123.0, 4.5, 0.9996, 500000.0, 7.0);
  EXPECT_EQ(tm.lonCentreDeg(), -123.0);
  EXPECT_EQ(tm.latOriginDeg(), 4.5);
  EXPECT_EQ(tm.scaleFactor(), 0.9996);
  EXPECT_EQ(tm.falseEasting(), 500000.0);
  EXPECT_EQ(tm.falseNorthing(), 7.0);
  EXPECT_EQ(tm.equatorialRadius(), 6378206.4);
  EXPECT_EQ(tm.eccentricitySquared(), clarke1866().eccentricitySquared());
  // The false origin is the image of (φ0, λ0).
  const glm::dvec2 o = tm.forward({4.5, -123.0});
  EXPECT_NEAR(o.x, 500000.0, 1e-9);
  EXPECT_NEAR(o.y, 7.0, 1e-8);
}

TEST(TransverseMercator, RejectsBadArgumentsAndPointsOutsideItsDomainNamingTheField) {
  using regolith::DomainError;
  using regolith::InvalidArgument;
  const Body wgs = Body::earthWgs84();
  auto contains = [](const std::string& s, const std::string& p) {
    return s.find(p) != std::string::npos;
  };
  std::string msg = messageOf<InvalidArgument>([&] { (void)TransverseMercator(wgs, kNaN); });
  EXPECT_TRUE(contains(msg, "TransverseMercator()") && contains(msg, "central meridian")) << msg;
  msg = messageOf<InvalidArgument>([&] { (void)TransverseMercator(wgs, 0.0, 91.0); });
  EXPECT_TRUE(contains(msg, "latitude")) << msg;
  msg = messageOf<InvalidArgument>([&] { (void)TransverseMercator(wgs, 0.0, 0.0, 0.0); });
  EXPECT_TRUE(contains(msg, "scale factor") && contains(msg, "expected > 0")) << msg;
  msg = messageOf<InvalidArgument>([&] { (void)TransverseMercator(wgs, 0.0, 0.0, 1.0, kNaN); });
  EXPECT_TRUE(contains(msg, "false easting")) << msg;
  msg =
      messageOf<InvalidArgument>([&] { (void)TransverseMercator(wgs, 0.0, 0.0, 1.0, 0.0, kNaN); });
  EXPECT_TRUE(contains(msg, "false northing")) << msg;
  msg = messageOf<InvalidArgument>([&] { (void)TransverseMercator::utm(wgs, 61, true); });
  EXPECT_TRUE(contains(msg, "zone is 61, expected 1 to 60")) << msg;
  EXPECT_THROW((void)TransverseMercator::utm(wgs, 0, false), InvalidArgument);

  const TransverseMercator tm = TransverseMercator::utm(wgs, 10, true);
  msg = messageOf<DomainError>([&] { (void)tm.forward({10.0, -123.0 + 95.0}); });
  EXPECT_TRUE(contains(msg, "TransverseMercator::forward()") &&
              contains(msg, "from the central meridian"))
      << msg;
  EXPECT_THROW((void)tm.forward({0.0, 57.0}), DomainError);  // the antimeridian
  EXPECT_THROW((void)tm.forward({kNaN, 0.0}), InvalidArgument);
  EXPECT_THROW((void)tm.forward({0.0, kNaN}), InvalidArgument);
  EXPECT_THROW((void)tm.forward({90.5, -123.0}), InvalidArgument);
  msg = messageOf<DomainError>([&] { (void)tm.inverse({500000.0, 2.5e7}); });  // beyond a pole
  EXPECT_TRUE(contains(msg, "TransverseMercator::inverse()") && contains(msg, "domain")) << msg;
  EXPECT_THROW((void)tm.inverse({1e12, 1000.0}), DomainError);
  msg = messageOf<InvalidArgument>([&] { (void)tm.inverse({kNaN, 0.0}); });
  EXPECT_TRUE(contains(msg, "x is")) << msg;
}

// ---- Placement -------------------------------------------------------------------------

TEST(TransverseMercatorPlacement, PositionsAreTheInverseProjectionOnTheBodyAndMatchProjCart) {
  const Body clarke = clarke1866();
  const Placement pl(clarke, TransverseMercator::utm(clarke, 10, true));
  EXPECT_EQ(pl.kind(), Placement::Kind::TransverseMercator);
  ASSERT_NE(pl.transverseMercator(), nullptr);
  EXPECT_EQ(pl.polarStereographic(), nullptr);
  EXPECT_EQ(pl.equirectangular(), nullptr);
  EXPECT_EQ(pl.localTangentPlane(), nullptr);
  EXPECT_EQ(pl.latitudeType(), regolith::topo::LatitudeType::Planetodetic);
  // PROJ: UTM inverse, then geodetic → Cartesian on the same ellipsoid.
  const Proj proj(
      "+proj=pipeline +step +inv +proj=utm +zone=10 +ellps=clrk66 "
      "+step +proj=cart +ellps=clrk66");
  ASSERT_TRUE(proj.ok()) << proj.error();
  double worst = 0.0;
  for (const double x : {300000.0, 557880.0, 700000.0}) {
    for (const double y : {100.0, 5114985.0, 7.5e6}) {
      for (const double h : {-400.0, 0.0, 1234.5}) {
        const glm::dvec3 p = pl.toBodyFixed(x, y, h);
        const glm::dvec3 ref = proj.trans(PJ_FWD, x, y, h);
        worst = std::max(worst, glm::length(p - ref));
        EXPECT_LT(glm::length(p - ref), 1e-3) << x << ", " << y << ", " << h;
        const glm::dvec3 back = pl.fromBodyFixed(p);
        EXPECT_NEAR(back.x, x, 1e-6);
        EXPECT_NEAR(back.y, y, 1e-6);
        EXPECT_NEAR(back.z, h, 1e-6);
        const Geodetic g = pl.toGeodetic(x, y, h);
        const glm::dvec3 xyh = pl.fromGeodetic(g);
        EXPECT_NEAR(glm::length(xyh - glm::dvec3(x, y, h)), 0.0, 1e-6);
      }
    }
  }
  report("utm10_placement.body_fixed_vs_PROJ_cart_max_m", worst);
}

TEST(TransverseMercatorPlacement, RefusesAProjectionMadeOnAnotherEllipsoid) {
  const Body wgs = Body::earthWgs84();
  const std::string msg = messageOf<regolith::InvalidArgument>(
      [&] { (void)Placement(clarke1866(), TransverseMercator::utm(wgs, 10, true)); });
  EXPECT_NE(msg.find("Placement(): the transverse Mercator projection is on an ellipsoid of "
                     "a = 6378137"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("Earth (Clarke 1866): a = 6378206.4"), std::string::npos) << msg;
  EXPECT_THROW((void)Placement(Body::marsSphere(), TransverseMercator(Body::marsEllipsoid(), 0.0)),
               regolith::InvalidArgument);
}

TEST(TransverseMercatorPlacement, AFlatGridsNormalIsTheEllipsoidNormalAndTheJacobianScalesByK) {
  // The Jacobian is central differences over ±0.5 m: on Earth positions round to ~1e-9 m, so
  // its columns are good to ~1e-9 relative.
  const Body wgs = Body::earthWgs84();
  const Placement pl(wgs, TransverseMercator(wgs, 15.0, 0.0, 0.9996, 500000.0, 0.0));
  const Proj factors(
      "+proj=tmerc +algo=poder_engsager +lon_0=15 +k_0=0.9996 +x_0=500000 "
      "+ellps=WGS84");
  ASSERT_TRUE(factors.ok()) << factors.error();
  for (const double x : {300000.0, 500000.0, 850000.0}) {
    for (const double y : {2.0e6, 6.0e6}) {
      const Geodetic g = pl.toGeodetic(x, y, 0.0);
      const glm::dvec3 up = wgs.enuFrame(g.latDeg, g.lonDeg)[2];
      const glm::dvec3 n = pl.normalToBodyFixed({0.0, 0.0, 1.0}, x, y, 0.0);
      EXPECT_LT(glm::length(n - up), 1e-8) << x << ", " << y;
      // A grid metre is 1/k metres on the ground (the map is conformal): PROJ's point scale.
      const PJ_FACTORS f = proj_factors(
          factors.get(), proj_coord(g.lonDeg * kRadPerDeg, g.latDeg * kRadPerDeg, 0.0, 0.0));
      const glm::dmat3 j = pl.jacobian(x, y, 0.0);
      EXPECT_NEAR(glm::length(j[0]), 1.0 / f.parallel_scale, 1e-8) << x << ", " << y;
      EXPECT_NEAR(glm::length(j[1]), 1.0 / f.meridional_scale, 1e-8) << x << ", " << y;
      EXPECT_NEAR(glm::dot(j[0], j[1]), 0.0, 1e-8);
    }
  }
}

}  // namespace
