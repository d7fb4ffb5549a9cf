// Tests for regolith::topo::Body against an outside oracle: PROJ's C API (geocentric
// `cart`, geocentric latitude `geoc`, `topocentric`, and the IAU_2015 / EPSG ellipsoids in
// proj.db). Nothing here is compared with values computed by Regolith itself, except where
// a test checks an internal consistency property (round trip, orthonormality).
//
// The largest errors observed against PROJ are printed on stdout and recorded as test
// properties (gtest --gtest_output=xml shows them).

#include <regolith/core/Error.hpp>
#include <regolith/topo/Body.hpp>

#include "support/ProjOracle.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using regolith::topo::Body;
using regolith::topo::Geodetic;
using regolith::topo::LatitudeType;

constexpr double kPi = std::numbers::pi;
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

using regolith::test::num;
using regolith::test::Proj;
using regolith::test::projEllipsoid;

/// Geodetic (lon deg, lat deg, h m) <-> geocentric Cartesian (m) pipeline.
std::string projCart(const Body& body) {
  return "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=cart" +
         projEllipsoid(body);
}

using regolith::test::messageOf;
using regolith::test::report;

double lonDiffDeg(double a, double b) { return std::remainder(a - b, 360.0); }

/// Latitudes, longitudes and heights for the geodetic grids: poles, equator, ±180.
const std::vector<double> kGridLats = {-90.0, -89.9999999, -89.99, -80.0,    -60.0, -45.0, -33.3,
                                       -10.0, -1e-9,       0.0,    1e-7,     0.5,   15.0,  44.999,
                                       60.0,  75.5,        89.9,   89.99999, 90.0};
const std::vector<double> kGridLons = {-180.0, -179.999, -135.0, -90.0, -45.0,  -1e-8,
                                       0.0,    12.3456,  90.0,   135.0, 179.99, 180.0};
const std::vector<double> kGridHeights = {-10000.0, -1000.0, -1.0,  0.0,   0.001, 100.0,
                                          1000.0,   10000.0, 1.0e5, 5.0e5, 1.0e6};

struct CartErrors {
  double position = 0.0;       // |toBodyFixed − PROJ cart|, m
  double horizontal = 0.0;     // toGeodetic angular error × a, m
  double height = 0.0;         // toGeodetic height error, m
  double vsProjInverse = 0.0;  // PROJ's own cart inverse vs exact, m (angles × a)
};

/// Checks toBodyFixed and toGeodetic at one geodetic point against PROJ cart.
void checkCartPoint(const Body& body, const Proj& cart, const Geodetic& g, CartErrors& worst) {
  const double a = body.equatorialRadius();
  const double tolM = 1e-3;
  const double tolDeg = tolM / a / kRadPerDeg;

  const glm::dvec3 ref = cart.trans(PJ_FWD, g.lonDeg, g.latDeg, g.height);
  ASSERT_TRUE(std::isfinite(ref.x) && std::isfinite(ref.y) && std::isfinite(ref.z));
  const glm::dvec3 ours = body.toBodyFixed(g);
  const double dp = glm::length(ours - ref);
  EXPECT_LT(dp, tolM) << body.name() << " toBodyFixed at lat " << g.latDeg << " lon " << g.lonDeg
                      << " h " << g.height;
  worst.position = std::max(worst.position, dp);

  // Inverse: the exact geodetic point that PROJ's closed-form forward mapped to `ref`.
  const Geodetic back = body.toGeodetic(ref);
  const double cosLat = std::cos(g.latDeg * kRadPerDeg);
  const double dLat = std::abs(back.latDeg - g.latDeg);
  const double dLon = std::abs(lonDiffDeg(back.lonDeg, g.lonDeg)) * cosLat;
  const double dH = std::abs(back.height - g.height);
  EXPECT_LT(dLat, tolDeg) << body.name() << " toGeodetic lat at lat " << g.latDeg << " lon "
                          << g.lonDeg << " h " << g.height;
  EXPECT_LT(dLon, tolDeg) << body.name() << " toGeodetic lon at lat " << g.latDeg << " lon "
                          << g.lonDeg << " h " << g.height;
  EXPECT_LT(dH, tolM) << body.name() << " toGeodetic height at lat " << g.latDeg << " lon "
                      << g.lonDeg << " h " << g.height;
  EXPECT_GT(back.lonDeg, -180.0);
  EXPECT_LE(back.lonDeg, 180.0);
  worst.horizontal = std::max(worst.horizontal, std::max(dLat, dLon) * kRadPerDeg * a);
  worst.height = std::max(worst.height, dH);

  // PROJ's own inverse (cart.cpp: a single, non-iterated Bowring step) is not an exact
  // oracle at high altitude: it is off by centimetres at 1000 km on Mars. So the check is
  // that ours is at least as close to the exact point as PROJ's inverse is.
  const glm::dvec3 projInv = cart.trans(PJ_INV, ref.x, ref.y, ref.z);
  const double projErr =
      std::max({std::abs(projInv.y - g.latDeg) * kRadPerDeg * a,
                std::abs(lonDiffDeg(projInv.x, g.lonDeg)) * cosLat * kRadPerDeg * a,
                std::abs(projInv.z - g.height)});
  const double oursErr = std::max({dLat * kRadPerDeg * a, dLon * kRadPerDeg * a, dH});
  // Slack: a few ulps of the coordinates (1.5e-8 m for Saturn's 6e7 m radius).
  EXPECT_LE(oursErr, projErr + std::max(1e-8, 2e-15 * a))
      << body.name() << " toGeodetic less accurate than PROJ "
      << "at lat " << g.latDeg << " lon " << g.lonDeg << " h " << g.height;
  const double dP = projErr;
  worst.vsProjInverse = std::max(worst.vsProjInverse, dP);
}

