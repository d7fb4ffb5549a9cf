// Queries at the edges of their domain (issue 16): points exactly on a reported grid edge,
// height and normal validity next to holes, body-frame normals next to a pole a DEM reaches.
// Oracles: the edges TopoGrid reports, planes (whose one-sided differences are exact) and
// the body's own radial "up" for a flat DEM.
#include <regolith/core/Error.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>
#include <vector>

using namespace regolith;
using namespace regolith::topo;

namespace {

constexpr Interpolation kAll[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                  Interpolation::Bicubic};
constexpr double kDeg = std::numbers::pi / 180.0;

Placement marsPlane() {
  return Placement(LocalTangentPlane(Body::marsSphere(), {-2.05, -5.5, 0.0}, 0.0));
}

std::shared_ptr<InMemorySamples> flat(std::size_t rows, std::size_t cols, float v = 10.0F) {
  return std::make_shared<InMemorySamples>(rows, cols, std::vector<float>(rows * cols, v));
}

// Grid origins and spacings whose edges round: origins far from zero relative to the spacing.
struct GridCase {
  double x0, y0, dx, dy;
  std::size_t rows, cols;
};
const std::vector<GridCase> kDemGrids = {
    {0.0, 0.0, 1.0, 1.0, 5, 7},
    {100000.3, -2000000.7, 0.3, 0.3, 11, 13},
    {-3396190.123, 1234567.891, 0.25, 0.7, 9, 4},
    {123456.789, 987654.321, 463.3127, 463.3127, 30, 40},
    {5e6 + 0.1, -5e6 - 0.1, 1.0 / 3.0, 0.1, 17, 3},
    {-0.05, 0.05, 0.1, 0.1, 1, 1},
};

// The four corners of the pixel extent as TopoGrid reports them.
std::vector<glm::dvec2> corners(const TopoGrid& g) {
  return {
      {g.west(), g.north()}, {g.east(), g.north()}, {g.west(), g.south()}, {g.east(), g.south()}};
}

// Whether any of a grid's reported edges lands beyond ±0.5 in fractional indices when
// computed naively: the rounding the slack must absorb.
bool edgeRoundsOutward(const TopoGrid& g) {
  const double cmax = static_cast<double>(g.cols()) - 0.5,
               rmax = static_cast<double>(g.rows()) - 0.5;
  for (const glm::dvec2& c : corners(g)) {
    const glm::dvec2 f = g.fractionalIndex(c.x, c.y);
    if (f.x < -0.5 || f.x > cmax || f.y < -0.5 || f.y > rmax) return true;
  }
  for (const double r : {-0.5, rmax}) {
    for (const double c : {-0.5, cmax}) {
      const glm::dvec2 p = g.sampleCentre(r, c);
      const glm::dvec2 f = g.fractionalIndex(p.x, p.y);
      if (f.x < -0.5 || f.x > cmax || f.y < -0.5 || f.y > rmax) return true;
    }
  }
  return false;
}

}  // namespace

