// TopoPlanet: lat/lon grids, longitude wrapping, polar caps, regional grids, normals.
#include <regolith/core/Error.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "support/TestSources.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

using namespace regolith;
using namespace regolith::topo;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;

// A smooth function on the sphere (of the unit position vector), so it is single-valued at
// the poles and periodic in longitude.
double field(double latDeg, double lonDeg) {
  const double x = std::cos(latDeg * kDeg) * std::cos(lonDeg * kDeg);
  const double y = std::cos(latDeg * kDeg) * std::sin(lonDeg * kDeg);
  const double z = std::sin(latDeg * kDeg);
  return 3000.0 * z + 2000.0 * x - 1500.0 * y * y + 800.0 * x * z;
}

// Global grid with `perDeg` samples per degree, pixel-is-area, west edge at `west`.
TopoPlanet globalPlanet(double perDeg, double west, const Body& body = Body::marsSphere(),
                        LatitudeType lt = LatitudeType::Planetocentric) {
  const double d = 1.0 / perDeg;
  const auto rows = static_cast<std::size_t>(std::lround(180.0 * perDeg));
  const auto cols = static_cast<std::size_t>(std::lround(360.0 * perDeg));
  TopoGrid g(rows, cols, west + d / 2, 90.0 - d / 2, d, d);
  return {g, body, lt, InMemorySamples::fromFunction(rows, cols, [&](std::size_t r, std::size_t c) {
            const glm::dvec2 p = g.sampleCentre(double(r), double(c));
            return float(field(p.y, p.x));
          })};
}
}  // namespace

TEST(TopoPlanet, DetectsGlobalGridsAndPolarCaps) {
  const TopoPlanet p = globalPlanet(1.0, 0.0);
  EXPECT_TRUE(p.isGlobalInLongitude());
  EXPECT_TRUE(p.hasNorthCap());
  EXPECT_TRUE(p.hasSouthCap());
  const TopoGrid regional(10, 10, 0.5, 9.5, 1.0, 1.0);
  const TopoPlanet r(regional, Body::moon(), LatitudeType::Planetocentric,
                     std::make_shared<InMemorySamples>(10, 10, std::vector<float>(100, 1.0f)));
  EXPECT_FALSE(r.isGlobalInLongitude());
  EXPECT_FALSE(r.hasNorthCap());
}

TEST(TopoPlanet, InterpolatesASmoothFieldToTheExpectedAccuracy) {
  const TopoPlanet p = globalPlanet(2.0, -180.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> lat(-89.0, 89.0), lon(-180.0, 180.0);
  double maxLin = 0.0, maxCub = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double a = lat(rng), b = lon(rng);
    maxLin =
        std::max(maxLin, std::abs(p.height({a, b}, Interpolation::Bilinear).height - field(a, b)));
    maxCub =
        std::max(maxCub, std::abs(p.height({a, b}, Interpolation::Bicubic).height - field(a, b)));
  }
  // Second derivatives are ≲ 5000 m/rad², spacing 0.5° = 0.0087 rad: h''·d²/8 ≈ 0.05 m.
  EXPECT_LT(maxLin, 0.2);
  EXPECT_LT(maxCub, 0.02);
  EXPECT_LT(maxCub, maxLin);
}

TEST(TopoPlanet, LongitudeWrapsWhateverRangeItIsGivenIn) {
  const TopoPlanet a = globalPlanet(1.0, 0.0);     // grid 0…360
  const TopoPlanet b = globalPlanet(1.0, -180.0);  // grid −180…180
  for (double lon : {-170.3, -0.25, 10.6, 179.9}) {
    const double h = a.height({12.3, lon}, Interpolation::Bicubic).height;
    for (double alt : {lon + 360.0, lon - 360.0, lon + 720.0}) {
      EXPECT_NEAR(a.height({12.3, alt}, Interpolation::Bicubic).height, h, 1e-9);
      EXPECT_NEAR(b.height({12.3, alt}, Interpolation::Bicubic).height, h, 1e-9);
    }
  }
}

