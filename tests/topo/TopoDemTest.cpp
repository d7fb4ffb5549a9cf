// TopoDem queries against analytic surfaces: kernels, normals in both frames, nodata,
// outside-grid results, batch = single, and a non-contiguous sample source.
#include <regolith/core/Error.hpp>
#include <regolith/topo/TopoDem.hpp>

#include "support/TestSources.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace regolith;
using namespace regolith::topo;

namespace {

constexpr Interpolation kAll[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                  Interpolation::Bicubic};

Placement marsPlane(double heading = 0.0) {
  return Placement(LocalTangentPlane(Body::marsSphere(), {-2.05, -5.5, 0.0}, heading));
}

// rows×cols grid with spacing 1 m, sample (0,0) at x=0, y=0 (so y = −row).
TopoDem demOf(std::size_t rows, std::size_t cols, const std::function<float(double x, double y)>& f,
              std::optional<float> nodata = std::nullopt, double spacing = 1.0) {
  TopoGrid g(rows, cols, 0.0, 0.0, spacing, spacing, nodata);
  auto s = InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
    const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return f(p.x, p.y);
  });
  return {g, marsPlane(), s};
}

}  // namespace

TEST(TopoDem, BilinearAndBicubicReproduceAPlaneExactly) {
  // Integer heights are exact in float: h = 2x − 3y + 7 (y = −row).
  const TopoDem dem = demOf(20, 30, [](double x, double y) { return float(2 * x - 3 * y + 7); });
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(0.0, 29.0), uy(-19.0, 0.0);
  for (int i = 0; i < 200; ++i) {
    const double x = ux(rng), y = uy(rng);
    for (Interpolation k : {Interpolation::Bilinear, Interpolation::Bicubic}) {
      const SurfaceSample s = dem.surface(x, y, k);
      ASSERT_TRUE(s.valid());
      EXPECT_NEAR(s.height, 2 * x - 3 * y + 7, 1e-9);
      const glm::dvec3 n = glm::normalize(glm::dvec3(-2.0, 3.0, 1.0));
      EXPECT_NEAR(glm::length(s.normal - n), 0.0, 1e-12) << "x=" << x << " y=" << y;
    }
  }
}

TEST(TopoDem, BicubicReproducesAQuadraticAwayFromTheBorder) {
  const TopoDem dem = demOf(16, 16, [](double x, double y) { return float(x * x + x * y); });
  for (double x : {3.25, 7.5, 10.9}) {
    for (double y : {-3.7, -8.0, -11.2}) {
      const SurfaceSample s = dem.surface(x, y, Interpolation::Bicubic);
      EXPECT_NEAR(s.height, x * x + x * y, 1e-9);
      const glm::dvec3 n = glm::normalize(glm::dvec3(-(2 * x + y), -x, 1.0));
      EXPECT_NEAR(glm::length(s.normal - n), 0.0, 1e-9);
    }
  }
}

TEST(TopoDem, NearestReturnsTheNearestSampleAndACentralDifferenceNormal) {
  const TopoDem dem = demOf(5, 5, [](double x, double y) { return float(x * x - y); });
  const SurfaceSample s = dem.surface(2.4, -1.6, Interpolation::Nearest);  // sample (2, 2)
  EXPECT_DOUBLE_EQ(s.height, 4.0 + 2.0);
  // ∂h/∂x by central differences at x=2: ((9) − (1)) / 2 = 4; ∂h/∂y = −1.
  EXPECT_NEAR(glm::length(s.normal - glm::normalize(glm::dvec3(-4.0, 1.0, 1.0))), 0.0, 1e-12);
}