// Item 3: the corners that `info` prints (west/east/north/south) are inside, and so are the
// pixel-extent corners given as grid indices (−0.5, rows − 0.5); one part in 1e6 of a pixel
// further out is outside.
TEST(EdgesOfDomain, DemEdgesAreInsideInEveryCoordinateMode) {
  bool anyRounds = false;
  for (const GridCase& gc : kDemGrids) {
    const TopoGrid g(gc.rows, gc.cols, gc.x0, gc.y0, gc.dx, gc.dy);
    anyRounds = anyRounds || edgeRoundsOutward(g);
    const TopoDem dem(g, marsPlane(), flat(gc.rows, gc.cols));
    std::vector<glm::dvec2> pts = corners(g);
    const double rmax = static_cast<double>(gc.rows) - 0.5,
                 cmax = static_cast<double>(gc.cols) - 0.5;
    for (const double r : {-0.5, rmax}) {
      for (const double c : {-0.5, cmax}) pts.push_back(g.sampleCentre(r, c));  // grid mode
    }
    for (const glm::dvec2& p : pts) {
      EXPECT_TRUE(g.contains(p.x, p.y)) << gc.x0 << " " << p.x << " " << p.y;
      for (const Interpolation k : kAll) {
        EXPECT_EQ(dem.height(p.x, p.y, k).status, QueryStatus::Ok) << gc.x0 << " " << p.x;
        const SurfaceSample s = dem.surface(p.x, p.y, k);
        EXPECT_EQ(s.status, QueryStatus::Ok) << gc.x0 << " " << p.x << " " << p.y;
        EXPECT_EQ(s.height, 10.0);
      }
    }
    // Batch calls agree (their fast path ends before the edges).
    std::vector<double> xs, ys;
    for (const glm::dvec2& p : pts) xs.push_back(p.x), ys.push_back(p.y);
    std::vector<double> h(xs.size());
    std::vector<QueryStatus> st(xs.size());
    for (const Interpolation k : kAll) {
      dem.heights(xs, ys, h, st, k);
      for (const QueryStatus s : st) EXPECT_EQ(s, QueryStatus::Ok) << gc.x0;
    }
    // Just beyond: outside.
    const double eps = 1e-6;
    for (const glm::dvec2& p : {g.sampleCentre(-0.5 - eps, 0.0), g.sampleCentre(0.0, -0.5 - eps),
                                g.sampleCentre(rmax + eps, 0.0), g.sampleCentre(0.0, cmax + eps)}) {
      EXPECT_FALSE(g.contains(p.x, p.y));
      EXPECT_EQ(dem.height(p.x, p.y, Interpolation::Bicubic).status, QueryStatus::OutsideGrid);
    }
  }
  // The cases above must include edges whose fractional index rounds beyond ±0.5, or this
  // test could not fail without the slack.
  EXPECT_TRUE(anyRounds);
}

TEST(EdgesOfDomain, PlanetEdgesAreInsideAsLongitudeAndLatitude) {
  bool anyRounds = false;
  const std::vector<GridCase> grids = {
      {137.123, -4.567, 0.00123, 0.00117, 40, 30},  // a regional grid
      {-179.9, 59.9, 0.2, 0.2, 50, 100},
      {100.0 + 1.0 / 3.0, 10.0 / 3.0, 1.0 / 7.0, 1.0 / 9.0, 8, 9},
  };
  for (const GridCase& gc : grids) {
    const TopoGrid g(gc.rows, gc.cols, gc.x0, gc.y0, gc.dx, gc.dy);
    anyRounds = anyRounds || edgeRoundsOutward(g);
    const TopoPlanet planet(g, Body::marsSphere(), LatitudeType::Planetocentric,
                            flat(gc.rows, gc.cols));
    std::vector<glm::dvec2> pts = corners(g);
    for (const double r : {-0.5, static_cast<double>(gc.rows) - 0.5}) {
      for (const double c : {-0.5, static_cast<double>(gc.cols) - 0.5}) {
        pts.push_back(g.sampleCentre(r, c));
      }
    }
    for (const glm::dvec2& p : pts) {
      for (const Interpolation k : kAll) {
        const SurfaceSample s = planet.surface({p.y, p.x}, k);
        EXPECT_EQ(s.status, QueryStatus::Ok) << gc.x0 << " lon " << p.x << " lat " << p.y;
        EXPECT_EQ(s.height, 10.0);
      }
    }
    const double eps = 1e-6;
    for (const glm::dvec2& p : {g.sampleCentre(-0.5 - eps, 0.0), g.sampleCentre(0.0, -0.5 - eps),
                                g.sampleCentre(static_cast<double>(gc.rows) - 0.5 + eps, 0.0),
                                g.sampleCentre(0.0, static_cast<double>(gc.cols) - 0.5 + eps)}) {
      EXPECT_EQ(planet.height({p.y, p.x}).status, QueryStatus::OutsideGrid) << p.x << " " << p.y;
    }
  }
  EXPECT_TRUE(anyRounds);
}

