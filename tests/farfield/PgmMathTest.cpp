// The PGM geometry (farfield/PgmMath.hpp) against outside oracles: ray–sphere intersection
// solved directly in long double, PROJ's polar stereographic and topo::Body's frames.

#include <regolith/core/Error.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmMath.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>

namespace regolith::farfield {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMars = 3396190.0;

/// Oracle: the normal angle of the front hit, by the quadratic in long double with the eye
/// at (0, 0, d), the centre at the origin and the ray (sin ω, 0, −cos ω).
std::optional<long double> oracleFront(long double omega, long double d, long double r) {
  const long double dx = std::sin(omega), dz = -std::cos(omega);
  // |E + t·r̂|² = r²: t² + 2t·(E·r̂) + d² − r² = 0.
  const long double b = d * dz, c = d * d - r * r, disc = b * b - c;
  if (disc < 0) return std::nullopt;
  const long double t = -b - std::sqrt(disc);
  if (t < 0) return std::nullopt;
  const long double x = t * dx, z = d + t * dz;
  return std::atan2(x, z);
}

TEST(PgmMath, FrontNormalAngleMatchesTheQuadraticFromOrbitDownToOneMillimetre) {
  std::mt19937_64 rng(7);
  for (const double altitude : {4.0e8, 2.0e7, 4.0e5, 1000.0, 2.0, 1e-3}) {
    const double d = kMars + altitude;
    const double tau = std::asin(kMars / d);
    std::uniform_real_distribution<double> om(0.0, tau);
    for (int i = 0; i < 2000; ++i) {
      const double omega = i == 0 ? 0.0 : om(rng);
      const auto g = frontNormalAngle(omega, d, kMars);
      const auto ref = oracleFront(omega, d, kMars);
      ASSERT_TRUE(g.has_value() && ref.has_value()) << altitude << " " << omega;
      // 1e-12 rad is 3 µm on Mars; near the tangent the angle is ill-conditioned in ω itself.
      const double tol = 1e-12 + 1e-9 * omega / std::max(tau - omega, 1e-6);
      EXPECT_NEAR(*g, static_cast<double>(*ref), tol) << altitude << " " << omega;
    }
    EXPECT_FALSE(frontNormalAngle(tau * 1.000001 + 1e-9, d, kMars).has_value()) << altitude;
  }
}

TEST(PgmMath, EyeSpacePointLiesOnTheSphereAlongTheRay) {
  const glm::dvec3 nadir(0.0, 0.0, -1.0), k(1.0, 0.0, 0.0);
  for (const double altitude : {3.0e7, 1.0e5, 1.0, 1e-3}) {
    const double d = kMars + altitude;
    for (const double f : {0.0, 0.1, 0.5, 0.9, 0.999}) {
      const double omega = f * std::asin(kMars / d);
      const double g = *frontNormalAngle(omega, d, kMars);
      const glm::dvec3 p = eyeSpacePoint(g, d, kMars, nadir, k);
      const glm::dvec3 world = glm::dvec3(0.0, 0.0, d) + p;  // centre at the origin
      EXPECT_NEAR(glm::length(world), kMars, 1e-6) << altitude << " " << f;
      const glm::dvec3 ray(std::sin(omega), 0.0, -std::cos(omega));
      EXPECT_NEAR(glm::length(glm::cross(glm::normalize(p), ray)), 0.0, 1e-12)
          << altitude << " " << f;
    }
    // ω = 0: straight down, the point is the altitude below the eye, exactly.
    EXPECT_EQ(eyeSpacePoint(0.0, d, kMars, nadir, k), glm::dvec3(0.0, 0.0, -(d - kMars)));
  }
}

TEST(PgmMath, ReferenceSpheresFollowEquationsThreeAndFour) {
  const double rMin = kMars - 8000.0, rMax = kMars + 21000.0;
  for (const double d : {kMars + 5000.0, kMars + 4.0e5, 5.0 * kMars, 9.0 * kMars}) {
    const ReferenceSpheres s = referenceSpheres(d, rMin, rMax, 0.9);
    EXPECT_DOUBLE_EQ(s.tau0, std::asin(rMin / d));
    // γ₀ is the back hit of the primary tangent ray with the maximum sphere (oracle: the far
    // root of the quadratic).
    const long double om = s.tau0, dx = std::sin(om), dz = -std::cos(om);
    const long double b = d * dz,
                      c = static_cast<long double>(d) * d - static_cast<long double>(rMax) * rMax;
    const long double t = -b + std::sqrt(b * b - c);
    EXPECT_NEAR(s.gamma0, static_cast<double>(std::atan2(t * dx, d + t * dz)), 1e-12) << d;
    EXPECT_NEAR(s.secondary, d * std::cos(s.gamma0), 1e-6);
    if (s.secondaryExists()) {
      EXPECT_LE(s.secondary, s.primary);
      // The secondary's tangent ray meets it at γ₀ (the farthest point that can rise into view).
      EXPECT_NEAR(0.5 * kPi - s.tauS, s.gamma0, 1e-9) << d;
      EXPECT_NEAR(blendedNormalAngle(s, s.tauTop), s.gamma0, 1e-9) << d;
    }
  }
  // Mars with 21 km mountains: the secondary sphere vanishes a few radii out, as the paper
  // says ("sufficiently far away to replace the planet with an impostor").
  EXPECT_TRUE(referenceSpheres(5.0 * kMars, rMin, rMax, 0.9).secondaryExists());
  EXPECT_FALSE(referenceSpheres(20.0 * kMars, rMin, rMax, 0.9).secondaryExists());
}

TEST(PgmMath, BlendedNormalAngleIsMonotoneContinuousAndFiniteInEveryCase) {
  const double rMin = kMars - 8000.0, rMax = kMars + 21000.0;
  struct Case {
    double d, primary;
    const char* what;
  };
  // r_s → 0⁺: find the distance where the secondary sphere just vanishes by bisection.
  double lo = 1.01 * kMars, hi = 100.0 * kMars;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (referenceSpheres(mid, rMin, rMax, 0.9).secondaryExists() ? lo : hi) = mid;
  }
  const Case cases[] = {{kMars + 4.0e5, rMin, "low orbit"},
                        {kMars + 2.0, kMars, "2 m above the datum"},
                        {kMars + 1e-3, kMars, "1 mm above the primary sphere"},
                        {kMars + 1000.0, rMin, "below the maximum sphere"},
                        {lo, rMin, "r_s -> 0+"}};
  for (const Case& c : cases) {
    const ReferenceSpheres s = referenceSpheres(c.d, c.primary, rMax, 0.9);
    ASSERT_TRUE(s.secondaryExists()) << c.what;
    double prev = -1.0;
    for (int i = 0; i <= 4000; ++i) {
      const double omega = s.tauTop * (i / 4000.0) * 1.02;  // a little past the top too
      const double g = blendedNormalAngle(s, omega);
      ASSERT_TRUE(std::isfinite(g)) << c.what << " " << omega;
      EXPECT_GE(g, prev - 1e-9) << c.what << " " << omega;
      EXPECT_LE(g, s.gamma0 + 1e-9) << c.what;
      if (omega <= s.begin) {
        EXPECT_NEAR(g, *frontNormalAngle(omega, c.d, s.primary), 1e-12) << c.what;
      }
      prev = g;
    }
    // Continuous at b.
    EXPECT_NEAR(blendedNormalAngle(s, s.begin * (1 + 1e-9)), s.gammaBegin, 1e-6) << c.what;
  }
}

