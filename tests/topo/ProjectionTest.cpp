// Tests for the map projections in regolith/topo/Projection.hpp against outside oracles:
// PROJ's C API (eqc, stere, cart + topocentric) and Snyder's published worked example
// (Map Projections: A Working Manual, USGS PP 1395, polar stereographic ellipsoid).
//
// The largest errors observed against PROJ are printed on stdout and recorded as test
// properties (gtest --gtest_output=xml shows them).

#include <regolith/core/Error.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/Projection.hpp>

#include "support/ProjOracle.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace {

using regolith::topo::Body;
using regolith::topo::Equirectangular;
using regolith::topo::Geodetic;
using regolith::topo::LatLon;
using regolith::topo::LocalTangentPlane;
using regolith::topo::PolarStereographic;
using Pole = regolith::topo::PolarStereographic::Pole;

constexpr double kPi = std::numbers::pi;
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

using regolith::test::num;
using regolith::test::Proj;
using regolith::test::projEllipsoid;

/// A projection taking (lon deg, lat deg) in and giving metres out.
std::string degreesIn(const std::string& projection) {
  return "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step " + projection;
}

using regolith::test::messageOf;
using regolith::test::report;

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

double lonDiffDeg(double a, double b) { return std::remainder(a - b, 360.0); }

/// Angular difference between two lat/lon positions expressed in metres on radius r.
double angularErrorM(const LatLon& got, const LatLon& want, double r) {
  const double dLat = std::abs(got.latDeg - want.latDeg);
  const double dLon =
      std::abs(lonDiffDeg(got.lonDeg, want.lonDeg)) * std::cos(want.latDeg * kRadPerDeg);
  return std::max(dLat, dLon) * kRadPerDeg * r;
}

// =======================================================================================
// Equirectangular
// =======================================================================================

struct EqcCase {
  std::string label;
  double radius, latTs, lon0, lat0;
  [[nodiscard]] Equirectangular make() const { return {radius, latTs, lon0, lat0}; }
  [[nodiscard]] std::string proj() const {
    return degreesIn("+proj=eqc +lat_ts=" + num(latTs) + " +lat_0=" + num(lat0) +
                     " +lon_0=" + num(lon0) + " +x_0=0 +y_0=0 +R=" + num(radius));
  }
};

std::vector<EqcCase> eqcCases() {
  return {{"MarsSphere_ts0", 3396190.0, 0.0, 0.0, 0.0},
          {"MarsSphere_ts30_lon137", 3396190.0, 30.0, 137.4, 0.0},
          {"Moon_tsm45_lonm170_lat0_10", 1737400.0, -45.5, -170.0, 10.0},
          {"Mars_ts89_lon180_lat0m20", 3396190.0, 89.0, 180.0, -20.0}};
}

const std::vector<double> kEqcLats = {-90.0, -89.9999, -75.0, -45.0, -10.0,   -1e-9, 0.0,
                                      0.25,  30.0,     60.0,  89.0,  89.9999, 90.0};
const std::vector<double> kEqcLons = {-180.0, -179.9, -137.4, -90.0, -42.6, -1e-9, 0.0,
                                      17.0,   90.0,   137.4,  179.9, 180.0, 359.0, -400.0};

TEST(Equirectangular, ForwardAndInverseMatchProjEqc) {
  double worstFwd = 0.0, worstInv = 0.0, worstInvVsProj = 0.0;
  for (const EqcCase& c : eqcCases()) {
    const Equirectangular eq = c.make();
    const Proj proj(c.proj());
    ASSERT_TRUE(proj.ok()) << proj.error();
    const double period = 2.0 * kPi * c.radius * std::cos(c.latTs * kRadPerDeg);
    for (const double lat : kEqcLats) {
      for (const double lon : kEqcLons) {
        const glm::dvec3 ref = proj.trans(PJ_FWD, lon, lat);
        ASSERT_TRUE(std::isfinite(ref.x) && std::isfinite(ref.y)) << c.label;
        const glm::dvec2 xy = eq.forward({lat, lon});
        // x is defined modulo one turn of longitude: on the meridian opposite λ0 we give
        // −180° (documented [−180, 180)) where PROJ may give +180°.
        const double dx = std::abs(std::remainder(xy.x - ref.x, period));
        const double dy = std::abs(xy.y - ref.y);
        worstFwd = std::max({worstFwd, dx, dy});
        EXPECT_LT(dx, 1e-6) << c.label << " lat " << lat << " lon " << lon;
        EXPECT_LT(dy, 1e-6) << c.label << " lat " << lat << " lon " << lon;
        EXPECT_LE(std::abs(xy.x), period / 2.0 + 1e-6) << c.label;

        // Our inverse of PROJ's forward gives back the point.
        const LatLon back = eq.inverse({ref.x, ref.y});
        const double e = angularErrorM(back, {lat, lon}, c.radius);
        worstInv = std::max(worstInv, e);
        EXPECT_LT(e, 1e-6) << c.label << " inverse at lat " << lat << " lon " << lon;
        EXPECT_GE(back.lonDeg, -180.0);
        EXPECT_LT(back.lonDeg, 180.0);
        // And agrees with PROJ's inverse.
        const glm::dvec3 projInv = proj.trans(PJ_INV, ref.x, ref.y);
        const double ep = angularErrorM(back, {projInv.y, projInv.x}, c.radius);
        worstInvVsProj = std::max(worstInvVsProj, ep);
        EXPECT_LT(ep, 1e-6) << c.label << " inverse vs PROJ at lat " << lat << " lon " << lon;
      }
    }
  }
  report("eqc.forward_vs_PROJ_max_m", worstFwd);
  report("eqc.inverse_of_PROJ_forward_vs_exact_max_m", worstInv);
  report("eqc.inverse_vs_PROJ_inverse_max_m", worstInvVsProj);
}

TEST(Equirectangular, InverseOfCoordinatesBeyondTheAntimeridianWrapsLikeProj) {
  const EqcCase c = eqcCases()[1];
  const Equirectangular eq = c.make();
  const Proj proj(c.proj());
  ASSERT_TRUE(proj.ok()) << proj.error();
  const double halfWidth = kPi * c.radius * std::cos(c.latTs * kRadPerDeg);
  for (const double fx : {-2.7, -1.3, -1.0001, 1.0001, 1.5, 2.9}) {
    for (const double y : {-3.0e6, 0.0, 4.0e6}) {
      const LatLon ours = eq.inverse({fx * halfWidth, y});
      const glm::dvec3 ref = proj.trans(PJ_INV, fx * halfWidth, y);
      EXPECT_NEAR(ours.latDeg, ref.y, 1e-12);
      EXPECT_NEAR(lonDiffDeg(ours.lonDeg, ref.x), 0.0, 1e-9) << fx;
      EXPECT_GE(ours.lonDeg, -180.0);
      EXPECT_LT(ours.lonDeg, 180.0);
    }
  }
}

