#pragma once
/// \file
/// The renderer's view of terrain heights: one grid per pyramid level, each with its samples.

#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Pyramid.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

namespace regolith::clod {

/// How a pyramid's grid coordinates become 3-D positions.
/// - Plane: x, y are map metres (x east, y north) and the height is z: the DEM is drawn in
///   its own grid frame (x, y, h), as a flat-earth local DEM.
/// - Planet: x is longitude and y latitude in degrees (a topo::TopoPlanet grid) and the
///   height is along the body's normal; positions are body-fixed metres.
enum class SurfaceKind { Plane, Planet };

/// Heights of one terrain as a pyramid of levels: level 0 is the finest, each level has
/// (about) twice the spacing of the one below. Every level is a TopoGrid (geometry, nodata)
/// and a topo::SampleSource of its samples.
///
/// This is the only way clod reads terrain, so the renderer never includes the store:
/// in-memory grids use fromSamples() (topo::downsample2x2(), the store's pyramid rule), and
/// a store exports its grids as topo::GridPyramid (store::Pager::pyramid()).
///
/// Immutable after construction; thread-safe as far as its sources are (SampleSource
/// const members are thread-safe by contract).
class HeightPyramid {
 public:
  using Level = topo::PyramidLevel;

  /// Throws InvalidArgument if `levels` is empty, a source is null or its size differs from
  /// its grid, a level's spacing is not twice the one below (to 1e-6 relative), or a Planet
  /// pyramid has no body.
  HeightPyramid(std::vector<Level> levels, SurfaceKind kind,
                std::optional<topo::Body> body = std::nullopt,
                topo::LatitudeType latitudeType = topo::LatitudeType::Planetocentric);

  /// A grid pyramid in topo terms, as a store exports it (store::Pager::pyramid()): a
  /// Planet pyramid on its body if it names one, else a Plane. Same checks as above.
  explicit HeightPyramid(topo::GridPyramid pyramid);

  /// A planar DEM placed on its body (a topo::TopoDem's placement): grid coordinates
  /// (x, y, h) as for a Plane, but scene positions are body-fixed metres, so the DEM sits
  /// where it belongs on a planet. Same checks as above.
  HeightPyramid(std::vector<Level> levels, topo::Placement placement);

  /// Builds `levelCount` levels (0: until a level is at most 2×2) from level-0 samples by
  /// 2×2 means; a coarse sample is missing (NaN) only if all four are. Level l sample (r, c)
  /// sits at the centre of the four level-(l−1) samples it averages.
  static HeightPyramid fromSamples(
      const topo::TopoGrid& grid, std::shared_ptr<const topo::SampleSource> samples,
      SurfaceKind kind, std::optional<topo::Body> body = std::nullopt,
      topo::LatitudeType latitudeType = topo::LatitudeType::Planetocentric,
      std::size_t levelCount = 0);

  /// fromSamples() for a placed DEM.
  static HeightPyramid fromSamples(const topo::TopoGrid& grid,
                                   std::shared_ptr<const topo::SampleSource> samples,
                                   const topo::Placement& placement, std::size_t levelCount = 0);

  [[nodiscard]] std::size_t levelCount() const noexcept { return levels_.size(); }
  /// The placement of a placed DEM (nullopt otherwise).
  [[nodiscard]] const std::optional<topo::Placement>& placement() const noexcept {
    return placement_;
  }
  [[nodiscard]] const Level& level(std::size_t i) const { return levels_.at(i); }
  [[nodiscard]] SurfaceKind kind() const noexcept { return kind_; }
  /// The body (Planet pyramids; nullopt for planes).
  [[nodiscard]] const std::optional<topo::Body>& body() const noexcept { return body_; }
  /// How a Planet grid's latitudes are read.
  [[nodiscard]] topo::LatitudeType latitudeType() const noexcept { return latType_; }

  /// The scene position of grid point (x, y) at height h: (x, y, h) for a Plane, through
  /// the placement for a placed DEM, the body-fixed position of (latitude y, longitude x,
  /// height h) for a Planet. Metres, double.
  [[nodiscard]] glm::dvec3 position(double x, double y, double h) const;
  /// Grid coordinates (x, y) of a scene point: (p.x, p.y) for a Plane, the placement's
  /// inverse for a placed DEM; (longitude, latitude) in degrees for a Planet, longitude in
  /// (−180, 180].
  [[nodiscard]] glm::dvec2 gridPoint(const glm::dvec3& p) const;
  /// Unit "up" at a scene point: +z for a Plane, the grid's h axis in body-fixed
  /// coordinates for a placed DEM, the body's surface normal for a Planet.
  [[nodiscard]] glm::dvec3 up(const glm::dvec3& p) const;

 private:
  std::vector<Level> levels_;
  SurfaceKind kind_;
  std::optional<topo::Body> body_;
  topo::LatitudeType latType_;
  std::optional<topo::Placement> placement_;
};

}  // namespace regolith::clod