TEST(TopoPlanet, RegionalGridIsOutsideBeyondItsExtentAndAcceptsEitherLongitudeRange) {
  // A region straddling 0°: 350°…10°E, 20°S…20°N, 1° pixels.
  const TopoGrid g(40, 20, 350.5, 19.5, 1.0, 1.0);
  const TopoPlanet p(g, Body::marsSphere(), LatitudeType::Planetocentric,
                     InMemorySamples::fromFunction(
                         40, 20, [&](std::size_t r, std::size_t c) { return float(100 * r + c); }));
  EXPECT_TRUE(p.height({0.0, 355.0}).valid());
  EXPECT_DOUBLE_EQ(p.height({0.0, -5.0}).height, p.height({0.0, 355.0}).height);
  EXPECT_DOUBLE_EQ(p.height({19.5, 5.5}, Interpolation::Nearest).height, 15.0);
  EXPECT_EQ(p.height({0.0, 10.6}).status, QueryStatus::OutsideGrid);
  EXPECT_EQ(p.height({0.0, 349.4}).status, QueryStatus::OutsideGrid);
  EXPECT_EQ(p.height({20.6, 0.0}).status, QueryStatus::OutsideGrid);
  EXPECT_EQ(p.height({-20.6, 0.0}).status, QueryStatus::OutsideGrid);
  EXPECT_TRUE(p.height({20.0, 10.0}).valid());  // the pixel-extent corner is inside
}

TEST(TopoPlanet, PoleHeightIsOneValueAndTheCapJoinsTheGridContinuously) {
  const TopoPlanet p = globalPlanet(1.0, 0.0);
  const double pole = p.height({90.0, 0.0}).height;
  EXPECT_NEAR(pole, p.northPoleHeight(), 1e-12);
  for (double lon : {-180.0, -45.0, 33.3, 90.0, 180.0, 359.0}) {
    for (Interpolation k :
         {Interpolation::Nearest, Interpolation::Bilinear, Interpolation::Bicubic}) {
      EXPECT_DOUBLE_EQ(p.height({90.0, lon}, k).height, pole);
    }
  }
  // The pole mean of the first row matches the field's pole value to the grid's accuracy.
  EXPECT_NEAR(pole, field(90.0, 0.0), 2.0);
  // Continuity at the edge of the cap (last row centre at 89.5°).
  for (Interpolation k : {Interpolation::Bilinear, Interpolation::Bicubic}) {
    const double in = p.height({89.5 - 1e-9, 40.0}, k).height;
    const double out = p.height({89.5 + 1e-9, 40.0}, k).height;
    EXPECT_NEAR(in, out, 1e-4);
  }
}

namespace {
// A copy of a resident planet's samples.
std::shared_ptr<InMemorySamples> samplesOf(const TopoPlanet& p) {
  const float* s = p.samples().contiguous();
  const std::size_t n = p.grid().rows() * p.grid().cols();
  return std::make_shared<InMemorySamples>(p.grid().rows(), p.grid().cols(),
                                           std::vector<float>(s, s + n));
}
}  // namespace

