#pragma once
/// \file
/// Names and rules of the store format shared by the reader (Store.cpp) and the writer
/// (StoreWriter.cpp). docs/store-format.md is the specification; keep the two in step.

#include <regolith/store/GridInfo.hpp>

#include <hdf5.h>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace regolith::store::format {

// Root group.
inline constexpr const char* kMarker = "regolith_store";
inline constexpr const char* kMarkerValue = "Regolith terrain store; see docs/store-format.md";
inline constexpr const char* kFormatVersion = "format_version";
inline constexpr const char* kGrids = "grids";

// Grid group attributes.
inline constexpr const char* kKind = "kind";
inline constexpr const char* kRows = "rows";
inline constexpr const char* kCols = "cols";
inline constexpr const char* kX0 = "x0";
inline constexpr const char* kY0 = "y0";
inline constexpr const char* kSpacing = "spacing";
inline constexpr const char* kUnits = "units";
inline constexpr const char* kSampleType = "sample_type";
inline constexpr const char* kScale = "scale";
inline constexpr const char* kOffset = "offset";
inline constexpr const char* kNodata = "nodata";
inline constexpr const char* kBody = "body";
inline constexpr const char* kEquatorialRadius = "equatorial_radius";
inline constexpr const char* kPolarRadius = "polar_radius";
inline constexpr const char* kLatitudeType = "latitude_type";
inline constexpr const char* kLevels = "levels";
inline constexpr const char* kPatchShape = "patch_shape";
// Placement (DEM grids only).
inline constexpr const char* kPlacement = "placement";
inline constexpr const char* kOriginLat = "origin_lat_deg";
inline constexpr const char* kOriginLon = "origin_lon_deg";
inline constexpr const char* kOriginHeight = "origin_height";
inline constexpr const char* kHeading = "heading_deg";
inline constexpr const char* kPole = "pole";
inline constexpr const char* kLatTrueScale = "lat_true_scale_deg";
inline constexpr const char* kScaleFactor = "scale_factor";
inline constexpr const char* kLonCentre = "lon_centre_deg";
inline constexpr const char* kFalseEasting = "false_easting";
inline constexpr const char* kFalseNorthing = "false_northing";
inline constexpr const char* kProjectionRadius = "projection_radius";
inline constexpr const char* kLatOrigin = "lat_origin_deg";
inline constexpr const char* kCrsWkt = "crs_wkt";

// Tiled grids (format 1.1): the grid's attribute tile_count, its group tiles/<i> per tile
// with the attributes below, and either a dataset level0 or the two external attributes.
inline constexpr int kTiledFormatMinor = 1;
inline constexpr const char* kTileCount = "tile_count";
inline constexpr const char* kTiles = "tiles";
inline constexpr const char* kTileRow0 = "row0";
inline constexpr const char* kTileCol0 = "col0";
inline constexpr const char* kTileRows = "rows";
inline constexpr const char* kTileCols = "cols";
inline constexpr const char* kExternalFile = "external_file";
inline constexpr const char* kExternalGrid = "external_grid";

inline constexpr std::string_view kDem = "dem";
inline constexpr std::string_view kPlanet = "planet";
inline constexpr std::string_view kPlanetocentric = "planetocentric";
inline constexpr std::string_view kPlanetodetic = "planetodetic";
inline constexpr std::string_view kLocalTangentPlane = "local_tangent_plane";
inline constexpr std::string_view kPolarStereographic = "polar_stereographic";
inline constexpr std::string_view kEquirectangular = "equirectangular";
inline constexpr std::string_view kTransverseMercator = "transverse_mercator";
inline constexpr std::string_view kProjected = "projected";

// Transverse Mercator placements (format 1.2): a grid with one has format_version [1, 2].
inline constexpr int kTransverseMercatorFormatMinor = 2;

// Height statistics of level 0 (format 1.3), optional: all four or none.
inline constexpr int kStatisticsFormatMinor = 3;
inline constexpr const char* kHeightMin = "height_min";
inline constexpr const char* kHeightMax = "height_max";
inline constexpr const char* kHeightMean = "height_mean";
inline constexpr const char* kValidSamples = "valid_samples";
// Provenance (format 1.3, optional): a JSON string.
inline constexpr const char* kProvenance = "provenance";

