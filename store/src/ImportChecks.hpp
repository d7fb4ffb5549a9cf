#pragma once
/// \file
/// Private checks of an import that catch what GDAL reads but no body can have
/// (docs/reliability.md, "Catalogue of hostile input"): impossible georeferencing, samples
/// that overflow float, and heights beyond the body's plausible range. Every message names
/// the source file, not the store being written.

#include <regolith/store/GridInfo.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <atomic>
#include <memory>
#include <string>

namespace regolith::store::gdal {

/// Throws ImportError "<prefix>: <field> is <value>, expected <bound>" if the grid GDAL's
/// georeferencing gives is impossible: a pixel width or height that is not finite and > 0,
/// or larger than the whole body (360 x 180 deg; the body's circumference in metres), a
/// first sample's position that is not finite, a planet's west edge beyond +-360 deg, or an
/// equirectangular DEM more than one pixel wider than 360 deg of longitude. `prefix` is
/// "<operation>: <source>".
void checkGeoreferencing(const GridInfo& info, const std::string& prefix);

/// The bound of plausible heights on `info`'s body: a tenth of its equatorial radius, in
/// metres, either side of the reference surface; infinite for a grid on no body (radius 0).
/// DEMs on no body also have no bound on their pixel size in checkGeoreferencing().
[[nodiscard]] double plausibleHeightLimit(const GridInfo& info) noexcept;

/// A raster's heights as they go to the writer, checked on the way: an infinite value (a
/// source value beyond float's range after scale and offset) throws ImportError naming the
/// source and the sample; heights beyond +-plausibleHeightLimit() are counted, or, with
/// `strict`, throw ImportError. Thread-safety: as the wrapped source; the count is atomic.
class CheckedHeights final : public topo::SampleSource {
 public:
  CheckedHeights(std::shared_ptr<const topo::SampleSource> source, const GridInfo& info,
                 std::string prefix, bool strict);

  [[nodiscard]] std::size_t rows() const noexcept override { return source_->rows(); }
  [[nodiscard]] std::size_t cols() const noexcept override { return source_->cols(); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override;
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override;
  /// Heights beyond the limit read so far.
  [[nodiscard]] std::size_t implausible() const noexcept { return implausible_.load(); }
  [[nodiscard]] double limit() const noexcept { return limit_; }

 private:
  std::shared_ptr<const topo::SampleSource> source_;
  std::string prefix_;
  double limit_;
  bool strict_;
  mutable std::atomic<std::size_t> implausible_{0};
};

}  // namespace regolith::store::gdal