TEST(TopoPlanet, PoleHeightsAreComputedAtTheFirstCapQueryOnceAndSharedByCopies) {
  const TopoPlanet ref = globalPlanet(1.0, 0.0);
  const TopoGrid& g = ref.grid();
  const auto src = std::make_shared<test::BlockSource>(
      g.rows(), g.cols(),
      std::vector<float>(ref.samples().contiguous(),
                         ref.samples().contiguous() + g.rows() * g.cols()));
  // Read sample by sample: made without reading any sample.
  const TopoPlanet bySamples(g, ref.body(), ref.latitudeType(), src);
  EXPECT_EQ(src->sampleCalls.load(), 0U);
  EXPECT_EQ(src->blockCalls.load(), 0U);
  EXPECT_EQ(bySamples.northPoleHeight(), ref.northPoleHeight());
  EXPECT_EQ(src->sampleCalls.load(), g.cols()) << "the first row, sample by sample";

  // Given a function: called once per pole, at the first query in its cap, by any copy.
  std::atomic<int> calls{0};
  std::vector<std::size_t> rows;
  const TopoPlanet p(g, ref.body(), ref.latitudeType(), samplesOf(ref), [&](std::size_t row) {
    calls.fetch_add(1);
    rows.push_back(row);
    return row == 0 ? ref.northPoleHeight() : ref.southPoleHeight();
  });
  const TopoPlanet copy = p;
  for (const Interpolation k :
       {Interpolation::Nearest, Interpolation::Bilinear, Interpolation::Bicubic}) {
    EXPECT_TRUE(p.surface({45.0, 10.0}, k).valid());
    EXPECT_TRUE(p.surface({-89.0, 10.0}, k).valid());  // the last row of centres is at 89.5°
  }
  EXPECT_EQ(calls.load(), 0) << "no query reached a cap";
  for (const Interpolation k :
       {Interpolation::Nearest, Interpolation::Bilinear, Interpolation::Bicubic}) {
    for (const double lat : {89.8, 90.0}) {
      const SurfaceSample a = ref.surface({lat, 33.0}, k), b = copy.surface({lat, 33.0}, k);
      EXPECT_EQ(a.height, b.height) << lat;
      EXPECT_EQ(a.normal, b.normal) << lat;
    }
  }
  EXPECT_EQ(calls.load(), 1);
  EXPECT_EQ(p.height({89.9, -70.0}).height, ref.height({89.9, -70.0}).height);
  EXPECT_EQ(p.southPoleHeight(), ref.southPoleHeight());
  EXPECT_EQ(copy.height({-90.0, 5.0}).height, ref.height({-90.0, 5.0}).height);
  EXPECT_EQ(calls.load(), 2);
  EXPECT_EQ(rows, (std::vector<std::size_t>{0, g.rows() - 1}));

  // A grid that reaches neither pole asks for no row.
  const TopoGrid regional(10, 10, 0.5, 9.5, 1.0, 1.0);
  int regionalCalls = 0;
  const TopoPlanet r(regional, Body::moon(), LatitudeType::Planetocentric,
                     std::make_shared<InMemorySamples>(10, 10, std::vector<float>(100, 1.0f)),
                     [&](std::size_t) { return ++regionalCalls, 1.0; });
  EXPECT_TRUE(std::isnan(r.northPoleHeight()));
  EXPECT_TRUE(std::isnan(r.southPoleHeight()));
  EXPECT_EQ(regionalCalls, 0);
}

TEST(TopoPlanet, APoleWhoseRowCannotBeReadFailsItsQueryAndIsAskedForAgain) {
  const TopoPlanet ref = globalPlanet(1.0, 0.0);
  int calls = 0;
  const TopoPlanet p(ref.grid(), ref.body(), ref.latitudeType(), samplesOf(ref),
                     [&](std::size_t) -> double {
                       if (++calls == 1) throw std::runtime_error("disk gone");
                       return ref.northPoleHeight();
                     });
  EXPECT_THROW((void)p.height({89.9, 0.0}), std::runtime_error);
  EXPECT_EQ(p.height({89.9, 0.0}).height, ref.height({89.9, 0.0}).height);
  EXPECT_EQ(calls, 2);
  try {
    const TopoPlanet bad(ref.grid(), ref.body(), ref.latitudeType(), samplesOf(ref),
                         TopoPlanet::RowMean());
    ADD_FAILURE() << "an empty RowMean was taken";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "TopoPlanet(): rowMean is empty, expected a function");
  }
}

TEST(TopoPlanet, ThreadsRacingToTheFirstCapQueryGetOnePoleHeight) {
  const TopoPlanet ref = globalPlanet(2.0, -180.0);
  for (int round = 0; round < 20; ++round) {
    std::atomic<int> calls{0};
    const TopoPlanet p(ref.grid(), ref.body(), ref.latitudeType(), samplesOf(ref),
                       [&](std::size_t row) {
                         calls.fetch_add(1);
                         return row == 0 ? ref.northPoleHeight() : ref.southPoleHeight();
                       });
    std::vector<double> got(4);
    std::vector<std::thread> threads;
    for (std::size_t t = 0; t < got.size(); ++t) {
      threads.emplace_back([&, t] { got[t] = p.height({90.0, 10.0 * double(t)}).height; });
    }
    for (std::thread& t : threads) t.join();
    for (const double h : got) EXPECT_EQ(h, ref.northPoleHeight());
    EXPECT_GE(calls.load(), 1);
    EXPECT_LE(calls.load(), 4);  // each racing thread may compute it once; never more
  }
}

