#pragma once
/// \file
/// Planet bodies (sphere or biaxial ellipsoid), latitude types and body-fixed frames.

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <string>
#include <string_view>

namespace regolith::topo {

/// How a grid's latitudes are measured.
/// - Planetocentric: angle between the equator and the line from the body centre.
/// - Planetodetic: angle between the equator and the surface normal (geodetic latitude).
/// The two agree on a sphere.
enum class LatitudeType { Planetocentric, Planetodetic };

/// A position on the reference surface, in degrees. Longitude is east-positive; any value
/// is accepted and wraps (−180, 180 and 360 denote the same meridian as 180/0).
struct LatLon {
  double latDeg = 0.0;
  double lonDeg = 0.0;
};

/// A planetodetic position: latitude/longitude in degrees and height in metres above the
/// reference surface, measured along the surface normal.
struct Geodetic {
  double latDeg = 0.0;
  double lonDeg = 0.0;
  double height = 0.0;
};

/// A planet body: a sphere or a biaxial (oblate) ellipsoid of revolution.
///
/// Body-fixed frame: origin at the centre, +Z through the north pole, +X through 0°E on the
/// equator, +Y through 90°E. All lengths are metres. Immutable and thread-safe.
class Body {
 public:
  /// A sphere. Throws InvalidArgument unless radius is finite and > 0.
  static Body sphere(std::string name, double radius);
  /// A biaxial ellipsoid with equatorial radius a and polar radius b (0 < b ≤ a).
  static Body ellipsoid(std::string name, double equatorialRadius, double polarRadius);

  /// IAU 2015 Mars sphere, R = 3,396,190 m.
  static Body marsSphere();
  /// IAU 2015 Mars ellipsoid, a = 3,396,190 m, b = 3,376,200 m.
  static Body marsEllipsoid();
  /// IAU 2015 Moon sphere, R = 1,737,400 m.
  static Body moon();
  /// WGS84, a = 6,378,137 m, 1/f = 298.257223563.
  static Body earthWgs84();

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] double equatorialRadius() const noexcept { return a_; }
  [[nodiscard]] double polarRadius() const noexcept { return b_; }
  [[nodiscard]] bool isSphere() const noexcept { return a_ == b_; }
  /// First eccentricity squared, (a² − b²)/a².
  [[nodiscard]] double eccentricitySquared() const noexcept { return e2_; }
  /// Flattening, (a − b)/a.
  [[nodiscard]] double flattening() const noexcept { return (a_ - b_) / a_; }

  /// Planetocentric latitude (degrees) of the surface point with the given planetodetic
  /// latitude. Exact at ±90°.
  [[nodiscard]] double planetocentricFromPlanetodetic(double latDeg) const noexcept;
  /// Planetodetic latitude (degrees) of the surface point with the given planetocentric
  /// latitude. Exact at ±90°.
  [[nodiscard]] double planetodeticFromPlanetocentric(double latDeg) const noexcept;
  /// Converts a latitude of the given type to planetodetic.
  [[nodiscard]] double toPlanetodetic(double latDeg, LatitudeType type) const noexcept;
  /// The sine and cosine of a latitude's planetodetic value.
  struct SinCos {
    double sin = 0.0, cos = 1.0;
  };
  /// sin and cos of toPlanetodetic(latDeg, type) without forming the angle: from a
  /// planetocentric latitude φc on an ellipsoid, (sin φd, cos φd) = (a² sin φc, b² cos φc)
  /// / |(a² sin φc, b² cos φc)| (tan φd = (a/b)² tan φc): one sine and cosine and one square
  /// root where the angle costs an arctangent more. Within a few ulp of the sine and cosine
  /// of toPlanetodetic(); exactly (±1, cos) at the poles' ±90°, as it.
  [[nodiscard]] SinCos planetodeticSinCos(double latDeg, LatitudeType type) const noexcept;
  /// Converts a planetodetic latitude to the given type.
  [[nodiscard]] double fromPlanetodetic(double latDeg, LatitudeType type) const noexcept;

  /// Body-fixed Cartesian position (metres) of a planetodetic position.
  [[nodiscard]] glm::dvec3 toBodyFixed(const Geodetic& g) const noexcept;
  /// Planetodetic position of a body-fixed point. Accurate to well under 1 mm from
  /// −10 km to +1000 km altitude (Bowring's method, iterated to convergence). At the
  /// poles the longitude is 0. Longitude is returned in (−180, 180].
  [[nodiscard]] Geodetic toGeodetic(const glm::dvec3& p) const noexcept;

  /// East-north-up frame at a planetodetic latitude/longitude: the columns are the unit
  /// east, north and up (surface normal) vectors in body-fixed coordinates. Defined at the
  /// poles too, where east is the direction of increasing longitude at lonDeg.
  [[nodiscard]] glm::dmat3 enuFrame(double latDeg, double lonDeg) const noexcept;
  /// enuFrame() given the sine and cosine of the planetodetic latitude (of latDeg·π/180, for
  /// the same bits), for callers that have them already: a per-query normal needs them for
  /// its radii of curvature too.
  [[nodiscard]] static glm::dmat3 enuFrameOf(double sinLat, double cosLat, double lonDeg) noexcept;

  /// Meridian radius of curvature M at a planetodetic latitude (metres).
  [[nodiscard]] double meridianRadius(double latDeg) const noexcept;
  /// Prime-vertical radius of curvature N at a planetodetic latitude (metres).
  [[nodiscard]] double primeVerticalRadius(double latDeg) const noexcept;
  /// Both radii of curvature (metres) given the sine of the planetodetic latitude (of
  /// latDeg·π/180: then the same bits as meridianRadius() and primeVerticalRadius()).
  struct Radii {
    double meridian = 0.0, primeVertical = 0.0;
  };
  [[nodiscard]] Radii radiiOfCurvature(double sinLat) const noexcept;

 private:
  Body(std::string name, double a, double b);
  std::string name_;
  double a_;
  double b_;
  double e2_;
};

/// Wraps a longitude in degrees into [−180, 180), for any finite longitude up to ±1.8e308:
/// beyond two turns it is first reduced exactly (fmod(lon, 360)), so 1e308 names the
/// meridian fmod does; then shifted by 180 (rounding by at most an ulp of 540).
[[nodiscard]] double wrapLongitude180(double lonDeg) noexcept;
/// Wraps a longitude in degrees into [0, 360) (exact but for a tiny negative longitude,
/// which rounds to 0 rather than to the double below 360).
[[nodiscard]] double wrapLongitude360(double lonDeg) noexcept;

/// Throws InvalidArgument naming `operation` and `field`: v is not finite (requireFinite()).
[[noreturn]] void throwNotFinite(double v, const char* operation, const char* field);
/// Throws InvalidArgument naming `operation` and `field` unless v is finite. Inline, the
/// throw out of line: point queries check every coordinate, at some tens of millions a second.
inline void requireFinite(double v, const char* operation, const char* field) {
  if (!std::isfinite(v)) [[unlikely]]
    throwNotFinite(v, operation, field);
}

}  // namespace regolith::topo