TEST(TopoDem, AllKernelsAgreeExactlyAtSampleCentres) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> h(-100.f, 100.f);
  std::vector<float> data(12 * 9);
  for (auto& v : data) v = h(rng);
  const TopoGrid g(12, 9, 10.0, 20.0, 0.5, 0.5);
  const TopoDem dem(g, marsPlane(), std::make_shared<InMemorySamples>(12, 9, data));
  for (std::size_t r = 0; r < 12; ++r) {
    for (std::size_t c = 0; c < 9; ++c) {
      const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      for (Interpolation k : kAll) {
        EXPECT_NEAR(dem.height(p.x, p.y, k).height, data[r * 9 + c], 1e-4)
            << int(k) << " r=" << r << " c=" << c;
      }
    }
  }
}

TEST(TopoDem, NodataGivesNanAndInvalidNeverZeroOrANeighbour) {
  const float nd = -32768.0f;
  TopoDem dem = demOf(
      6, 6, [&](double x, double y) { return (x == 2.0 && y == -2.0) ? nd : float(100.0 + x); },
      nd);
  for (Interpolation k : kAll) {
    const HeightSample h = dem.height(2.2, -2.3, k);
    EXPECT_FALSE(h.valid());
    EXPECT_EQ(h.status, QueryStatus::Nodata);
    EXPECT_TRUE(std::isnan(h.height));
    const SurfaceSample s = dem.surface(2.2, -2.3, k);
    EXPECT_EQ(s.status, QueryStatus::Nodata);
    EXPECT_TRUE(std::isnan(s.normal.x));
  }
  // Far from the hole everything is valid.
  EXPECT_TRUE(dem.height(4.6, -4.4, Interpolation::Bicubic).valid());
  // Bilinear exactly on the valid sample (3, 2): the hole has zero weight for the height,
  // but the normal needs the whole cell.
  EXPECT_TRUE(dem.height(3.0, -2.0, Interpolation::Bilinear).valid());
  EXPECT_DOUBLE_EQ(dem.height(3.0, -2.0, Interpolation::Bilinear).height, 103.0);
  // Bicubic stencil reaches the hole from one cell away.
  EXPECT_EQ(dem.height(3.5, -2.5, Interpolation::Bicubic).status, QueryStatus::Nodata);
  EXPECT_TRUE(dem.height(3.5, -2.5, Interpolation::Bilinear).valid());
}

TEST(TopoDem, NanSamplesAreNodataEvenWithoutADeclaredValue) {
  const TopoDem dem = demOf(4, 4, [](double x, double) {
    return x < 1.0 ? std::numeric_limits<float>::quiet_NaN() : 1.0f;
  });
  EXPECT_EQ(dem.height(0.5, -1.0).status, QueryStatus::Nodata);
  EXPECT_TRUE(dem.height(2.5, -1.0).valid());
}

TEST(TopoDem, OutsideThePixelExtentIsExplicitlyOutsideGrid) {
  const TopoDem dem = demOf(4, 5, [](double x, double) { return float(x); });
  // Pixel extent: x in [−0.5, 4.5], y in [−3.5, 0.5].
  for (Interpolation k : kAll) {
    for (auto [x, y] :
         {std::pair{-0.51, -1.0}, {4.51, -1.0}, {2.0, 0.51}, {2.0, -3.51}, {1e9, 0.0}}) {
      const SurfaceSample s = dem.surface(x, y, k);
      EXPECT_EQ(s.status, QueryStatus::OutsideGrid);
      EXPECT_TRUE(std::isnan(s.height));
      EXPECT_EQ(dem.height(x, y, k).status, QueryStatus::OutsideGrid);
    }
  }
}

