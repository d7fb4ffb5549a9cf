#pragma once
/// \file
/// Query options and results shared by TopoDem and TopoPlanet.

#include <glm/vec3.hpp>

#include <cstdint>
#include <limits>

namespace regolith::topo {

/// Interpolation kernel (docs/queries.md).
/// - Nearest: the nearest sample; its normal comes from central differences of the
///   neighbouring samples.
/// - Bilinear: the 2×2 cell; C0.
/// - Bicubic: Keys cubic convolution (a = −0.5) over 4×4; C1; exact for quadratics.
enum class Interpolation : std::uint8_t { Nearest, Bilinear, Bicubic };

/// Frame a normal is expressed in.
/// - Grid: the grid's own frame. TopoDem: (x, y, h) map/plane axes. TopoPlanet: the local
///   east-north-up frame at the query point.
/// - BodyFixed: the body's Cartesian frame.
enum class NormalFrame : std::uint8_t { Grid, BodyFixed };

/// Outcome of one query (of its height, or of its normal). Values are NaN unless Ok.
/// - Nodata: a sample the kernel needs is missing (NaN or the nodata value).
/// - OutsideGrid: the point lies outside the grid's pixel extent.
/// - Unmappable: the placement's projection cannot map the point (beyond its domain: the
///   pole opposite a polar stereographic centre, 90° or more from a transverse Mercator
///   central meridian). One such point never fails a batch.
enum class QueryStatus : std::uint8_t { Ok = 0, Nodata = 1, OutsideGrid = 2, Unmappable = 3 };

/// Lower-case name of a status ("ok", "nodata", "outside", "unmappable"), as the CLI prints.
[[nodiscard]] constexpr const char* statusName(QueryStatus s) noexcept {
  switch (s) {
    case QueryStatus::Ok: return "ok";
    case QueryStatus::Nodata: return "nodata";
    case QueryStatus::OutsideGrid: return "outside";
    case QueryStatus::Unmappable: return "unmappable";
  }
  return "unknown";
}

/// Height at one point, in metres.
struct HeightSample {
  double height = std::numeric_limits<double>::quiet_NaN();
  QueryStatus status = QueryStatus::OutsideGrid;
  [[nodiscard]] constexpr bool valid() const noexcept { return status == QueryStatus::Ok; }
};

/// Height (metres) and unit surface normal at one point, each with its own status.
/// `status` is the height's: Ok wherever the height kernel has its samples. `normalStatus`
/// is the normal's: its stencil may reach a hole the height does not (the normal then
/// falls back to a one-sided stencil where it has one, docs/queries.md), so a valid height
/// can come with an invalid normal, never the reverse. The normal is NaN unless
/// normalStatus is Ok.
struct SurfaceSample {
  double height = std::numeric_limits<double>::quiet_NaN();
  glm::dvec3 normal{std::numeric_limits<double>::quiet_NaN()};
  QueryStatus status = QueryStatus::OutsideGrid;
  QueryStatus normalStatus = QueryStatus::OutsideGrid;
  /// The height is valid.
  [[nodiscard]] constexpr bool valid() const noexcept { return status == QueryStatus::Ok; }
  /// The normal is valid (and so is the height).
  [[nodiscard]] constexpr bool normalValid() const noexcept {
    return normalStatus == QueryStatus::Ok;
  }
};

}  // namespace regolith::topo
