#pragma once
/// \file
/// Map projections, forward and inverse, in double precision.
///
/// Conventions: latitudes/longitudes in degrees (latitudes planetodetic unless stated),
/// projected coordinates in metres. Every projection is an immutable value and thread-safe.
/// Formulas follow Snyder, "Map Projections: A Working Manual" (USGS PP 1395, 1987), and
/// are checked against PROJ in tests/topo/ProjectionTest.cpp.

#include <regolith/topo/Body.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>

namespace regolith::topo {

/// Equirectangular (simple cylindrical, PROJ `eqc`) on a sphere of radius `radius`:
///   x = R (λ − λ0) cos φts,  y = R (φ − φ0).
/// φ is the projection's own latitude; a placement says whether it is planetocentric or
/// planetodetic on the body. λ − λ0 is wrapped into [−180°, 180°).
class Equirectangular {
 public:
  /// Throws InvalidArgument for a non-positive radius or |latTrueScaleDeg| ≥ 90.
  Equirectangular(double radius, double latTrueScaleDeg, double lonCentreDeg,
                  double latOriginDeg = 0.0);

  [[nodiscard]] glm::dvec2 forward(const LatLon& ll) const;
  /// Forward with λ − λ0 taken in the turn whose x lies nearest xNear (metres) instead of
  /// [−180°, 180°): PROJ's `+over`, for a map that runs past ±180° from its centre (a DEM
  /// centred on 180° that reaches past −180°). forward() is forwardNear(ll, 0).
  [[nodiscard]] glm::dvec2 forwardNear(const LatLon& ll, double xNear) const;
  /// Inverse; latitude beyond ±90° (y outside the map) throws DomainError.
  [[nodiscard]] LatLon inverse(const glm::dvec2& xy) const;

  [[nodiscard]] double radius() const noexcept { return r_; }
  [[nodiscard]] double latTrueScaleDeg() const noexcept { return latTsDeg_; }
  [[nodiscard]] double lonCentreDeg() const noexcept { return lon0Deg_; }
  [[nodiscard]] double latOriginDeg() const noexcept { return lat0Deg_; }

 private:
  double r_, latTsDeg_, lon0Deg_, lat0Deg_;
  double cosTs_;
};

/// Polar stereographic, north or south, on a sphere or biaxial ellipsoid (Snyder §21;
/// PROJ `stere` with lat_0 = ±90). Scale is given either by a latitude of true scale or by
/// the scale factor at the pole. Grid north points from the pole along λ0 (north aspect)
/// or towards it (south aspect), as in PROJ.
class PolarStereographic {
 public:
  enum class Pole { North, South };

  /// Scale set by a latitude of true scale (degrees, same hemisphere as the pole; ±90
  /// means k0 = 1 at the pole).
  static PolarStereographic withTrueScaleLatitude(const Body& body, Pole pole,
                                                  double latTrueScaleDeg, double lonCentreDeg,
                                                  double falseEasting = 0.0,
                                                  double falseNorthing = 0.0);
  /// Scale set by the scale factor k0 at the pole.
  static PolarStereographic withScaleFactor(const Body& body, Pole pole, double k0,
                                            double lonCentreDeg, double falseEasting = 0.0,
                                            double falseNorthing = 0.0);

  /// Forward. Exactly at the centre pole gives (falseEasting, falseNorthing). The opposite
  /// pole maps to infinity and throws DomainError.
  [[nodiscard]] glm::dvec2 forward(const LatLon& ll) const;
  /// Inverse. At the centre pole the longitude is λ0.
  [[nodiscard]] LatLon inverse(const glm::dvec2& xy) const;
  /// Point scale factor k at a planetodetic latitude.
  [[nodiscard]] double scaleFactor(double latDeg) const;

  [[nodiscard]] Pole pole() const noexcept { return pole_; }
  [[nodiscard]] double lonCentreDeg() const noexcept { return lon0Deg_; }
  [[nodiscard]] double scaleFactorAtPole() const noexcept { return k0_; }
  [[nodiscard]] double falseEasting() const noexcept { return fe_; }
  [[nodiscard]] double falseNorthing() const noexcept { return fn_; }
  [[nodiscard]] double equatorialRadius() const noexcept { return a_; }
  [[nodiscard]] double eccentricitySquared() const noexcept { return e_ * e_; }