TEST(Equirectangular, RoundTripsToWithin1e12OfTheRadius) {
  double worstLL = 0.0, worstXY = 0.0;
  for (const EqcCase& c : eqcCases()) {
    const Equirectangular eq = c.make();
    for (double lat = -90.0; lat <= 90.0; lat += 2.5) {
      for (double lon = -180.0; lon < 180.0; lon += 7.5) {
        const LatLon back = eq.inverse(eq.forward({lat, lon}));
        const double e = angularErrorM(back, {lat, lon}, c.radius) / c.radius;
        worstLL = std::max(worstLL, e);
        EXPECT_LT(e, 1e-12) << c.label << ' ' << lat << ' ' << lon;
      }
    }
    const double halfWidth = kPi * c.radius * std::cos(c.latTs * kRadPerDeg);
    const double yMin = (-90.0 - c.lat0) * kRadPerDeg * c.radius;
    const double yMax = (90.0 - c.lat0) * kRadPerDeg * c.radius;
    for (double fx = -0.999; fx < 1.0; fx += 0.111) {
      for (double fy = 0.0005; fy < 1.0; fy += 0.0999) {
        const glm::dvec2 xy(fx * halfWidth, yMin + fy * (yMax - yMin));
        const glm::dvec2 again = eq.forward(eq.inverse(xy));
        const double e = glm::length(again - xy) / c.radius;
        worstXY = std::max(worstXY, e);
        EXPECT_LT(e, 1e-12) << c.label << ' ' << xy.x << ' ' << xy.y;
      }
    }
  }
  report("eqc.round_trip_ll_max_relative", worstLL);
  report("eqc.round_trip_xy_max_relative", worstXY);
}

TEST(Equirectangular, CentreMapsToOriginAndPolesAndAntipodeAreFiniteAndMatchProj) {
  for (const EqcCase& c : eqcCases()) {
    const Equirectangular eq = c.make();
    const Proj proj(c.proj());
    ASSERT_TRUE(proj.ok()) << proj.error();
    // Centre (lat0, lon0) ↔ (0, 0).
    const glm::dvec2 centre = eq.forward({c.lat0, c.lon0});
    EXPECT_EQ(centre.x, 0.0) << c.label;
    EXPECT_EQ(centre.y, 0.0) << c.label;
    const LatLon back = eq.inverse({0.0, 0.0});
    EXPECT_NEAR(back.latDeg, c.lat0, 1e-13) << c.label;
    EXPECT_NEAR(lonDiffDeg(back.lonDeg, c.lon0), 0.0, 1e-13) << c.label;

    // Poles: finite, PROJ's y, and the inverse returns exactly the pole.
    for (const double pole : {90.0, -90.0}) {
      for (const double lon : {c.lon0, c.lon0 + 33.0}) {
        const glm::dvec2 p = eq.forward({pole, lon});
        const glm::dvec3 ref = proj.trans(PJ_FWD, lon, pole);
        ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y));
        EXPECT_NEAR(p.y, ref.y, 1e-6) << c.label << " pole " << pole;
        EXPECT_NEAR(std::remainder(p.x - ref.x, 2.0 * kPi * c.radius), 0.0, 1e-6);
        const LatLon q = eq.inverse(p);
        EXPECT_NEAR(q.latDeg, pole, 1e-12) << c.label;
        EXPECT_LE(std::abs(q.latDeg), 90.0) << c.label;
      }
    }

    // Antipode of the centre: finite, on the edge x = −π R cos φts, PROJ's |x| and y.
    const LatLon anti{-c.lat0, c.lon0 + 180.0};
    const glm::dvec2 a = eq.forward(anti);
    const glm::dvec3 ref = proj.trans(PJ_FWD, anti.lonDeg, anti.latDeg);
    const double halfWidth = kPi * c.radius * std::cos(c.latTs * kRadPerDeg);
    ASSERT_TRUE(std::isfinite(a.x) && std::isfinite(a.y));
    EXPECT_NEAR(a.x, -halfWidth, 1e-6) << c.label;
    EXPECT_NEAR(std::abs(a.x), std::abs(ref.x), 1e-6) << c.label;
    EXPECT_NEAR(a.y, ref.y, 1e-6) << c.label;
    // lon0 − 180 is the same meridian and gives the same point.
    const glm::dvec2 a2 = eq.forward({-c.lat0, c.lon0 - 180.0});
    EXPECT_NEAR(a2.x, a.x, 1e-6) << c.label;
    EXPECT_EQ(a2.y, a.y) << c.label;
    const LatLon aBack = eq.inverse(a);
    EXPECT_NEAR(aBack.latDeg, anti.latDeg, 1e-12) << c.label;
    EXPECT_NEAR(lonDiffDeg(aBack.lonDeg, anti.lonDeg), 0.0, 1e-12) << c.label;
  }
}

TEST(Equirectangular, InverseBeyondThePoleThrowsDomainError) {
  const Equirectangular eq(3396190.0, 0.0, 0.0);
  const double yPole = 3396190.0 * kPi / 2.0;
  for (const double y : {yPole + 1.0, -yPole - 1.0, 3.0 * yPole}) {
    const std::string msg = messageOf<regolith::DomainError>([&] { (void)eq.inverse({0.0, y}); });
    EXPECT_TRUE(contains(msg, "Equirectangular::inverse()")) << msg;
    EXPECT_TRUE(contains(msg, "y = ")) << msg;
    EXPECT_TRUE(contains(msg, "beyond the pole")) << msg;
  }
  EXPECT_NO_THROW((void)eq.inverse({0.0, yPole}));
  EXPECT_NO_THROW((void)eq.inverse({0.0, -yPole}));
}