TEST(PgmMath, SamplingCameraCoversEveryPertinentRayOfTheView) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(-1.0, 1.0), unit(0.0, 1.0);
  const double rMax = kMars + 21000.0;
  int views = 0, lookedAway = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double altitude = std::pow(10.0, 1.0 + 7.0 * unit(rng));  // 10 m to 10^8 m
    const double d = kMars + altitude;
    const glm::dvec3 eye(0.0, 0.0, d);
    const glm::dvec3 nadir(0.0, 0.0, -1.0);
    glm::dvec3 fwd = glm::normalize(glm::dvec3(uni(rng), uni(rng), uni(rng)));
    if (trial % 4 == 0) fwd = glm::normalize(glm::dvec3(0.05 * uni(rng), 0.05 * uni(rng), -1.0));
    const glm::dvec3 right = glm::normalize(glm::cross(fwd, glm::dvec3(0.3, 1.0, 0.2)));
    const glm::dvec3 up = glm::cross(right, fwd);
    const double fov = 0.3 + 1.2 * unit(rng), aspect = 0.5 + 1.5 * unit(rng);
    const Frustum view = viewFrustum(fwd, right, up, fov, aspect);
    const ReferenceSpheres s = referenceSpheres(d, kMars - 8000.0, rMax, 0.9);
    const SamplingCamera cam = samplingCamera(view, nadir, s.tauTop);
    lookedAway += cam.lookedAway ? 1 : 0;
    ++views;
    ASSERT_TRUE(std::isfinite(cam.left) && std::isfinite(cam.right) && std::isfinite(cam.bottom) &&
                std::isfinite(cam.top));
    ASSERT_LT(cam.left, cam.right);
    ASSERT_LT(cam.bottom, cam.top);
    // Every ray of the view that meets the maximum sphere (or, inside it, points below the
    // horizontal) lies inside the sampling frustum, unless pulled in by the half-angle limit.
    const double th = std::tan(0.5 * fov), tw = th * aspect;
    for (int i = 0; i < 200; ++i) {
      const glm::dvec3 r = glm::normalize(fwd + tw * uni(rng) * right + th * uni(rng) * up);
      const double omega = std::acos(std::clamp(glm::dot(r, nadir), -1.0, 1.0));
      if (omega > s.tauTop) continue;
      const double z = glm::dot(r, cam.forward);
      if (z < std::cos(1.45)) continue;
      const double x = glm::dot(r, cam.rightAxis) / z, y = glm::dot(r, cam.up) / z;
      const double eps = 1e-9 * (1.0 + std::abs(x) + std::abs(y));
      EXPECT_TRUE(x >= cam.left - eps && x <= cam.right + eps && y >= cam.bottom - eps &&
                  y <= cam.top + eps)
          << "trial " << trial << " altitude " << altitude;
    }
    // holds(): the grid's own rays, inside and on the edges, and not beyond them or behind.
    EXPECT_TRUE(cam.holds(cam.ray(0.5, 0.5)) && cam.holds(cam.ray(0.0, 1.0)) &&
                cam.holds(cam.ray(1.0, 0.0)))
        << trial;
    EXPECT_FALSE(cam.holds(cam.ray(-0.01, 0.5)) || cam.holds(cam.ray(0.5, 1.01)) ||
                 cam.holds(-cam.forward))
        << trial;
    // The nadir is always sampled, so the even-error spread is never turned off
    // (PgmRenderer draws a frame whose grid does not hold the nadir without it).
    EXPECT_TRUE(cam.holds(nadir)) << trial;
    const double zn = glm::dot(nadir, cam.forward);
    if (zn > std::cos(1.45)) {
      const double xn = glm::dot(nadir, cam.rightAxis) / zn, yn = glm::dot(nadir, cam.up) / zn;
      EXPECT_TRUE(xn >= cam.left - 1e-9 && xn <= cam.right + 1e-9 && yn >= cam.bottom - 1e-9 &&
                  yn <= cam.top + 1e-9)
          << trial;
    }
  }
  EXPECT_GT(lookedAway, 0);  // the random views include some that look away
  EXPECT_LT(lookedAway, views);
}

