#pragma once
/// \file
/// A local Cartesian DEM placed on a body.

#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <span>

namespace regolith::topo {

/// A planar grid of heights in metres (grid x, y in metres, row 0 north/top), placed on a
/// body by a Placement.
///
/// Queries take grid coordinates (x, y) in metres. Points inside the pixel extent but
/// beyond the outermost sample centres use the edge samples (the kernel's stencil is
/// clamped to the grid); points outside the pixel extent return OutsideGrid and NaN. NaN
/// or infinite coordinates throw InvalidArgument. Samples that are NaN or equal the grid's
/// nodata value give Nodata and NaN (docs/queries.md lists the exact rules).
///
/// Thread-safety: all queries are const and may run concurrently if the SampleSource
/// allows it (InMemorySamples does).
class TopoDem {
 public:
  /// Throws InvalidArgument if samples is null or its size differs from the grid's.
  TopoDem(TopoGrid grid, Placement placement, std::shared_ptr<const SampleSource> samples);

  [[nodiscard]] const TopoGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const Placement& placement() const noexcept { return placement_; }
  [[nodiscard]] const Body& body() const noexcept { return placement_.body(); }
  [[nodiscard]] const SampleSource& samples() const noexcept { return *samples_; }
  [[nodiscard]] std::shared_ptr<const SampleSource> sharedSamples() const noexcept {
    return samples_;
  }

  /// Height at grid point (x, y).
  [[nodiscard]] HeightSample height(double x, double y,
                                    Interpolation interp = Interpolation::Bilinear) const;
  /// Height and unit normal at grid point (x, y).
  [[nodiscard]] SurfaceSample surface(double x, double y,
                                      Interpolation interp = Interpolation::Bilinear,
                                      NormalFrame frame = NormalFrame::Grid) const;

  /// Batch heights: arrays in, arrays out, all the same length (else InvalidArgument).
  /// status may be empty. All inputs are checked for NaN/inf before anything is written.
  void heights(std::span<const double> xs, std::span<const double> ys, std::span<double> out,
               std::span<QueryStatus> status, Interpolation interp = Interpolation::Bilinear) const;
  /// Batch heights and normals.
  void surfaces(std::span<const double> xs, std::span<const double> ys,
                std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                std::span<QueryStatus> status, Interpolation interp = Interpolation::Bilinear,
                NormalFrame frame = NormalFrame::Grid) const;

  /// Body-fixed position of grid point (x, y) at height h.
  [[nodiscard]] glm::dvec3 toBodyFixed(double x, double y, double h) const {
    return placement_.toBodyFixed(x, y, h);
  }
  /// Body-fixed position of sample (row, col) at its stored height (NaN if nodata).
  [[nodiscard]] glm::dvec3 samplePosition(std::size_t row, std::size_t col) const;

 private:
  TopoGrid grid_;
  Placement placement_;
  std::shared_ptr<const SampleSource> samples_;
  const float* resident_ = nullptr;  // samples_->contiguous(), cached for the fast path
  double nodata_;                    // the nodata value, or NaN
  bool hasNodataValue_;              // a nodata value other than NaN is declared
  double uMax_, vMax_;               // cols − 1, rows − 1
  double invDx_, invDy_;             // 1 / spacing
  bool exactReciprocal_;             // both reciprocals are exact (powers of two)
};

}  // namespace regolith::topo
