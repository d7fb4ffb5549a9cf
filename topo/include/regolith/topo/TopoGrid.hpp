#pragma once
/// \file
/// Raster geometry and the sample-source abstraction.

#include <glm/vec2.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace regolith::topo {

/// Geometry of a north-up raster.
///
/// Pixel-centre convention (docs/grid-convention.md): sample (row, col) sits at the centre
/// of its pixel, exactly where GDAL's geotransform puts it:
///   x = x0 + col · dx,  y = y0 − row · dy,
/// where (x0, y0) is the centre of sample (0, 0) and dx, dy > 0. Row 0 is the north/top
/// edge. The grid covers the pixel extent, half a pixel beyond the outermost centres.
///
/// For a TopoDem x and y are map metres; for a TopoPlanet x is longitude and y latitude in
/// degrees. An optional nodata value marks missing samples; NaN samples are always missing.
/// Value type; thread-safe.
class TopoGrid {
 public:
  /// Throws InvalidArgument unless rows, cols ≥ 1 and dx, dy are finite and > 0.
  TopoGrid(std::size_t rows, std::size_t cols, double x0, double y0, double dx, double dy,
           std::optional<float> nodata = std::nullopt);

  /// From a GDAL geotransform [originX, dx, rotX, originY, rotY, −dy] (outer pixel corner).
  /// Rotated or south-up transforms throw InvalidArgument.
  static TopoGrid fromGeoTransform(const std::array<double, 6>& gt, std::size_t rows,
                                   std::size_t cols, std::optional<float> nodata = std::nullopt);
  /// The equivalent GDAL geotransform.
  [[nodiscard]] std::array<double, 6> geoTransform() const noexcept;

  [[nodiscard]] std::size_t rows() const noexcept { return rows_; }
  [[nodiscard]] std::size_t cols() const noexcept { return cols_; }
  [[nodiscard]] double x0() const noexcept { return x0_; }
  [[nodiscard]] double y0() const noexcept { return y0_; }
  [[nodiscard]] double spacingX() const noexcept { return dx_; }
  [[nodiscard]] double spacingY() const noexcept { return dy_; }
  [[nodiscard]] const std::optional<float>& nodata() const noexcept { return nodata_; }

  /// Position of the centre of sample (row, col).
  [[nodiscard]] glm::dvec2 sampleCentre(double row, double col) const noexcept {
    return {x0_ + col * dx_, y0_ - row * dy_};
  }
  /// Fractional (col, row) of a position; integers at sample centres.
  [[nodiscard]] glm::dvec2 fractionalIndex(double x, double y) const noexcept {
    return {(x - x0_) / dx_, (y0_ - y) / dy_};
  }
  /// Pixel-extent edges.
  [[nodiscard]] double west() const noexcept { return x0_ - 0.5 * dx_; }
  [[nodiscard]] double east() const noexcept {
    return x0_ + (static_cast<double>(cols_) - 0.5) * dx_;
  }
  [[nodiscard]] double north() const noexcept { return y0_ + 0.5 * dy_; }
  [[nodiscard]] double south() const noexcept {
    return y0_ - (static_cast<double>(rows_) - 0.5) * dy_;
  }
  /// True if (x, y) lies within the pixel extent, edges included: a point on an edge that
  /// west() … north() report is inside, even when rounding puts its fractional index a few
  /// ulps beyond ±0.5 (see edgeSlack()).
  [[nodiscard]] bool contains(double x, double y) const noexcept;
  /// How far beyond the pixel extent, in fractional index units (col, row), a point still
  /// counts as on its edge: 4 ulps of the grid's largest coordinate over the spacing, plus
  /// 4 ulps of the largest index. That covers the rounding of an edge's own coordinate, of
  /// x − x0 and of the division, in every coordinate mode (grid indices, grid coordinates,
  /// longitude/latitude), and is far below any distance a grid resolves (1e-11 of a pixel
  /// for x0 = 1e5 spacings).
  [[nodiscard]] glm::dvec2 edgeSlack() const noexcept;
  /// True if sample value s is missing (NaN or equal to nodata).
  [[nodiscard]] bool isNodata(float s) const noexcept {
    return s != s || (nodata_ && s == *nodata_);
  }

 private:
  std::size_t rows_, cols_;
  double x0_, y0_, dx_, dy_;
  std::optional<float> nodata_;
};

class PagedQueries;

/// Where a grid's samples come from. Implementations: InMemorySamples here; the store's
/// pager (regolith::store) pages them from HDF5 patch by patch (store::BlockSource).
///
/// Thread-safety: every const member may be called from several threads at once.
class SampleSource {
 public:
  SampleSource() = default;
  SampleSource(const SampleSource&) = delete;
  SampleSource& operator=(const SampleSource&) = delete;
  virtual ~SampleSource() = default;

  [[nodiscard]] virtual std::size_t rows() const noexcept = 0;
  [[nodiscard]] virtual std::size_t cols() const noexcept = 0;
  /// One sample; row < rows(), col < cols() (an assertion, not a check).
  [[nodiscard]] virtual float sample(std::size_t row, std::size_t col) const = 0;
  /// A row-major window into out (size nrows·ncols). The window must lie inside the grid.
  virtual void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                          std::span<float> out) const;
  /// All samples as one row-major array if they are resident, else nullptr. Queries use
  /// it as their fast path.
  [[nodiscard]] virtual const float* contiguous() const noexcept { return nullptr; }
  /// The bilinear fast paths of a source whose samples are resident in blocks (the store's
  /// pager), or null: queries then read samples through contiguous() or sample(). The
  /// object lives as long as the source.
  [[nodiscard]] virtual const PagedQueries* paged() const noexcept { return nullptr; }
  /// A block of samples: rows [row0, row0 + rows), columns [col0, col0 + cols).
  struct Window {
    std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
  };
  /// A hint that `windows` are likely to be read soon (a renderer's ring around the window it
  /// has just read): a paged source loads them in the background (a store's pyramid:
  /// coarser levels first) and drops what is still queued of this source's previous hint.
  /// Windows are clipped to the grid. Returns at once; never fails (a load that fails here is the
  /// later read's to report). Default: nothing (samples in memory).
  virtual void prefetch(std::span<const Window> windows) const noexcept { (void)windows; }
  /// Makes `windows` resident before the caller reads them (a renderer's window it needs
  /// now): a paged source loads them through its loader (a store's pyramid: its Prefetcher,
  /// ahead of every hint, on the calling thread; not windows over half its cache) and
  /// returns when each is loaded or failed. Windows are clipped to the grid. Never fails (the
  /// read reports a load that failed). Default: nothing (samples in memory).
  virtual void load(std::span<const Window> windows) const noexcept { (void)windows; }
};

/// Samples held in one row-major float array.
class InMemorySamples final : public SampleSource {
 public:
  /// Throws InvalidArgument if data.size() != rows·cols or the grid is empty.
  InMemorySamples(std::size_t rows, std::size_t cols, std::vector<float> data);
  /// Fills the grid from f(row, col).
  static std::shared_ptr<InMemorySamples> fromFunction(
      std::size_t rows, std::size_t cols, const std::function<float(std::size_t, std::size_t)>& f);

  [[nodiscard]] std::size_t rows() const noexcept override { return rows_; }
  [[nodiscard]] std::size_t cols() const noexcept override { return cols_; }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override;
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override;
  [[nodiscard]] const float* contiguous() const noexcept override { return data_.data(); }
  [[nodiscard]] const std::vector<float>& data() const noexcept { return data_; }

 private:
  std::size_t rows_, cols_;
  std::vector<float> data_;
};

}  // namespace regolith::topo
