// The cut-out geometry (render/CutOutGeometry.hpp, and clod::cutOutProjection()) without a GL
// context: cell masks, the border skirt against a walk of the DEM's border written here, the
// skirt's drop against the exact sagitta of a chord, the eye → cell map against
// topo::TopoGrid::fractionalIndex and clod::Camera::project, and the planet cell under a point near
// the poles and the seam.
#include <regolith/clod/Camera.hpp>
#include <regolith/clod/CutOut.hpp>
#include <regolith/render/CutOutGeometry.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/matrix.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <set>
#include <utility>
#include <vector>

namespace regolith::render {
namespace {

using clod::Camera;
using clod::cutOutProjection;
using clod::CutOutTransform;
using clod::HeightPyramid;
using clod::SurfaceKind;

constexpr float kNodata = -9999.0F;

// A 7 × 9 DEM at 2 m spacing whose heights are the plane h = 5 + 0.1 x + 0.2 y (grid
// frame), with sample (3, 4) missing (nodata), so the four cells around it have no data and
// the border has an outer ring and a hole.
struct Dem {
  topo::TopoGrid grid{7, 9, 100.0, 300.0, 2.0, 2.0, kNodata};
  std::vector<float> heights;
  static double plane(const glm::dvec2& xy) { return 5.0 + 0.1 * xy.x + 0.2 * xy.y; }
  Dem() {
    for (std::size_t r = 0; r < grid.rows(); ++r)
      for (std::size_t c = 0; c < grid.cols(); ++c)
        heights.push_back(static_cast<float>(
            plane(grid.sampleCentre(static_cast<double>(r), static_cast<double>(c)))));
    heights[3 * grid.cols() + 4] = kNodata;
  }
};

TEST(CutOutGeometry, CellMaskHasACellWhereAllFourCornersHaveData) {
  Dem d;
  d.heights[0] = std::numeric_limits<float>::quiet_NaN();  // NaN is missing too
  const CellMask m = cellMask(d.grid, d.heights);
  ASSERT_EQ(m.rows, 6U);
  ASSERT_EQ(m.cols, 8U);
  std::size_t empty = 0;
  for (long long r = 0; r < 6; ++r)
    for (long long c = 0; c < 8; ++c) {
      const bool aroundHole = (r == 2 || r == 3) && (c == 3 || c == 4);
      const bool corner = r == 0 && c == 0;
      EXPECT_EQ(m.has(r, c), !aroundHole && !corner) << r << ", " << c;
      empty += m.has(r, c) ? 0U : 1U;
    }
  EXPECT_EQ(empty, 5U);
  EXPECT_FALSE(m.has(-1, 0));
  EXPECT_FALSE(m.has(0, 8));
  EXPECT_FALSE(m.has(6, 0));
}

TEST(CutOutGeometry, SkirtTopsLieOnTheDemBorderAndItsSidesFaceOutward) {
  const Dem d;
  const CellMask m = cellMask(d.grid, d.heights);
  const BorderSkirt s = borderSkirt(d.grid, d.heights, m);
  // The border, walked here cell side by cell side: the outer ring 2·(6 + 8) sides, the
  // hole's 8.
  const std::size_t sides = 2 * (6 + 8) + 8;
  ASSERT_EQ(s.vertices.size(), 6 * sides + 6);  // + the floor
  // The mask's centre, at h = 0.
  EXPECT_DOUBLE_EQ(s.anchor.x, 100.0 + 8.0);
  EXPECT_DOUBLE_EQ(s.anchor.y, 300.0 - 6.0);
  EXPECT_EQ(s.anchor.z, 0.0);

  double lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < 6 * sides; ++i) {
    const SkirtVertex& v = s.vertices[i];
    const glm::dvec3 p = glm::dvec3(v.position) + s.anchor;
    // On a sample of the grid, at the plane's height there (float).
    const glm::dvec2 f = d.grid.fractionalIndex(p.x, p.y);
    EXPECT_NEAR(f.x, std::round(f.x), 1e-5);
    EXPECT_NEAR(f.y, std::round(f.y), 1e-5);
    EXPECT_NEAR(p.z, Dem::plane({p.x, p.y}), 1e-4);
    lo = std::min(lo, p.z);
    hi = std::max(hi, p.z);
    // The side separates a cell with data (inside) from one without (outside): the cell
    // half a cell inward of the side's midpoint has data, half a cell outward has none.
    const SkirtVertex& a = s.vertices[i - i % 6];
    const SkirtVertex& b = s.vertices[i - i % 6 + 1];
    const glm::dvec3 mid = 0.5 * (glm::dvec3(a.position) + glm::dvec3(b.position)) + s.anchor;
    const glm::dvec3 n(v.normal);
    ASSERT_NEAR(glm::length(n), 1.0, 1e-12);
    const glm::dvec2 in = d.grid.fractionalIndex(mid.x - n.x, mid.y - n.y);
    const glm::dvec2 out = d.grid.fractionalIndex(mid.x + n.x, mid.y + n.y);
    EXPECT_TRUE(
        m.has(static_cast<long long>(std::floor(in.y)), static_cast<long long>(std::floor(in.x))));
    EXPECT_FALSE(m.has(static_cast<long long>(std::floor(out.y)),
                       static_cast<long long>(std::floor(out.x))));
    // Each side: two triangles, three bottom vertices (drawn at the floor) and three tops.
    EXPECT_TRUE(v.bottom == 0.0F || v.bottom == 1.0F);
  }
  for (std::size_t q = 0; q < sides; ++q) {
    float bottoms = 0.0F;
    for (std::size_t k = 0; k < 6; ++k) bottoms += s.vertices[6 * q + k].bottom;
    EXPECT_EQ(bottoms, 3.0F);
  }
  // Border heights: the plane over the outer ring and the hole's ring (all data samples
  // next to the missing one); the plane rises to the north-east.
  const auto planeAt = [&](double r, double c) { return Dem::plane(d.grid.sampleCentre(r, c)); };
  EXPECT_NEAR(s.edgeLow, planeAt(6.0, 0.0), 1e-4);   // south-west corner
  EXPECT_NEAR(s.edgeHigh, planeAt(0.0, 8.0), 1e-4);  // north-east corner
  EXPECT_NEAR(lo, s.edgeLow, 1e-4);
  EXPECT_NEAR(hi, s.edgeHigh, 1e-4);
  EXPECT_NEAR(s.lowest, planeAt(6.0, 0.0), 1e-4);
  // The outer corners' flanges are mitred: the north-west corner's is (−1, 1).
  bool nw = false;
  for (std::size_t i = 0; i < 6 * sides; ++i) {
    const glm::dvec3 p = glm::dvec3(s.vertices[i].position) + s.anchor;
    if (std::abs(p.x - 100.0) < 1e-6 && std::abs(p.y - 300.0) < 1e-6) {
      EXPECT_EQ(s.vertices[i].flange, glm::vec3(-1.0F, 1.0F, 0.0F));
      nw = true;
    }
  }
  EXPECT_TRUE(nw);
  // The floor: the data's bounding box (the whole grid), all bottom, no normal.
  std::set<std::pair<double, double>> corners;
  for (std::size_t i = 6 * sides; i < s.vertices.size(); ++i) {
    const SkirtVertex& v = s.vertices[i];
    EXPECT_EQ(v.bottom, 1.0F);
    EXPECT_EQ(v.normal, glm::vec3(0.0F));
    const glm::dvec3 p = glm::dvec3(v.position) + s.anchor;
    corners.insert({std::round(p.x * 1e3) / 1e3, std::round(p.y * 1e3) / 1e3});
  }
  EXPECT_EQ(corners, (std::set<std::pair<double, double>>{
                         {100.0, 288.0}, {116.0, 288.0}, {116.0, 300.0}, {100.0, 300.0}}));
}

TEST(CutOutGeometry, NoCellWithDataMeansNoSkirt) {
  const topo::TopoGrid grid(2, 3, 0.0, 0.0, 1.0, 1.0, kNodata);
  const std::vector<float> h{1.0F, kNodata, 1.0F, 1.0F, 1.0F, kNodata};
  const CellMask m = cellMask(grid, h);
  EXPECT_FALSE(m.has(0, 0));
  EXPECT_FALSE(m.has(0, 1));
  EXPECT_TRUE(borderSkirt(grid, h, m).vertices.empty());
}

// The exact sagitta of a chord of length c on a circle of radius R.
double sagitta(double c, double r) { return r - std::sqrt(r * r - 0.25 * c * c); }

TEST(CutOutGeometry, SkirtDropsBelowThePlanetAndTheLowestSample) {
  const Dem d;
  const BorderSkirt s = borderSkirt(d.grid, d.heights, cellMask(d.grid, d.heights));
  const double r = topo::Body::marsSphere().polarRadius();
  // Planets under the DEM's origin: one 40 m below the border's lowest point, one 200 m
  // above it, on 0.5° and 1° cells.
  const double demHeight = -1200.0;
  const std::vector<PlanetUnderDem> planets{
      {demHeight + static_cast<double>(s.edgeLow) - 40.0, demHeight, 0.5, r},
      {demHeight + static_cast<double>(s.edgeLow) + 200.0, demHeight, 1.0, r}};
  const double coarsest = 8.0, mask = 2.0;
  const SkirtDrop drop = skirtDrop(s, planets, coarsest, mask, false);
  EXPECT_EQ(drop.inward, 8.0);
  // Below each planet's surface anywhere along the border: its sample, less the sag of a
  // chord across two of its cells (exact sagitta), relative to the DEM's origin height.
  for (const PlanetUnderDem& p : planets) {
    const double c = 2.0 * p.spacingDegrees * std::numbers::pi / 180.0 * r;
    const double surface = p.planetHeight - sagitta(c, r) - demHeight;
    EXPECT_LT(drop.floor, surface - drop.inward);
  }
  EXPECT_LT(drop.floor, static_cast<double>(s.lowest) - drop.inward);
  // Not deeper than it must be: the largest offset of a planet from the border (200 m),
  // the largest chord's sag and the margins.
  const double c1 = 2.0 * std::numbers::pi / 180.0 * r;
  EXPECT_GE(drop.floor,
            static_cast<double>(s.edgeLow) - 200.0 - sagitta(c1, r) - drop.inward - 1.0 - 1e-6);
  // The second planet lies above the whole border (edgeHigh − edgeLow is 4 m): a pit, with
  // a flange rising to that planet's lowest chord (a quarter of the 2-cell sag).
  const double above = planets[1].planetHeight - 0.25 * c1 * c1 / (8.0 * r) - demHeight -
                       static_cast<double>(s.edgeHigh);
  ASSERT_GT(above, 0.0);
  EXPECT_NEAR(drop.flange.y, above, 1e-9);
  EXPECT_NEAR(drop.flange.x, std::max(4.0 * above, drop.inward), 1e-9);
  // A coarse mask (level > 0) doubles its cell in the inward reach; without planets there
  // is no flange and the floor is under the lowest sample.
  const SkirtDrop alone = skirtDrop(s, {}, 1.0, 3.0, true);
  EXPECT_EQ(alone.inward, 6.0);
  EXPECT_EQ(alone.flange, glm::dvec2(0.0));
  EXPECT_DOUBLE_EQ(alone.floor, static_cast<double>(s.edgeLow) - 6.0 - 1.0);
}

// A pose of planetary magnitude: a DEM frame 3.39e6 m from the centre, tilted.
scenegraph::Pose demInPlanet() {
  scenegraph::Pose p;
  p.translation = {2.1e6, -1.3e6, 2.3e6};
  p.rotation = glm::normalize(glm::dquat(0.8, 0.1, -0.35, 0.2));
  return p;
}

TEST(CutOutGeometry, EyeToCellAgreesWithTheGridsFractionalIndexInDouble) {
  const topo::TopoGrid g(601, 401, -600.0, 800.0, 2.0, 4.0);
  const scenegraph::Pose demToPlanet = demInPlanet();
  const scenegraph::Pose planetToDem = demToPlanet.inverse();
  Camera cam;
  cam.position = demToPlanet.apply({-900.0, 1500.0, 700.0});
  cam.target = demToPlanet.apply({100.0, -200.0, 0.0});
  cam.up = glm::normalize(demToPlanet.translation);
  const glm::dmat3 worldToEye = cam.rotation();
  const CutOutTransform t =
      cutOutTransform(planetToDem, glm::transpose(worldToEye), cam.position, g);
  double worst = 0.0;
  for (const glm::dvec3 q : {glm::dvec3(-600.0, 800.0, 0.0), glm::dvec3(200.0, -399.0, 13.0),
                             glm::dvec3(-1.0, 1.0, -50.0), glm::dvec3(0.3, 0.7, 2.0),
                             glm::dvec3(1500.0, -2000.0, 300.0)}) {
    const glm::dvec3 p = demToPlanet.apply(q);  // a planet-frame point
    const glm::dvec3 eye = worldToEye * (p - cam.position);
    const glm::dvec3 cell = t.eyeToCell * eye + t.cellOfCamera;
    const glm::dvec3 inGrid = planetToDem.apply(p);
    const glm::dvec2 want = g.fractionalIndex(inGrid.x, inGrid.y);
    worst = std::max({worst, std::abs(cell.x - want.x), std::abs(cell.y - want.y)});
    EXPECT_NEAR(cell.z, q.z, 1e-6);
  }
  // Camera-relative in double: a millionth of a cell, though the frames are 3.4e6 m apart.
  EXPECT_LT(worst, 1e-6);
  // Cast to float as the shader takes it, a fragment 2 km away still lands within 1e-3 of
  // its cell.
  const glm::dvec3 p = demToPlanet.apply({150.0, 250.0, 0.0});
  const glm::vec3 eye(worldToEye * (p - cam.position));
  const glm::vec3 cell = glm::mat3(t.eyeToCell) * eye + glm::vec3(t.cellOfCamera);
  const glm::dvec3 inGrid = planetToDem.apply(p);
  const glm::dvec2 want = g.fractionalIndex(inGrid.x, inGrid.y);
  EXPECT_NEAR(cell.x, want.x, 1e-3);
  EXPECT_NEAR(cell.y, want.y, 1e-3);
}

TEST(CutOutGeometry, ProjectionRebuildsTheEyePositionFromAFragment) {
  // A fragment's window position and reversed-Z depth (clod::Camera::project: x right and
  // y down from the top-left, depth near / distance) give back its eye position through
  // the cut-out shader's formula and cutOutProjection().
  Camera cam;
  cam.position = {10.0, -20.0, 30.0};
  cam.target = {0.0, 0.0, 0.0};
  cam.up = {0.0, 0.0, 1.0};
  cam.fovYDegrees = 38.0;
  cam.width = 320;
  cam.height = 200;
  cam.near = 0.5;
  const glm::dvec2 viewportOrigin{40.0, 25.0};  // a viewport inside a larger framebuffer
  const glm::dvec3 proj = cutOutProjection(cam.near, cam.fovYDegrees, cam.width, cam.height);
  for (const glm::dvec3 p : {glm::dvec3(0.0), glm::dvec3(3.0, 2.0, -1.0),
                             glm::dvec3(-8.0, 5.0, 4.0), glm::dvec3(12.0, -9.0, 20.0)}) {
    const glm::dvec3 px = cam.project(p);
    const glm::dvec2 frag = viewportOrigin + glm::dvec2(px.x, cam.height - px.y);  // GL: y up
    // The shader (CutOutShader.hpp): d = near / depth; ndc from the viewport; eye.
    const double d = proj.x / px.z;
    const glm::dvec2 ndc =
        2.0 * (frag - viewportOrigin) / glm::dvec2(cam.width, cam.height) - glm::dvec2(1.0);
    const glm::dvec3 eye(ndc.x * d * proj.y, ndc.y * d * proj.z, -d);
    const glm::dvec3 want = cam.rotation() * (p - cam.position);
    EXPECT_NEAR(glm::length(eye - want), 0.0, 1e-9 * glm::length(want));
  }
}

TEST(CutOutGeometry, PlanetCellUnderAPointClampsAtThePolesAndTheSeam) {
  const topo::Body mars = topo::Body::marsSphere();
  const double r = mars.polarRadius();
  const topo::TopoGrid grid(180, 360, -179.5, 89.5, 1.0, 1.0);
  auto samples =
      topo::InMemorySamples::fromFunction(180, 360, [](std::size_t, std::size_t) { return 0.0F; });
  const auto planet = HeightPyramid::fromSamples(grid, samples, SurfaceKind::Planet, mars);
  const auto at = [&](double latDeg, double lonDeg) {
    const double la = latDeg * std::numbers::pi / 180.0, lo = lonDeg * std::numbers::pi / 180.0;
    return (r + 5000.0) *
           glm::dvec3(std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la));
  };
  // 10.3° N, 20.7° W: row 89.5 − 10.3 = 79.2 → 79, col 179.5 − 20.7 = 158.8 → 158.
  EXPECT_EQ(planetCellUnder(planet, 0, at(10.3, -20.7)), (PlanetCell{0, 79, 158}));
  // Level 1: 2° samples, the first at the mean of level 0's first two (89° N, 179° W):
  // row (89 − 10.3) / 2 = 39.35 → 39, col (179 − 20.7) / 2 = 79.15 → 79.
  ASSERT_DOUBLE_EQ(planet.level(1).grid.y0(), 89.0);
  ASSERT_DOUBLE_EQ(planet.level(1).grid.x0(), -179.0);
  EXPECT_EQ(planetCellUnder(planet, 1, at(10.3, -20.7)), (PlanetCell{1, 39, 79}));
  // Beyond the first and last sample rows and columns: clamped onto the grid.
  EXPECT_EQ(planetCellUnder(planet, 0, at(89.9, -179.9)), (PlanetCell{0, 0, 0}));
  EXPECT_EQ(planetCellUnder(planet, 0, at(-89.9, 179.9)), (PlanetCell{0, 179, 359}));
  EXPECT_EQ(planetCellUnder(planet, 0, at(-90.0, 0.0)).row, 179U);
}

TEST(CutOutGeometry, MaskLevelIsTheFinestSmallEnoughLevel) {
  const topo::TopoGrid grid(9, 17, 0.0, 0.0, 1.0, 1.0);
  auto samples = topo::InMemorySamples::fromFunction(
      9, 17, [](std::size_t r, std::size_t c) { return static_cast<float>(r + c); });
  const auto dem = HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane);
  ASSERT_GE(dem.levelCount(), 3U);
  EXPECT_EQ(cutOutMaskLevel(dem, 17), 0U);
  EXPECT_EQ(cutOutMaskLevel(dem, 16), 1U);  // level 1: 5 × 9
  EXPECT_EQ(cutOutMaskLevel(dem, 9), 1U);
  EXPECT_EQ(cutOutMaskLevel(dem, 8), 2U);
  EXPECT_EQ(cutOutMaskLevel(dem, 1), dem.levelCount() - 1);  // none: the coarsest
}

}  // namespace
}  // namespace regolith::render