void checkCartAgainstProj(const Body& body, const std::string& label) {
  const Proj cart(projCart(body));
  ASSERT_TRUE(cart.ok()) << cart.error();
  CartErrors worst;
  int count = 0;
  for (const double lat : kGridLats) {
    for (const double lon : kGridLons) {
      for (const double h : kGridHeights) {
        checkCartPoint(body, cart, {lat, lon, h}, worst);
        ++count;
      }
    }
  }
  // Plus random points, fixed seed, uniformly over the same altitude band.
  std::mt19937_64 rng(20240601u);
  std::uniform_real_distribution<double> uz(-1.0, 1.0);
  std::uniform_real_distribution<double> ulon(-180.0, 180.0);
  std::uniform_real_distribution<double> uh(-10000.0, 1.0e6);
  for (int i = 0; i < 20000; ++i) {
    const double lat = std::asin(uz(rng)) / kRadPerDeg;
    checkCartPoint(body, cart, {lat, ulon(rng), uh(rng)}, worst);
    ++count;
  }
  EXPECT_GT(count, 20000);
  report(label + ".toBodyFixed_vs_PROJ_cart_max_m", worst.position);
  report(label + ".toGeodetic_horizontal_vs_exact_max_m", worst.horizontal);
  report(label + ".toGeodetic_height_vs_exact_max_m", worst.height);
  report(label + ".PROJ_cart_inverse_vs_exact_max_m(for_comparison)", worst.vsProjInverse);
}

/// Parameters (a, b) of the ellipsoid of a CRS or ellipsoid known to proj.db.
bool projEllipsoidOf(const char* code, double& a, double& b) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* obj = proj_create(ctx, code);
  bool ok = false;
  if (obj != nullptr) {
    PJ* ell = proj_get_ellipsoid(ctx, obj);
    if (ell != nullptr) {
      int computed = 0;
      double invFlattening = 0.0;
      ok = proj_ellipsoid_get_parameters(ctx, ell, &a, &b, &computed, &invFlattening) != 0;
      proj_destroy(ell);
    }
    proj_destroy(obj);
  }
  proj_context_destroy(ctx);
  return ok;
}

// ---- Bodies and radii ------------------------------------------------------------------

TEST(Body, IauPresetsMatchProjIau2015AndEpsgEllipsoids) {
  double a = 0.0, b = 0.0;

  // IAU_2015:49900 Mars (2015) - Sphere / Ocentric.
  ASSERT_TRUE(projEllipsoidOf("IAU_2015:49900", a, b));
  const Body marsSphere = Body::marsSphere();
  EXPECT_EQ(marsSphere.equatorialRadius(), a);
  EXPECT_EQ(marsSphere.polarRadius(), a);
  EXPECT_EQ(a, 3396190.0);
  EXPECT_TRUE(marsSphere.isSphere());
  EXPECT_EQ(marsSphere.eccentricitySquared(), 0.0);
  EXPECT_EQ(marsSphere.flattening(), 0.0);
  EXPECT_EQ(marsSphere.name(), "Mars");

  // IAU_2015:49901 Mars (2015) / Ographic: a = 3396190, b = 3376200.
  ASSERT_TRUE(projEllipsoidOf("IAU_2015:49901", a, b));
  const Body mars = Body::marsEllipsoid();
  EXPECT_EQ(mars.equatorialRadius(), a);
  EXPECT_EQ(mars.polarRadius(), b);
  EXPECT_EQ(a, 3396190.0);
  EXPECT_EQ(b, 3376200.0);
  EXPECT_FALSE(mars.isSphere());
  EXPECT_EQ(mars.name(), "Mars");

  // IAU_2015:30100 Moon (2015) - Sphere / Ocentric.
  ASSERT_TRUE(projEllipsoidOf("IAU_2015:30100", a, b));
  const Body moon = Body::moon();
  EXPECT_EQ(moon.equatorialRadius(), a);
  EXPECT_EQ(moon.polarRadius(), a);
  EXPECT_EQ(a, 1737400.0);
  EXPECT_TRUE(moon.isSphere());
  EXPECT_EQ(moon.name(), "Moon");

  // EPSG:4326 (WGS 84): a = 6378137, 1/f = 298.257223563; b = 6356752.314245179...
  ASSERT_TRUE(projEllipsoidOf("EPSG:4326", a, b));
  const Body earth = Body::earthWgs84();
  EXPECT_EQ(earth.equatorialRadius(), a);
  EXPECT_NEAR(earth.polarRadius(), b, 1e-9);
  EXPECT_NEAR(earth.polarRadius(), 6356752.314245, 1e-6);  // NIMA TR8350.2 table 3.1
  EXPECT_NEAR(1.0 / earth.flattening(), 298.257223563, 1e-8);
  EXPECT_NEAR(earth.eccentricitySquared(), 6.69437999014e-3, 1e-14);  // TR8350.2
  EXPECT_EQ(earth.name(), "Earth");
}