// Item 8: a valid height next to a hole stays valid, and its normal comes from a one-sided
// stencil. On a plane every one-sided difference is exact, so the normal must be the plane's.
TEST(EdgesOfDomain, HeightNextToAHoleIsValidWithAOneSidedNormal) {
  const std::size_t rows = 9, cols = 9;
  const TopoGrid g(rows, cols, 0.0, 0.0, 2.0, 2.0, -9999.0F);
  // Slopes chosen so that every sample is exact in float32.
  const auto plane = [](double x, double y) { return 100.0 + 0.25 * x - 0.5 * y; };
  auto s = InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
    if (r == 4 && c == 4) return -9999.0F;  // one hole in the middle
    const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return static_cast<float>(plane(p.x, p.y));
  });
  const TopoDem dem(g, marsPlane(), s);
  const glm::dvec3 expected = glm::normalize(glm::dvec3(-0.25, 0.5, 1.0));
  // Sample centres around the hole: every kernel's height is the sample itself.
  for (const auto& [r, c] : std::vector<std::pair<double, double>>{
           {3, 4}, {5, 4}, {4, 3}, {4, 5}, {3, 3}, {5, 5}, {2, 4}, {4, 6}}) {
    const glm::dvec2 p = g.sampleCentre(r, c);
    for (const Interpolation k : kAll) {
      const SurfaceSample q = dem.surface(p.x, p.y, k);
      ASSERT_EQ(q.status, QueryStatus::Ok) << r << "," << c << " kernel " << int(k);
      EXPECT_EQ(q.height, plane(p.x, p.y));
      ASSERT_EQ(q.normalStatus, QueryStatus::Ok) << r << "," << c << " kernel " << int(k);
      EXPECT_LT(glm::length(q.normal - expected), 1e-12) << r << "," << c << " kernel " << int(k);
    }
  }
  // On the edge of the hole's cell with zero weight on the hole (bilinear): valid, and the
  // normal is the plane through the cell's three samples.
  const glm::dvec2 onEdge = g.sampleCentre(3.0, 3.5);
  const SurfaceSample b = dem.surface(onEdge.x, onEdge.y, Interpolation::Bilinear);
  ASSERT_TRUE(b.valid());
  ASSERT_TRUE(b.normalValid());
  EXPECT_LT(glm::length(b.normal - expected), 1e-12);
  // The hole itself: neither.
  const glm::dvec2 hole = g.sampleCentre(4.0, 4.0);
  for (const Interpolation k : kAll) {
    const SurfaceSample q = dem.surface(hole.x, hole.y, k);
    EXPECT_EQ(q.status, QueryStatus::Nodata);
    EXPECT_EQ(q.normalStatus, QueryStatus::Nodata);
    EXPECT_TRUE(std::isnan(q.height) && std::isnan(q.normal.x));
  }
}

TEST(EdgesOfDomain, IsolatedSampleHasAHeightButNoNormal) {
  // A valid sample whose four neighbours are holes: its height is valid (every kernel has
  // the one sample it weighs), but no stencil gives it a slope.
  const std::size_t n = 5;
  std::vector<float> data(n * n, 1.0F);
  for (const auto& [r, c] : std::vector<std::pair<std::size_t, std::size_t>>{
           {1, 2}, {3, 2}, {2, 1}, {2, 3}, {1, 1}, {1, 3}, {3, 1}, {3, 3}}) {
    data[r * n + c] = std::numeric_limits<float>::quiet_NaN();
  }
  const TopoGrid g(n, n, 0.0, 0.0, 1.0, 1.0);
  const TopoDem dem(g, marsPlane(), std::make_shared<InMemorySamples>(n, n, data));
  const glm::dvec2 p = g.sampleCentre(2.0, 2.0);
  std::vector<double> xs{p.x}, ys{p.y}, h(1);
  std::vector<glm::dvec3> nrm(1);
  std::vector<QueryStatus> st(1), nst(1);
  for (const Interpolation k : kAll) {
    dem.surfaces(xs, ys, h, nrm, st, k, NormalFrame::Grid, nst);
    EXPECT_EQ(st[0], QueryStatus::Ok) << int(k);
    EXPECT_EQ(h[0], 1.0);
    EXPECT_EQ(nst[0], QueryStatus::Nodata) << int(k);
    EXPECT_TRUE(std::isnan(nrm[0].x));
  }
}

TEST(EdgesOfDomain, PlanetHeightNextToAHoleIsValid) {
  // A 2° global grid with one hole; at the neighbouring sample centres heights are valid and
  // the (bilinear, bicubic) normals fall back to the cell's gradient, nearest's to one side.
  const std::size_t rows = 90, cols = 180;
  const TopoGrid g(rows, cols, -179.0, 89.0, 2.0, 2.0);
  auto s = InMemorySamples::fromFunction(rows, cols, [](std::size_t r, std::size_t c) {
    return r == 40 && c == 100 ? std::numeric_limits<float>::quiet_NaN() : 5.0F;
  });
  const TopoPlanet planet(g, Body::marsSphere(), LatitudeType::Planetocentric, s);
  const glm::dvec2 p = g.sampleCentre(40.0, 101.0);
  for (const Interpolation k : kAll) {
    const SurfaceSample q = planet.surface({p.y, p.x}, k);
    EXPECT_EQ(q.status, QueryStatus::Ok) << int(k);
    EXPECT_EQ(q.height, 5.0);
    ASSERT_EQ(q.normalStatus, QueryStatus::Ok) << int(k);
    EXPECT_LT(glm::length(q.normal - glm::dvec3(0.0, 0.0, 1.0)), 1e-12);
  }
}

