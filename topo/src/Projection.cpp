#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/Projection.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <string>

namespace regolith::topo {
namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kHalfPi = std::numbers::pi / 2.0;

void requireLatitude(double latDeg, const char* op) {
  requireFinite(latDeg, op, "latitude");
  if (std::abs(latDeg) > 90.0) {
    throw InvalidArgument(std::string(op) + ": latitude is " + core::number(latDeg) +
                          " deg, expected within [-90, 90]");
  }
}

// A longitude beyond two turns reduced exactly into [−180, 180) first, so that lon − λ0
// does not round away what fmod(lon, 360) keeps (1e308 is a meridian like any other);
// smaller ones as given, so that λ0 ± 180 stays exactly on its side of the antimeridian.
double reducedLongitude(double lonDeg) noexcept {
  return std::abs(lonDeg) > 720.0 ? wrapLongitude180(lonDeg) : lonDeg;
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
    throw InvalidArgument(std::string(op) + ": radius is " + core::number(radius) +
                          " m, expected > 0");
  }
  if (std::abs(latTrueScaleDeg) >= 90.0) {
    throw InvalidArgument(std::string(op) + ": latitude of true scale is " +
                          core::number(latTrueScaleDeg) + " deg, expected |lat| < 90");
  }
  cosTs_ = std::cos(latTrueScaleDeg * kDeg);
}

glm::dvec2 Equirectangular::forward(const LatLon& ll) const {
  requireLatitude(ll.latDeg, "Equirectangular::forward()");
  requireFinite(ll.lonDeg, "Equirectangular::forward()", "longitude");
  const double dl = wrapLongitude180(reducedLongitude(ll.lonDeg) - lon0Deg_);
  return {r_ * dl * kDeg * cosTs_, r_ * (ll.latDeg - lat0Deg_) * kDeg};
}

glm::dvec2 Equirectangular::forwardNear(const LatLon& ll, double xNear) const {
  requireLatitude(ll.latDeg, "Equirectangular::forwardNear()");
  requireFinite(ll.lonDeg, "Equirectangular::forwardNear()", "longitude");
  requireFinite(xNear, "Equirectangular::forwardNear()", "x near");
  const double dl0 = wrapLongitude180(reducedLongitude(ll.lonDeg) - lon0Deg_);
  const double turns = std::round((xNear / (r_ * kDeg * cosTs_) - dl0) / 360.0);
  const double dl = dl0 + 360.0 * turns;
  return {r_ * dl * kDeg * cosTs_, r_ * (ll.latDeg - lat0Deg_) * kDeg};
}

