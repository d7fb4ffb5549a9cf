#pragma once
/// \file
/// A local Cartesian DEM placed on a body.

#include <regolith/topo/Bilinear.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
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
  /// Batch heights and normals. status receives the heights' statuses and normalStatus
  /// the normals' (either may be empty; see SurfaceSample). A point whose normal the
  /// placement cannot map gets normalStatus Unmappable; it never fails the batch.
  void surfaces(std::span<const double> xs, std::span<const double> ys,
                std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                std::span<QueryStatus> status, Interpolation interp = Interpolation::Bilinear,
                NormalFrame frame = NormalFrame::Grid,
                std::span<QueryStatus> normalStatus = {}) const;

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
  const float* resident_ = nullptr;      // samples_->contiguous(), cached
  const PagedQueries* paged_ = nullptr;  // samples_->paged(), cached
  kernel::DemIndexer index_;
  kernel::ResidentBilinear fast_;
  glm::dvec2 slack_{0.0};  // grid_.edgeSlack()

  [[nodiscard]] HeightSample heightGeneric(double x, double y, Interpolation interp) const;
  [[nodiscard]] SurfaceSample surfaceGeneric(double x, double y, Interpolation interp,
                                             NormalFrame frame) const;
  /// s with its grid-frame normal taken to the body-fixed frame (normalStatus Unmappable
  /// where the placement cannot map the point). Requires s.normalValid().
  [[nodiscard]] SurfaceSample toBodyFixedNormal(SurfaceSample s, double x, double y) const;
};

inline HeightSample TopoDem::height(double x, double y, Interpolation interp) const {
  if (interp == Interpolation::Bilinear) {
    const double u = index_.u(x), v = index_.v(y);
    kernel::CellValue cv;
    if (fast_.data != nullptr) {
      if (fast_.evalResident<false>(u, v, cv)) [[likely]]
        return {cv.h, QueryStatus::Ok};
    } else if (paged_ != nullptr) {
      const double h = paged_->bilinearHeight(fast_, u, v);
      if (h == h) [[likely]]
        return {h, QueryStatus::Ok};
    }
  }
  return heightGeneric(x, y, interp);
}

inline SurfaceSample TopoDem::surface(double x, double y, Interpolation interp,
                                      NormalFrame frame) const {
  if (interp == Interpolation::Bilinear) {
    // The normal comes from the height's four samples (their two further differences), on
    // height()'s fast paths.
    const double u = index_.u(x), v = index_.v(y);
    kernel::CellValue cv;
    const bool ok = fast_.data != nullptr ? fast_.evalResident<true>(u, v, cv)
                    : paged_ != nullptr   ? paged_->bilinearSurface(fast_, u, v, cv)
                                          : false;
    if (ok) [[likely]] {
      const SurfaceSample s{cv.h, kernel::gridNormal(index_, cv.dhdu, cv.dhdv), QueryStatus::Ok,
                            QueryStatus::Ok};
      return frame == NormalFrame::Grid ? s : toBodyFixedNormal(s, x, y);
    }
  }
  return surfaceGeneric(x, y, interp, frame);
}

}  // namespace regolith::topo