/// A step of the grid from ray angle w0 to w1 on the primary sphere: its ground length
/// squared over its distance from the eye, which a cell's screen-space error grows as.
double stepError(const ReferenceSpheres& s, double w0, double w1) {
  const double g0 = blendedNormalAngle(s, w0), g1 = blendedNormalAngle(s, w1);
  const glm::dvec3 n(0.0, 0.0, -1.0), k(1.0, 0.0, 0.0);
  const glm::dvec3 p = eyeSpacePoint(0.5 * (g0 + g1), s.d, s.primary, n, k);
  const double ground = s.primary * (g1 - g0);
  return ground * ground / glm::length(p);
}

TEST(PgmMath, EvenErrorSpreadIsMonotoneKeepsCoverageAndEvensTheStepsError) {
  const double rMin = kMars - 8000.0, rMax = kMars + 21000.0;
  struct Case {
    const char* what;
    double d;
  };
  // 0: the distance where r_s is barely positive.
  const Case cases[] = {
      {"3 R (global)", 3.0 * kMars},
      {"400 km (low)", kMars + 400e3},
      {"30 km above the highest point", rMax + 30e3},
      {"2 m above the lowest sphere", rMin + 2.0},
      {"r_s barely positive", 0.0},
  };
  for (const Case& c : cases) {
    // r_s → 0⁺: the largest distance with r_s > 1 m, by bisection.
    double d = c.d;
    if (d == 0.0) {
      double lo = 1.01 * rMax, hi = 1e3 * rMax;
      for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (referenceSpheres(mid, rMin, rMax, 0.9).secondary > 1.0 ? lo : hi) = mid;
      }
      d = lo;
    }
    const ReferenceSpheres s = referenceSpheres(d, rMin, rMax, 0.9);
    ASSERT_TRUE(s.secondaryExists()) << c.what;
    const RaySpread spread = evenErrorSpread(s, 256);
    ASSERT_TRUE(spread.active()) << c.what;
    ASSERT_EQ(spread.table.size(), 256U);
    EXPECT_EQ(spread.table.front(), 0.0) << c.what;
    EXPECT_EQ(spread.table.back(), s.tauTop) << c.what;
    // Monotone, finite, never below the identity (coverage), the identity beyond τ_top.
    double previous = -1.0;
    for (int i = 0; i <= 5000; ++i) {
      const double w = s.tauTop * i / 5000.0;
      const double f = spread.angle(w);
      ASSERT_TRUE(std::isfinite(f)) << c.what << " " << w;
      EXPECT_GE(f, previous) << c.what << " " << w;
      EXPECT_GE(f, w * (1.0 - 1e-12)) << c.what << " " << w;
      EXPECT_LE(f, s.tauTop) << c.what << " " << w;
      previous = f;
    }
    EXPECT_EQ(spread.angle(1.01 * s.tauTop), 1.01 * s.tauTop) << c.what;
    // The ray turned about the nadir keeps its azimuth and takes the new angle.
    const glm::dvec3 nadir(0.0, 0.0, -1.0);
    const double w = 0.37 * s.tauTop;
    const glm::dvec3 r(std::sin(w) * 0.6, std::sin(w) * 0.8, -std::cos(w));
    const glm::dvec3 turned = spread.ray(r, nadir);
    EXPECT_NEAR(std::acos(glm::dot(turned, nadir)), spread.angle(w), 1e-9) << c.what;
    EXPECT_NEAR(turned.y / turned.x, 0.8 / 0.6, 1e-9) << c.what;
    EXPECT_EQ(spread.ray(nadir, nadir), nadir);
    // A grid of 64 steps from the nadir to τ_top: the largest step's error, evenly spaced in
    // the ray angle against spread.
    double evenWorst = 0.0, spreadWorst = 0.0;
    for (int i = 0; i < 64; ++i) {
      const double u0 = s.tauTop * i / 64.0, u1 = s.tauTop * (i + 1) / 64.0;
      evenWorst = std::max(evenWorst, stepError(s, u0, u1));
      spreadWorst = std::max(spreadWorst, stepError(s, spread.angle(u0), spread.angle(u1)));
    }
    std::printf("[ %s ] largest step error: even grid %.4g, spread %.4g (%.1fx lower)\n", c.what,
                evenWorst, spreadWorst, evenWorst / spreadWorst);
    // 18–70× here; the ideal spreads the error evenly over the 64 steps.
    EXPECT_LE(spreadWorst * 8.0, evenWorst) << c.what;
  }
  // No ray angles to spread: inactive, and the identity.
  ReferenceSpheres none;
  EXPECT_FALSE(evenErrorSpread(none).active());
  EXPECT_EQ(RaySpread{}.angle(0.3), 0.3);
}