TEST(Body, CustomRadiiGiveClosedFormShapeParameters) {
  const Body titan = Body::sphere("Titan", 2574730.0);
  EXPECT_EQ(titan.name(), "Titan");
  EXPECT_EQ(titan.equatorialRadius(), 2574730.0);
  EXPECT_EQ(titan.polarRadius(), 2574730.0);
  EXPECT_TRUE(titan.isSphere());
  EXPECT_EQ(titan.eccentricitySquared(), 0.0);

  const double a = 60268000.0, b = 54364000.0;  // Saturn, 1-bar level
  const Body saturn = Body::ellipsoid("Saturn", a, b);
  EXPECT_EQ(saturn.name(), "Saturn");
  EXPECT_EQ(saturn.equatorialRadius(), a);
  EXPECT_EQ(saturn.polarRadius(), b);
  EXPECT_FALSE(saturn.isSphere());
  EXPECT_NEAR(saturn.flattening(), (a - b) / a, 1e-15);
  EXPECT_NEAR(saturn.eccentricitySquared(), 1.0 - (b / a) * (b / a), 1e-15);
  // e² = 2f − f² for any ellipsoid.
  const double f = saturn.flattening();
  EXPECT_NEAR(saturn.eccentricitySquared(), 2.0 * f - f * f, 1e-15);

  // An "ellipsoid" with equal radii is a sphere.
  const Body round = Body::ellipsoid("Round", 1000.0, 1000.0);
  EXPECT_TRUE(round.isSphere());
  EXPECT_EQ(round.eccentricitySquared(), 0.0);
}

TEST(Body, SphereRejectsNonPositiveAndNonFiniteRadiusNamingOperationAndField) {
  for (const double r : {0.0, -1.0, -3396190.0, kNaN, kInf, -kInf}) {
    const std::string msg =
        messageOf<regolith::InvalidArgument>([&] { (void)Body::sphere("Vesta", r); });
    EXPECT_NE(msg.find("Body::sphere()"), std::string::npos) << msg;
    EXPECT_NE(msg.find("radius"), std::string::npos) << msg;
    EXPECT_NE(msg.find("Vesta"), std::string::npos) << msg;
    EXPECT_NE(msg.find("> 0"), std::string::npos) << msg;
  }
  const std::string msg =
      messageOf<regolith::InvalidArgument>([] { (void)Body::sphere("Vesta", -12.5); });
  EXPECT_NE(msg.find("-12.5"), std::string::npos) << msg;
  // InvalidArgument is a regolith::Error.
  EXPECT_THROW((void)Body::sphere("x", 0.0), regolith::Error);
}

TEST(Body, EllipsoidRejectsBadRadiiNamingOperationAndField) {
  struct Case {
    double a, b;
  };
  for (const Case c : {Case{3376200.0, 3396190.0},  // b > a (prolate)
                       Case{3396190.0, 0.0}, Case{3396190.0, -1.0}, Case{-1.0, -2.0},
                       Case{0.0, 0.0}, Case{kNaN, 3376200.0}, Case{3396190.0, kNaN},
                       Case{kInf, 3376200.0}, Case{3396190.0, kInf}, Case{kInf, kInf}}) {
    const std::string msg =
        messageOf<regolith::InvalidArgument>([&] { (void)Body::ellipsoid("Phobos", c.a, c.b); });
    EXPECT_NE(msg.find("Body::ellipsoid()"), std::string::npos) << msg;
    EXPECT_NE(msg.find("radii"), std::string::npos) << msg;
    EXPECT_NE(msg.find("a = "), std::string::npos) << msg;
    EXPECT_NE(msg.find("b = "), std::string::npos) << msg;
    EXPECT_NE(msg.find("Phobos"), std::string::npos) << msg;
    EXPECT_NE(msg.find("0 < b <= a"), std::string::npos) << msg;
  }
  EXPECT_NO_THROW((void)Body::ellipsoid("ok", 2.0, 1.0));
  EXPECT_NO_THROW((void)Body::ellipsoid("ok", 2.0, 2.0));
}

// ---- Planetocentric <-> planetodetic latitude -----------------------------------------

TEST(BodyLatitude, PlanetocentricMatchesProjGeocAndClosedForm) {
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84(),
                           Body::ellipsoid("Saturn", 60268000.0, 54364000.0)}) {
    // PROJ `geoc` converts geodetic to geocentric latitude.
    const Proj geoc(
        "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad "
        "+step +proj=geoc" +
        projEllipsoid(body) + " +step +proj=unitconvert +xy_in=rad +xy_out=deg");
    ASSERT_TRUE(geoc.ok()) << geoc.error();
    const double a = body.equatorialRadius(), b = body.polarRadius();
    double worstProj = 0.0, worstClosed = 0.0;
    for (double pd = -89.75; pd <= 89.75; pd += 0.25) {
      const double pc = body.planetocentricFromPlanetodetic(pd);
      const double ref = geoc.trans(PJ_FWD, 10.0, pd, 0.0).y;
      worstProj = std::max(worstProj, std::abs(pc - ref));
      EXPECT_NEAR(pc, ref, 1e-12) << body.name() << " planetodetic " << pd;
      // Closed form: tan(pc) = (b/a)² tan(pd).
      const double closed = std::atan((b / a) * (b / a) * std::tan(pd * kRadPerDeg)) / kRadPerDeg;
      worstClosed = std::max(worstClosed, std::abs(pc - closed));
      EXPECT_NEAR(pc, closed, 1e-12) << body.name() << " planetodetic " << pd;
      // The inverse against PROJ's inverse.
      const double refInv = geoc.trans(PJ_INV, 10.0, pd, 0.0).y;
      EXPECT_NEAR(body.planetodeticFromPlanetocentric(pd), refInv, 1e-12)
          << body.name() << " planetocentric " << pd;
      // Planetocentric latitude is closer to the equator (oblate body).
      if (pd != 0.0) {
        EXPECT_LT(std::abs(pc), std::abs(pd));
      }
    }
    report("latitude." + body.name() + ".planetocentric_vs_PROJ_geoc_max_deg", worstProj);
    report("latitude." + body.name() + ".planetocentric_vs_closed_form_max_deg", worstClosed);
  }
}

