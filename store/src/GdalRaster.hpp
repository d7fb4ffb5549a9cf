#pragma once
/// \file
/// Private GDAL plumbing of the import: one opened single-band raster, analysed into a
/// GridInfo, and read as heights in metres. No GDAL handle leaves store/src.

#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <gdal.h>
#include <ogr_srs_api.h>

#include <array>
#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace regolith::store::gdal {

/// An equirectangular DEM (x, y in metres from the projection's origin) that covers all
/// longitudes (within half a pixel, at the label's resolution if it has one) becomes a planet
/// grid at its exact resolution: 360°/cols in longitude; in latitude the label's own
/// resolution `labelPixelsPerDegree` (PDS3 MAP_RESOLUTION, ISIS3 Scale) where it exists and
/// agrees with the map scale to 1 % (within 1e-6 of 180°/rows it is that: labels print it
/// rounded, GDAL's writers derive it from the metres), else 180°/rows if the rows cover all
/// latitudes within half a pixel, else the map scale's. Samples are placed by their pixel
/// offsets from the projection's origin. Returns whether the spacing was snapped; leaves
/// other grids alone.
bool globalToPlanet(GridInfo& info, std::optional<double> labelPixelsPerDegree = std::nullopt);

/// A projected CRS without an analytic placement in topo (sinusoidal, Lambert conformal conic,
/// orthographic, equirectangular on an ellipsoid, ...), placed through PROJ: info becomes a DEM
/// with a PlacementInfo::Kind::Projected placement (the CRS as WKT2), its x, y the map's metres
/// (false easting/northing included) from GDAL's geotransform `gt` in units of
/// `metresPerUnit`. Throws ImportError ("<prefix>: ...") if PROJ cannot use the CRS or the
/// grid's centre has no position on the body. GdalProjected.cpp.
void placeThroughProj(OGRSpatialReferenceH srs, const std::array<double, 6>& gt,
                      double metresPerUnit, GridInfo& info, const std::string& prefix,
                      const std::string& projection);

struct Layout;

/// A raster without a CRS, or one given ImportOptions::heightMap: placed as a height map on a
/// local tangent plane (Layout's grid, scale and offset set), or refused with an ImportError
/// ("<prefix>: ...") that names the options that would place it. HeightMap.cpp.
void placeHeightMap(GDALDatasetH ds, const ImportOptions& options, Layout& layout,
                    const std::string& prefix);

/// A planet grid whose rows span 180° (pole to pole) and whose edge lies beyond a pole by more
/// than topo::kPoleOverhangPixels and at most 0.9 pixel (offsets through a rounded map scale)
/// moved onto the poles; returns the shift in pixels (positive: south; 0: not moved).
double shiftOntoPoles(GridInfo& info);

/// Throws ImportError ("<prefix>: ...") if a planet grid's edges lie beyond a pole by more than
/// topo::kPoleOverhangPixels, which TopoPlanet refuses.
void requireWithinPoles(const GridInfo& info, const std::string& prefix);

/// Runs GDALAllRegister() once.
void registerOnce();

/// Collects GDAL's error messages on this thread for its lifetime (instead of printing them).
class ErrorCapture {
 public:
  ErrorCapture();
  ~ErrorCapture();
  ErrorCapture(const ErrorCapture&) = delete;
  ErrorCapture& operator=(const ErrorCapture&) = delete;
  ErrorCapture(ErrorCapture&&) = delete;
  ErrorCapture& operator=(ErrorCapture&&) = delete;
  /// The messages so far, joined by "; " (empty if none).
  [[nodiscard]] std::string messages() const;

 private:
  std::string messages_;
  static void handler(CPLErr cls, CPLErrorNum num, const char* msg);
};

struct DatasetCloser {
  void operator()(GDALDatasetH ds) const noexcept { GDALClose(ds); }
};
using Dataset = std::unique_ptr<void, DatasetCloser>;