TEST(Equirectangular, RejectsNonFiniteAndOutOfRangeArgumentsNamingTheField) {
  struct Bad {
    double r, ts, lon0, lat0;
    const char* field;
  };
  for (const Bad& b :
       {Bad{kNaN, 0, 0, 0, "radius"}, Bad{kInf, 0, 0, 0, "radius"}, Bad{0.0, 0, 0, 0, "radius"},
        Bad{-5.0, 0, 0, 0, "radius"}, Bad{1.0, kNaN, 0, 0, "latitude of true scale"},
        Bad{1.0, 90.0, 0, 0, "latitude of true scale"},
        Bad{1.0, -90.0, 0, 0, "latitude of true scale"},
        Bad{1.0, 120.0, 0, 0, "latitude of true scale"}, Bad{1.0, 0, -kInf, 0, "centre longitude"},
        Bad{1.0, 0, 0, kNaN, "latitude of origin"}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>(
        [&] { (void)Equirectangular(b.r, b.ts, b.lon0, b.lat0); });
    EXPECT_TRUE(contains(msg, "Equirectangular()")) << msg;
    EXPECT_TRUE(contains(msg, b.field)) << msg;
  }
  const Equirectangular eq(3396190.0, 10.0, 20.0);
  for (const LatLon ll :
       {LatLon{kNaN, 0.0}, LatLon{kInf, 0.0}, LatLon{90.5, 0.0}, LatLon{-91.0, 0.0}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] { (void)eq.forward(ll); });
    EXPECT_TRUE(contains(msg, "Equirectangular::forward()")) << msg;
    EXPECT_TRUE(contains(msg, "latitude")) << msg;
  }
  for (const double lon : {kNaN, kInf, -kInf}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] {
      (void)eq.forward({0.0, lon});
    });
    EXPECT_TRUE(contains(msg, "Equirectangular::forward()")) << msg;
    EXPECT_TRUE(contains(msg, "longitude")) << msg;
  }
  std::string msg = messageOf<regolith::InvalidArgument>([&] { (void)eq.inverse({kNaN, 0.0}); });
  EXPECT_TRUE(contains(msg, "Equirectangular::inverse()") && contains(msg, "x is")) << msg;
  msg = messageOf<regolith::InvalidArgument>([&] { (void)eq.inverse({0.0, -kInf}); });
  EXPECT_TRUE(contains(msg, "Equirectangular::inverse()") && contains(msg, "y is")) << msg;
}

// =======================================================================================
// Polar stereographic
// =======================================================================================

/// International (Hayford 1924) ellipsoid as Snyder gives it: a = 6378388, e² = 0.00672267.
Body snyderInternational() {
  const double a = 6378388.0, e2 = 0.00672267;
  return Body::ellipsoid("International", a, a * std::sqrt(1.0 - e2));
}

TEST(PolarStereographic, SouthEllipsoidMatchesSnyderWorkedExample) {
  // Snyder (1987), polar stereographic, ellipsoid, south aspect: International ellipsoid,
  // φc = −71°, λ0 = −100°; φ = −75°, λ = 150° → x = −1,540,033.6 m, y = −560,526.4 m,
  // k = 0.9896256 (published values rounded to 0.1 m and 7 decimals).
  const Body intl = snyderInternational();
  const auto ps = PolarStereographic::withTrueScaleLatitude(intl, Pole::South, -71.0, -100.0);
  const glm::dvec2 xy = ps.forward({-75.0, 150.0});
  EXPECT_NEAR(xy.x, -1540033.6, 0.1);
  EXPECT_NEAR(xy.y, -560526.4, 0.1);
  EXPECT_NEAR(ps.scaleFactor(-75.0), 0.9896256, 1e-7);
  // Snyder's inverse example: the rounded (x, y) give back φ, λ to the rounding (0.05 m is
  // about 5e-7°).
  const LatLon ll = ps.inverse({-1540033.6, -560526.4});
  EXPECT_NEAR(ll.latDeg, -75.0, 1e-6);
  EXPECT_NEAR(ll.lonDeg, 150.0, 2e-6);

  // Cross-check: PROJ agrees with both Snyder and us.
  const std::string def =
      "+proj=stere +lat_0=-90 +lat_ts=-71 +lon_0=-100 +x_0=0 +y_0=0 "
      "+a=6378388 +es=0.00672267";
  const Proj proj(degreesIn(def));
  ASSERT_TRUE(proj.ok()) << proj.error();
  const glm::dvec3 ref = proj.trans(PJ_FWD, 150.0, -75.0);
  EXPECT_NEAR(ref.x, -1540033.6, 0.1);
  EXPECT_NEAR(ref.y, -560526.4, 0.1);
  EXPECT_NEAR(xy.x, ref.x, 1e-6);
  EXPECT_NEAR(xy.y, ref.y, 1e-6);
  const Proj projRad(def);
  ASSERT_TRUE(projRad.ok()) << projRad.error();
  const PJ_FACTORS f =
      proj_factors(projRad.get(), proj_coord(150.0 * kRadPerDeg, -75.0 * kRadPerDeg, 0.0, 0.0));
  EXPECT_NEAR(f.parallel_scale, 0.9896256, 1e-7);
  EXPECT_NEAR(ps.scaleFactor(-75.0), f.parallel_scale, 1e-9);
  report("snyder.x_minus_published_m", xy.x - -1540033.6);
  report("snyder.y_minus_published_m", xy.y - -560526.4);
  report("snyder.k_minus_published", ps.scaleFactor(-75.0) - 0.9896256);
  report("snyder.xy_vs_PROJ_m", glm::length(xy - glm::dvec2(ref.x, ref.y)));
}

struct StereCase {
  std::string label;
  Body body;
  Pole pole;
  bool byTrueScaleLatitude;
  double latTsOrK0;
  double lon0, fe, fn;

  [[nodiscard]] PolarStereographic make() const {
    return byTrueScaleLatitude
               ? PolarStereographic::withTrueScaleLatitude(body, pole, latTsOrK0, lon0, fe, fn)
               : PolarStereographic::withScaleFactor(body, pole, latTsOrK0, lon0, fe, fn);
  }
  /// PROJ definition with radians in (for proj_factors).
  [[nodiscard]] std::string projRadians() const {
    const std::string scale =
        byTrueScaleLatitude ? " +lat_ts=" + num(latTsOrK0) : " +k_0=" + num(latTsOrK0);
    return "+proj=stere +lat_0=" + std::string(pole == Pole::North ? "90" : "-90") + scale +
           " +lon_0=" + num(lon0) + " +x_0=" + num(fe) + " +y_0=" + num(fn) + projEllipsoid(body);
  }
  [[nodiscard]] std::string proj() const { return degreesIn(projRadians()); }
  /// Latitude in the projection's own hemisphere: sign +1 north, −1 south.
  [[nodiscard]] double sign() const { return pole == Pole::North ? 1.0 : -1.0; }
};

std::vector<StereCase> stereCases() {
  const Body mars = Body::marsEllipsoid();
  const Body wgs = Body::earthWgs84();
  return {
      {"MarsEllipsoid_N_ts70", mars, Pole::North, true, 70.0, 0.0, 0.0, 0.0},
      {"MarsEllipsoid_S_tsm70_lon137", mars, Pole::South, true, -70.0, 137.0, 0.0, 0.0},
      {"WGS84_UPS_N_k0.994", wgs, Pole::North, false, 0.994, 0.0, 2.0e6, 2.0e6},
      {"WGS84_UPS_S_k0.994", wgs, Pole::South, false, 0.994, 0.0, 2.0e6, 2.0e6},
      {"WGS84_N_ts71_lonm45", wgs, Pole::North, true, 71.0, -45.0, 0.0, 0.0},
      {"MarsSphere_N_ts60_fe", Body::marsSphere(), Pole::North, true, 60.0, -45.0, 1000.0, -500.0},
      {"Moon_S_ts90", Body::moon(), Pole::South, true, -90.0, 0.0, 0.0, 0.0},
      {"Moon_N_k0.97_lon180", Body::moon(), Pole::North, false, 0.97, 180.0, 0.0, 0.0},
      {"International_S_tsm71_lonm100", snyderInternational(), Pole::South, true, -71.0, -100.0,
       0.0, 0.0},
  };
}