TEST(BodyLatitude, PlanetocentricIsTheDirectionOfTheSurfacePointFromTheCentre) {
  // Independent geometric definition: the surface point of planetodetic latitude pd (from
  // PROJ cart) seen from the centre makes the planetocentric angle with the equator.
  const Body mars = Body::marsEllipsoid();
  const Proj cart(projCart(mars));
  ASSERT_TRUE(cart.ok()) << cart.error();
  for (double pd = -89.0; pd <= 89.0; pd += 7.0) {
    const glm::dvec3 p = cart.trans(PJ_FWD, 33.0, pd, 0.0);
    const double pcGeom = std::atan2(p.z, std::hypot(p.x, p.y)) / kRadPerDeg;
    EXPECT_NEAR(mars.planetocentricFromPlanetodetic(pd), pcGeom, 1e-12) << pd;
    EXPECT_NEAR(mars.planetodeticFromPlanetocentric(pcGeom), pd, 1e-12) << pd;
  }
}

TEST(BodyLatitude, RoundTripIsExactToRoundingAndPolesAndEquatorAreExact) {
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84(),
                           Body::ellipsoid("Saturn", 60268000.0, 54364000.0)}) {
    double worst = 0.0;
    for (double lat = -90.0; lat <= 90.0; lat += 0.125) {
      const double viaPc =
          body.planetodeticFromPlanetocentric(body.planetocentricFromPlanetodetic(lat));
      const double viaPd =
          body.planetocentricFromPlanetodetic(body.planetodeticFromPlanetocentric(lat));
      worst = std::max({worst, std::abs(viaPc - lat), std::abs(viaPd - lat)});
      EXPECT_NEAR(viaPc, lat, 1e-12) << body.name() << ' ' << lat;
      EXPECT_NEAR(viaPd, lat, 1e-12) << body.name() << ' ' << lat;
    }
    report("latitude." + body.name() + ".round_trip_max_deg", worst);
    // Exact at the poles and the equator.
    EXPECT_EQ(body.planetocentricFromPlanetodetic(90.0), 90.0) << body.name();
    EXPECT_EQ(body.planetocentricFromPlanetodetic(-90.0), -90.0) << body.name();
    EXPECT_EQ(body.planetodeticFromPlanetocentric(90.0), 90.0) << body.name();
    EXPECT_EQ(body.planetodeticFromPlanetocentric(-90.0), -90.0) << body.name();
    EXPECT_EQ(body.planetocentricFromPlanetodetic(0.0), 0.0) << body.name();
    EXPECT_EQ(body.planetodeticFromPlanetocentric(0.0), 0.0) << body.name();
  }
}

TEST(BodyLatitude, TypesAgreeOnASphereAndDispatchOnAnEllipsoid) {
  for (const Body& sphere : {Body::marsSphere(), Body::moon(), Body::ellipsoid("R", 5.0, 5.0)}) {
    for (double lat = -90.0; lat <= 90.0; lat += 2.5) {
      EXPECT_EQ(sphere.planetocentricFromPlanetodetic(lat), lat);
      EXPECT_EQ(sphere.planetodeticFromPlanetocentric(lat), lat);
      EXPECT_EQ(sphere.toPlanetodetic(lat, LatitudeType::Planetocentric), lat);
      EXPECT_EQ(sphere.fromPlanetodetic(lat, LatitudeType::Planetocentric), lat);
    }
  }
  const Body mars = Body::marsEllipsoid();
  const Proj geoc(
      "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad "
      "+step +proj=geoc" +
      projEllipsoid(mars) + " +step +proj=unitconvert +xy_in=rad +xy_out=deg");
  ASSERT_TRUE(geoc.ok()) << geoc.error();
  for (const double lat : {-60.0, -12.0, 30.0, 45.0, 80.0}) {
    EXPECT_EQ(mars.toPlanetodetic(lat, LatitudeType::Planetodetic), lat);
    EXPECT_EQ(mars.fromPlanetodetic(lat, LatitudeType::Planetodetic), lat);
    EXPECT_NEAR(mars.toPlanetodetic(lat, LatitudeType::Planetocentric),
                geoc.trans(PJ_INV, 0.0, lat, 0.0).y, 1e-12);
    EXPECT_NEAR(mars.fromPlanetodetic(lat, LatitudeType::Planetocentric),
                geoc.trans(PJ_FWD, 0.0, lat, 0.0).y, 1e-12);
    // Mars' planetocentric and planetodetic latitudes differ by up to ~0.34°.
    EXPECT_GT(std::abs(mars.toPlanetodetic(lat, LatitudeType::Planetocentric) - lat), 0.05);
  }
}

