#pragma once
/// \file
/// The CPU geometry of cut-outs (render::SceneRenderer::addCutOut): a DEM's cell mask, the skirt
/// that hangs from its data border, how deep that skirt must reach below a planet, and the map from
/// a planet fragment's eye coordinates to the DEM's mask cells. Pure functions of their arguments:
/// no GL, no I/O (the heights come in as arrays), so they are tested without a context.
/// Thread-safe.
///
/// Frames: a DEM's grid frame is (x east, y north, h up) metres of its topo::TopoGrid; a
/// planet's frame is body-fixed metres; eye coordinates are the camera's (x right, y up,
/// looking down −z), camera-relative.

#include <regolith/clod/CutOut.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/scenegraph/Pose.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <tuple>
#include <vector>

namespace regolith::render {

/// Which cells of a grid level have data: cell (r, c) spans samples r..r+1, c..c+1 and has
/// data if all four corner samples do. Row 0 is the grid's first (northernmost) row.
struct CellMask {
  std::size_t rows = 0, cols = 0;   ///< cells: samples − 1 each way
  std::vector<std::uint8_t> cells;  ///< row-major, 255 with data, 0 without
  /// False outside the mask (negative or too large indices).
  [[nodiscard]] bool has(long long row, long long col) const noexcept {
    return row >= 0 && col >= 0 && row < static_cast<long long>(rows) &&
           col < static_cast<long long>(cols) &&
           cells[static_cast<std::size_t>(row) * cols + static_cast<std::size_t>(col)] != 0;
  }
};

/// The cell mask of `heights` (grid.rows() × grid.cols(), row-major; a sample is missing if
/// grid.isNodata() says so, NaN included). Asserts that the sizes agree and the grid has at
/// least 2 × 2 samples.
[[nodiscard]] CellMask cellMask(const topo::TopoGrid& grid, std::span<const float> heights);

/// One skirt vertex as the scene mesh shader takes it (float, relative to BorderSkirt::anchor).
struct SkirtVertex {
  glm::vec3 position{0.0F};  ///< grid frame − anchor; bottom vertices: the top they hang from
  glm::vec3 normal{0.0F};    ///< the border side's outward normal (zero for the floor)
  float bottom = 0.0F;       ///< 1: drawn at the skirt's floor height (SkirtDrop), 0: as is
  glm::vec3 flange{0.0F};    ///< pits: outward direction, mitred at corners (sum of normals)
};

/// The skirt of a DEM level's data border, built once when the cut-out is added.
struct BorderSkirt {
  /// Grid frame: the mask's centre at h = 0; vertex positions are relative to it.
  glm::dvec3 anchor{0.0};
  /// Triangles: one vertical quad (two triangles, top edge on the border's samples, bottom
  /// edge with bottom = 1) per cell side between a cell with data and one without, in cell
  /// order (row by row; north, south, west, east), then a floor rectangle (bottom = 1,
  /// normal 0) under the bounding box of every cell with data. Empty if no cell has data.
  std::vector<SkirtVertex> vertices;
  /// Lowest and highest sample on the border (grid frame h; max/lowest float if none).
  float edgeLow = 0.0F, edgeHigh = 0.0F;
  /// Lowest corner sample of any cell with data (max float if none).
  float lowest = 0.0F;
};

/// The border skirt of `heights` (as for cellMask) with its mask `mask`.
[[nodiscard]] BorderSkirt borderSkirt(const topo::TopoGrid& grid, std::span<const float> heights,
                                      const CellMask& mask);

/// Largest side, in samples, of the pyramid level a cut-out's mask is built from.
inline constexpr std::size_t kMaxCutOutMaskSide = 4096;

/// The finest level of `dem` with at most `maxSide` samples a side, or its coarsest level if
/// none is that small (the caller rejects it then).
[[nodiscard]] std::size_t cutOutMaskLevel(const clod::HeightPyramid& dem,
                                          std::size_t maxSide = kMaxCutOutMaskSide);

/// The cut-out map (clod::CutOutTransform: eye → DEM mask cell, double precision) of mask
/// grid `maskGrid`, for a camera at `cameraInPlanet` whose eye axes in the planet frame are
/// the columns of `eyeToPlanet` (clod::Camera::rotation() transposed), with `planetToDem`
/// the pose planet frame → DEM grid frame.
[[nodiscard]] clod::CutOutTransform cutOutTransform(const scenegraph::Pose& planetToDem,
                                                    const glm::dmat3& eyeToPlanet,
                                                    const glm::dvec3& cameraInPlanet,
                                                    const topo::TopoGrid& maskGrid);

/// The planet sample (row, col) of pyramid level `level` whose cell holds the planet-frame
/// point `point` (the cell's north-west sample, clamped onto the grid).
struct PlanetCell {
  std::size_t level = 0, row = 0, col = 0;
  friend bool operator==(const PlanetCell&, const PlanetCell&) = default;
  friend bool operator<(const PlanetCell& a, const PlanetCell& b) noexcept {
    return std::tie(a.level, a.row, a.col) < std::tie(b.level, b.row, b.col);
  }
};
[[nodiscard]] PlanetCell planetCellUnder(const clod::HeightPyramid& planet, std::size_t level,
                                         const glm::dvec3& point);

/// One planet under a DEM, as the skirt's depth needs it.
struct PlanetUnderDem {
  double planetHeight = 0.0;    ///< the planet's sample at planetCellUnder(DEM origin), metres
  double demHeight = 0.0;       ///< the DEM origin's geodetic height on that planet, metres
  double spacingDegrees = 0.0;  ///< the planet level's latitude spacing (the level drawn)
  double radius = 1.0;          ///< the body's polar radius, metres
};

/// How a DEM's border skirt is drawn this frame (grid frame metres).
struct SkirtDrop {
  double floor = 0.0;   ///< height of the bottom vertices (and the floor), grid frame h
  double inward = 0.0;  ///< how far the second pass pulls bottom vertices inward
  /// A pit (the planet lies above the border): the flange's bottom vertices go `flange.x`
  /// outward and `flange.y` up from the border. Zero: no flange.
  glm::dvec2 flange{0.0};
};

/// The skirt's drop for DEM border `skirt` over the planets `planets`: below the lowest
/// sample and below every planet along the border (the planet's offset from the border,
/// plus the sag c²/8R of a chord across c, two of the planet's cells), and `inward` past the
/// coarsest DEM level drawn (`coarsestSpacing`) and the mask's cells (`maskSpacing`, doubled if the
/// mask comes from a coarser level than 0: `coarseMask`), then 1 m more.
[[nodiscard]] SkirtDrop skirtDrop(const BorderSkirt& skirt, std::span<const PlanetUnderDem> planets,
                                  double coarsestSpacing, double maskSpacing, bool coarseMask);

}  // namespace regolith::render