// Placements in any projected CRS through PROJ (format 1.4): placement "projected" and the
// CRS as WKT2 in crs_wkt.
inline constexpr int kProjectedFormatMinor = 4;

/// The minor format version a grid needs: 0, 1 for a tiled grid, 2 for a transverse
/// Mercator placement, 3 with height statistics, 4 for a PROJ placement (minor versions are
/// cumulative: a 1.2 reader reads tiles too).
[[nodiscard]] inline int gridFormatMinor(const GridInfo& info, bool tiled,
                                         bool statistics = false) noexcept {
  if (info.kind == GridKind::Dem && info.placement.kind == PlacementInfo::Kind::Projected) {
    return kProjectedFormatMinor;
  }
  if (statistics || !info.provenance.empty()) return kStatisticsFormatMinor;
  if (info.kind == GridKind::Dem &&
      info.placement.kind == PlacementInfo::Kind::TransverseMercator) {
    return kTransverseMercatorFormatMinor;
  }
  return tiled ? kTiledFormatMinor : 0;
}

/// Level dataset name: "level0", "level1", ...
[[nodiscard]] inline std::string levelName(std::size_t level) {
  return "level" + std::to_string(level);
}

/// The number of levels until the level is 1×1 (the most a grid may have).
[[nodiscard]] inline std::size_t maxLevels(std::size_t rows, std::size_t cols) noexcept {
  std::size_t levels = 1;
  std::size_t n = rows > cols ? rows : cols;
  while (n > 1) {
    n = (n + 1) / 2;
    ++levels;
  }
  return levels;
}

/// Chunk shape of one level: the patch shape clipped to the level's size.
[[nodiscard]] inline std::array<hsize_t, 2> chunkShape(const GridInfo& info, std::size_t level) {
  const std::size_t r = info.levelRows(level), c = info.levelCols(level);
  return {static_cast<hsize_t>(info.patchRows < r ? info.patchRows : r),
          static_cast<hsize_t>(info.patchCols < c ? info.patchCols : c)};
}

/// Chunk shape of an internal tile's level0 dataset: the patch shape clipped to the tile.
[[nodiscard]] inline std::array<hsize_t, 2> tileChunkShape(const GridInfo& info, std::size_t rows,
                                                           std::size_t cols) {
  return {static_cast<hsize_t>(info.patchRows < rows ? info.patchRows : rows),
          static_cast<hsize_t>(info.patchCols < cols ? info.patchCols : cols)};
}

/// Stored sample types the reader accepts (the writer writes Float32).
enum class SampleType { Int16, UInt16, Int32, Float32, Float64 };

[[nodiscard]] inline std::string_view toString(SampleType t) noexcept {
  switch (t) {
    case SampleType::Int16: return "int16";
    case SampleType::UInt16: return "uint16";
    case SampleType::Int32: return "int32";
    case SampleType::Float32: return "float32";
    case SampleType::Float64: return "float64";
  }
  return "?";
}

[[nodiscard]] inline std::optional<SampleType> sampleTypeFrom(std::string_view s) noexcept {
  for (SampleType t : {SampleType::Int16, SampleType::UInt16, SampleType::Int32,
                       SampleType::Float32, SampleType::Float64}) {
    if (s == toString(t)) return t;
  }
  return std::nullopt;
}

[[nodiscard]] inline std::size_t sizeOf(SampleType t) noexcept {
  switch (t) {
    case SampleType::Int16:
    case SampleType::UInt16: return 2;
    case SampleType::Int32:
    case SampleType::Float32: return 4;
    case SampleType::Float64: return 8;
  }
  return 0;
}

/// The native (memory) HDF5 type of a sample type.
[[nodiscard]] inline hid_t nativeType(SampleType t) noexcept {
  switch (t) {
    case SampleType::Int16: return H5T_NATIVE_INT16;
    case SampleType::UInt16: return H5T_NATIVE_UINT16;
    case SampleType::Int32: return H5T_NATIVE_INT32;
    case SampleType::Float32: return H5T_NATIVE_FLOAT;
    case SampleType::Float64: return H5T_NATIVE_DOUBLE;
  }
  return H5I_INVALID_HID;
}

}  // namespace regolith::store::format