// ---- Geodetic <-> body-fixed Cartesian -------------------------------------------------

TEST(BodyCartesian, MarsEllipsoidMatchesProjCartFromMinus10KmTo1000Km) {
  checkCartAgainstProj(Body::marsEllipsoid(), "MarsEllipsoid");
}

TEST(BodyCartesian, EarthWgs84MatchesProjCartFromMinus10KmTo1000Km) {
  checkCartAgainstProj(Body::earthWgs84(), "EarthWGS84");
}

TEST(BodyCartesian, SpheresMatchProjCartFromMinus10KmTo1000Km) {
  checkCartAgainstProj(Body::marsSphere(), "MarsSphere");
  checkCartAgainstProj(Body::moon(), "Moon");
}

TEST(BodyCartesian, StronglyFlattenedBodyMatchesProjCart) {
  // Saturn (f ≈ 0.098): a far larger eccentricity than any terrestrial body, testing that
  // the iteration in toGeodetic converges for a custom body too.
  checkCartAgainstProj(Body::ellipsoid("Saturn", 60268000.0, 54364000.0), "Saturn");
}

TEST(BodyCartesian, PointsOnTheAxisAreExactlyAtThePolesWithLongitudeZero) {
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84(), Body::moon()}) {
    const double b = body.polarRadius();
    for (const double h : {-10000.0, 0.0, 1234.5, 1.0e6}) {
      const Geodetic north = body.toGeodetic({0.0, 0.0, b + h});
      EXPECT_EQ(north.latDeg, 90.0) << body.name();
      EXPECT_EQ(north.lonDeg, 0.0) << body.name();
      EXPECT_NEAR(north.height, h, 1e-9) << body.name();
      const Geodetic south = body.toGeodetic({0.0, 0.0, -(b + h)});
      EXPECT_EQ(south.latDeg, -90.0) << body.name();
      EXPECT_EQ(south.lonDeg, 0.0) << body.name();
      EXPECT_NEAR(south.height, h, 1e-9) << body.name();
    }
    // And toBodyFixed at the poles lies on the axis (to rounding) at distance b + h.
    const glm::dvec3 p = body.toBodyFixed({90.0, 77.0, 500.0});
    EXPECT_LT(std::hypot(p.x, p.y), 1e-6);
    EXPECT_NEAR(p.z, b + 500.0, 1e-9);
    const glm::dvec3 q = body.toBodyFixed({-90.0, -120.0, 500.0});
    EXPECT_LT(std::hypot(q.x, q.y), 1e-6);
    EXPECT_NEAR(q.z, -(b + 500.0), 1e-9);
  }
}

TEST(BodyCartesian, LongitudeIsReturnedInMinus180Exclusive180Inclusive) {
  // −180° and 180° are one meridian; toGeodetic documents (−180, 180].
  for (const Body& body : {Body::marsEllipsoid(), Body::moon()}) {
    const double a = body.equatorialRadius();
    for (const glm::dvec3& p :
         {glm::dvec3(-a, 0.0, 0.0), glm::dvec3(-a, -0.0, 0.0), glm::dvec3(-a, -1e-300, 1000.0),
          body.toBodyFixed({0.0, -180.0, 0.0}), body.toBodyFixed({45.0, -180.0, 100.0}),
          body.toBodyFixed({-30.0, 180.0, 0.0})}) {
      const Geodetic g = body.toGeodetic(p);
      EXPECT_EQ(g.lonDeg, 180.0) << body.name() << " at (" << p.x << ", " << p.y << ", " << p.z
                                 << ")";
    }
    EXPECT_NEAR(body.toGeodetic(body.toBodyFixed({10.0, 359.0, 0.0})).lonDeg, -1.0, 1e-10);
    EXPECT_NEAR(body.toGeodetic(body.toBodyFixed({10.0, -181.0, 0.0})).lonDeg, 179.0, 1e-10);
  }
}

TEST(BodyCartesian, RadiiOfCurvatureMatchTheGeometryOfProjCart) {
  // N: distance from the surface point to the polar axis along the normal, N cos φ = ρ.
  // M: arc length along the meridian per radian, from a central difference of PROJ points.
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84()}) {
    const Proj cart(projCart(body));
    ASSERT_TRUE(cart.ok()) << cart.error();
    for (double lat = -85.0; lat <= 85.0; lat += 5.0) {
      const glm::dvec3 p = cart.trans(PJ_FWD, 20.0, lat, 0.0);
      const double nRef = std::hypot(p.x, p.y) / std::cos(lat * kRadPerDeg);
      EXPECT_NEAR(body.primeVerticalRadius(lat), nRef, 1e-6) << body.name() << ' ' << lat;
      const double d = 1e-4;  // degrees; chord/arc error ~ (d·π/180)² / 24 relative
      const glm::dvec3 lo = cart.trans(PJ_FWD, 20.0, lat - d, 0.0);
      const glm::dvec3 hi = cart.trans(PJ_FWD, 20.0, lat + d, 0.0);
      const double mRef = glm::length(hi - lo) / (2.0 * d * kRadPerDeg);
      EXPECT_NEAR(body.meridianRadius(lat), mRef, 1e-3) << body.name() << ' ' << lat;
    }
    // Closed forms at the equator and the pole: M(0) = b²/a, N(0) = a, M(90) = N(90) = a²/b.
    const double a = body.equatorialRadius(), b = body.polarRadius();
    EXPECT_NEAR(body.meridianRadius(0.0), b * b / a, 1e-6);
    EXPECT_NEAR(body.primeVerticalRadius(0.0), a, 1e-6);
    EXPECT_NEAR(body.meridianRadius(90.0), a * a / b, 1e-6);
    EXPECT_NEAR(body.primeVerticalRadius(90.0), a * a / b, 1e-6);
  }
}

