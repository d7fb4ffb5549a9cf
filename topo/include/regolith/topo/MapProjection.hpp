#pragma once
/// \file
/// A map projection that topo does not write itself: the seam through which another module
/// places a DEM in any projection (store's PROJ-backed placement, store::projPlacement()).

#include <regolith/topo/Body.hpp>

#include <glm/vec2.hpp>

#include <string>

namespace regolith::topo {

/// A projected coordinate reference system on a body: planetodetic latitude/longitude on the
/// projection's ellipsoid (degrees) to map coordinates x (east), y (north) in metres, false
/// easting/northing included, and back. topo's own projections (Projection.hpp) are the
/// analytic fast paths; an implementation of this interface covers the rest (sinusoidal,
/// Lambert conformal conic, orthographic, Mollweide, ...).
///
/// Implementations are immutable after construction, and forward()/inverse() may be called
/// from any number of threads at once.
class MapProjection {
 public:
  MapProjection() = default;
  MapProjection(const MapProjection&) = delete;
  MapProjection& operator=(const MapProjection&) = delete;
  MapProjection(MapProjection&&) = delete;
  MapProjection& operator=(MapProjection&&) = delete;
  virtual ~MapProjection() = default;

  /// Map coordinates (metres) of a planetodetic latitude/longitude (degrees). Throws
  /// DomainError where the projection has no image (beyond an orthographic map's horizon).
  [[nodiscard]] virtual glm::dvec2 forward(const LatLon& ll) const = 0;
  /// Planetodetic latitude/longitude (degrees) of map coordinates (metres). Throws DomainError
  /// for a point off the map (outside a sinusoidal map's outline).
  [[nodiscard]] virtual LatLon inverse(const glm::dvec2& xy) const = 0;

  /// The CRS's full definition, as text its implementation reads back (WKT2 for PROJ): what
  /// a store records so that it re-opens with the same placement.
  [[nodiscard]] virtual const std::string& definition() const noexcept = 0;
  /// A short name for people (the CRS's name).
  [[nodiscard]] virtual const std::string& name() const noexcept = 0;
  /// The ellipsoid the latitudes are planetodetic on: equatorial radius (metres) and
  /// eccentricity squared.
  [[nodiscard]] virtual double equatorialRadius() const noexcept = 0;
  [[nodiscard]] virtual double eccentricitySquared() const noexcept = 0;
};

}  // namespace regolith::topo
