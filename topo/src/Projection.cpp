#include <regolith/topo/Error.hpp>
#include <regolith/topo/Projection.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace regolith::topo {
namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kHalfPi = std::numbers::pi / 2.0;

void requireLatitude(double latDeg, const char* op) {
  requireFinite(latDeg, op, "latitude");
  if (std::abs(latDeg) > 90.0) {
    throw InvalidArgument(std::string(op) + ": latitude is " + std::to_string(latDeg) +
                          " deg, expected within [-90, 90]");
  }
}

// Snyder (15-9): t = tan(π/4 − φ/2) / ((1 − e sinφ)/(1 + e sinφ))^(e/2). tan(π/4 − φ/2)
// is written cos φ / (1 + sin φ) in the projection's hemisphere and (1 − sin φ) / cos φ in
// the other, so it stays accurate (and finite) next to both poles.
double stereoT(double phi, double e) {
  const double s = std::sin(phi);
  const double base = phi >= 0.0 ? std::cos(phi) / (1.0 + s) : (1.0 - s) / std::cos(phi);
  if (e == 0.0) return base;
  return base / std::pow((1.0 - e * s) / (1.0 + e * s), 0.5 * e);
}
}  // namespace

// ---- Equirectangular -------------------------------------------------------------------

Equirectangular::Equirectangular(double radius, double latTrueScaleDeg, double lonCentreDeg,
                                 double latOriginDeg)
    : r_(radius), latTsDeg_(latTrueScaleDeg), lon0Deg_(lonCentreDeg), lat0Deg_(latOriginDeg) {
  constexpr const char* op = "Equirectangular()";
  requireFinite(radius, op, "radius");
  requireFinite(latTrueScaleDeg, op, "latitude of true scale");
  requireFinite(lonCentreDeg, op, "centre longitude");
  requireFinite(latOriginDeg, op, "latitude of origin");
  if (radius <= 0.0) {
    throw InvalidArgument(std::string(op) + ": radius is " + std::to_string(radius) +
                          " m, expected > 0");
  }
  if (std::abs(latTrueScaleDeg) >= 90.0) {
    throw InvalidArgument(std::string(op) + ": latitude of true scale is " +
                          std::to_string(latTrueScaleDeg) + " deg, expected |lat| < 90");
  }
  cosTs_ = std::cos(latTrueScaleDeg * kDeg);
}

glm::dvec2 Equirectangular::forward(const LatLon& ll) const {
  requireLatitude(ll.latDeg, "Equirectangular::forward()");
  requireFinite(ll.lonDeg, "Equirectangular::forward()", "longitude");
  const double dl = wrapLongitude180(ll.lonDeg - lon0Deg_);
  return {r_ * dl * kDeg * cosTs_, r_ * (ll.latDeg - lat0Deg_) * kDeg};
}

LatLon Equirectangular::inverse(const glm::dvec2& xy) const {
  requireFinite(xy.x, "Equirectangular::inverse()", "x");
  requireFinite(xy.y, "Equirectangular::inverse()", "y");
  const double lat = lat0Deg_ + xy.y / r_ / kDeg;
  if (std::abs(lat) > 90.0 + 1e-9) {
    throw DomainError("Equirectangular::inverse(): y = " + std::to_string(xy.y) +
                      " m gives latitude " + std::to_string(lat) + " deg, beyond the pole");
  }
  const double lon = lon0Deg_ + xy.x / (r_ * cosTs_) / kDeg;
  return {std::clamp(lat, -90.0, 90.0), wrapLongitude180(lon)};
}

// ---- PolarStereographic ----------------------------------------------------------------

PolarStereographic::PolarStereographic(double a, double e, Pole pole, double k0, double lon0Deg,
                                       double fe, double fn)
    : a_(a), e_(e), pole_(pole), k0_(k0), lon0Deg_(lon0Deg), fe_(fe), fn_(fn) {
  // Snyder (21-33): ρ = 2 a k0 t / sqrt((1+e)^(1+e) (1−e)^(1−e)).
  const double c = std::sqrt(std::pow(1.0 + e, 1.0 + e) * std::pow(1.0 - e, 1.0 - e));
  rhoFactor_ = 2.0 * a * k0 / c;
}