// ---- East-north-up frame ---------------------------------------------------------------

/// Columns of m as vectors.
glm::dvec3 col(const glm::dmat3& m, int i) { return m[i]; }

TEST(BodyEnuFrame, IsOrthonormalAndRightHandedEverywhereIncludingThePoles) {
  double worst = 0.0;
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84(), Body::moon()}) {
    for (const double lat : kGridLats) {
      for (const double lon : kGridLons) {
        const glm::dmat3 f = body.enuFrame(lat, lon);
        const glm::dvec3 e = col(f, 0), n = col(f, 1), u = col(f, 2);
        for (const glm::dvec3& v : {e, n, u}) {
          ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
          worst = std::max(worst, std::abs(glm::length(v) - 1.0));
          EXPECT_NEAR(glm::length(v), 1.0, 1e-15) << lat << ' ' << lon;
        }
        worst = std::max(
            {worst, std::abs(glm::dot(e, n)), std::abs(glm::dot(n, u)), std::abs(glm::dot(e, u))});
        EXPECT_NEAR(glm::dot(e, n), 0.0, 1e-15) << lat << ' ' << lon;
        EXPECT_NEAR(glm::dot(n, u), 0.0, 1e-15) << lat << ' ' << lon;
        EXPECT_NEAR(glm::dot(e, u), 0.0, 1e-15) << lat << ' ' << lon;
        // Right-handed: E × N = U.
        const glm::dvec3 exn = glm::cross(e, n);
        worst = std::max(worst, glm::length(exn - u));
        EXPECT_LT(glm::length(exn - u), 1e-15) << lat << ' ' << lon;
        EXPECT_GT(glm::determinant(f), 0.0);
      }
    }
  }
  report("enu.orthonormality_max", worst);
}

TEST(BodyEnuFrame, UpIsTheEllipsoidNormalAndEastNorthFollowTheCoordinateLines) {
  double worstUp = 0.0, worstGrad = 0.0;
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84(), Body::moon()}) {
    const Proj cart(projCart(body));
    ASSERT_TRUE(cart.ok()) << cart.error();
    const double a = body.equatorialRadius(), b = body.polarRadius();
    for (const double lat : kGridLats) {
      for (const double lon : kGridLons) {
        const glm::dmat3 f = body.enuFrame(lat, lon);
        // Finite difference in height of PROJ's geodetic → Cartesian (exactly linear in h).
        const glm::dvec3 hi = cart.trans(PJ_FWD, lon, lat, 500.0);
        const glm::dvec3 lo = cart.trans(PJ_FWD, lon, lat, -500.0);
        const glm::dvec3 upFd = (hi - lo) / 1000.0;
        worstUp = std::max(worstUp, glm::length(upFd - col(f, 2)));
        EXPECT_LT(glm::length(upFd - col(f, 2)), 1e-9) << body.name() << ' ' << lat << ' ' << lon;
        // Same finite difference of our own toBodyFixed.
        const glm::dvec3 upOurs =
            (body.toBodyFixed({lat, lon, 500.0}) - body.toBodyFixed({lat, lon, -500.0})) / 1000.0;
        EXPECT_LT(glm::length(upOurs - col(f, 2)), 1e-9) << body.name() << ' ' << lat;
        // Gradient of x²/a² + y²/a² + z²/b² at the surface point, normalised.
        const glm::dvec3 s = cart.trans(PJ_FWD, lon, lat, 0.0);
        const glm::dvec3 grad =
            glm::normalize(glm::dvec3(s.x / (a * a), s.y / (a * a), s.z / (b * b)));
        worstGrad = std::max(worstGrad, glm::length(grad - col(f, 2)));
        EXPECT_LT(glm::length(grad - col(f, 2)), 1e-12) << body.name() << ' ' << lat << ' ' << lon;

        // East and north: central differences of PROJ's mapping in longitude and latitude,
        // which are smooth through the pole (latitude 90 + d is the far meridian).
        // PROJ rejects |lat| > 90, so the difference is one-sided at the poles (direction
        // error about half the step, 9e-8 rad, instead of O(step²)).
        const double d = 1e-5;
        const double latLo = std::max(lat - d, -90.0), latHi = std::min(lat + d, 90.0);
        const double tolN = (latHi - latLo < 1.5 * d) ? 2e-7 : 1e-8;
        const glm::dvec3 dLat =
            cart.trans(PJ_FWD, lon, latHi, 0.0) - cart.trans(PJ_FWD, lon, latLo, 0.0);
        EXPECT_LT(glm::length(glm::normalize(dLat) - col(f, 1)), tolN)
            << body.name() << " north at " << lat << ' ' << lon;
        if (std::abs(lat) < 89.9) {
          const glm::dvec3 dLon =
              cart.trans(PJ_FWD, lon + d, lat, 0.0) - cart.trans(PJ_FWD, lon - d, lat, 0.0);
          EXPECT_LT(glm::length(glm::normalize(dLon) - col(f, 0)), 1e-8)
              << body.name() << " east at " << lat << ' ' << lon;
        }
      }
    }
  }
  report("enu.up_vs_PROJ_height_difference_max", worstUp);
  report("enu.up_vs_ellipsoid_gradient_max", worstGrad);
}

