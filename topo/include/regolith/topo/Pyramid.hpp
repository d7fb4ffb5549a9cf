#pragma once
/// \file
/// Grid pyramids in topo terms: the seam between the stores that hold terrain and the
/// renderers that draw it. A store exports a grid as a GridPyramid (store::Pager::pyramid()),
/// in-memory grids build one with the same 2×2 rule, and renderers take either without
/// knowing where the samples come from.
///
/// Thread-safety: values; a level's source is as thread-safe as SampleSource promises (its
/// const members may be called from any thread).

#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

namespace regolith::topo {

/// One level of a pyramid: its geometry (spacing, origin, nodata) and its samples.
struct PyramidLevel {
  TopoGrid grid;
  std::shared_ptr<const SampleSource> source;
};

/// One grid at every resolution: level 0 is the finest, each level has twice the spacing of
/// the one below (levels built by downsample2x2()). A planar DEM grid (x east, y north, in
/// metres) has no body; a latitude/longitude planet grid (x longitude, y latitude, degrees)
/// names its body and how its latitudes are read.
struct GridPyramid {
  std::vector<PyramidLevel> levels;
  std::optional<Body> planetBody{};
  LatitudeType latitudeType = LatitudeType::Planetocentric;
};

/// The grid of the level above `fine`: (rows + 1) / 2 × (cols + 1) / 2 samples at twice the
/// spacing, sample (r, c) at the centre of fine samples (2r, 2c) … (2r + 1, 2c + 1). Same
/// nodata value.
[[nodiscard]] TopoGrid coarserGrid(const TopoGrid& fine);

/// The pyramid rule of Regolith (the store format's, docs/store-format.md "Pyramid levels",
/// and the renderer's for in-memory grids; one definition for both): coarse sample (r, c) is
/// the mean, summed in double, of the fine samples (2r + i, 2c + j), i, j ∈ {0, 1}, that lie
/// inside the fine grid and are not missing; it is `missingOut` only if all of them are.
///
/// `fine` is `fineRows` × `fineCols` row-major, starting at fine row 2·r0 and column 2·c0 of
/// a window whose coarse origin is (r0, c0); it must hold every fine sample of the `rows` ×
/// `cols` coarse window that exists (the window may end at the fine grid's edge). `isMissing`
/// tells missing samples (NaN, a nodata value). `coarse` receives rows × cols samples.
template <typename IsMissing>
void downsample2x2(const float* fine, std::size_t fineRows, std::size_t fineCols, float* coarse,
                   std::size_t rows, std::size_t cols, IsMissing isMissing, float missingOut) {
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      double sum = 0.0;
      int count = 0;
      for (std::size_t dr = 0; dr < 2 && 2 * r + dr < fineRows; ++dr) {
        for (std::size_t dc = 0; dc < 2 && 2 * c + dc < fineCols; ++dc) {
          const float v = fine[(2 * r + dr) * fineCols + 2 * c + dc];
          if (!isMissing(v)) {
            sum += static_cast<double>(v);
            ++count;
          }
        }
      }
      coarse[r * cols + c] = count > 0 ? static_cast<float>(sum / count) : missingOut;
    }
  }
}

}  // namespace regolith::topo