PolarStereographic PolarStereographic::withTrueScaleLatitude(const Body& body, Pole pole,
                                                             double latTrueScaleDeg,
                                                             double lonCentreDeg,
                                                             double falseEasting,
                                                             double falseNorthing) {
  constexpr const char* op = "PolarStereographic::withTrueScaleLatitude()";
  requireLatitude(latTrueScaleDeg, op);
  requireFinite(lonCentreDeg, op, "centre longitude");
  requireFinite(falseEasting, op, "false easting");
  requireFinite(falseNorthing, op, "false northing");
  const bool north = pole == Pole::North;
  if ((north && latTrueScaleDeg <= 0.0) || (!north && latTrueScaleDeg >= 0.0)) {
    throw InvalidArgument(std::string(op) + ": latitude of true scale is " +
                          std::to_string(latTrueScaleDeg) +
                          " deg, expected in the hemisphere of the projection's pole");
  }
  const double e = std::sqrt(body.eccentricitySquared());
  double k0 = 1.0;
  if (std::abs(latTrueScaleDeg) != 90.0) {
    // Snyder (21-34) with (14-15): ρ = a m_c t / t_c, so k0 = m_c c / (2 t_c).
    const double phic = std::abs(latTrueScaleDeg) * kDeg;
    const double sc = std::sin(phic);
    const double mc = std::cos(phic) / std::sqrt(1.0 - e * e * sc * sc);
    const double tc = stereoT(phic, e);
    const double c = std::sqrt(std::pow(1.0 + e, 1.0 + e) * std::pow(1.0 - e, 1.0 - e));
    k0 = mc * c / (2.0 * tc);
  }
  return {body.equatorialRadius(), e, pole, k0, lonCentreDeg, falseEasting, falseNorthing};
}

PolarStereographic PolarStereographic::withScaleFactor(const Body& body, Pole pole, double k0,
                                                       double lonCentreDeg, double falseEasting,
                                                       double falseNorthing) {
  constexpr const char* op = "PolarStereographic::withScaleFactor()";
  requireFinite(k0, op, "scale factor");
  requireFinite(lonCentreDeg, op, "centre longitude");
  requireFinite(falseEasting, op, "false easting");
  requireFinite(falseNorthing, op, "false northing");
  if (k0 <= 0.0) {
    throw InvalidArgument(std::string(op) + ": scale factor is " + std::to_string(k0) +
                          ", expected > 0");
  }
  return {body.equatorialRadius(),
          std::sqrt(body.eccentricitySquared()),
          pole,
          k0,
          lonCentreDeg,
          falseEasting,
          falseNorthing};
}

glm::dvec2 PolarStereographic::forward(const LatLon& ll) const {
  constexpr const char* op = "PolarStereographic::forward()";
  requireLatitude(ll.latDeg, op);
  requireFinite(ll.lonDeg, op, "longitude");
  const bool north = pole_ == Pole::North;
  // Snyder: the south aspect is the north aspect with the signs of φ, λ, x, y changed.
  const double latN = north ? ll.latDeg : -ll.latDeg;
  if (latN == 90.0) return {fe_, fn_};
  if (latN == -90.0) {
    throw DomainError(std::string(op) + ": latitude " + std::to_string(ll.latDeg) +
                      " deg is the pole opposite the projection's centre; it maps to infinity");
  }
  const double rho = rhoFactor_ * stereoT(latN * kDeg, e_);
  const double dl = (ll.lonDeg - lon0Deg_) * kDeg;
  const double x = rho * std::sin(dl);
  const double y = north ? -rho * std::cos(dl) : rho * std::cos(dl);
  return {x + fe_, y + fn_};
}