TEST(BodyEnuFrame, MatchesProjTopocentricAxesIncludingThePoles) {
  // PROJ topocentric maps a geocentric point to ENU about an origin; the ENU coordinates of
  // origin + column i of our frame must be the i-th unit vector.
  double worst = 0.0;
  for (const Body& body : {Body::marsEllipsoid(), Body::earthWgs84()}) {
    for (const double lat : {-90.0, -45.0, 0.0, 30.0, 89.99999, 90.0}) {
      for (const double lon : {-180.0, -60.0, 0.0, 135.0, 180.0}) {
        const Proj topo("+proj=topocentric +lat_0=" + num(lat) + " +lon_0=" + num(lon) + " +h_0=0" +
                        projEllipsoid(body));
        ASSERT_TRUE(topo.ok()) << topo.error();
        const glm::dvec3 o = body.toBodyFixed({lat, lon, 0.0});
        const glm::dmat3 f = body.enuFrame(lat, lon);
        for (int i = 0; i < 3; ++i) {
          const glm::dvec3 p = o + 1000.0 * col(f, i);
          const glm::dvec3 enu = topo.trans(PJ_FWD, p.x, p.y, p.z) / 1000.0;
          glm::dvec3 expected(0.0);
          expected[i] = 1.0;
          worst = std::max(worst, glm::length(enu - expected));
          EXPECT_LT(glm::length(enu - expected), 1e-11)
              << body.name() << " axis " << i << " at " << lat << ' ' << lon;
        }
      }
    }
  }
  report("enu.axes_vs_PROJ_topocentric_max", worst);
}

TEST(BodyEnuFrame, AtThePolesEastIsIncreasingLongitudeAtTheGivenMeridian) {
  const Body mars = Body::marsEllipsoid();
  for (const double lon : {-180.0, -90.0, 0.0, 33.0, 180.0}) {
    const double l = lon * kRadPerDeg;
    for (const double pole : {90.0, -90.0}) {
      const glm::dmat3 f = mars.enuFrame(pole, lon);
      // East: the limit of the longitude direction, (−sin λ, cos λ, 0).
      EXPECT_LT(glm::length(col(f, 0) - glm::dvec3(-std::sin(l), std::cos(l), 0.0)), 1e-15);
      // Up: ±Z.
      EXPECT_LT(glm::length(col(f, 2) - glm::dvec3(0.0, 0.0, pole > 0 ? 1.0 : -1.0)), 1e-15);
      // North at the north pole points down the meridian λ + 180°, at the south pole up λ.
      const glm::dvec3 nExpected = pole > 0 ? glm::dvec3(-std::cos(l), -std::sin(l), 0.0)
                                            : glm::dvec3(std::cos(l), std::sin(l), 0.0);
      EXPECT_LT(glm::length(col(f, 1) - nExpected), 1e-15);
      // Continuous with the frame just off the pole.
      const glm::dmat3 near = mars.enuFrame(pole > 0 ? 89.999999 : -89.999999, lon);
      for (int i = 0; i < 3; ++i) {
        EXPECT_LT(glm::length(col(near, i) - col(f, i)), 1e-7);
      }
    }
  }
}

// ---- Helpers declared in Body.hpp ------------------------------------------------------

TEST(BodyHelpers, RequireFiniteThrowsInvalidArgumentNamingOperationAndField) {
  for (const double v : {kNaN, kInf, -kInf}) {
    const std::string msg = messageOf<regolith::InvalidArgument>(
        [&] { regolith::topo::requireFinite(v, "Thing::frob()", "easting"); });
    EXPECT_EQ(msg.rfind("Thing::frob()", 0), 0u) << msg;  // starts with the operation
    EXPECT_NE(msg.find("easting"), std::string::npos) << msg;
    EXPECT_NE(msg.find("finite"), std::string::npos) << msg;
  }
  EXPECT_NO_THROW(regolith::topo::requireFinite(-1e300, "op", "field"));
  EXPECT_NO_THROW(regolith::topo::requireFinite(0.0, "op", "field"));
}

TEST(BodyHelpers, LongitudeWrappingHitsTheDocumentedHalfOpenRanges) {
  using regolith::topo::wrapLongitude180;
  using regolith::topo::wrapLongitude360;
  EXPECT_EQ(wrapLongitude180(180.0), -180.0);
  EXPECT_EQ(wrapLongitude180(-180.0), -180.0);
  EXPECT_EQ(wrapLongitude180(540.0), -180.0);
  EXPECT_EQ(wrapLongitude180(359.0), -1.0);
  EXPECT_EQ(wrapLongitude180(-190.0), 170.0);
  EXPECT_EQ(wrapLongitude180(0.0), 0.0);
  EXPECT_EQ(wrapLongitude360(360.0), 0.0);
  EXPECT_EQ(wrapLongitude360(-1.0), 359.0);
  EXPECT_EQ(wrapLongitude360(-720.0), 0.0);
  for (const double tiny : {-1e-300, -1e-20, -1e-15}) {
    EXPECT_GE(wrapLongitude360(tiny), 0.0);
    EXPECT_LT(wrapLongitude360(tiny), 360.0);
    EXPECT_GE(wrapLongitude180(-180.0 + tiny), -180.0);
    EXPECT_LT(wrapLongitude180(-180.0 + tiny), 180.0);
  }
  for (double lon = -1000.0; lon <= 1000.0; lon += 0.37) {
    const double w = wrapLongitude180(lon);
    EXPECT_GE(w, -180.0);
    EXPECT_LT(w, 180.0);
    EXPECT_NEAR(std::remainder(w - lon, 360.0), 0.0, 1e-12);
    const double w3 = wrapLongitude360(lon);
    EXPECT_GE(w3, 0.0);
    EXPECT_LT(w3, 360.0);
    EXPECT_NEAR(std::remainder(w3 - lon, 360.0), 0.0, 1e-12);
  }
}

}  // namespace