// Item 4: body-frame normals close to the pole an equirectangular DEM reaches. A flat DEM's
// body-frame normal is the ellipsoid's up at the point; the finite-difference Jacobian once
// stepped beyond the pole and threw DomainError for the whole batch.
TEST(EdgesOfDomain, BodyNormalsNextToAPoleAnEquirectangularDemReaches) {
  const Body body = Body::marsSphere();
  const double r = body.equatorialRadius();
  const Equirectangular eqc(r, 0.0, 0.0);
  const double yPole = r * 90.0 * kDeg;
  const double dx = 2.0;
  const std::size_t rows = 50, cols = 50;
  // North edge of the pixel extent exactly at the pole.
  const TopoGrid g(rows, cols, -50.0, yPole - 0.5 * dx, dx, dx);
  const TopoDem dem(g, Placement(body, eqc), flat(rows, cols, 0.0F));
  std::vector<double> xs, ys;
  for (const double off : {0.0, 1e-9, 1e-3, 0.1, 0.3, 0.49, 0.7, 1.0, 3.0}) {
    xs.push_back(-3.0);
    ys.push_back(yPole - off);
  }
  std::vector<double> h(xs.size());
  std::vector<glm::dvec3> n(xs.size());
  std::vector<QueryStatus> st(xs.size()), nst(xs.size());
  ASSERT_NO_THROW(
      dem.surfaces(xs, ys, h, n, st, Interpolation::Bilinear, NormalFrame::BodyFixed, nst));
  for (std::size_t i = 0; i < xs.size(); ++i) {
    EXPECT_EQ(st[i], QueryStatus::Ok) << ys[i];
    ASSERT_EQ(nst[i], QueryStatus::Ok) << yPole - ys[i];
    const Geodetic geo = dem.placement().toGeodetic(xs[i], ys[i], 0.0);
    const glm::dvec3 up = body.enuFrame(geo.latDeg, geo.lonDeg)[2];
    EXPECT_NEAR(glm::length(n[i]), 1.0, 1e-12);
    // At the pole itself x collapses to one point (∂P/∂x = 0): the normal there is only as
    // good as the one-sided difference, so the bound is looser within a metre of it.
    EXPECT_LT(glm::length(n[i] - up), yPole - ys[i] < 1.0 ? 1e-6 : 1e-9) << yPole - ys[i];
  }
}

namespace {
// A 2° global planet grid (row centres at ±89°, a polar cap beyond) of a field smooth on
// the sphere, so that it has one value and one gradient at each pole.
TopoPlanet capPlanet() {
  const std::size_t rows = 90, cols = 180;
  const TopoGrid g(rows, cols, -179.0, 89.0, 2.0, 2.0);
  auto s = InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
    const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    const double lat = p.y * kDeg, lon = p.x * kDeg;
    const glm::dvec3 u(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
    return static_cast<float>(1000.0 * u.x + 700.0 * u.y * u.z + 300.0 * u.z * u.z);
  });
  return {g, Body::marsSphere(), LatitudeType::Planetocentric, s};
}

double angle(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// Angle between body-frame normals at two points.
double normalJump(const TopoPlanet& p, Interpolation k, LatLon a, LatLon b) {
  const SurfaceSample sa = p.surface(a, k, NormalFrame::BodyFixed);
  const SurfaceSample sb = p.surface(b, k, NormalFrame::BodyFixed);
  EXPECT_TRUE(sa.normalValid() && sb.normalValid());
  return angle(sa.normal, sb.normal);
}
}  // namespace