/// Latitudes in the north aspect's terms (negate for the south aspect): from the centre
/// pole through the equator to close to the opposite pole.
const std::vector<double> kStereLats = {90.0, 89.9999999, 89.99, 89.0,  85.0,  80.0,
                                        75.0, 70.0,       60.0,  45.0,  30.0,  10.0,
                                        0.0,  -10.0,      -30.0, -60.0, -80.0, -89.0};
const std::vector<double> kStereLons = {-180.0, -179.5, -135.0, -100.0, -90.0, -45.0, -0.5, 0.0,
                                        0.5,    10.0,   45.0,   90.0,   137.0, 179.5, 180.0};

TEST(PolarStereographic, NorthAndSouthSphereAndEllipsoidMatchProjStere) {
  double worstFwd = 0.0, worstFwdRel = 0.0, worstInv = 0.0, worstInvVsProj = 0.0;
  for (const StereCase& c : stereCases()) {
    const PolarStereographic ps = c.make();
    const Proj proj(c.proj());
    ASSERT_TRUE(proj.ok()) << proj.error();
    const double a = c.body.equatorialRadius();
    for (const double latN : kStereLats) {
      const double lat = c.sign() * latN;
      for (const double lon : kStereLons) {
        const glm::dvec3 ref = proj.trans(PJ_FWD, lon, lat);
        ASSERT_TRUE(std::isfinite(ref.x) && std::isfinite(ref.y)) << c.label;
        const glm::dvec2 xy = ps.forward({lat, lon});
        const double d = glm::length(xy - glm::dvec2(ref.x, ref.y));
        // Far from the pole the coordinates reach 1e9 m; allow their rounding.
        const double scale = std::hypot(ref.x - c.fe, ref.y - c.fn);
        const double tol = 1e-6 + 1e-14 * scale;
        if (scale <= 2.0e7) {
          worstFwd = std::max(worstFwd, d);
        } else {
          worstFwdRel = std::max(worstFwdRel, d / scale);
        }
        EXPECT_LT(d, tol) << c.label << " forward at lat " << lat << " lon " << lon;

        // Our inverse of PROJ's (closed-form) forward returns the point.
        const LatLon back = ps.inverse({ref.x, ref.y});
        const double e = angularErrorM(back, {lat, lon}, a);
        worstInv = std::max(worstInv, e);
        EXPECT_LT(e, 1e-6) << c.label << " inverse at lat " << lat << " lon " << lon;
        EXPECT_GE(back.lonDeg, -180.0);
        EXPECT_LT(back.lonDeg, 180.0);
        // PROJ's own inverse iterates only to ~1e-9 rad (millimetres: 6 mm on WGS84), so it
        // is a looser oracle: agree with it to 2e-9 rad and be at least as close to the
        // exact point as it is.
        const glm::dvec3 pinv = proj.trans(PJ_INV, ref.x, ref.y);
        const double ep = angularErrorM(back, {pinv.y, pinv.x}, a);
        worstInvVsProj = std::max(worstInvVsProj, ep);
        EXPECT_LT(ep, 2e-9 * a) << c.label << " inverse vs PROJ at lat " << lat << " lon " << lon;
        const double projErr = angularErrorM({pinv.y, pinv.x}, {lat, lon}, a);
        EXPECT_LE(e, projErr + 1e-8)
            << c.label << " inverse less accurate than PROJ's at lat " << lat << " lon " << lon;
      }
    }
  }
  report("stere.forward_vs_PROJ_max_m(rho<=2e7m)", worstFwd);
  report("stere.forward_vs_PROJ_max_relative(rho>2e7m)", worstFwdRel);
  report("stere.inverse_of_PROJ_forward_vs_exact_max_m", worstInv);
  report("stere.inverse_vs_PROJ_inverse_max_m", worstInvVsProj);
}

TEST(PolarStereographic, NearTheOppositePoleForwardStaysFiniteAndMatchesProj) {
  // Within 1e-8° of the opposite pole the coordinates reach 1e17 m; they must still be
  // finite and agree with PROJ to a relative 1e-12 (1 + sin φ cancels there, a classic
  // source of error and of division by zero).
  //
  // PROJ's spherical branch evaluates tan(π/4 + φ/2), which loses accuracy there (and
  // overflows beyond 1e-7° from the pole), while its ellipsoidal branch (pj_tsfn) is
  // accurate. For spheres PROJ is therefore given 1/f = 1e15, whose effect on t is a
  // relative e² = 2e-15.
  double worst = 0.0;
  for (const StereCase& c : stereCases()) {
    const PolarStereographic ps = c.make();
    std::string def = c.proj();
    if (c.body.isSphere()) {
      const std::string sphere = projEllipsoid(c.body);
      def.replace(def.find(sphere), sphere.size(),
                  " +a=" + num(c.body.equatorialRadius()) + " +rf=1e15");
    }
    const Proj proj(def);
    ASSERT_TRUE(proj.ok()) << proj.error();
    for (const double latN :
         {-89.9, -89.99, -89.999, -89.9999, -89.99999, -89.999999, -89.9999999, -89.99999999}) {
      const double lat = c.sign() * latN;
      for (const double lon : {c.lon0, c.lon0 + 30.0, -120.0}) {
        const glm::dvec3 ref = proj.trans(PJ_FWD, lon, lat);
        ASSERT_TRUE(std::isfinite(ref.x) && std::isfinite(ref.y)) << c.label << ' ' << lat;
        const glm::dvec2 xy = ps.forward({lat, lon});
        ASSERT_TRUE(std::isfinite(xy.x) && std::isfinite(xy.y))
            << c.label << " forward not finite at lat " << lat;
        const double rel =
            glm::length(xy - glm::dvec2(ref.x, ref.y)) / glm::length(glm::dvec2(ref.x, ref.y));
        worst = std::max(worst, rel);
        EXPECT_LT(rel, 1e-12) << c.label << " at lat " << lat << " lon " << lon;
        const LatLon back = ps.inverse(xy);
        EXPECT_NEAR(back.latDeg, lat, 1e-9) << c.label;
      }
    }
  }
  report("stere.near_opposite_pole_vs_PROJ_max_relative", worst);
}