 private:
  PolarStereographic(double a, double e, Pole pole, double k0, double lon0Deg, double fe,
                     double fn);
  double a_, e_;
  Pole pole_;
  double k0_, lon0Deg_, fe_, fn_;
  double rhoFactor_;  // ρ = rhoFactor_ · t
};

/// Transverse Mercator on a sphere or biaxial ellipsoid (EPSG method 9807, PROJ `tmerc`;
/// UTM is the case k0 = 0.9996, λ0 = 6°·zone − 183°, false easting 500 km, false northing 0
/// north of the equator or 10,000 km south of it).
///
/// The Krüger series in n = f/(2 − f) to 6th order, as given by Karney, "Transverse Mercator
/// with an accuracy of a few nanometers", J. Geodesy 85 (2011) 475–485, eqs. (7)–(9), (11)–(21),
/// (35)–(36): errors below 5 nm within 4000 km of the central meridian, checked against PROJ in
/// tests/topo/ProjectionTest.cpp. Hand-written because topo depends on nothing but GLM.
///
///   x = FE + k0 A η,   y = FN + k0 A (ξ − ξ0)
///
/// where ξ + iη is the conformal map of the point and ξ0 that of the latitude of origin on the
/// central meridian. Latitudes are planetodetic.
class TransverseMercator {
 public:
  /// Throws InvalidArgument for a non-finite argument, |latOriginDeg| > 90 or k0 ≤ 0.
  TransverseMercator(const Body& body, double lonCentreDeg, double latOriginDeg = 0.0,
                     double scaleFactor = 1.0, double falseEasting = 0.0,
                     double falseNorthing = 0.0);
  /// Universal Transverse Mercator zone 1…60, north or south hemisphere.
  static TransverseMercator utm(const Body& body, int zone, bool north);

  /// Forward. Points 90° or more from the central meridian (λ − λ0 wrapped into
  /// [−180°, 180°)) throw DomainError: the map does not reach them.
  [[nodiscard]] glm::dvec2 forward(const LatLon& ll) const;
  /// Inverse. Map points that no point within 90° of the central meridian reaches (beyond
  /// the poles' images, or |x − FE| far beyond the equator's) throw DomainError.
  [[nodiscard]] LatLon inverse(const glm::dvec2& xy) const;

  [[nodiscard]] double lonCentreDeg() const noexcept { return lon0Deg_; }
  [[nodiscard]] double latOriginDeg() const noexcept { return lat0Deg_; }
  [[nodiscard]] double scaleFactor() const noexcept { return k0_; }
  [[nodiscard]] double falseEasting() const noexcept { return fe_; }
  [[nodiscard]] double falseNorthing() const noexcept { return fn_; }
  [[nodiscard]] double equatorialRadius() const noexcept { return a_; }
  [[nodiscard]] double eccentricitySquared() const noexcept { return e2_; }

 private:
  /// ξ + iη of a planetodetic latitude and a longitude from the central meridian (radians).
  [[nodiscard]] glm::dvec2 conformalMap(double phi, double lambda) const;

  double a_, e2_, e_;
  double lon0Deg_, lat0Deg_, k0_, fe_, fn_;
  double kA_;                               // k0 · A, A the rectifying radius
  double xi0_;                              // ξ of the latitude of origin on the central meridian
  std::array<double, 6> alpha_{}, beta_{};  // Krüger series coefficients, forward, inverse
};

/// A local tangent plane: a right-handed Cartesian frame whose origin is a planetodetic
/// position, whose z axis is the surface normal there (up), and whose y axis points at
/// azimuth `headingDeg` (clockwise from north; 0 = y points north, x points east).
/// Forward and inverse are exact (no map distortion: this is a rigid frame, the "ENU"
/// frame rotated by the heading; PROJ `topocentric` for heading 0).
class LocalTangentPlane {
 public:
  LocalTangentPlane(const Body& body, const Geodetic& origin, double headingDeg = 0.0);

  /// Planetodetic position → plane coordinates (x, y, z) in metres.
  [[nodiscard]] glm::dvec3 forward(const Geodetic& g) const;
  /// Plane coordinates → planetodetic position.
  [[nodiscard]] Geodetic inverse(const glm::dvec3& xyz) const;
  /// Plane coordinates → body-fixed position.
  [[nodiscard]] glm::dvec3 toBodyFixed(const glm::dvec3& xyz) const noexcept;
  /// Body-fixed position → plane coordinates.
  [[nodiscard]] glm::dvec3 fromBodyFixed(const glm::dvec3& p) const noexcept;

  [[nodiscard]] const Body& body() const noexcept { return body_; }
  [[nodiscard]] const Geodetic& origin() const noexcept { return origin_; }
  [[nodiscard]] double headingDeg() const noexcept { return headingDeg_; }
  /// Plane axes in body-fixed coordinates (unit vectors).
  [[nodiscard]] const glm::dvec3& xAxis() const noexcept { return ex_; }
  [[nodiscard]] const glm::dvec3& yAxis() const noexcept { return ey_; }
  [[nodiscard]] const glm::dvec3& zAxis() const noexcept { return ez_; }
  [[nodiscard]] const glm::dvec3& originBodyFixed() const noexcept { return o_; }

 private:
  Body body_;
  Geodetic origin_;
  double headingDeg_;
  glm::dvec3 o_{}, ex_{}, ey_{}, ez_{};
};

}  // namespace regolith::topo