TEST(TopoDem, TheHalfPixelBorderHoldsTheEdgeValueNotGarbage) {
  // grid_map PR #459: −1.47 from non-negative data at the edge. Here a non-negative ramp
  // queried all around the border band returns the edge values exactly.
  const TopoDem dem = demOf(5, 5, [](double x, double y) { return float(x - 2 * y); });
  for (Interpolation k : kAll) {
    EXPECT_NEAR(dem.height(-0.5, -2.0, k).height, 4.0, 1e-12);  // left edge: x clamped to 0
    EXPECT_NEAR(dem.height(4.5, -2.0, k).height, 8.0, 1e-12);
    EXPECT_NEAR(dem.height(2.0, 0.5, k).height, 2.0, 1e-12);
    EXPECT_NEAR(dem.height(2.0, -4.5, k).height, 10.0, 1e-12);
    EXPECT_NEAR(dem.height(-0.5, 0.5, k).height, 0.0, 1e-12);  // corner
    EXPECT_NEAR(dem.height(4.5, -4.5, k).height, 12.0, 1e-12);
  }
  // A constant grid stays constant everywhere in the extent, for every kernel.
  const TopoDem flat = demOf(3, 3, [](double, double) { return 5.0f; });
  for (Interpolation k : kAll) {
    for (double x = -0.5; x <= 2.5; x += 0.25) {
      for (double y = 0.5; y >= -2.5; y -= 0.25) {
        const SurfaceSample s = flat.surface(x, y, k);
        ASSERT_TRUE(s.valid());
        EXPECT_DOUBLE_EQ(s.height, 5.0);
        EXPECT_DOUBLE_EQ(s.normal.z, 1.0);
      }
    }
  }
}

TEST(TopoDem, NonFiniteCoordinatesThrowAClearError) {
  const TopoDem dem = demOf(3, 3, [](double, double) { return 0.0f; });
  try {
    (void)dem.height(std::nan(""), 0.0);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "TopoDem::height(): x is nan, expected a finite number");
  }
  EXPECT_THROW((void)dem.surface(0.0, std::numeric_limits<double>::infinity()), InvalidArgument);
}

TEST(TopoDem, BatchEqualsSingleQueriesBitForBit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 40.0), v(-40.0, 1.0);
  const TopoDem dem = demOf(40, 40, [](double x, double y) {
    return (x == 10.0 && y == -10.0) ? std::numeric_limits<float>::quiet_NaN()
                                     : float(std::sin(x * 0.3) * 20.0 + std::cos(y * 0.2) * 7.0);
  });
  const std::size_t n = 2000;
  std::vector<double> xs(n), ys(n), hs(n), hs2(n);
  std::vector<glm::dvec3> ns(n);
  std::vector<QueryStatus> st(n), st2(n);
  for (std::size_t i = 0; i < n; ++i) xs[i] = u(rng), ys[i] = v(rng);
  for (Interpolation k : kAll) {
    dem.heights(xs, ys, hs, st, k);
    dem.surfaces(xs, ys, hs2, ns, st2, k, NormalFrame::BodyFixed);
    for (std::size_t i = 0; i < n; ++i) {
      const HeightSample h = dem.height(xs[i], ys[i], k);
      const SurfaceSample s = dem.surface(xs[i], ys[i], k, NormalFrame::BodyFixed);
      EXPECT_EQ(st[i], h.status);
      EXPECT_EQ(st2[i], s.status);
      if (h.valid())
        EXPECT_EQ(hs[i], h.height);
      else
        EXPECT_TRUE(std::isnan(hs[i]));
      if (s.valid()) {
        EXPECT_EQ(hs2[i], s.height);
        EXPECT_EQ(ns[i], s.normal);
      }
    }
  }
}

TEST(TopoDem, BatchRejectsBadInputBeforeWritingAnything) {
  const TopoDem dem = demOf(3, 3, [](double, double) { return 1.0f; });
  std::vector<double> xs{0.0, 1.0, std::nan("")}, ys{0.0, -1.0, -1.0}, out(3, 42.0);
  try {
    dem.heights(xs, ys, out, {});
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "TopoDem::heights(): xs[2] is nan, expected a finite number");
  }
  EXPECT_EQ(out, (std::vector<double>{42.0, 42.0, 42.0}));
  std::vector<double> shortOut(2);
  EXPECT_THROW(dem.heights(xs, ys, shortOut, {}), InvalidArgument);
}

