#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/Body.hpp>

#include <cmath>
#include <numbers>
#include <string>

namespace regolith::topo {
namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
}

void throwNotFinite(double v, const char* operation, const char* field) {
  throw InvalidArgument(std::string(operation) + ": " + field + " is " + core::number(v) +
                        ", expected a finite number");
}

double wrapLongitude180(double lonDeg) noexcept {
  // Beyond two turns, fmod (exact) first: lon + 180 would round away what fmod(lon, 360)
  // keeps (at 1e308 all of it). Within them, lon + 180 rounds by at most an ulp of 900,
  // which keeps λ0 + 180 − λ0 on the −180 side as callers expect.
  const double r = std::abs(lonDeg) > 720.0 ? std::fmod(lonDeg, 360.0) : lonDeg;
  double w = std::fmod(r + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  if (w >= 360.0) w -= 360.0;  // fmod of a tiny negative can round up to 360
  return w - 180.0;
}

double wrapLongitude360(double lonDeg) noexcept {
  double w = std::fmod(lonDeg, 360.0);
  if (w < 0.0) w += 360.0;
  if (w >= 360.0) w -= 360.0;  // −tiny + 360 rounds to 360
  return w;
}

Body::Body(std::string name, double a, double b)
    : name_(std::move(name)), a_(a), b_(b), e2_((a * a - b * b) / (a * a)) {}

Body Body::sphere(std::string name, double radius) {
  if (!(std::isfinite(radius) && radius > 0.0)) {
    throw InvalidArgument("Body::sphere(): body '" + name + "' has radius " + core::number(radius) +
                          " m, expected finite and > 0");
  }
  return Body(std::move(name), radius, radius);
}

Body Body::ellipsoid(std::string name, double equatorialRadius, double polarRadius) {
  if (!(std::isfinite(equatorialRadius) && std::isfinite(polarRadius) && polarRadius > 0.0 &&
        polarRadius <= equatorialRadius)) {
    throw InvalidArgument(
        "Body::ellipsoid(): body '" + name + "' has radii a = " + core::number(equatorialRadius) +
        " m, b = " + core::number(polarRadius) + " m, expected finite 0 < b <= a");
  }
  return Body(std::move(name), equatorialRadius, polarRadius);
}

Body Body::marsSphere() { return sphere("Mars", 3396190.0); }
Body Body::marsEllipsoid() { return ellipsoid("Mars", 3396190.0, 3376200.0); }
Body Body::moon() { return sphere("Moon", 1737400.0); }
Body Body::earthWgs84() {
  constexpr double a = 6378137.0;
  constexpr double f = 1.0 / 298.257223563;
  return ellipsoid("Earth", a, a * (1.0 - f));
}

double Body::planetocentricFromPlanetodetic(double latDeg) const noexcept {
  if (isSphere()) return latDeg;
  const double p = latDeg * kDeg;
  // atan2 form: exact at ±90° where tan() would overflow.
  return std::atan2(b_ * b_ * std::sin(p), a_ * a_ * std::cos(p)) / kDeg;
}

double Body::planetodeticFromPlanetocentric(double latDeg) const noexcept {
  if (isSphere()) return latDeg;
  const double p = latDeg * kDeg;
  return std::atan2(a_ * a_ * std::sin(p), b_ * b_ * std::cos(p)) / kDeg;
}

double Body::toPlanetodetic(double latDeg, LatitudeType type) const noexcept {
  return type == LatitudeType::Planetodetic ? latDeg : planetodeticFromPlanetocentric(latDeg);
}

Body::SinCos Body::planetodeticSinCos(double latDeg, LatitudeType type) const noexcept {
  const double p = latDeg * kDeg;
  const double sp = std::sin(p), cp = std::cos(p);
  if (type == LatitudeType::Planetodetic || isSphere()) return {sp, cp};
  // The vector whose angle planetodeticFromPlanetocentric() takes, normalised.
  const double y = a_ * a_ * sp, x = b_ * b_ * cp;
  const double r = std::sqrt(x * x + y * y);
  return {y / r, x / r};
}

double Body::fromPlanetodetic(double latDeg, LatitudeType type) const noexcept {
  return type == LatitudeType::Planetodetic ? latDeg : planetocentricFromPlanetodetic(latDeg);
}

// On a sphere (e² = 0) both radii are the radius; the formulas give it bit for bit, and the
// shortcut saves the sine that per-query callers (planet normals, composition quality) pay.
double Body::primeVerticalRadius(double latDeg) const noexcept {
  if (isSphere()) return a_;
  return radiiOfCurvature(std::sin(latDeg * kDeg)).primeVertical;
}

double Body::meridianRadius(double latDeg) const noexcept {
  if (isSphere()) return a_;
  return radiiOfCurvature(std::sin(latDeg * kDeg)).meridian;
}

Body::Radii Body::radiiOfCurvature(double sinLat) const noexcept {
  if (isSphere()) return {a_, a_};
  const double w = 1.0 - e2_ * sinLat * sinLat;
  const double root = std::sqrt(w);
  return {a_ * (1.0 - e2_) / (w * root), a_ / root};
}

glm::dvec3 Body::toBodyFixed(const Geodetic& g) const noexcept {
  const double phi = g.latDeg * kDeg;
  const double lam = g.lonDeg * kDeg;
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double n = a_ / std::sqrt(1.0 - e2_ * sp * sp);
  return {(n + g.height) * cp * std::cos(lam), (n + g.height) * cp * std::sin(lam),
          (n * (1.0 - e2_) + g.height) * sp};
}

Geodetic Body::toGeodetic(const glm::dvec3& p) const noexcept {
  const double rxy = std::hypot(p.x, p.y);
  double lon = (rxy == 0.0) ? 0.0 : std::atan2(p.y, p.x) / kDeg;
  // atan2 gives −π for y = −0 or a y that is negative by rounding only (toBodyFixed at
  // −180°); the documented range is (−180, 180].
  if (lon <= -180.0) lon += 360.0;
  if (isSphere()) {
    const double r = std::hypot(rxy, p.z);
    return {std::atan2(p.z, rxy) / kDeg, lon, r - a_};
  }
  // Bowring's method: reduced latitude β from the current φ, φ from β; each step gains
  // about three orders of magnitude, so four steps are far below a nanometre for
  // altitudes from −10 km to 1000 km (tests/topo/BodyTest.cpp checks against PROJ).
  const double ep2 = (a_ * a_ - b_ * b_) / (b_ * b_);
  double beta = std::atan2(a_ * p.z, b_ * rxy);
  double phi = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double sb = std::sin(beta), cb = std::cos(beta);
    phi = std::atan2(p.z + ep2 * b_ * sb * sb * sb, rxy - e2_ * a_ * cb * cb * cb);
    beta = std::atan2(b_ * std::sin(phi), a_ * std::cos(phi));
  }
  const double sp = std::sin(phi), cp = std::cos(phi);
  // Stable everywhere, including the poles (no division by cos φ).
  const double h = rxy * cp + p.z * sp - a_ * std::sqrt(1.0 - e2_ * sp * sp);
  return {phi / kDeg, lon, h};
}

glm::dmat3 Body::enuFrame(double latDeg, double lonDeg) const noexcept {
  const double phi = latDeg * kDeg;
  return enuFrameOf(std::sin(phi), std::cos(phi), lonDeg);
}

glm::dmat3 Body::enuFrameOf(double sp, double cp, double lonDeg) noexcept {
  const double lam = lonDeg * kDeg;
  const double sl = std::sin(lam), cl = std::cos(lam);
  const glm::dvec3 east(-sl, cl, 0.0);
  const glm::dvec3 north(-sp * cl, -sp * sl, cp);
  const glm::dvec3 up(cp * cl, cp * sl, sp);
  return glm::dmat3(east, north, up);
}

}  // namespace regolith::topo