/// How an opened raster becomes a grid.
struct Layout {
  GridInfo info;
  std::string driver, projection;
  double scale = 1.0, offset = 0.0, radiusReference = 0.0;
  std::optional<double> declaredNodata, extraNodata;
  bool readMask = false;  // GDAL's mask band has more to say than the nodata value
  bool voidMarker = false, offsetCorrected = false, spacingSnapped = false;
  /// The label's map resolution in pixels per degree (PDS3 MAP_RESOLUTION, ISIS3 Scale).
  std::optional<double> labelPixelsPerDegree;
  /// The grid is the source's rows from rowOffset and columns from colOffset (rows or columns
  /// dropped beyond a pole or beyond 360°).
  std::size_t rowOffset = 0, colOffset = 0;
  std::size_t droppedNorthRows = 0, droppedSouthRows = 0, droppedColumns = 0;
  /// A pole-to-pole grid moved onto the poles, in pixels (0: not moved).
  double poleShiftPixels = 0.0;
  std::optional<SampleWindow> window;  // ImportOptions::window or bbox, as applied
  OGRSpatialReferenceH srs = nullptr;  // owned by the dataset
};

/// One raster opened with GDAL, read as heights in metres (offset + scale · value − radius
/// reference; missing samples NaN). Thread-safety: reads are serialised by a mutex (a GDAL
/// dataset handle is not thread-safe).
class Raster final : public topo::SampleSource {
 public:
  /// Opens and analyses; throws ImportError naming the file and the reason. A mosaic's tile
  /// leaves the pole shift and the check of its edges against the poles to the mosaic.
  Raster(const std::filesystem::path& path, const ImportOptions& options, std::string operation,
         bool mosaicTile = false);
  ~Raster() override;
  Raster(const Raster&) = delete;
  Raster& operator=(const Raster&) = delete;
  Raster(Raster&&) = delete;
  Raster& operator=(Raster&&) = delete;

  [[nodiscard]] const Layout& layout() const noexcept { return layout_; }
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] std::size_t rows() const noexcept override { return layout_.info.rows; }
  [[nodiscard]] std::size_t cols() const noexcept override { return layout_.info.cols; }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override;
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override;
  /// Missing samples delivered by readWindow() so far.
  [[nodiscard]] std::size_t missingRead() const noexcept { return missing_.load(); }
  /// Of those, the −32768 voids of a file declaring no nodata (Layout::voidMarker).
  [[nodiscard]] std::size_t voidsRead() const noexcept { return voids_.load(); }
  /// "<operation>: <file>"
  [[nodiscard]] const std::string& prefix() const noexcept { return prefix_; }
  /// Provenance (JSON, docs/store-format.md): this raster's files as GDAL lists them (a label
  /// and its data file, ...) with sizes and SHA-256 digests read through GDAL's virtual file
  /// layer (so /vsizip/ paths work), GDAL's driver and version, the label's map projection
  /// group (PDS3 IMAGE_MAP_PROJECTION, ISIS3 Mapping), the geotransform and the CRS.
  /// Without `digests`, the files' sizes only (nothing read). Throws ImportError if a file
  /// cannot be read.
  [[nodiscard]] std::string provenance(bool digests) const;
  /// The path opened and every file GDAL reads for it (a label and its data file, ...).
  [[nodiscard]] std::vector<std::filesystem::path> files() const;

 private:
  std::filesystem::path path_;
  std::string prefix_;
  bool tile_ = false;
  Dataset ds_;
  GDALRasterBandH band_ = nullptr;
  Layout layout_;
  mutable std::mutex mutex_;
  mutable std::atomic<std::size_t> missing_{0}, voids_{0};

  void open(const ImportOptions& options, bool pdsShift);
  void analyse(const ImportOptions& options);
  void detectRadii();
  void resolvePoles();
  void dropRepeatedColumns();
  void applyWindow(const ImportOptions& options);
  [[nodiscard]] SampleWindow windowOfBox(const std::array<double, 4>& box) const;
  /// Reads source rows/cols (not offset by the window) as readWindow does; returns the
  /// number of missing samples.
  std::size_t readSource(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                         std::span<float> out, std::size_t* voids = nullptr) const;
  /// Whether every sample of the source's rows row0… (or columns col0…) is missing.
  [[nodiscard]] bool allMissing(std::size_t row0, std::size_t nrows, std::size_t col0,
                                std::size_t ncols) const;
};

}  // namespace regolith::store::gdal