TEST(PgmMath, SamplingCameraLookingAwayUsesThePlanetFrustumCorners) {
  const double d = 3.0 * kMars;
  const ReferenceSpheres s = referenceSpheres(d, kMars, kMars, 0.9);
  const glm::dvec3 nadir(0.0, 0.0, -1.0);
  const Frustum view = viewFrustum(glm::dvec3(0.0, 0.0, 1.0), glm::dvec3(1.0, 0.0, 0.0),
                                   glm::dvec3(0.0, 1.0, 0.0), 0.8, 1.0);
  const SamplingCamera cam = samplingCamera(view, nadir, s.tauTop);
  EXPECT_TRUE(cam.lookedAway);
  // Every grid ray then points at the planet's cone or just beside it: the corners of a square
  // about a cone of half-angle τ are √2·tan τ off the axis.
  for (const double u : {0.0, 0.5, 1.0}) {
    for (const double v : {0.0, 0.5, 1.0}) {
      const double w = std::acos(glm::dot(cam.ray(u, v), nadir));
      EXPECT_LE(w, std::atan(std::sqrt(2.0) * std::tan(s.tauTop)) + 1e-9) << u << " " << v;
    }
  }
}

TEST(PgmMath, MapProjectionsMatchProjAtThePolesAndTheSeam) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* north = proj_create(ctx, "+proj=stere +lat_0=90 +lat_ts=90 +lon_0=0 +R=1 +k_0=1");
  PJ* south = proj_create(ctx, "+proj=stere +lat_0=-90 +lat_ts=-90 +lon_0=0 +R=1 +k_0=1");
  ASSERT_NE(north, nullptr);
  ASSERT_NE(south, nullptr);
  const double lats[] = {90.0, 89.999999, 85.0, 60.0, 30.0, 0.0};
  const double lons[] = {-180.0, -179.9999999, -90.0, 0.0, 45.0, 179.9999999, 180.0};
  for (const double lat : lats) {
    for (const double lon : lons) {
      for (const bool isNorth : {true, false}) {
        const double phi = (isNorth ? lat : -lat) * kPi / 180.0, lam = lon * kPi / 180.0;
        const glm::dvec3 n(std::cos(phi) * std::cos(lam), std::cos(phi) * std::sin(lam),
                           std::sin(phi));
        const MapCoords m = polarStereographic(n, isNorth);
        PJ_COORD in = proj_coord(proj_torad(lon), proj_torad(isNorth ? lat : -lat), 0, 0);
        const PJ_COORD out = proj_trans(isNorth ? north : south, PJ_FWD, in);
        // PROJ's +lat_ts=±90 with k_0 = 1 is 2·tan(π/4 − |φ|/2) on the unit sphere.
        EXPECT_NEAR(m.p, out.xy.x, 1e-12) << lat << " " << lon << " " << isNorth;
        EXPECT_NEAR(m.q, out.xy.y, 1e-12) << lat << " " << lon << " " << isNorth;
      }
      const double phi = lat * kPi / 180.0, lam = lon * kPi / 180.0;
      const glm::dvec3 n(std::cos(phi) * std::cos(lam), std::cos(phi) * std::sin(lam),
                         std::sin(phi));
      const MapCoords e = equirectangular(n, kPi, 0.0);  // centred on the seam
      EXPECT_NEAR(e.q, phi, 1e-12);
      EXPECT_GE(e.p, -kPi);
      EXPECT_LT(e.p, kPi);
      if (lat < 90.0) {
        // Longitudes either side of ±180° land either side of p = 0, continuously.
        double expect = std::remainder(lam - kPi, 2.0 * kPi);
        if (expect >= kPi) expect -= 2.0 * kPi;
        EXPECT_NEAR(e.p, expect, 1e-9) << lat << " " << lon;
      }
    }
  }
  proj_destroy(north);
  proj_destroy(south);
  proj_context_destroy(ctx);
}

