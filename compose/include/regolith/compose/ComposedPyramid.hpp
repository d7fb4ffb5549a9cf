#pragma once
/// \file
/// The composed surface as a renderer's pyramid: each level's samples are the composed
/// heights at that level's sample positions, so a clipmap (or any renderer that reads a
/// topo::GridPyramid) draws exactly the surface the CPU queries answer.

#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Pyramid.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstddef>
#include <memory>
#include <optional>

namespace regolith::compose {

/// The samples of one grid (a latitude/longitude planet grid, or a placed planar grid)
/// taken from a composed surface at a ground resolution: sample (r, c) is
/// ComposedSurface::heightAt() at the sample's position (NaN where nothing covers it).
/// - Planet grids: x is longitude, y latitude of `latitudeType`; heights are along the
///   body's normal, as the composed surface's.
/// - Placed grids: (x, y) through the placement. Map projections carry heights along the
///   body's normal; a tangent plane carries them along its own normal, so the sample is
///   where the plane's normal line at (x, y) meets the composed surface (iterated).
/// Samples are computed on demand and not kept: a renderer's loader reads each window once.
/// Thread-safety: as ComposedSurface (immutable).
class ComposedSamples final : public topo::SampleSource {
 public:
  /// A planet grid. Throws InvalidArgument for a null surface.
  ComposedSamples(std::shared_ptr<const ComposedSurface> surface, const topo::TopoGrid& grid,
                  topo::LatitudeType latitudeType, double groundMetres);
  /// A placed planar grid (the placement must be on the surface's body). If it is level
  /// `ownLevel` of dataset `own` of the surface (same placement and lattice), samples where
  /// `own` alone makes the surface (no mask, past its feather, and no dataset of its tier or
  /// above overlaps it) are `own`'s own samples, read directly: what the composition gives
  /// there, at the cost of a plain read.
  ComposedSamples(std::shared_ptr<const ComposedSurface> surface, const topo::TopoGrid& grid,
                  const topo::Placement& placement, double groundMetres,
                  std::shared_ptr<const Dataset> own = nullptr, std::size_t ownLevel = 0);

  [[nodiscard]] std::size_t rows() const noexcept override { return grid_.rows(); }
  [[nodiscard]] std::size_t cols() const noexcept override { return grid_.cols(); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override;
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override;

  /// The composed height at sample (row, col), in double (what sample() rounds to float).
  [[nodiscard]] double height(std::size_t row, std::size_t col) const;

 private:
  std::shared_ptr<const ComposedSurface> surface_;
  topo::TopoGrid grid_;
  topo::LatitudeType latType_ = topo::LatitudeType::Planetodetic;
  std::optional<topo::Placement> placement_;
  double metres_ = 0.0;
  std::shared_ptr<const Dataset> own_;  // null unless its samples may be read directly
  std::shared_ptr<const topo::SampleSource> ownSource_;
  topo::TopoGrid ownGrid0_{1, 1, 0.0, 0.0, 1.0, 1.0};
};

/// A planet pyramid of the composed surface over `grid` (level 0) and `levels` levels
/// (topo::coarserGrid() geometry, 0: until a level is at most 2 × 2 samples), each level's
/// samples composed at its own ground spacing (each dataset reading the pyramid level that
/// serves it). Ready for clod::HeightPyramid.
[[nodiscard]] topo::GridPyramid composedPlanetPyramid(
    const std::shared_ptr<const ComposedSurface>& surface, const topo::TopoGrid& grid,
    topo::LatitudeType latitudeType = topo::LatitudeType::Planetodetic, std::size_t levels = 0);

/// A planar pyramid of the composed surface over a placed grid (heights in the placement's
/// convention); draw it with clod::HeightPyramid(levels, placement).
/// `own`: the dataset whose lattice this is, if any (ComposedSamples' direct reads).
[[nodiscard]] topo::GridPyramid composedDemPyramid(
    const std::shared_ptr<const ComposedSurface>& surface, const topo::TopoGrid& grid,
    const topo::Placement& placement, std::size_t levels = 0,
    const std::shared_ptr<const Dataset>& own = nullptr);

/// A grid to draw a composed surface on, chosen for a view: a global latitude/longitude grid
/// away from the poles, a polar stereographic grid about a pole near one (a latitude/longitude
/// lattice converges there: its cells become slivers and its shading streaks).
struct DrawingFrame {
  topo::GridPyramid pyramid;                 ///< levels of composed samples
  std::optional<topo::Placement> placement;  ///< set for the polar grid (planar levels)
  double spacingMetres = 0.0;                ///< level 0's ground spacing
  bool polar = false;
};

/// The frame for a view centred near planetodetic latitude `lookLatDeg`: within 40° of a
/// pole (|lat| ≥ 50°) a polar stereographic grid about it (true scale at the pole, from the
/// pole down to 10° latitude, the pole at its centre sample), else a global
/// latitude/longitude grid; both at `spacingMetres` on the ground (the finest height
/// dataset's when ≤ 0, at least 1 mm). Throws InvalidArgument if the grid would exceed 2^31
/// samples a side.
[[nodiscard]] DrawingFrame drawingFrame(const std::shared_ptr<const ComposedSurface>& surface,
                                        double lookLatDeg, double spacingMetres = 0.0);

}  // namespace regolith::compose
