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

/// Outcome of one query. Heights are NaN unless Ok.
/// - Nodata: a sample the kernel needs is missing (NaN or the nodata value).
/// - OutsideGrid: the point lies outside the grid's pixel extent.
enum class QueryStatus : std::uint8_t { Ok = 0, Nodata = 1, OutsideGrid = 2 };

/// Height at one point, in metres.
struct HeightSample {
  double height = std::numeric_limits<double>::quiet_NaN();
  QueryStatus status = QueryStatus::OutsideGrid;
  [[nodiscard]] constexpr bool valid() const noexcept { return status == QueryStatus::Ok; }
};

/// Height (metres) and unit surface normal at one point. The normal is NaN unless Ok.
struct SurfaceSample {
  double height = std::numeric_limits<double>::quiet_NaN();
  glm::dvec3 normal{std::numeric_limits<double>::quiet_NaN()};
  QueryStatus status = QueryStatus::OutsideGrid;
  [[nodiscard]] constexpr bool valid() const noexcept { return status == QueryStatus::Ok; }
};

}  // namespace regolith::topo
