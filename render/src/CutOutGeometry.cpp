#include <regolith/core/Assert.hpp>
#include <regolith/render/CutOutGeometry.hpp>

#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>

namespace regolith::render {

CellMask cellMask(const topo::TopoGrid& grid, std::span<const float> heights) {
  const std::size_t rows = grid.rows(), cols = grid.cols();
  REGOLITH_ASSERT(rows >= 2 && cols >= 2 && heights.size() == rows * cols,
                  "cellMask(): heights must hold the grid's samples, at least 2 × 2");
  CellMask m;
  m.rows = rows - 1;
  m.cols = cols - 1;
  m.cells.assign(m.rows * m.cols, 0);
  const auto missing = [&](std::size_t r, std::size_t c) {
    return grid.isNodata(heights[r * cols + c]);
  };
  for (std::size_t r = 0; r < m.rows; ++r)
    for (std::size_t c = 0; c < m.cols; ++c)
      m.cells[r * m.cols + c] =
          !missing(r, c) && !missing(r, c + 1) && !missing(r + 1, c) && !missing(r + 1, c + 1) ? 255
                                                                                               : 0;
  return m;
}

BorderSkirt borderSkirt(const topo::TopoGrid& grid, std::span<const float> heights,
                        const CellMask& mask) {
  const std::size_t cols = grid.cols(), cr = mask.rows, cc = mask.cols;
  REGOLITH_ASSERT(grid.rows() == cr + 1 && cols == cc + 1 && heights.size() == grid.rows() * cols,
                  "borderSkirt(): the mask and the heights must be the grid's");
  const auto at = [&](std::size_t r, std::size_t c) { return heights[r * cols + c]; };
  BorderSkirt s;
  s.anchor = {grid.x0() + 0.5 * static_cast<double>(cc) * grid.spacingX(),
              grid.y0() - 0.5 * static_cast<double>(cr) * grid.spacingY(), 0.0};
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  const auto point = [&](std::size_t r, std::size_t c) {
    const float v = at(r, c);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    const glm::dvec2 xy = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return glm::vec3(glm::dvec3(xy.x, xy.y, static_cast<double>(v)) - s.anchor);
  };
  // Border sides between sample points ka and kb (row·cols + col), outward normal n; the
  // flange direction at a point sums the normals of the sides meeting there (a mitre).
  struct Side {
    std::size_t ka, kb;
    glm::vec3 n;
  };
  std::vector<Side> sides;
  std::map<std::size_t, glm::vec3> mitre;
  const auto side = [&](std::size_t ra, std::size_t ca, std::size_t rb, std::size_t cb,
                        glm::vec3 n) {
    sides.push_back({ra * cols + ca, rb * cols + cb, n});
    mitre[ra * cols + ca] += n;
    mitre[rb * cols + cb] += n;
  };
  for (long long r = 0; r < static_cast<long long>(cr); ++r)
    for (long long c = 0; c < static_cast<long long>(cc); ++c) {
      if (!mask.has(r, c)) continue;
      const auto ur = static_cast<std::size_t>(r), uc = static_cast<std::size_t>(c);
      if (!mask.has(r - 1, c)) side(ur, uc, ur, uc + 1, {0, 1, 0});           // north
      if (!mask.has(r + 1, c)) side(ur + 1, uc, ur + 1, uc + 1, {0, -1, 0});  // south
      if (!mask.has(r, c - 1)) side(ur, uc, ur + 1, uc, {-1, 0, 0});          // west
      if (!mask.has(r, c + 1)) side(ur, uc + 1, ur + 1, uc + 1, {1, 0, 0});   // east
    }
  std::vector<SkirtVertex>& verts = s.vertices;
  for (const Side& sd : sides) {
    const glm::vec3 a = point(sd.ka / cols, sd.ka % cols), b = point(sd.kb / cols, sd.kb % cols);
    const glm::vec3 fa = mitre[sd.ka], fb = mitre[sd.kb];
    for (const auto& [q, bottom, f] : {std::tuple{a, 0.0F, fa},
                                       {b, 0.0F, fb},
                                       {b, 1.0F, fb},
                                       {a, 0.0F, fa},
                                       {b, 1.0F, fb},
                                       {a, 1.0F, fa}})
      verts.push_back({q, sd.n, bottom, f});
  }
  s.edgeLow = lo;
  s.edgeHigh = hi;
  // The floor: a rectangle under every cell with data, at the skirts' bottom. Whatever small
  // crack a DEM's own clipmap levels leave (where a level's border meets the grid's edge
  // its skirt is cut), the view through it ends on the floor, not on the planet's far side.
  s.lowest = std::numeric_limits<float>::max();
  double fx0 = std::numeric_limits<double>::max(), fx1 = -fx0, fy0 = fx0, fy1 = -fx0;
  for (std::size_t r = 0; r < cr; ++r)
    for (std::size_t c = 0; c < cc; ++c) {
      if (mask.cells[r * cc + c] == 0) continue;
      for (std::size_t k = 0; k < 4; ++k) {
        const std::size_t rr = r + k / 2, ccol = c + k % 2;
        s.lowest = std::min(s.lowest, at(rr, ccol));
        const glm::dvec2 xy = grid.sampleCentre(static_cast<double>(rr), static_cast<double>(ccol));
        fx0 = std::min(fx0, xy.x), fx1 = std::max(fx1, xy.x);
        fy0 = std::min(fy0, xy.y), fy1 = std::max(fy1, xy.y);
      }
    }
  if (!verts.empty()) {
    const auto corner = [&](double x, double y) {
      return glm::vec3(glm::dvec3(x, y, 0.0) - s.anchor);
    };
    for (const glm::vec3& q : {corner(fx0, fy0), corner(fx1, fy0), corner(fx1, fy1),
                               corner(fx0, fy0), corner(fx1, fy1), corner(fx0, fy1)})
      verts.push_back({q, glm::vec3(0.0F), 1.0F, glm::vec3(0.0F)});
  }
  return s;
}

std::size_t cutOutMaskLevel(const clod::HeightPyramid& dem, std::size_t maxSide) {
  std::size_t m = 0;
  while (m + 1 < dem.levelCount() &&
         std::max(dem.level(m).grid.rows(), dem.level(m).grid.cols()) > maxSide)
    ++m;
  return m;
}

clod::CutOutTransform cutOutTransform(const scenegraph::Pose& planetToDem,
                                      const glm::dmat3& eyeToPlanet,
                                      const glm::dvec3& cameraInPlanet,
                                      const topo::TopoGrid& maskGrid) {
  const topo::TopoGrid& g = maskGrid;
  const glm::dmat3 eyeToGrid = planetToDem.matrix() * eyeToPlanet;
  const glm::dvec3 camInGrid = planetToDem.apply(cameraInPlanet);
  // Grid frame → (col, row, h): fractionalIndex, written as a matrix and an offset.
  glm::dmat3 s(1.0);
  s[0][0] = 1.0 / g.spacingX();
  s[1][1] = -1.0 / g.spacingY();
  clod::CutOutTransform t;
  t.eyeToCell = s * eyeToGrid;
  t.cellOfCamera = s * camInGrid + glm::dvec3(-g.x0() / g.spacingX(), g.y0() / g.spacingY(), 0.0);
  return t;
}

PlanetCell planetCellUnder(const clod::HeightPyramid& planet, std::size_t level,
                           const glm::dvec3& point) {
  const auto& pg = planet.level(level).grid;
  const glm::dvec2 ll = planet.gridPoint(point);
  const glm::dvec2 idx = pg.fractionalIndex(ll.x, ll.y);
  PlanetCell cell;
  cell.level = level;
  cell.row = static_cast<std::size_t>(
      std::clamp(std::floor(idx.y), 0.0, static_cast<double>(pg.rows() - 1)));
  cell.col = static_cast<std::size_t>(
      std::clamp(std::floor(idx.x), 0.0, static_cast<double>(pg.cols() - 1)));
  return cell;
}

SkirtDrop skirtDrop(const BorderSkirt& skirt, std::span<const PlanetUnderDem> planets,
                    double coarsestSpacing, double maskSpacing, bool coarseMask) {
  const auto edgeLow = static_cast<double>(skirt.edgeLow);
  const auto edgeHigh = static_cast<double>(skirt.edgeHigh);
  double gap = 0.0, sag = 0.0, above = 0.0;
  for (const PlanetUnderDem& p : planets) {
    // How far the planet's surface can be from the DEM border: the planet's relief over
    // the cell under the DEM and the sag of a chord across its coarsest cell drawn.
    const double r = p.radius;
    const double cell = 2.0 * p.spacingDegrees * std::numbers::pi / 180.0 * r;
    sag = std::max(sag, cell * cell / (8.0 * r));
    gap = std::max({gap, std::abs(p.demHeight + edgeLow - p.planetHeight),
                    std::abs(p.demHeight + edgeHigh - p.planetHeight)});
    // How far the planet's chords surely lie above the border's highest point (a DEM set
    // lower than the planet: a pit whose walls rise from the border to the planet).
    // (The chord across one cell sags at most c²/8R below its samples.)
    above =
        std::max(above, p.planetHeight - 0.25 * cell * cell / (8.0 * r) - p.demHeight - edgeHigh);
  }
  SkirtDrop d;
  // Inward: past the coarsest drawn level's inset, and past a coarse mask's cells.
  d.inward = std::max(coarsestSpacing, coarseMask ? 2.0 * maskSpacing : maskSpacing);
  // The bottom: below the lowest sample and below the planet anywhere along the border.
  d.floor = std::min(static_cast<double>(skirt.lowest), edgeLow - gap - sag) - d.inward - 1.0;
  // A pit: a flange from the border rising outward under the planet (slope 1:4) to the
  // planet's lowest chord height there, so a view into the pit meets a wall.
  if (above > 0.0) d.flange = {std::max(4.0 * above, d.inward), above};
  return d;
}

}  // namespace regolith::render