TEST(PolarStereographic, RoundTripsToWithin1e12OfTheRadius) {
  double worstLL = 0.0, worstXY = 0.0;
  for (const StereCase& c : stereCases()) {
    const PolarStereographic ps = c.make();
    const double a = c.body.equatorialRadius();
    for (double latN = 90.0; latN >= -80.0; latN -= 1.25) {
      for (double lon = -180.0; lon < 180.0; lon += 9.5) {
        const double lat = c.sign() * latN;
        const LatLon back = ps.inverse(ps.forward({lat, lon}));
        const double e = angularErrorM(back, {lat, lon}, a) / a;
        worstLL = std::max(worstLL, e);
        EXPECT_LT(e, 1e-12) << c.label << ' ' << lat << ' ' << lon;
      }
    }
    for (double x = -1.2e7; x <= 1.2e7; x += 7.3e5) {
      for (double y = -1.2e7; y <= 1.2e7; y += 6.1e5) {
        const glm::dvec2 xy(x + c.fe, y + c.fn);
        const glm::dvec2 again = ps.forward(ps.inverse(xy));
        const double e = glm::length(again - xy) / a;
        worstXY = std::max(worstXY, e);
        EXPECT_LT(e, 1e-12) << c.label << ' ' << x << ' ' << y;
      }
    }
  }
  report("stere.round_trip_ll_max_relative", worstLL);
  report("stere.round_trip_xy_max_relative", worstXY);
}

TEST(PolarStereographic, CentrePoleGivesFalseOriginAndInverseGivesThePole) {
  for (const StereCase& c : stereCases()) {
    const PolarStereographic ps = c.make();
    const Proj proj(c.proj());
    ASSERT_TRUE(proj.ok()) << proj.error();
    const double pole = 90.0 * c.sign();
    for (const double lon : {-180.0, 0.0, c.lon0, 77.7}) {
      const glm::dvec2 xy = ps.forward({pole, lon});
      EXPECT_EQ(xy.x, c.fe) << c.label;
      EXPECT_EQ(xy.y, c.fn) << c.label;
      const glm::dvec3 ref = proj.trans(PJ_FWD, lon, pole);
      EXPECT_NEAR(xy.x, ref.x, 1e-6) << c.label;
      EXPECT_NEAR(xy.y, ref.y, 1e-6) << c.label;
    }
    const LatLon ll = ps.inverse({c.fe, c.fn});
    EXPECT_EQ(ll.latDeg, pole) << c.label;
    EXPECT_NEAR(lonDiffDeg(ll.lonDeg, c.lon0), 0.0, 1e-12) << c.label;
    const glm::dvec3 pinv = proj.trans(PJ_INV, c.fe, c.fn);
    EXPECT_NEAR(pinv.y, pole, 1e-12) << c.label;
    // A millimetre away the inverse is within a millimetre of the pole.
    const LatLon near = ps.inverse({c.fe + 1e-3, c.fn});
    EXPECT_NEAR(near.latDeg, pole, 2e-3 / c.body.equatorialRadius() / kRadPerDeg) << c.label;
  }
}

TEST(PolarStereographic, OppositePoleThrowsDomainErrorWhereProjDiverges) {
  for (const StereCase& c : stereCases()) {
    const PolarStereographic ps = c.make();
    const double opposite = -90.0 * c.sign();
    for (const double lon : {0.0, c.lon0, -33.0}) {
      const std::string msg = messageOf<regolith::DomainError>([&] {
        (void)ps.forward({opposite, lon});
      });
      EXPECT_TRUE(contains(msg, "PolarStereographic::forward()")) << msg;
      EXPECT_TRUE(contains(msg, "opposite")) << msg;
      EXPECT_TRUE(contains(msg, "infinity")) << msg;
    }
    const std::string msg =
        messageOf<regolith::DomainError>([&] { (void)ps.scaleFactor(opposite); });
    EXPECT_TRUE(contains(msg, "PolarStereographic::scaleFactor()")) << msg;
    EXPECT_TRUE(contains(msg, "opposite")) << msg;
    // PROJ has no meaningful answer there either: it fails, or (as cos(−π/2) is 6e-17 in
    // double) returns a distance of the order of 1e23 m.
    const Proj proj(c.proj());
    ASSERT_TRUE(proj.ok()) << proj.error();
    const glm::dvec3 ref = proj.trans(PJ_FWD, c.lon0, opposite);
    const bool projFailed = !std::isfinite(ref.x) || !std::isfinite(ref.y) || proj.lastError() != 0;
    EXPECT_TRUE(projFailed || std::hypot(ref.x - c.fe, ref.y - c.fn) > 1e20)
        << c.label << " PROJ gave " << ref.x << ", " << ref.y;
  }
}

TEST(PolarStereographic, ScaleFactorMatchesProjFactorsIsK0AtPoleAndOneAtTrueScaleLatitude) {
  double worst = 0.0;
  for (const StereCase& c : stereCases()) {
    const PolarStereographic ps = c.make();
    const Proj proj(c.projRadians());
    ASSERT_TRUE(proj.ok()) << proj.error();
    for (const double latN :
         {89.999, 89.0, 85.0, 80.0, 71.0, 60.0, 45.0, 20.0, 0.0, -30.0, -60.0}) {
      const double lat = c.sign() * latN;
      const PJ_FACTORS f =
          proj_factors(proj.get(), proj_coord(30.0 * kRadPerDeg, lat * kRadPerDeg, 0.0, 0.0));
      ASSERT_EQ(proj.lastError(), 0) << c.label << ' ' << lat;
      const double k = ps.scaleFactor(lat);
      // PROJ evaluates the factors by numerical differentiation.
      const double rel = std::abs(k - f.parallel_scale) / f.parallel_scale;
      worst = std::max(worst, rel);
      EXPECT_LT(rel, 1e-8) << c.label << " k at lat " << lat;
      // Conformal: the meridian scale is the same.
      EXPECT_NEAR(f.meridional_scale, k, 1e-7 * k) << c.label << " h at lat " << lat;
    }
    // At the pole: k0, continuous with the general formula just off the pole.
    const double pole = 90.0 * c.sign();
    EXPECT_EQ(ps.scaleFactor(pole), ps.scaleFactorAtPole()) << c.label;
    EXPECT_NEAR(ps.scaleFactor(c.sign() * 89.99999), ps.scaleFactorAtPole(), 1e-12) << c.label;
    const PJ_FACTORS fp = proj_factors(
        proj.get(), proj_coord(30.0 * kRadPerDeg, c.sign() * 89.9999 * kRadPerDeg, 0.0, 0.0));
    EXPECT_NEAR(ps.scaleFactorAtPole(), fp.parallel_scale, 1e-8) << c.label;
    if (c.byTrueScaleLatitude) {
      // k = 1 on the latitude of true scale.
      EXPECT_NEAR(ps.scaleFactor(c.latTsOrK0), 1.0, 1e-14) << c.label;
      if (std::abs(c.latTsOrK0) == 90.0) {
        EXPECT_EQ(ps.scaleFactorAtPole(), 1.0) << c.label;
      } else {
        EXPECT_LT(ps.scaleFactorAtPole(), 1.0) << c.label;
      }
    } else {
      EXPECT_EQ(ps.scaleFactorAtPole(), c.latTsOrK0) << c.label;
    }
  }
  report("stere.scale_factor_vs_PROJ_factors_max_relative", worst);
}