TEST(PgmMath, EllipsoidHelpersMatchTheBody) {
  const topo::Body mars = topo::Body::marsEllipsoid();
  const double a = mars.equatorialRadius(), b = mars.polarRadius();
  for (const double lat : {-90.0, -60.0, -1e-7, 0.0, 33.3, 89.9999, 90.0}) {
    for (const double lon : {-180.0, 0.0, 123.0}) {
      const glm::dvec3 p = mars.toBodyFixed({lat, lon, 0.0});
      const glm::dvec3 s = glm::normalize(p);
      const glm::dvec3 up = mars.enuFrame(lat, lon)[2];
      EXPECT_NEAR(glm::length(geodeticNormal(s, a, b) - up), 0.0, 1e-12) << lat << " " << lon;
      EXPECT_NEAR(ellipsoidRadiusAbove(s, a, b, b - 8000.0), glm::length(p) - (b - 8000.0), 1e-6)
          << lat;
    }
  }
}

}  // namespace
}  // namespace regolith::farfield

namespace regolith::farfield {
namespace {

TEST(HeightLayers, BadOptionsAreNamedWithTheirRange) {
  const topo::Body mars = topo::Body::marsSphere();
  const auto flat = [](double, double, double) { return 0.0; };
  LayerOptions o;
  o.equirectWidth = 63;
  try {
    (void)HeightLayers::build(mars, flat, o);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "farfield::HeightLayers::build(): equirectWidth is 63, expected in [64, 16384]");
  }
  o.equirectWidth = 130;
  o.capLatitude = 89.0;
  EXPECT_THROW((void)HeightLayers::build(mars, flat, o), InvalidArgument);
  o.capLatitude = 60.0;
  o.equirectWidth = 129;  // odd
  EXPECT_THROW((void)HeightLayers::build(mars, flat, o), InvalidArgument);
  o.equirectWidth = 128;
  EXPECT_THROW((void)HeightLayers::build(mars, HeightLayers::HeightFunction{}, o), InvalidArgument);
  // NaN heights are missing texels, set to 0 and counted.
  o.capSize = 16;
  const HeightLayers l = HeightLayers::build(
      mars, [](double lat, double, double) { return lat > 80.0 ? std::nan("") : 5.0; }, o);
  EXPECT_GT(l.missing(), 0U);
  EXPECT_EQ(l.maxHeight(), 5.0);
  EXPECT_EQ(l.minHeight(), 0.0);
}

}  // namespace
}  // namespace regolith::farfield