// Item 2: a pole is one point, with one body-frame normal whatever longitude is passed.
TEST(EdgesOfDomain, OneNormalAtAPoleWhateverTheLongitude) {
  const TopoPlanet p = capPlanet();
  for (const Interpolation k : kAll) {
    for (const double lat : {90.0, -90.0}) {
      const SurfaceSample s0 = p.surface({lat, 0.0}, k, NormalFrame::BodyFixed);
      ASSERT_TRUE(s0.normalValid());
      for (const double lon : {45.0, -77.7, 123.0, 180.0, 359.0}) {
        const SurfaceSample s = p.surface({lat, lon}, k, NormalFrame::BodyFixed);
        EXPECT_EQ(s.height, s0.height);
        ASSERT_TRUE(s.normalValid());
        EXPECT_LT(angle(s.normal, s0.normal), 1e-15) << int(k) << " " << lat << " " << lon;
      }
    }
  }
}

// Item 1: bicubic normals are continuous across the polar cap's edge (the outermost row of
// centres, ±89° here) and across the pole: the largest turn over a 1e-6° step there is at
// most twice the largest over the same step elsewhere (across sample rows and between them).
TEST(EdgesOfDomain, BicubicNormalsAreContinuousAcrossTheCapEdgeAndThePole) {
  const TopoPlanet p = capPlanet();
  const double step = 1e-6;
  const Interpolation k = Interpolation::Bicubic;
  double elsewhere = 0.0;
  for (const double lat : {87.0, 85.0, 60.3, 1.0, -45.0, -87.0}) {
    for (const double lon : {-179.0, -33.3, 0.0, 77.0, 150.5}) {
      elsewhere =
          std::max(elsewhere, normalJump(p, k, {lat - 0.5 * step, lon}, {lat + 0.5 * step, lon}));
    }
  }
  ASSERT_GT(elsewhere, 0.0);
  double atCap = 0.0, acrossPole = 0.0;
  for (const double lon : {-179.0, -33.3, 0.0, 77.0, 150.5}) {
    for (const double edge : {89.0, -89.0}) {
      atCap = std::max(atCap, normalJump(p, k, {edge - 0.5 * step, lon}, {edge + 0.5 * step, lon}));
    }
    for (const double pole : {90.0, -90.0}) {
      const double lat = pole - std::copysign(0.5 * step, pole);
      acrossPole = std::max(acrossPole, normalJump(p, k, {lat, lon}, {lat, lon + 180.0}));
    }
  }
  EXPECT_LE(atCap, 2.0 * elsewhere) << "elsewhere " << elsewhere;
  EXPECT_LE(acrossPole, 2.0 * elsewhere) << "elsewhere " << elsewhere;
  std::printf(
      "[ measured ] cap.bicubic_normal_jump_1e-6deg: cap edge %.3e, across pole %.3e, "
      "elsewhere %.3e rad\n",
      atCap, acrossPole, elsewhere);
}

// Item 10: longitudes of any size reduce exactly as fmod(lon, 360) does, and subnormal
// spacings are refused (they put every point outside).
TEST(EdgesOfDomain, HugeLongitudesReduceExactly) {
  for (const double lon : {1e308, -1e308, 1.7976931348623157e308, 1e20 + 0.5, -7.3e15, 540.0}) {
    const double r = std::fmod(lon, 360.0);
    const double expected = r >= 180.0 ? r - 360.0 : (r < -180.0 ? r + 360.0 : r);
    EXPECT_NEAR(wrapLongitude180(lon), expected, 2e-13) << lon;  // within an ulp of 540
    EXPECT_EQ(wrapLongitude360(lon), r < 0.0 ? r + 360.0 : r) << lon;
  }
  const TopoPlanet p = capPlanet();
  for (const double lon : {1e308, -1e308, 1e20 + 0.5}) {
    const double same = wrapLongitude180(lon);
    for (const Interpolation k : kAll) {
      const SurfaceSample a = p.surface({12.3, lon}, k, NormalFrame::BodyFixed);
      const SurfaceSample b = p.surface({12.3, same}, k, NormalFrame::BodyFixed);
      EXPECT_EQ(a.height, b.height) << lon;
      EXPECT_EQ(a.normal, b.normal) << lon;
    }
  }
}

TEST(EdgesOfDomain, SubnormalSpacingsAreRefused) {
  try {
    (void)TopoGrid(2, 2, 0.0, 0.0, 5e-324, 1.0);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "TopoGrid(): spacing is (5e-324, 1), expected normal doubles (at least "
                 "2.2250738585072014e-308)");
  }
  EXPECT_NO_THROW((void)TopoGrid(2, 2, 0.0, 0.0, 2.2250738585072014e-308, 1.0));
}