TEST(PolarStereographic, AccessorsReportTheConstructionParameters) {
  const Body mars = Body::marsEllipsoid();
  const auto ps =
      PolarStereographic::withScaleFactor(mars, Pole::South, 0.994, 25.0, 100.0, -200.0);
  EXPECT_EQ(ps.pole(), Pole::South);
  EXPECT_EQ(ps.lonCentreDeg(), 25.0);
  EXPECT_EQ(ps.scaleFactorAtPole(), 0.994);
  EXPECT_EQ(ps.falseEasting(), 100.0);
  EXPECT_EQ(ps.falseNorthing(), -200.0);
  EXPECT_EQ(ps.equatorialRadius(), mars.equatorialRadius());
  EXPECT_NEAR(ps.eccentricitySquared(), mars.eccentricitySquared(), 1e-17);
}

TEST(PolarStereographic, RejectsNonFiniteAndInconsistentArgumentsNamingTheField) {
  const Body mars = Body::marsEllipsoid();
  constexpr const char* kTs = "PolarStereographic::withTrueScaleLatitude()";
  constexpr const char* kK0 = "PolarStereographic::withScaleFactor()";
  struct Bad {
    Pole pole;
    double ts, lon0, fe, fn;
    const char* field;
  };
  for (const Bad& b :
       {Bad{Pole::North, kNaN, 0, 0, 0, "latitude"}, Bad{Pole::North, 91.0, 0, 0, 0, "latitude"},
        Bad{Pole::North, -70.0, 0, 0, 0, "hemisphere"},
        Bad{Pole::South, 70.0, 0, 0, 0, "hemisphere"}, Bad{Pole::North, 0.0, 0, 0, 0, "hemisphere"},
        Bad{Pole::North, 70.0, kInf, 0, 0, "centre longitude"},
        Bad{Pole::North, 70.0, 0, kNaN, 0, "false easting"},
        Bad{Pole::North, 70.0, 0, 0, -kInf, "false northing"}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] {
      (void)PolarStereographic::withTrueScaleLatitude(mars, b.pole, b.ts, b.lon0, b.fe, b.fn);
    });
    EXPECT_TRUE(contains(msg, kTs)) << msg;
    EXPECT_TRUE(contains(msg, b.field)) << msg;
  }
  struct BadK {
    double k0, lon0, fe, fn;
    const char* field;
  };
  for (const BadK& b :
       {BadK{0.0, 0, 0, 0, "scale factor"}, BadK{-1.0, 0, 0, 0, "scale factor"},
        BadK{kNaN, 0, 0, 0, "scale factor"}, BadK{kInf, 0, 0, 0, "scale factor"},
        BadK{1.0, kNaN, 0, 0, "centre longitude"}, BadK{1.0, 0, kInf, 0, "false easting"},
        BadK{1.0, 0, 0, kNaN, "false northing"}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] {
      (void)PolarStereographic::withScaleFactor(mars, Pole::North, b.k0, b.lon0, b.fe, b.fn);
    });
    EXPECT_TRUE(contains(msg, kK0)) << msg;
    EXPECT_TRUE(contains(msg, b.field)) << msg;
  }

  const auto ps = PolarStereographic::withTrueScaleLatitude(mars, Pole::North, 70.0, 0.0);
  for (const LatLon ll : {LatLon{kNaN, 0.0}, LatLon{-kInf, 0.0}, LatLon{90.0001, 0.0}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] { (void)ps.forward(ll); });
    EXPECT_TRUE(contains(msg, "PolarStereographic::forward()") && contains(msg, "latitude")) << msg;
  }
  std::string msg = messageOf<regolith::InvalidArgument>([&] { (void)ps.forward({80.0, kNaN}); });
  EXPECT_TRUE(contains(msg, "PolarStereographic::forward()") && contains(msg, "longitude")) << msg;
  msg = messageOf<regolith::InvalidArgument>([&] { (void)ps.inverse({kInf, 0.0}); });
  EXPECT_TRUE(contains(msg, "PolarStereographic::inverse()") && contains(msg, "x is")) << msg;
  msg = messageOf<regolith::InvalidArgument>([&] { (void)ps.inverse({0.0, kNaN}); });
  EXPECT_TRUE(contains(msg, "PolarStereographic::inverse()") && contains(msg, "y is")) << msg;
  msg = messageOf<regolith::InvalidArgument>([&] { (void)ps.scaleFactor(kNaN); });
  EXPECT_TRUE(contains(msg, "PolarStereographic::scaleFactor()") && contains(msg, "latitude"))
      << msg;
}

// =======================================================================================
// Local tangent plane
// =======================================================================================

struct LtpCase {
  std::string label;
  Body body;
  Geodetic origin;
};

std::vector<LtpCase> ltpCases() {
  return {
      {"MarsEllipsoid_Jezero", Body::marsEllipsoid(), {18.4447, 77.4508, -2569.0}},
      {"WGS84_Sydney", Body::earthWgs84(), {-33.8688, 151.2093, 58.0}},
      {"MarsEllipsoid_equator_180", Body::marsEllipsoid(), {0.0, 180.0, 0.0}},
      {"MarsEllipsoid_NorthPole", Body::marsEllipsoid(), {90.0, 0.0, 0.0}},
      {"WGS84_SouthPole_lon45_h2835", Body::earthWgs84(), {-90.0, 45.0, 2835.0}},
      {"Moon_Shackleton", Body::moon(), {-89.9, 0.0, -4200.0}},
      {"MarsSphere_highOrigin", Body::marsSphere(), {-45.0, -120.0, 400000.0}},
  };
}

std::string ltpProj(const LtpCase& c) {
  const std::string ell = projEllipsoid(c.body);
  return degreesIn("+proj=cart" + ell + " +step +proj=topocentric +lat_0=" + num(c.origin.latDeg) +
                   " +lon_0=" + num(c.origin.lonDeg) + " +h_0=" + num(c.origin.height) + ell);
}