LatLon PolarStereographic::inverse(const glm::dvec2& xy) const {
  constexpr const char* op = "PolarStereographic::inverse()";
  requireFinite(xy.x, op, "x");
  requireFinite(xy.y, op, "y");
  const bool north = pole_ == Pole::North;
  const double x = xy.x - fe_, y = xy.y - fn_;
  const double rho = std::hypot(x, y);
  if (rho == 0.0) return {north ? 90.0 : -90.0, wrapLongitude180(lon0Deg_)};
  const double t = rho / rhoFactor_;
  // Snyder (7-9), iterated to convergence (≤ 6 steps for any planet's eccentricity).
  double phi = kHalfPi - 2.0 * std::atan(t);
  if (e_ != 0.0) {
    for (int i = 0; i < 30; ++i) {
      const double es = e_ * std::sin(phi);
      const double next =
          kHalfPi - 2.0 * std::atan(t * std::pow((1.0 - es) / (1.0 + es), 0.5 * e_));
      const double delta = std::abs(next - phi);
      phi = next;
      if (delta < 1e-15) break;
    }
  }
  const double dl = north ? std::atan2(x, -y) : std::atan2(x, y);
  const double lat = phi / kDeg;
  return {north ? lat : -lat, wrapLongitude180(lon0Deg_ + dl / kDeg)};
}

double PolarStereographic::scaleFactor(double latDeg) const {
  requireLatitude(latDeg, "PolarStereographic::scaleFactor()");
  const double latN = pole_ == Pole::North ? latDeg : -latDeg;
  if (latN == 90.0) return k0_;
  if (latN == -90.0) {
    throw DomainError("PolarStereographic::scaleFactor(): the opposite pole has infinite scale");
  }
  const double phi = latN * kDeg;
  const double s = std::sin(phi);
  const double m = std::cos(phi) / std::sqrt(1.0 - e_ * e_ * s * s);
  return rhoFactor_ * stereoT(phi, e_) / (a_ * m);
}

// ---- LocalTangentPlane -----------------------------------------------------------------

LocalTangentPlane::LocalTangentPlane(const Body& body, const Geodetic& origin, double headingDeg)
    : body_(body), origin_(origin), headingDeg_(headingDeg) {
  constexpr const char* op = "LocalTangentPlane()";
  requireLatitude(origin.latDeg, op);
  requireFinite(origin.lonDeg, op, "origin longitude");
  requireFinite(origin.height, op, "origin height");
  requireFinite(headingDeg, op, "heading");
  o_ = body_.toBodyFixed(origin_);
  const glm::dmat3 enu = body_.enuFrame(origin_.latDeg, origin_.lonDeg);
  const double th = headingDeg * kDeg;
  const double c = std::cos(th), s = std::sin(th);
  ex_ = c * enu[0] - s * enu[1];
  ey_ = s * enu[0] + c * enu[1];
  ez_ = enu[2];
}

glm::dvec3 LocalTangentPlane::forward(const Geodetic& g) const {
  constexpr const char* op = "LocalTangentPlane::forward()";
  requireLatitude(g.latDeg, op);
  requireFinite(g.lonDeg, op, "longitude");
  requireFinite(g.height, op, "height");
  return fromBodyFixed(body_.toBodyFixed(g));
}

Geodetic LocalTangentPlane::inverse(const glm::dvec3& xyz) const {
  constexpr const char* op = "LocalTangentPlane::inverse()";
  requireFinite(xyz.x, op, "x");
  requireFinite(xyz.y, op, "y");
  requireFinite(xyz.z, op, "z");
  return body_.toGeodetic(toBodyFixed(xyz));
}

glm::dvec3 LocalTangentPlane::toBodyFixed(const glm::dvec3& xyz) const noexcept {
  return o_ + xyz.x * ex_ + xyz.y * ey_ + xyz.z * ez_;
}

glm::dvec3 LocalTangentPlane::fromBodyFixed(const glm::dvec3& p) const noexcept {
  const glm::dvec3 d = p - o_;
  return {glm::dot(ex_, d), glm::dot(ey_, d), glm::dot(ez_, d)};
}

}  // namespace regolith::topo