TEST(TopoPlanet, EnuNormalMatchesFiniteDifferencesOfBodyFixedPositions) {
  for (const bool ellipsoid : {false, true}) {
    const Body body = ellipsoid ? Body::marsEllipsoid() : Body::marsSphere();
    const TopoPlanet p = globalPlanet(4.0, 0.0, body, LatitudeType::Planetocentric);
    for (auto [lat, lon] : {std::pair{10.1, 20.2},
                            {-45.3, 300.7},
                            {70.05, 181.3},
                            {89.0, 10.0},
                            {89.95, 123.0},
                            {-89.95, 2.0}}) {
      const SurfaceSample s = p.surface({lat, lon}, Interpolation::Bicubic, NormalFrame::BodyFixed);
      ASSERT_TRUE(s.valid());
      EXPECT_NEAR(glm::length(s.normal), 1.0, 1e-12);
      // Oracle: tangents from positions of nearby points (1e-4° ≈ 6 m apart).
      const double e = 1e-4;
      auto P = [&](double a, double b) {
        return p.toBodyFixed({a, b}, p.height({a, b}, Interpolation::Bicubic).height);
      };
      glm::dvec3 fd = glm::normalize(
          glm::cross(P(lat, lon + e) - P(lat, lon - e), P(lat + e, lon) - P(lat - e, lon)));
      // In the polar cap the blend is only C0 across longitudes at the same latitude, so
      // compare more loosely there.
      const double tol = std::abs(lat) > 89.875 ? 2e-2 : 1e-5;
      EXPECT_LT(glm::length(s.normal - fd), tol) << lat << "," << lon << " ellipsoid=" << ellipsoid;
      // Grid-frame (ENU) normal rotated into the body frame gives the same vector.
      const SurfaceSample g = p.surface({lat, lon}, Interpolation::Bicubic, NormalFrame::Grid);
      const glm::dmat3 enu =
          body.enuFrame(body.toPlanetodetic(lat, LatitudeType::Planetocentric), lon);
      EXPECT_LT(glm::length(enu * g.normal - s.normal), 1e-12);
    }
  }
}

TEST(TopoPlanet, FlatPlanetHasUpNormalsEverywhereIncludingThePoles) {
  const TopoGrid g(18, 36, 5.0, 85.0, 10.0, 10.0);
  const TopoPlanet p(
      g, Body::marsEllipsoid(), LatitudeType::Planetodetic,
      std::make_shared<InMemorySamples>(18, 36, std::vector<float>(18 * 36, 250.0f)));
  for (double lat : {-90.0, -89.99, -30.0, 0.0, 45.0, 89.999, 90.0}) {
    for (double lon : {-180.0, 0.0, 77.0}) {
      const SurfaceSample s = p.surface({lat, lon}, Interpolation::Bilinear, NormalFrame::Grid);
      ASSERT_TRUE(s.valid());
      EXPECT_DOUBLE_EQ(s.height, 250.0);
      EXPECT_NEAR(s.normal.z, 1.0, 1e-9) << lat << "," << lon;
    }
  }
}

TEST(TopoPlanet, LatitudeBeyondNinetyAndNonFiniteInputThrow) {
  const TopoPlanet p = globalPlanet(1.0, 0.0);
  try {
    (void)p.height({90.5, 0.0});
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "TopoPlanet::height(): latitude is 90.5 deg, expected within [-90, 90]");
  }
  EXPECT_THROW((void)p.surface({0.0, std::nan("")}), InvalidArgument);
  std::vector<double> lats{0.0, std::numeric_limits<double>::infinity()}, lons{0.0, 0.0}, out(2);
  EXPECT_THROW(p.heights(lats, lons, out, {}), InvalidArgument);
}