TEST(TopoDem, APagedStyleSourceGivesTheSameAnswersAsTheInMemoryOne) {
  const TopoGrid g(30, 25, 100.0, 200.0, 2.0, 2.0, -1.0f);
  std::vector<float> data(30 * 25);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> h(0.f, 50.f);
  for (auto& v : data) v = h(rng);
  data[40] = -1.0f;  // a hole
  const TopoDem mem(g, marsPlane(), std::make_shared<InMemorySamples>(30, 25, data));
  const TopoDem gen(g, marsPlane(), std::make_shared<test::SampleOnlySource>(30, 25, data));
  std::uniform_real_distribution<double> ux(98.0, 151.0), uy(140.0, 202.0);
  for (int i = 0; i < 500; ++i) {
    const double x = ux(rng), y = uy(rng);
    for (Interpolation k : kAll) {
      const SurfaceSample a = mem.surface(x, y, k), b = gen.surface(x, y, k);
      ASSERT_EQ(a.status, b.status);
      if (a.valid()) {
        EXPECT_EQ(a.height, b.height);
        EXPECT_EQ(a.normal, b.normal);
      }
    }
  }
}

TEST(TopoDem, RejectsMismatchedSamples) {
  const TopoGrid g(3, 3, 0, 0, 1, 1);
  EXPECT_THROW(
      TopoDem(g, marsPlane(), std::make_shared<InMemorySamples>(3, 4, std::vector<float>(12))),
      InvalidArgument);
  EXPECT_THROW(TopoDem(g, marsPlane(), nullptr), InvalidArgument);
}

TEST(TopoDem, TangentPlaneSamplesHaveBodyFixedPositionsInThePlaneFrame) {
  const Placement pl = marsPlane(30.0);
  const TopoGrid g(4, 4, -10.0, 10.0, 5.0, 5.0);
  const TopoDem dem(g, pl, InMemorySamples::fromFunction(4, 4, [](std::size_t r, std::size_t c) {
                      return float(r + 2 * c);
                    }));
  const LocalTangentPlane& ltp = *pl.localTangentPlane();
  const glm::dvec3 p = dem.samplePosition(2, 3);
  const glm::dvec3 expect =
      ltp.originBodyFixed() + 5.0 * ltp.xAxis() + 0.0 * ltp.yAxis() + 8.0 * ltp.zAxis();
  EXPECT_NEAR(glm::length(p - expect), 0.0, 1e-8);
  EXPECT_THROW((void)dem.samplePosition(4, 0), InvalidArgument);
}

// The body-fixed normal must equal the cross product of finite differences of body-fixed
// surface positions, whatever the placement (an oracle independent of the Jacobian code).
class PlacedDemNormal : public ::testing::TestWithParam<int> {};