// The premise of TopoPlanet's and compose::Dataset's shortcut on a sphere (both radii of
// curvature taken as the radius, two sines fewer): Body's formulas give the radius there
// bit for bit, at every latitude.
TEST(Body, OnASphereBothRadiiOfCurvatureAreTheRadiusExactly) {
  for (const Body& b : {Body::marsSphere(), Body::moon(), Body::sphere("round", 1234.5678)}) {
    ASSERT_TRUE(b.isSphere()) << b.name();
    for (double lat = -90.0; lat <= 90.0; lat += 0.37) {
      EXPECT_EQ(b.primeVerticalRadius(lat), b.equatorialRadius()) << b.name() << " " << lat;
      EXPECT_EQ(b.meridianRadius(lat), b.equatorialRadius()) << b.name() << " " << lat;
    }
  }
  EXPECT_FALSE(Body::marsEllipsoid().isSphere());
}

TEST(Body, RadiiAndFrameFromTheLatitudesSineGiveThePerLatitudeFunctionsBits) {
  // radiiOfCurvature() and enuFrameOf() take the sine (and cosine) a per-query normal has
  // already computed (TopoPlanet): given those of latDeg·π/180, the same bits as
  // meridianRadius(), primeVerticalRadius() and enuFrame().
  const double deg = std::numbers::pi / 180.0;
  for (const Body& b : {Body::marsEllipsoid(), Body::earthWgs84(), Body::marsSphere(),
                        Body::ellipsoid("flat", 1000.0, 300.0)}) {
    for (double lat = -90.0; lat <= 90.0; lat += 0.173) {
      for (const double l : {lat, -90.0, 90.0, 0.0, 1e-300}) {
        const double s = std::sin(l * deg), c = std::cos(l * deg);
        const Body::Radii r = b.radiiOfCurvature(s);
        EXPECT_EQ(r.meridian, b.meridianRadius(l)) << b.name() << " " << l;
        EXPECT_EQ(r.primeVertical, b.primeVerticalRadius(l)) << b.name() << " " << l;
        for (const double lon : {-180.0, -33.3, 0.0, 77.5, 180.0}) {
          const glm::dmat3 f = Body::enuFrameOf(s, c, lon), g = b.enuFrame(l, lon);
          for (int k = 0; k < 3; ++k) EXPECT_EQ(f[k], g[k]) << b.name() << " " << l << " " << lon;
        }
      }
    }
  }
}

TEST(Body, PlanetodeticSinCosIsTheSineAndCosineOfTheConvertedLatitude) {
  // planetodeticSinCos() forms no angle; its oracle is the sine and cosine of
  // toPlanetodetic() (an arctangent, checked against PROJ above): within a few ulp, the
  // same bits where no conversion happens (planetodetic latitudes, spheres), exact poles.
  const double deg = std::numbers::pi / 180.0;
  for (const Body& b : {Body::marsEllipsoid(), Body::earthWgs84(), Body::marsSphere(),
                        Body::ellipsoid("flat", 1000.0, 300.0)}) {
    for (const LatitudeType type : {LatitudeType::Planetocentric, LatitudeType::Planetodetic}) {
      for (double lat = -90.0; lat <= 90.0; lat += 0.0731) {
        for (const double l : {lat, -90.0, 90.0, 0.0, 1e-300, 89.999999, -89.999999}) {
          const double d = b.toPlanetodetic(l, type) * deg;
          const Body::SinCos sc = b.planetodeticSinCos(l, type);
          if (type == LatitudeType::Planetodetic || b.isSphere()) {
            EXPECT_EQ(sc.sin, std::sin(d)) << b.name() << " " << l;
            EXPECT_EQ(sc.cos, std::cos(d)) << b.name() << " " << l;
          } else {
            EXPECT_NEAR(sc.sin, std::sin(d), 4e-16) << b.name() << " " << l;
            EXPECT_NEAR(sc.cos, std::cos(d), 4e-16) << b.name() << " " << l;
          }
          EXPECT_NEAR(sc.sin * sc.sin + sc.cos * sc.cos, 1.0, 1e-15) << b.name() << " " << l;
        }
      }
      EXPECT_EQ(b.planetodeticSinCos(90.0, type).sin, 1.0) << b.name();
      EXPECT_EQ(b.planetodeticSinCos(-90.0, type).sin, -1.0) << b.name();
      EXPECT_EQ(b.planetodeticSinCos(0.0, type).sin, 0.0) << b.name();
      EXPECT_EQ(b.planetodeticSinCos(0.0, type).cos, 1.0) << b.name();
    }
  }
}