TEST(TopoPlanet, BatchEqualsSingleQueries) {
  const TopoPlanet p = globalPlanet(1.0, -180.0);
  std::vector<double> lats{-90.0, -10.5, 0.0, 45.25, 89.9}, lons{0.0, 179.99, -180.0, 360.0, 10.0};
  std::vector<double> h(5), h2(5);
  std::vector<glm::dvec3> n(5);
  std::vector<QueryStatus> st(5);
  p.heights(lats, lons, h, st, Interpolation::Bicubic);
  p.surfaces(lats, lons, h2, n, {}, Interpolation::Bicubic, NormalFrame::BodyFixed);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(h[i], p.height({lats[i], lons[i]}, Interpolation::Bicubic).height);
    const SurfaceSample s =
        p.surface({lats[i], lons[i]}, Interpolation::Bicubic, NormalFrame::BodyFixed);
    EXPECT_EQ(h2[i], s.height);
    EXPECT_EQ(n[i], s.normal);
  }
}

TEST(TopoPlanet, RejectsGridsBeyondThePolesOrWiderThan360Degrees) {
  auto s = std::make_shared<InMemorySamples>(2, 2, std::vector<float>(4));
  EXPECT_THROW(TopoPlanet(TopoGrid(2, 2, 0.5, 90.0, 1.0, 1.0), Body::moon(),
                          LatitudeType::Planetocentric, s),
               InvalidArgument);
  EXPECT_THROW(TopoPlanet(TopoGrid(2, 2, 0.0, 0.0, 200.0, 1.0), Body::moon(),
                          LatitudeType::Planetocentric, s),
               InvalidArgument);
}

namespace {
bool sameBits(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }
bool sameBits(const glm::dvec3& a, const glm::dvec3& b) {
  return sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z);
}
/// A global 2° grid of field(), resident and in 7 × 5 blocks, and a regional 0.5° one.
struct ThreeGrids {
  TopoPlanet resident, blocks, part;
  ThreeGrids(const Body& body, LatitudeType lt)
      : resident(global(), body, lt, std::make_shared<InMemorySamples>(90, 180, of(global()))),
        blocks(global(), body, lt, std::make_shared<test::BlockSource>(90, 180, of(global()))),
        part(regional(), body, lt, std::make_shared<InMemorySamples>(20, 30, of(regional()))) {}
  static TopoGrid global() { return {90, 180, -179.0, 89.0, 2.0, 2.0}; }
  static TopoGrid regional() { return {20, 30, 10.0, 20.0, 0.5, 0.5}; }
  static std::vector<float> of(const TopoGrid& grid) {
    std::vector<float> s(grid.rows() * grid.cols());
    for (std::size_t r = 0; r < grid.rows(); ++r) {
      for (std::size_t c = 0; c < grid.cols(); ++c) {
        const glm::dvec2 p = grid.sampleCentre(double(r), double(c));
        s[r * grid.cols() + c] = float(field(p.y, p.x));
      }
    }
    return s;
  }
};
}  // namespace

TEST(TopoPlanet, PrefetchIsAHintThatTakesAnyPointAndChangesNoAnswer) {
  // prefetch() (a composition overlaps its datasets' memory misses with it) on a resident and
  // a block-paged global grid and a regional one, for points inside, on the seam, in the caps,
  // beyond the extent and not numbers at all: no error, and every height after it is the one
  // before it, bit for bit.
  const ThreeGrids grids(Body::marsSphere(), LatitudeType::Planetodetic);
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<LatLon> pts = {{0.0, 0.0},     {89.9, 10.0},  {-90.0, 0.0},  {90.0, 180.0},
                             {12.0, -179.9}, {12.0, 179.9}, {15.0, 25.0},  {-60.0, 1e308},
                             {0.0, -1e308},  {90.5, 0.0},   {-1e300, 0.0}, {nan, 0.0},
                             {0.0, nan},     {inf, 0.0},    {0.0, -inf},   {5.0, 720.0}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> lat(-90.0, 90.0), lon(-540.0, 540.0);
  for (int i = 0; i < 500; ++i) pts.push_back({lat(rng), lon(rng)});
  for (const TopoPlanet* t : {&grids.resident, &grids.blocks, &grids.part}) {
    std::vector<HeightSample> before;
    for (const LatLon& p : pts) {
      const bool valid =
          std::isfinite(p.latDeg) && std::isfinite(p.lonDeg) && std::abs(p.latDeg) <= 90.0;
      before.push_back(valid ? t->height(p) : HeightSample{});
    }
    for (const LatLon& p : pts) t->prefetch(p);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!(std::isfinite(pts[i].latDeg) && std::isfinite(pts[i].lonDeg) &&
            std::abs(pts[i].latDeg) <= 90.0))
        continue;
      const HeightSample h = t->height(pts[i]);
      ASSERT_EQ(h.status, before[i].status) << pts[i].latDeg << ", " << pts[i].lonDeg;
      ASSERT_TRUE(sameBits(h.height, before[i].height)) << pts[i].latDeg << ", " << pts[i].lonDeg;
    }
  }
}