/// PROJ's ENU rotated into the plane of the given heading (y at azimuth `heading`).
glm::dvec3 rotateEnu(const glm::dvec3& enu, double headingDeg) {
  const double c = std::cos(headingDeg * kRadPerDeg), s = std::sin(headingDeg * kRadPerDeg);
  return {c * enu.x - s * enu.y, s * enu.x + c * enu.y, enu.z};
}

/// Test points around an origin, plus far-away ones (the antipode and both poles).
std::vector<Geodetic> ltpPoints(const Geodetic& o) {
  std::vector<Geodetic> pts;
  for (const double dLat : {-20.0, -3.0, -0.5, -0.01, 0.0, 0.01, 0.5, 3.0, 20.0}) {
    for (const double dLon : {-30.0, -1.0, -0.001, 0.0, 0.001, 1.0, 30.0}) {
      for (const double h : {-10000.0, 0.0, 1000.0, 100000.0, 1.0e6}) {
        const double lat = std::clamp(o.latDeg + dLat, -90.0, 90.0);
        pts.push_back({lat, o.lonDeg + dLon, h});
      }
    }
  }
  pts.push_back({-o.latDeg, o.lonDeg + 180.0, 0.0});
  pts.push_back({90.0, 0.0, 0.0});
  pts.push_back({-90.0, 0.0, 0.0});
  return pts;
}

TEST(LocalTangentPlane, MatchesProjTopocentricForAnyHeading) {
  double worstFwd = 0.0, worstInv = 0.0, worstToBf = 0.0;
  for (const LtpCase& c : ltpCases()) {
    const Proj proj(ltpProj(c));
    ASSERT_TRUE(proj.ok()) << proj.error();
    const Proj cart(degreesIn("+proj=cart" + projEllipsoid(c.body)));
    ASSERT_TRUE(cart.ok()) << cart.error();
    const double a = c.body.equatorialRadius();
    for (const double heading : {0.0, 30.0, 90.0, 180.0, -45.0, 271.5}) {
      const LocalTangentPlane ltp(c.body, c.origin, heading);
      for (const Geodetic& g : ltpPoints(c.origin)) {
        const glm::dvec3 enu = proj.trans(PJ_FWD, g.lonDeg, g.latDeg, g.height);
        ASSERT_TRUE(std::isfinite(enu.x) && std::isfinite(enu.y) && std::isfinite(enu.z));
        const glm::dvec3 ref = rotateEnu(enu, heading);
        const glm::dvec3 xyz = ltp.forward(g);
        const double d = glm::length(xyz - ref);
        worstFwd = std::max(worstFwd, d);
        EXPECT_LT(d, 1e-6) << c.label << " heading " << heading << " at " << g.latDeg << ' '
                           << g.lonDeg << ' ' << g.height;

        // Inverse of PROJ's plane coordinates gives back the exact point.
        const Geodetic back = ltp.inverse(ref);
        const double e =
            std::max(angularErrorM({back.latDeg, back.lonDeg}, {g.latDeg, g.lonDeg}, a),
                     std::abs(back.height - g.height));
        worstInv = std::max(worstInv, e);
        EXPECT_LT(e, 1e-6) << c.label << " heading " << heading << " inverse at " << g.latDeg << ' '
                           << g.lonDeg << ' ' << g.height;

        // Plane → body-fixed against PROJ's cart of the same point.
        const glm::dvec3 bf = cart.trans(PJ_FWD, g.lonDeg, g.latDeg, g.height);
        const double db = glm::length(ltp.toBodyFixed(ref) - bf);
        worstToBf = std::max(worstToBf, db);
        EXPECT_LT(db, 1e-6) << c.label << " heading " << heading;
        EXPECT_LT(glm::length(ltp.fromBodyFixed(bf) - ref), 1e-6) << c.label;
      }
    }
  }
  report("ltp.forward_vs_PROJ_topocentric_max_m", worstFwd);
  report("ltp.inverse_of_PROJ_vs_exact_max_m", worstInv);
  report("ltp.toBodyFixed_vs_PROJ_cart_max_m", worstToBf);
}

TEST(LocalTangentPlane, HeadingPointsTheYAxisAtThatAzimuthClockwiseFromNorth) {
  // Independent of the rotation formula: step 1 km from the origin along the local
  // direction of azimuth `heading` (ENU (sin h, cos h, 0), converted by PROJ's topocentric
  // inverse) and expect plane (0, 1000, 0); the direction 90° clockwise is +x.
  for (const LtpCase& c : ltpCases()) {
    const Proj topo("+proj=topocentric +lat_0=" + num(c.origin.latDeg) + " +lon_0=" +
                    num(c.origin.lonDeg) + " +h_0=" + num(c.origin.height) + projEllipsoid(c.body));
    ASSERT_TRUE(topo.ok()) << topo.error();
    for (const double heading : {0.0, 45.0, 90.0, 135.0, 200.0, -60.0}) {
      const LocalTangentPlane ltp(c.body, c.origin, heading);
      const double h = heading * kRadPerDeg;
      const glm::dvec3 ahead = topo.trans(PJ_INV, 1000.0 * std::sin(h), 1000.0 * std::cos(h), 0.0);
      const glm::dvec3 pAhead = ltp.fromBodyFixed(ahead);
      EXPECT_LT(glm::length(pAhead - glm::dvec3(0.0, 1000.0, 0.0)), 1e-8)
          << c.label << " heading " << heading;
      const glm::dvec3 right = topo.trans(PJ_INV, 1000.0 * std::cos(h), -1000.0 * std::sin(h), 0.0);
      EXPECT_LT(glm::length(ltp.fromBodyFixed(right) - glm::dvec3(1000.0, 0.0, 0.0)), 1e-8)
          << c.label << " heading " << heading;
      const glm::dvec3 up = topo.trans(PJ_INV, 0.0, 0.0, 1000.0);
      EXPECT_LT(glm::length(ltp.fromBodyFixed(up) - glm::dvec3(0.0, 0.0, 1000.0)), 1e-8)
          << c.label << " heading " << heading;
      // Axes: orthonormal and right-handed (x × y = z), z the ellipsoid normal.
      EXPECT_NEAR(glm::length(ltp.xAxis()), 1.0, 1e-15);
      EXPECT_NEAR(glm::length(ltp.yAxis()), 1.0, 1e-15);
      EXPECT_NEAR(glm::length(ltp.zAxis()), 1.0, 1e-15);
      EXPECT_NEAR(glm::dot(ltp.xAxis(), ltp.yAxis()), 0.0, 1e-15);
      EXPECT_LT(glm::length(glm::cross(ltp.xAxis(), ltp.yAxis()) - ltp.zAxis()), 1e-15);
      EXPECT_LT(glm::length((up - ltp.originBodyFixed()) / 1000.0 - ltp.zAxis()), 1e-11);
    }
  }
}