TEST_P(PlacedDemNormal, BodyFixedNormalMatchesFiniteDifferencesOfPositions) {
  const Body mars = Body::marsEllipsoid();
  Placement pl = marsPlane(20.0);
  double x0 = 0.0, y0 = 0.0;
  switch (GetParam()) {
    case 0: pl = Placement(LocalTangentPlane(mars, {-2.05, -5.5, -1400.0}, 20.0)); break;
    case 1:
      pl = Placement(mars, PolarStereographic::withTrueScaleLatitude(
                               mars, PolarStereographic::Pole::South, -90.0, 0.0));
      x0 = 120000.0, y0 = -80000.0;
      break;
    case 2:
      pl = Placement(mars, Equirectangular(3396190.0, 12.6, 0.0), LatitudeType::Planetocentric);
      x0 = 2.108e6, y0 = 0.746e6;  // near Marth crater, 35.57°E 12.6°N
      break;
    case 3:  // a UTM-like zone on Mars, 3.3° east of its central meridian at 40°N
      pl = Placement(mars, TransverseMercator(mars, 30.0, 0.0, 0.9996, 500000.0, 0.0));
      x0 = 700000.0, y0 = 2.37e6;
      break;
  }
  const TopoGrid g(64, 64, x0, y0, 2.0, 2.0);
  auto f = [&](double x, double y) {
    return 3.0 * std::sin((x - x0) * 0.05) + 0.2 * (y - y0) + 5.0 * std::cos((y - y0) * 0.07);
  };
  const TopoDem dem(g, pl, InMemorySamples::fromFunction(64, 64, [&](std::size_t r, std::size_t c) {
                      const glm::dvec2 p = g.sampleCentre(double(r), double(c));
                      return float(f(p.x, p.y));
                    }));
  // Steps of 1 mm: the bicubic's truncation error is ~1e-9 and rounding ~2e-7 at 3.4e6 m.
  const double e = 1e-3;
  for (auto [dx, dy] : {std::pair{20.5, -30.25}, {60.0, -90.7}, {100.3, -10.1}}) {
    const double x = x0 + dx, y = y0 + dy;
    const SurfaceSample s = dem.surface(x, y, Interpolation::Bicubic, NormalFrame::BodyFixed);
    ASSERT_TRUE(s.valid());
    auto P = [&](double px, double py) {
      return dem.toBodyFixed(px, py, dem.height(px, py, Interpolation::Bicubic).height);
    };
    const glm::dvec3 fd =
        glm::normalize(glm::cross(P(x + e, y) - P(x - e, y), P(x, y + e) - P(x, y - e)));
    EXPECT_LT(glm::length(s.normal - fd), 2e-6) << "placement " << GetParam();
    // And it points away from the body (up), not into it.
    EXPECT_GT(glm::dot(s.normal, glm::normalize(P(x, y))), 0.8);  // slopes reach ~0.55
  }
}
INSTANTIATE_TEST_SUITE_P(Placements, PlacedDemNormal, ::testing::Values(0, 1, 2, 3));

TEST(TopoDem, ABlockSourceGivesTheSameAnswersAndRunsOfQueriesStayInOneBlock) {
  const TopoGrid g(30, 25, 100.0, 200.0, 2.0, 2.0, -1.0f);
  std::vector<float> data(30 * 25);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> h(0.f, 50.f);
  for (auto& v : data) v = h(rng);
  data[77] = -1.0f;  // a hole
  const TopoDem mem(g, marsPlane(), std::make_shared<InMemorySamples>(30, 25, data));
  auto blocks = std::make_shared<test::BlockSource>(30, 25, data);
  const TopoDem paged(g, marsPlane(), blocks);
  std::uniform_real_distribution<double> ux(98.0, 151.0), uy(140.0, 202.0);
  for (int i = 0; i < 2000; ++i) {
    const double x = ux(rng), y = uy(rng);
    for (Interpolation k : kAll) {
      const SurfaceSample a = mem.surface(x, y, k), b = paged.surface(x, y, k);
      ASSERT_EQ(a.status, b.status) << x << "," << y;
      if (a.valid()) {
        EXPECT_EQ(a.height, b.height);
        EXPECT_EQ(a.normal, b.normal);
      }
      EXPECT_EQ(mem.height(x, y, k).height == mem.height(x, y, k).height,
                paged.height(x, y, k).height == paged.height(x, y, k).height);
    }
  }
  // 1,000 bilinear queries inside one block's interior cells: one block fetch, no samples.
  blocks->blockCalls = 0;
  blocks->sampleCalls = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x = 100.0 + 2.0 * (5.0 + 2.5 * i / 1000.0);  // columns 5.0 … 7.5
    (void)paged.height(x, 200.0 - 2.0 * 8.5);                 // rows 8…9 (block rows 7…13)
  }
  EXPECT_EQ(blocks->blockCalls.load(), 1u);
  EXPECT_EQ(blocks->sampleCalls.load(), 0u);
}