TEST(TopoPlanet, HeightUncheckedIsHeightWithoutTheChecks) {
  // heightUnchecked() (the composition checks each point once) gives height()'s status and
  // bits at every valid point, on a global, a block-paged and a regional grid, in the caps,
  // on the seam and beyond a turn, for every interpolation; height() still refuses what
  // heightUnchecked() leaves to its caller.
  const ThreeGrids grids(Body::marsEllipsoid(), LatitudeType::Planetocentric);
  std::vector<LatLon> pts = {{0.0, 0.0},     {89.9, 10.0},  {-90.0, 0.0},  {90.0, 180.0},
                             {12.0, -180.0}, {12.0, 179.9}, {15.0, 25.0},  {-60.0, 1e308},
                             {0.0, -1e308},  {5.0, 720.0},  {19.75, 10.0}, {10.25, 24.75}};
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> lat(-90.0, 90.0), lon(-540.0, 540.0);
  for (int i = 0; i < 1000; ++i) pts.push_back({lat(rng), lon(rng)});
  std::uniform_real_distribution<double> rlat(9.0, 21.0), rlon(9.0, 26.0);
  for (int i = 0; i < 500; ++i) pts.push_back({rlat(rng), rlon(rng)});
  for (const TopoPlanet* t : {&grids.resident, &grids.blocks, &grids.part}) {
    for (const Interpolation interp :
         {Interpolation::Bilinear, Interpolation::Bicubic, Interpolation::Nearest}) {
      for (const LatLon& p : pts) {
        const HeightSample a = t->height(p, interp), b = t->heightUnchecked(p, interp);
        ASSERT_EQ(a.status, b.status) << p.latDeg << ", " << p.lonDeg;
        ASSERT_TRUE(sameBits(a.height, b.height)) << p.latDeg << ", " << p.lonDeg;
      }
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const LatLon bad :
       {LatLon{nan, 0.0}, LatLon{0.0, nan}, LatLon{90.5, 0.0}, LatLon{-1e300, 0.0},
        LatLon{0.0, -std::numeric_limits<double>::infinity()}}) {
    EXPECT_THROW((void)grids.resident.height(bad), InvalidArgument)
        << bad.latDeg << ", " << bad.lonDeg;
  }
}

TEST(TopoPlanet, BilinearFastPathsGiveTheGenericKernelsBits) {
  // One global 2°-grid with a nodata hole, read three ways: resident (the resident fast
  // path), in 7 × 5 blocks (the thread's-block fast path of paged sources) and sample by
  // sample (the generic kernel only). Heights, normals in both frames and both statuses must
  // agree bit for bit at random points, on sample lines, next to the hole, across the ±180°
  // seam's cell and in the polar caps, for heights alone and for surfaces, one by one and in
  // batches; the interior points also match a bilinear reference computed here in double.
  const double d = 2.0;
  const std::size_t rows = 90, cols = 180;
  const TopoGrid g(rows, cols, -180.0 + d / 2, 90.0 - d / 2, d, d, -9999.0);
  std::vector<float> s(rows * cols);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const glm::dvec2 p = g.sampleCentre(double(r), double(c));
      s[r * cols + c] = float(field(p.y, p.x));
    }
  }
  s[40 * cols + 100] = -9999.0F;  // a hole at lat 9°, lon 21°
  const Body body = Body::marsSphere();
  const auto lt = LatitudeType::Planetocentric;
  const TopoPlanet resident(g, body, lt, std::make_shared<InMemorySamples>(rows, cols, s));
  const TopoPlanet blocks(g, body, lt, std::make_shared<test::BlockSource>(rows, cols, s));
  const TopoPlanet generic(g, body, lt, std::make_shared<test::SampleOnlySource>(rows, cols, s));

  std::mt19937 rng(11);
  std::uniform_real_distribution<double> lat(-90.0, 90.0), lon(-180.0, 180.0), u01(0.0, 1.0);
  std::vector<LatLon> pts;
  for (int i = 0; i < 3000; ++i) pts.push_back({lat(rng), lon(rng)});
  for (int i = 0; i < 200; ++i) {
    pts.push_back({-89.0 + 2.0 * std::floor(u01(rng) * 90.0), lon(rng)});    // on sample rows
    pts.push_back({lat(rng), -179.0 + 2.0 * std::floor(u01(rng) * 180.0)});  // columns
    pts.push_back({6.0 + 6.0 * u01(rng), 18.0 + 6.0 * u01(rng)});            // the hole
    pts.push_back({lat(rng), 178.5 + 3.0 * u01(rng)});                       // the seam
    pts.push_back({88.5 + 1.5 * u01(rng), lon(rng)});                        // north cap
  }
  int interior = 0;
  for (const LatLon& p : pts) {
    const HeightSample gh = generic.height(p);
    for (const TopoPlanet* t : {&resident, &blocks}) {
      const HeightSample h = t->height(p);
      ASSERT_EQ(h.status, gh.status) << p.latDeg << ", " << p.lonDeg;
      ASSERT_TRUE(sameBits(h.height, gh.height)) << p.latDeg << ", " << p.lonDeg;
      for (const NormalFrame f : {NormalFrame::Grid, NormalFrame::BodyFixed}) {
        const SurfaceSample a = t->surface(p, Interpolation::Bilinear, f);
        const SurfaceSample b = generic.surface(p, Interpolation::Bilinear, f);
        ASSERT_EQ(a.status, b.status);
        ASSERT_EQ(a.normalStatus, b.normalStatus);
        ASSERT_TRUE(sameBits(a.height, b.height)) << p.latDeg << ", " << p.lonDeg;
        ASSERT_TRUE(sameBits(a.normal, b.normal)) << p.latDeg << ", " << p.lonDeg;
      }
    }
    // The reference, between sample centres away from the seam and the caps.
    const double v = (g.y0() - p.latDeg) / d, u = (p.lonDeg - g.x0()) / d;
    if (u < 0.0 || v < 0.0 || u >= double(cols - 1) || v >= double(rows - 1)) continue;
    const auto c = std::size_t(u), r = std::size_t(v);
    const double tu = u - double(c), tv = v - double(r);
    const double q[4] = {s[r * cols + c], s[r * cols + c + 1], s[(r + 1) * cols + c],
                         s[(r + 1) * cols + c + 1]};
    // A hole counts where its weight is not 0 (docs/queries.md: a point on a sample line
    // does not see the hole beside it).
    const double w[4] = {(1 - tu) * (1 - tv), tu * (1 - tv), (1 - tu) * tv, tu * tv};
    bool hole = false;
    double ref = 0.0;
    for (int k = 0; k < 4; ++k) {
      if (w[k] == 0.0) continue;
      hole = hole || q[k] == -9999.0;
      ref += w[k] * q[k];
    }
    if (hole) {
      EXPECT_EQ(gh.status, QueryStatus::Nodata) << p.latDeg << ", " << p.lonDeg;
      continue;
    }
    EXPECT_NEAR(resident.height(p).height, ref, 1e-9 * (1.0 + std::abs(ref)));
    ++interior;
  }
  EXPECT_GT(interior, 2000);
  // Batches take the same paths.
  std::vector<double> la, lo;
  for (const LatLon& p : pts) {
    la.push_back(p.latDeg);
    lo.push_back(p.lonDeg);
  }
  std::vector<double> h1(pts.size()), h2(pts.size());
  std::vector<glm::dvec3> n1(pts.size()), n2(pts.size());
  std::vector<QueryStatus> s1(pts.size()), s2(pts.size());
  resident.surfaces(la, lo, h1, n1, s1, Interpolation::Bilinear, NormalFrame::Grid, {});
  generic.surfaces(la, lo, h2, n2, s2, Interpolation::Bilinear, NormalFrame::Grid, {});
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(s1[i], s2[i]);
    ASSERT_TRUE(sameBits(h1[i], h2[i]));
    ASSERT_TRUE(sameBits(n1[i], n2[i]));
  }
}
