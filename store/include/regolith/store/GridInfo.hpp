#pragma once
/// \file
/// The description of one grid in a store: everything its HDF5 attributes record
/// (docs/store-format.md), and the conversions to topo's types.

#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace regolith::store {

/// What kind of grid: a planar DEM placed on a body, or a latitude/longitude planet grid.
enum class GridKind { Dem, Planet };

/// How a DEM is placed on its body (mirrors topo::Placement, as plain values).
struct PlacementInfo {
  enum class Kind {
    LocalTangentPlane,
    PolarStereographic,
    Equirectangular,
    TransverseMercator,
    Projected
  };
  Kind kind = Kind::LocalTangentPlane;
  // LocalTangentPlane: origin (planetodetic degrees, metres) and heading (degrees from north).
  double originLatDeg = 0.0, originLonDeg = 0.0, originHeight = 0.0, headingDeg = 0.0;
  // PolarStereographic: pole (+1 north, −1 south); scale by true-scale latitude or by k0
  // (exactly one of the two is set); centre longitude; false easting/northing (metres).
  int pole = 1;
  std::optional<double> latTrueScaleDeg;
  std::optional<double> scaleFactor;
  double lonCentreDeg = 0.0, falseEasting = 0.0, falseNorthing = 0.0;
  // Equirectangular: sphere radius of the projection, latitude of true scale, latitude of
  // origin (lonCentreDeg above is its centre longitude).
  // TransverseMercator (UTM among them), on the grid's body: central meridian lonCentreDeg,
  // latitude of origin latOriginDeg, scale factor k0 on the central meridian scaleFactor
  // (required), falseEasting, falseNorthing.
  double projectionRadius = 0.0, latOriginDeg = 0.0;
  // Projected (any other projected CRS, through PROJ: store/ProjPlacement.hpp): the CRS as
  // WKT2 (format 1.4); x, y are its map metres, false easting/northing included.
  std::string crs;
};

/// Level 0's heights summarised once, when the grid was written (format 1.3; absent in
/// grids written without them, which readers still open). Metres; NaN when no sample is
/// valid.
struct HeightStatistics {
  double min = 0.0, max = 0.0, mean = 0.0;
  /// Level-0 samples that are not missing.
  std::uint64_t validSamples = 0;
};

/// The most rows, and the most columns, a grid may have: 2^31 (2,147,483,648), far above
/// the JPL paper's 100K × 100K and LOLA's 184,320 × 92,160 at 512 px/deg. Stores that
/// declare more are refused when opened and when written (docs/store-format.md), so every
/// product of sizes in the reader (samples of a level, patches of a grid, bytes of a
/// window) fits 64 bits with room to spare.
inline constexpr std::size_t kMaxGridSide = std::size_t{1} << 31;
/// The most patches level 0 of a grid may have: 2^35 (34 billion; a 2^31 × 2^31 grid needs
/// patches of 256 × 512 samples or more). The pager's block table reserves 24 bytes of
/// address space per patch (store/BlockTable.hpp), 768 GiB at this limit, touched only where
/// patches are loaded.
inline constexpr std::size_t kMaxPatchesPerGrid = std::size_t{1} << 35;
/// The patches of level 0 of a grid of rows × cols samples in patchRows × patchCols patches
/// (sizes up to kMaxGridSide, patch sizes > 0).
[[nodiscard]] constexpr std::size_t patchCount(std::size_t rows, std::size_t cols,
                                               std::size_t patchRows, std::size_t patchCols) {
  return ((rows + patchRows - 1) / patchRows) * ((cols + patchCols - 1) / patchCols);
}

/// One grid's configuration. Sample (row, col) of level 0 sits at (x0 + col·dx,
/// y0 − row·dy) (docs/grid-convention.md); for a planet x is longitude and y latitude in
/// degrees. Level k has ⌈rows/2^k⌉ × ⌈cols/2^k⌉ samples with spacing 2^k·dx, its sample
/// (r, c) centred on the mean of level k−1's samples (2r…2r+1, 2c…2c+1).
struct GridInfo {
  std::string name;
  GridKind kind = GridKind::Dem;
  std::size_t rows = 0, cols = 0;
  double x0 = 0.0, y0 = 0.0, spacingX = 1.0, spacingY = 1.0;
  /// Heights in metres are offset + scale · stored value.
  double scale = 1.0, offset = 0.0;
  /// Stored value marking missing samples (besides NaN), if any.
  std::optional<float> nodata;
  std::string units = "m";
  std::string bodyName = "Mars";
  double equatorialRadius = 3396190.0, polarRadius = 3396190.0;
  topo::LatitudeType latitudeType = topo::LatitudeType::Planetocentric;
  PlacementInfo placement;                       // Dem only
  std::size_t levels = 1;                        // pyramid levels stored, level 0 included
  std::size_t patchRows = 256, patchCols = 256;  // HDF5 chunk = pager patch
  /// Read from the store; the writer computes them (WriteOptions::statistics).
  std::optional<HeightStatistics> statistics;
  /// Where the grid came from, as JSON text (format 1.3; empty: not recorded): the import's
  /// source files with sizes and SHA-256 digests, GDAL's driver and version, the label
  /// fields and geotransform that decided the georeferencing (docs/store-format.md).
  std::string provenance;

  [[nodiscard]] std::size_t levelRows(std::size_t level) const noexcept {
    return (rows + (std::size_t{1} << level) - 1) >> level;
  }
  [[nodiscard]] std::size_t levelCols(std::size_t level) const noexcept {
    return (cols + (std::size_t{1} << level) - 1) >> level;
  }
};

/// The placement kind's name, as the store records it and `info` prints it:
/// "local_tangent_plane", "polar_stereographic", "equirectangular", "transverse_mercator",
/// "projected".
[[nodiscard]] std::string_view placementKindName(PlacementInfo::Kind kind) noexcept;
/// The same name for a topo placement's kind (a catalogue's DEM, `info` on a catalogue).
[[nodiscard]] std::string_view placementKindName(topo::Placement::Kind kind) noexcept;

/// The body a grid is on. Throws regolith::InvalidArgument for bad radii.
[[nodiscard]] topo::Body bodyOf(const GridInfo& info);
/// The topo geometry of one level (x0/y0 and spacing scaled for level > 0; nodata NaN,
/// because the pager hands out heights after scale/offset with missing samples as NaN).
[[nodiscard]] topo::TopoGrid topoGridOf(const GridInfo& info, std::size_t level = 0);
/// The DEM's placement. Throws regolith::InvalidArgument if info.kind is not Dem or the
/// parameters are inconsistent.
[[nodiscard]] topo::Placement placementOf(const GridInfo& info);
/// The plain-value description of a topo placement.
[[nodiscard]] PlacementInfo placementInfoOf(const topo::Placement& placement);

}  // namespace regolith::store