LatLon Equirectangular::inverse(const glm::dvec2& xy) const {
  requireFinite(xy.x, "Equirectangular::inverse()", "x");
  requireFinite(xy.y, "Equirectangular::inverse()", "y");
  const double lat = lat0Deg_ + xy.y / r_ / kDeg;
  if (std::abs(lat) > 90.0 + 1e-9) {
    throw DomainError("Equirectangular::inverse(): y = " + core::number(xy.y) +
                      " m gives latitude " + core::number(lat) + " deg, beyond the pole");
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
                          core::number(latTrueScaleDeg) +
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
    throw InvalidArgument(std::string(op) + ": scale factor is " + core::number(k0) +
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
    throw DomainError(std::string(op) + ": latitude " + core::number(ll.latDeg) +
                      " deg is the pole opposite the projection's centre; it maps to infinity");
  }
  const double rho = rhoFactor_ * stereoT(latN * kDeg, e_);
  const double dl = (reducedLongitude(ll.lonDeg) - lon0Deg_) * kDeg;
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

// ---- TransverseMercator ----------------------------------------------------------------
//
// Karney (2011), "Transverse Mercator with an accuracy of a few nanometers". Written out here
// (no PROJ dependency in topo: it depends on GLM only); PROJ `tmerc` is the oracle in the tests.

namespace {
/// τ' = tan χ (χ the conformal latitude) of τ = tan φ: Karney eqs. (7)–(9), accurate near
/// the poles too (no tan(π/4 + φ/2) forms).
double conformalTan(double tau, double e) {
  if (e == 0.0) return tau;
  const double sigma = std::sinh(e * std::atanh(e * tau / std::hypot(1.0, tau)));
  return tau * std::hypot(1.0, sigma) - sigma * std::hypot(1.0, tau);
}

/// τ = tan φ of τ' = tan χ: Newton's method on conformalTan, Karney eqs. (19)–(21); two or
/// three steps reach full double precision for any planet's eccentricity.
double geodeticTan(double taup, double e) {
  if (e == 0.0 || !std::isfinite(taup)) return taup;  // a pole stays a pole
  const double e2m = 1.0 - e * e;
  double tau = taup / e2m;
  const double tol = 4.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(taup));
  for (int i = 0; i < 10; ++i) {
    const double tp = conformalTan(tau, e);
    const double dtau =
        (taup - tp) * (1.0 + e2m * tau * tau) / (e2m * std::hypot(1.0, tau) * std::hypot(1.0, tp));
    tau += dtau;
    if (!(std::abs(dtau) >= tol)) break;
  }
  return tau;
}
}  // namespace

TransverseMercator::TransverseMercator(const Body& body, double lonCentreDeg, double latOriginDeg,
                                       double scaleFactor, double falseEasting,
                                       double falseNorthing)
    : a_(body.equatorialRadius()),
      e2_(body.eccentricitySquared()),
      e_(std::sqrt(body.eccentricitySquared())),
      lon0Deg_(lonCentreDeg),
      lat0Deg_(latOriginDeg),
      k0_(scaleFactor),
      fe_(falseEasting),
      fn_(falseNorthing) {
  constexpr const char* op = "TransverseMercator()";
  requireFinite(lonCentreDeg, op, "central meridian");
  requireLatitude(latOriginDeg, op);
  requireFinite(scaleFactor, op, "scale factor");
  requireFinite(falseEasting, op, "false easting");
  requireFinite(falseNorthing, op, "false northing");
  if (scaleFactor <= 0.0) {
    throw InvalidArgument(std::string(op) + ": scale factor is " + core::number(scaleFactor) +
                          ", expected > 0");
  }
  const double f = body.flattening();
  const double n = f / (2.0 - f);
  const double n2 = n * n, n3 = n2 * n, n4 = n3 * n, n5 = n4 * n, n6 = n5 * n;
  // Rectifying radius, Karney eq. (14).
  const double A = a_ / (1.0 + n) * (1.0 + n2 / 4.0 + n4 / 64.0 + n6 / 256.0);
  kA_ = k0_ * A;
  // Karney eq. (35): conformal (χ) → rectifying (ξ) coordinates.
  alpha_ = {
      n / 2.0 - 2.0 * n2 / 3.0 + 5.0 * n3 / 16.0 + 41.0 * n4 / 180.0 - 127.0 * n5 / 288.0 +
          7891.0 * n6 / 37800.0,
      13.0 * n2 / 48.0 - 3.0 * n3 / 5.0 + 557.0 * n4 / 1440.0 + 281.0 * n5 / 630.0 -
          1983433.0 * n6 / 1935360.0,
      61.0 * n3 / 240.0 - 103.0 * n4 / 140.0 + 15061.0 * n5 / 26880.0 + 167603.0 * n6 / 181440.0,
      49561.0 * n4 / 161280.0 - 179.0 * n5 / 168.0 + 6601661.0 * n6 / 7257600.0,
      34729.0 * n5 / 80640.0 - 3418889.0 * n6 / 1995840.0,
      212378941.0 * n6 / 319334400.0};
  // Karney eq. (36): rectifying → conformal.
  beta_ = {
      n / 2.0 - 2.0 * n2 / 3.0 + 37.0 * n3 / 96.0 - n4 / 360.0 - 81.0 * n5 / 512.0 +
          96199.0 * n6 / 604800.0,
      n2 / 48.0 + n3 / 15.0 - 437.0 * n4 / 1440.0 + 46.0 * n5 / 105.0 - 1118711.0 * n6 / 3870720.0,
      17.0 * n3 / 480.0 - 37.0 * n4 / 840.0 - 209.0 * n5 / 4480.0 + 5569.0 * n6 / 90720.0,
      4397.0 * n4 / 161280.0 - 11.0 * n5 / 504.0 - 830251.0 * n6 / 7257600.0,
      4583.0 * n5 / 161280.0 - 108847.0 * n6 / 3991680.0,
      20648693.0 * n6 / 638668800.0};
  xi0_ = conformalMap(latOriginDeg * kDeg, 0.0).x;
}

TransverseMercator TransverseMercator::utm(const Body& body, int zone, bool north) {
  if (zone < 1 || zone > 60) {
    throw InvalidArgument("TransverseMercator::utm(): zone is " + core::number(zone) +
                          ", expected 1 to 60");
  }
  return {body, 6.0 * zone - 183.0, 0.0, 0.9996, 500000.0, north ? 0.0 : 10000000.0};
}

glm::dvec2 TransverseMercator::conformalMap(double phi, double lambda) const {
  // Karney eqs. (9)–(11): conformal latitude, then the spherical transverse Mercator in
  // (ξ', η'); at the poles τ is huge but finite in double and ξ' = ±π/2 as it should.
  const double tau = std::abs(phi) == kHalfPi ? std::copysign(1e300, phi) : std::tan(phi);
  const double taup = conformalTan(tau, e_);
  const double cl = std::cos(lambda);
  const double xip = std::atan2(taup, cl);
  const double etap = std::asinh(std::sin(lambda) / std::hypot(taup, cl));
  // Karney eq. (11): ζ = ζ' + Σ αj sin(2j ζ'), with ζ = ξ + iη.
  const std::complex<double> zp(xip, etap);
  std::complex<double> z = zp;
  for (std::size_t j = 0; j < alpha_.size(); ++j) {
    z += alpha_[j] * std::sin(2.0 * static_cast<double>(j + 1) * zp);
  }
  return {z.real(), z.imag()};
}

glm::dvec2 TransverseMercator::forward(const LatLon& ll) const {
  constexpr const char* op = "TransverseMercator::forward()";
  requireLatitude(ll.latDeg, op);
  requireFinite(ll.lonDeg, op, "longitude");
  const double dl = wrapLongitude180(reducedLongitude(ll.lonDeg) - lon0Deg_);
  if (std::abs(dl) >= 90.0 && std::abs(ll.latDeg) != 90.0) {
    throw DomainError(std::string(op) + ": longitude " + core::number(ll.lonDeg) + " deg is " +
                      core::number(std::abs(dl)) + " deg from the central meridian " +
                      core::number(lon0Deg_) + " deg, expected less than 90");
  }
  const glm::dvec2 z = conformalMap(ll.latDeg * kDeg, dl * kDeg);
  return {fe_ + kA_ * z.y, fn_ + kA_ * (z.x - xi0_)};
}

LatLon TransverseMercator::inverse(const glm::dvec2& xy) const {
  constexpr const char* op = "TransverseMercator::inverse()";
  requireFinite(xy.x, op, "x");
  requireFinite(xy.y, op, "y");
  const double xi = (xy.y - fn_) / kA_ + xi0_;
  const double eta = (xy.x - fe_) / kA_;
  // Karney eq. (11) inverted with the β series: ζ' = ζ − Σ βj sin(2j ζ).
  const std::complex<double> z(xi, eta);
  std::complex<double> zp = z;
  for (std::size_t j = 0; j < beta_.size(); ++j) {
    zp -= beta_[j] * std::sin(2.0 * static_cast<double>(j + 1) * z);
  }
  const double xip = zp.real(), etap = zp.imag();
  const double c = std::max(0.0, std::cos(xip)), sh = std::sinh(etap);
  const double cRaw = std::cos(xip);
  // cos ξ' < 0 (or |ξ'| > π): beyond the poles' images, where the points more than 90° from
  // the central meridian would map; forward() does not go there either.
  if (!std::isfinite(sh) || cRaw < -1e-12 || std::abs(xip) > std::numbers::pi) {
    throw DomainError(std::string(op) + ": (" + core::number(xy.x) + ", " + core::number(xy.y) +
                      ") m maps 90 deg or more from the central meridian, outside the "
                      "projection's domain");
  }
  // Karney eqs. (18)–(21).
  const double taup = std::sin(xip) / std::hypot(sh, c);
  const double lambda = std::atan2(sh, c);
  const double phi = std::atan(geodeticTan(taup, e_));
  return {phi / kDeg, wrapLongitude180(lon0Deg_ + lambda / kDeg)};
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