// Item 7 in C++: a DEM cell the placement cannot map (an equirectangular grid reaching past
// the pole) has a height in the grid's terms but no body-frame normal: normalStatus
// Unmappable for that point, and the rest of the batch is answered.
TEST(EdgesOfDomain, AnUnmappablePointNeverFailsABatch) {
  const Body body = Body::marsSphere();
  const double r = body.equatorialRadius();
  const double yPole = r * 90.0 * kDeg;
  const std::size_t rows = 20, cols = 10;
  const TopoGrid g(rows, cols, 0.0, yPole + 5000.0, 1000.0, 1000.0);  // 5 km beyond the pole
  const TopoDem dem(g, Placement(body, Equirectangular(r, 0.0, 0.0)), flat(rows, cols, 3.0F));
  const std::vector<double> xs{2000.0, 2000.0, 2000.0}, ys{yPole + 2500.0, yPole - 4000.0, 1e9};
  std::vector<double> h(3);
  std::vector<glm::dvec3> n(3);
  std::vector<QueryStatus> st(3), nst(3);
  ASSERT_NO_THROW(
      dem.surfaces(xs, ys, h, n, st, Interpolation::Bicubic, NormalFrame::BodyFixed, nst));
  EXPECT_EQ(st,
            (std::vector<QueryStatus>{QueryStatus::Ok, QueryStatus::Ok, QueryStatus::OutsideGrid}));
  EXPECT_EQ(nst, (std::vector<QueryStatus>{QueryStatus::Unmappable, QueryStatus::Ok,
                                           QueryStatus::OutsideGrid}));
  EXPECT_EQ(h[0], 3.0);
  EXPECT_TRUE(std::isnan(n[0].x));
  EXPECT_NEAR(glm::length(n[1]), 1.0, 1e-12);
  EXPECT_STREQ(statusName(nst[0]), "unmappable");
}

// Item 8 with rounding: a sample centre given as grid indices lands a few ulps off the sample
// line on a UTM-like grid, so a hole beside it got a weight of 1e-15 and made it invalid.
// On the line to a few ulps is on it: every kernel's height there is the sample.
TEST(EdgesOfDomain, SampleCentresNextToHolesAreValidDespiteRounding) {
  const std::size_t rows = 40, cols = 40;
  std::size_t offLine = 0, checked = 0;
  for (const auto& [x0, y0, d] :
       std::vector<std::tuple<double, double, double>>{{500123.45, 4987654.35, 0.3},
                                                       {123456.789, -987654.321, 463.3127},
                                                       {4e6 + 0.1, 0.7, 1.0 / 3.0}}) {
    const TopoGrid g(rows, cols, x0, y0, d, d, -9999.0F);
    std::vector<float> data(rows * cols, 0.0F);
    for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<float>(i % 97);
    std::vector<std::pair<std::size_t, std::size_t>> holes;
    for (std::size_t r = 3; r < rows - 3; r += 5) {
      for (std::size_t c = 3; c < cols - 3; c += 5) {
        data[r * cols + c] = -9999.0F;
        holes.emplace_back(r, c);
      }
    }
    const TopoDem dem(g, marsPlane(), std::make_shared<InMemorySamples>(rows, cols, data));
    for (const auto& [hr, hc] : holes) {
      for (const auto& [dr, dc] :
           std::vector<std::pair<int, int>>{{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const double r = static_cast<double>(hr) + dr, c = static_cast<double>(hc) + dc;
        const glm::dvec2 p = g.sampleCentre(r, c);
        const glm::dvec2 f = g.fractionalIndex(p.x, p.y);
        offLine += (f.x != c || f.y != r) ? 1U : 0U;
        const float expected =
            data[static_cast<std::size_t>(r) * cols + static_cast<std::size_t>(c)];
        for (const Interpolation k : kAll) {
          const SurfaceSample s = dem.surface(p.x, p.y, k);
          EXPECT_EQ(s.status, QueryStatus::Ok) << r << "," << c << " kernel " << int(k);
          EXPECT_EQ(s.height, static_cast<double>(expected)) << r << "," << c;
          EXPECT_EQ(dem.height(p.x, p.y, k).status, QueryStatus::Ok);
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 100U);
  EXPECT_GT(offLine, 0U) << "no case lands off its sample line: the test could not fail";
}
