#pragma once
/// \file
/// GDAL import: any single-band raster GDAL reads as a DEM (GeoTIFF, PDS3, PDS4, ISIS3 cubes,
/// SRTM .hgt, ...) becomes a grid of a store. The rules per format, and the errors, are
/// written down in docs/import.md.

#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>

#include <array>
#include <atomic>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

namespace regolith::store {

/// A raster cannot be imported: GDAL cannot open it, it is not a single-band elevation
/// raster, its projection is unsupported, its tiles do not fit together. The message starts
/// with the operation, names the file and gives the reason.
class ImportError : public StoreError {
 public:
  using StoreError::StoreError;
};

/// A window of samples: rows row0 … row0 + rows − 1, columns col0 … col0 + cols − 1.
struct SampleWindow {
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
};

/// How to place a height map that has no georeferencing (a PNG, a GeoTIFF without a CRS):
/// a DEM on a local tangent plane of the body ImportOptions::body names, its centre sample at
/// the origin, its rows and columns along the plane's axes (columns east, rows south when the
/// heading is 0).
struct HeightMapOptions {
  /// Metres between samples along x (columns) and y (rows); finite and > 0.
  double spacingX = 0.0, spacingY = 0.0;
  /// Heights in metres are heightOffset + heightScale · (the value GDAL reads, after the
  /// file's own scale/offset if it has one); scale finite and non-zero.
  double heightScale = 1.0, heightOffset = 0.0;
  /// Planetodetic latitude/longitude (degrees) of the grid's centre, on the reference surface.
  double originLatDeg = 0.0, originLonDeg = 0.0;
  /// Azimuth of the grid's y axis (up the rows), degrees clockwise from north.
  double headingDeg = 0.0;
};

/// What to import and how to write it: the store's WriteOptions (patch size, levels, codec,
/// deflate level, threads and executor, progress, cancel; 0 levels: until a level fits one
/// patch), and the import's own choices.
struct ImportOptions : WriteOptions {
  /// Name of the grid written; empty: the file's stem (of the first tile).
  std::string gridName{};
  /// The body's name, where the CRS does not say it or says it wrongly (GDAL's PDS4 writer
  /// drops it); empty: the CRS's. The radii stay the CRS's.
  std::string body{};
  /// importRaster() only: import just these samples of the grid the import would write
  /// without a window (its rows and columns as describeRaster() gives them).
  std::optional<SampleWindow> window{};
  /// importRaster() only: import just the samples whose centres lie in this longitude/latitude
  /// box, {west, south, east, north} in degrees (east > west; a box may not cross the
  /// grid's seam). Planet grids: the grid's longitudes and latitudes; DEMs: the samples
  /// inside the grid-aligned rectangle that holds the box's outline through the placement
  /// (planetodetic latitudes). At most one of window and bbox.
  std::optional<std::array<double, 4>> bbox{};
  /// A source value (before scale/offset) that also means "missing", beside the ones the
  /// file declares.
  std::optional<double> nodata{};
  /// Refuse (ImportError) a height beyond +-(equatorial radius / 10) instead of counting it
  /// in ImportReport::implausibleSamples.
  bool strict = false;
  /// A raster without georeferencing is placed by these (with `body`: Mars, Moon or Earth);
  /// without them it is refused, and a georeferenced raster given them too.
  std::optional<HeightMapOptions> heightMap{};
  /// Whether the grid's provenance records each source file's SHA-256 digest, which reads
  /// every byte of it (0.25 s for 256 MB here). Off, a source's entry keeps its file, path and
  /// size only. regolith-mpi turns it off where the digest is taken apart (rasterProvenance()).
  bool digestSources = true;
};

/// What an import found and did.
struct ImportReport {
  /// The grid as written (levels and patch size included).
  GridInfo info;
  /// GDAL's short driver name (of the first tile), e.g. "GTiff", "ISIS3", "PDS", "PDS4".
  std::string driver;
  /// The source CRS's name and projection method, e.g. "SimpleCylindrical Moon
  /// (Equirectangular)".
  std::string projection;
  /// Subtracted from every value after scale/offset: the reference sphere's radius when the
  /// source holds planetary radii (ISIS shape models, LOLA), 0 when it holds heights.
  double radiusReference = 0.0;
  /// Whether the georeferencing GDAL reports by default was corrected (a PDS3 label in the
  /// other projection-offset convention, as the MOLA MEGDR) or snapped (a global grid's
  /// spacing to 360°/cols, 180°/rows).
  bool offsetCorrected = false, spacingSnapped = false;
  /// Whether a source without a declared nodata value had −32768 voids, taken as missing
  /// (inspectRaster(), which reads no samples: whether it would take them as missing).
  bool voidMarkerAssumed = false;
  /// Wholly missing rows beyond the north and the south pole (padding) that were dropped, and
  /// columns beyond 360° of longitude, equal to the first ones, that were dropped.
  std::size_t droppedNorthRows = 0, droppedSouthRows = 0, droppedColumns = 0;
  /// A pole-to-pole grid (rows × spacing = 180°) whose offsets, through a rounded map scale,
  /// put an edge up to 0.9 pixel beyond a pole is moved onto the poles by this many pixels
  /// (positive: south); 0 when not moved.
  double poleShiftPixels = 0.0;
  /// The window of ImportOptions::window or ::bbox, in the grid without a window.
  std::optional<SampleWindow> window;
  /// Level-0 samples that are missing (nodata, special pixels, NaN); for importTiles() also
  /// the samples of gaps that no tile covers.
  std::size_t missingSamples = 0;
  /// Level-0 heights beyond +-plausibleLimit (a tenth of the body's equatorial radius, in
  /// metres): written as they are, and worth a look (a spike, a wrong scale or unit);
  /// ImportOptions::strict refuses them instead.
  std::size_t implausibleSamples = 0;
  double plausibleLimit = 0.0;
  /// How the writer built the pyramid within ImportOptions::memoryBudgetBytes (whole-width
  /// bands, or column tiles of so many chunks), and its estimate of its own buffers.
  WriterMemoryPlan memory{};
  /// The process's peak resident set size when the import ended (getrusage's ru_maxrss), in
  /// bytes: everything the process has held since it started, GDAL's block cache, HDF5's
  /// caches and the libraries included; 0 where the system does not say.
  std::size_t peakRssBytes = 0;
  /// Number of source files.
  std::size_t tiles = 1;
  /// Wall time of the import.
  double seconds = 0.0;
};

/// How GDAL's raster maps onto a grid, without writing anything (levels and patch size as
/// the options ask; levels 0 left as 1). Throws ImportError.
[[nodiscard]] GridInfo describeRaster(const std::filesystem::path& raster,
                                      const ImportOptions& options = {});

/// The provenance (JSON, docs/store-format.md) importRaster() records for `raster` with these
/// options: its files with their sizes and, with options.digestSources, their SHA-256
/// digests; GDAL's driver, the label's projection group, the geotransform and the CRS. It does
/// not depend on a window. Throws ImportError naming the file that cannot be read.
[[nodiscard]] std::string rasterProvenance(const std::filesystem::path& raster,
                                           const ImportOptions& options = {});

/// Everything importRaster() would report (driver, projection, radius reference,
/// corrections), without writing: for `regolith info` on a raster. missingSamples and seconds
/// stay 0. Throws ImportError.
[[nodiscard]] ImportReport inspectRaster(const std::filesystem::path& raster,
                                         const ImportOptions& options = {});

/// Imports one raster as one grid of a new store at `store` (written crash-safely: no file
/// appears under that name unless the import completes). Throws ImportError for input it
/// cannot import (impossible georeferencing, a value beyond float's range, with
/// options.strict a height beyond the plausible range), StoreError for a failed or cancelled
/// write, InvalidArgument if `store` is one of the files GDAL reads for the raster
/// (core::refuseOverwritingInput(): through symlinks and hard links).
ImportReport importRaster(const std::filesystem::path& raster, const std::filesystem::path& store,
                          const ImportOptions& options = {});

/// Imports several rasters that tile one grid (same CRS, spacing and sample alignment, no
/// overlaps; gaps read as missing) as one tiled grid (docs/store-format.md, "Tiled grids").
/// Throws ImportError naming the offending file for tiles that do not fit together, and as
/// importRaster() otherwise.
ImportReport importTiles(std::span<const std::filesystem::path> tiles,
                         const std::filesystem::path& store, const ImportOptions& options = {});

}  // namespace regolith::store
