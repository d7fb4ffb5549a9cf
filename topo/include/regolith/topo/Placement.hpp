#pragma once
/// \file
/// Where a planar DEM sits on its body.

#include <regolith/topo/Body.hpp>
#include <regolith/topo/MapProjection.hpp>
#include <regolith/topo/Projection.hpp>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <memory>
#include <variant>

namespace regolith::topo {

/// Places a TopoDem's planar grid (x, y in metres, height h in metres) on a body, so that
/// every sample has a body-fixed position.
///
/// - LocalTangentPlane: (x, y, h) are coordinates in the plane's frame; h is measured along
///   the plane's normal (a flat-earth DEM, as SimScape's local DEMs).
/// - PolarStereographic / Equirectangular / TransverseMercator: (x, y) are projected map
///   metres (false easting/northing included); h is the height
///   above the body's reference surface along its normal at the inverse-projected point.
///   For Equirectangular the placement also says how the projection's latitude is read.
/// - Projected: any other map projection, through a MapProjection that another module
///   implements (store's PROJ-backed one); (x, y) and h as for the analytic projections.
///
/// Immutable and thread-safe (a Projected placement shares its MapProjection, which is).
class Placement {
 public:
  enum class Kind {
    LocalTangentPlane,
    PolarStereographic,
    Equirectangular,
    TransverseMercator,
    Projected
  };

  explicit Placement(LocalTangentPlane plane);
  Placement(const Body& body, PolarStereographic projection);
  Placement(const Body& body, Equirectangular projection,
            LatitudeType latitudeType = LatitudeType::Planetocentric);
  /// `projection` must be made on `body` (its latitudes are planetodetic on that ellipsoid);
  /// throws InvalidArgument if its radius or eccentricity differ.
  Placement(const Body& body, TransverseMercator projection);
  /// Any projection `projection` implements, on `body`; throws InvalidArgument for a null
  /// projection or one whose ellipsoid is not the body's.
  Placement(const Body& body, std::shared_ptr<const MapProjection> projection);

  [[nodiscard]] Kind kind() const noexcept;
  [[nodiscard]] const Body& body() const noexcept { return body_; }
  /// The latitude type the projection's latitudes are read as (planetodetic for polar
  /// stereographic, transverse Mercator and the tangent plane).
  [[nodiscard]] LatitudeType latitudeType() const noexcept { return latType_; }

  [[nodiscard]] const LocalTangentPlane* localTangentPlane() const noexcept;
  [[nodiscard]] const PolarStereographic* polarStereographic() const noexcept;
  [[nodiscard]] const Equirectangular* equirectangular() const noexcept;
  [[nodiscard]] const TransverseMercator* transverseMercator() const noexcept;
  [[nodiscard]] const MapProjection* mapProjection() const noexcept;

  /// Body-fixed position of grid point (x, y) at height h.
  [[nodiscard]] glm::dvec3 toBodyFixed(double x, double y, double h) const;
  /// Planetodetic position of grid point (x, y) at height h.
  [[nodiscard]] Geodetic toGeodetic(double x, double y, double h) const;
  /// Grid coordinates (x, y, h) of a planetodetic position: the inverse of toGeodetic.
  [[nodiscard]] glm::dvec3 fromGeodetic(const Geodetic& g) const;
  /// As fromGeodetic(), but an equirectangular map takes the longitude in the turn whose x
  /// lies nearest xNear (Equirectangular::forwardNear, PROJ's `+over`): a DEM that runs past
  /// ±180° from its central meridian passes the centre of its x extent. Other placements
  /// are single-valued in longitude and ignore xNear.
  [[nodiscard]] glm::dvec3 fromGeodeticNear(const Geodetic& g, double xNear) const;
  /// Grid coordinates (x, y, h) of a body-fixed point.
  [[nodiscard]] glm::dvec3 fromBodyFixed(const glm::dvec3& p) const;

  /// Columns: ∂P/∂x, ∂P/∂y, ∂P/∂h of the body-fixed position P at (x, y, h). Exact for the
  /// tangent plane; central differences over ±0.5 m for map projections (relative error
  /// ~1e-13, far below anything a DEM resolves), one-sided (second order) within 0.5 m of
  /// the edge of the projection's domain, such as a pole an equirectangular map reaches.
  /// Throws DomainError only if (x, y) itself has no image.
  [[nodiscard]] glm::dmat3 jacobian(double x, double y, double h) const;
  /// Converts a normal in the grid frame (x, y, h) at (x, y, h) to a unit body-fixed normal.
  [[nodiscard]] glm::dvec3 normalToBodyFixed(const glm::dvec3& gridNormal, double x, double y,
                                             double h) const;

 private:
  Body body_;
  LatitudeType latType_;
  std::variant<LocalTangentPlane, PolarStereographic, Equirectangular, TransverseMercator,
               std::shared_ptr<const MapProjection>>
      proj_;
};

}  // namespace regolith::topo