TEST(LocalTangentPlane, OriginIsZeroAndRoundTripsToWithin1e12OfTheRadius) {
  double worst = 0.0;
  for (const LtpCase& c : ltpCases()) {
    const Proj cart(degreesIn("+proj=cart" + projEllipsoid(c.body)));
    ASSERT_TRUE(cart.ok()) << cart.error();
    const double a = c.body.equatorialRadius();
    for (const double heading : {0.0, 123.0}) {
      const LocalTangentPlane ltp(c.body, c.origin, heading);
      EXPECT_EQ(ltp.headingDeg(), heading);
      EXPECT_EQ(ltp.origin().latDeg, c.origin.latDeg);
      EXPECT_EQ(ltp.body().equatorialRadius(), a);
      const glm::dvec3 o = cart.trans(PJ_FWD, c.origin.lonDeg, c.origin.latDeg, c.origin.height);
      EXPECT_LT(glm::length(ltp.originBodyFixed() - o), 1e-6) << c.label;
      // The origin is (0, 0, 0) exactly, and back.
      const glm::dvec3 zero = ltp.forward(c.origin);
      EXPECT_EQ(zero.x, 0.0) << c.label;
      EXPECT_EQ(zero.y, 0.0) << c.label;
      EXPECT_EQ(zero.z, 0.0) << c.label;
      const Geodetic g0 = ltp.inverse({0.0, 0.0, 0.0});
      EXPECT_NEAR(g0.latDeg, c.origin.latDeg, 1e-12) << c.label;
      if (std::abs(c.origin.latDeg) < 90.0) {
        EXPECT_NEAR(lonDiffDeg(g0.lonDeg, c.origin.lonDeg), 0.0, 1e-12) << c.label;
      }
      EXPECT_NEAR(g0.height, c.origin.height, 1e-8) << c.label;
      for (const Geodetic& g : ltpPoints(c.origin)) {
        const Geodetic back = ltp.inverse(ltp.forward(g));
        const double e =
            std::max(angularErrorM({back.latDeg, back.lonDeg}, {g.latDeg, g.lonDeg}, a),
                     std::abs(back.height - g.height)) /
            a;
        worst = std::max(worst, e);
        EXPECT_LT(e, 1e-12) << c.label << ' ' << g.latDeg << ' ' << g.lonDeg << ' ' << g.height;
      }
    }
  }
  report("ltp.round_trip_max_relative", worst);
}

TEST(LocalTangentPlane, AntipodeOfTheOriginIsFiniteStraightDownAndInvertsBack) {
  for (const LtpCase& c : ltpCases()) {
    const Proj proj(ltpProj(c));
    ASSERT_TRUE(proj.ok()) << proj.error();
    const LocalTangentPlane ltp(c.body, c.origin, 37.0);
    const Geodetic anti{-c.origin.latDeg, c.origin.lonDeg + 180.0, 0.0};
    const glm::dvec3 xyz = ltp.forward(anti);
    ASSERT_TRUE(std::isfinite(xyz.x) && std::isfinite(xyz.y) && std::isfinite(xyz.z));
    const glm::dvec3 ref = rotateEnu(proj.trans(PJ_FWD, anti.lonDeg, anti.latDeg, 0.0), 37.0);
    EXPECT_LT(glm::length(xyz - ref), 1e-6) << c.label;
    // Through the centre: on a sphere, or from a pole or the equator of an ellipsoid, the
    // antipode lies exactly below the origin.
    const bool straight =
        c.body.isSphere() || std::abs(c.origin.latDeg) == 90.0 || c.origin.latDeg == 0.0;
    if (straight) {
      EXPECT_LT(std::hypot(xyz.x, xyz.y), 1e-6) << c.label;
      const double depth = std::abs(c.origin.latDeg) == 90.0 && !c.body.isSphere()
                               ? 2.0 * c.body.polarRadius()
                               : 2.0 * c.body.equatorialRadius();
      EXPECT_NEAR(xyz.z, -(depth + c.origin.height), 1e-6) << c.label;
    }
    const Geodetic back = ltp.inverse(xyz);
    EXPECT_NEAR(back.latDeg, anti.latDeg, 1e-12) << c.label;
    if (std::abs(anti.latDeg) < 90.0) {
      EXPECT_NEAR(lonDiffDeg(back.lonDeg, anti.lonDeg), 0.0, 1e-12) << c.label;
    }
    EXPECT_NEAR(back.height, 0.0, 1e-8) << c.label;
  }
}

TEST(LocalTangentPlane, RejectsNonFiniteInputsNamingTheField) {
  const Body mars = Body::marsEllipsoid();
  struct Bad {
    Geodetic o;
    double heading = 0.0;
    const char* field = nullptr;
  };
  for (const Bad& b :
       {Bad{{kNaN, 0.0, 0.0}, 0.0, "latitude"}, Bad{{91.0, 0.0, 0.0}, 0.0, "latitude"},
        Bad{{0.0, kInf, 0.0}, 0.0, "origin longitude"}, Bad{{0.0, 0.0, kNaN}, 0.0, "origin height"},
        Bad{{0.0, 0.0, 0.0}, -kInf, "heading"}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>(
        [&] { (void)LocalTangentPlane(mars, b.o, b.heading); });
    EXPECT_TRUE(contains(msg, "LocalTangentPlane()")) << msg;
    EXPECT_TRUE(contains(msg, b.field)) << msg;
  }
  const LocalTangentPlane ltp(mars, {10.0, 20.0, 0.0}, 15.0);
  struct BadG {
    Geodetic g;
    const char* field = nullptr;
  };
  for (const BadG& b : {BadG{{kNaN, 0.0, 0.0}, "latitude"}, BadG{{-90.5, 0.0, 0.0}, "latitude"},
                        BadG{{0.0, -kInf, 0.0}, "longitude"}, BadG{{0.0, 0.0, kInf}, "height"}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] { (void)ltp.forward(b.g); });
    EXPECT_TRUE(contains(msg, "LocalTangentPlane::forward()")) << msg;
    EXPECT_TRUE(contains(msg, b.field)) << msg;
  }
  struct BadP {
    glm::dvec3 p{0.0};
    const char* field = nullptr;
  };
  for (const BadP& b : {BadP{{kNaN, 0.0, 0.0}, "x is"}, BadP{{0.0, kInf, 0.0}, "y is"},
                        BadP{{0.0, 0.0, -kInf}, "z is"}}) {
    const std::string msg = messageOf<regolith::InvalidArgument>([&] { (void)ltp.inverse(b.p); });
    EXPECT_TRUE(contains(msg, "LocalTangentPlane::inverse()")) << msg;
    EXPECT_TRUE(contains(msg, b.field)) << msg;
  }
}

}  // namespace
