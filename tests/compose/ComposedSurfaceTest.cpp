// The composition rule (docs/composition.md) against analytic expectations: each test builds
// datasets whose heights are simple functions, so the composed height, its weights and its
// normal can be written down independently of the code under test.

#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoDem.hpp>

#include "compose/ComposeFixtures.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace regolith::compose {
namespace {

using testing::demPyramid;
using testing::globalPlanet;
using testing::named;
using testing::planetPyramid;
using topo::QueryStatus;

constexpr double kDeg = std::numbers::pi / 180.0;
const topo::Body kMoon = topo::Body::moon();
const double kR = kMoon.equatorialRadius();

/// A catalogue of the Moon with a 1° global grid of height g(lat, lon) and a 0.5° regional
/// grid over lat −10…10, lon −10…10 of height f(lat, lon).
struct TwoPlanets {
  Catalogue catalogue{kMoon};
  DatasetId global = 0, regional = 0;
  TwoPlanets(const std::function<double(double, double)>& g,
             const std::function<double(double, double)>& f, double feather = 0.0,
             int regionalPriority = 0) {
    global = catalogue.add(Dataset::planet(globalPlanet(kMoon, 1.0, g), named("global")));
    regional = catalogue.add(Dataset::planet(planetPyramid(kMoon, 9.75, -9.75, 0.5, 40, 40, f),
                                             named("regional", feather, regionalPriority)));
  }
  [[nodiscard]] ComposedSurface surface(Policy p) const {
    return ComposedSurface(catalogue.snapshot(), Rules{p, 2.0});
  }
};

TEST(ComposedSurface, OneDatasetAnswersItsOwnHeightAndNormal) {
  auto f = [](double lat, double lon) { return 100.0 + 30.0 * lat - 12.0 * lon; };
  auto pyr = planetPyramid(kMoon, 9.75, -9.75, 0.5, 40, 40, f);
  topo::TopoPlanet own(pyr.levels[0].grid, kMoon, topo::LatitudeType::Planetodetic,
                       pyr.levels[0].source);
  Catalogue cat(kMoon);
  cat.add(Dataset::planet(pyr, named("only")));
  const ComposedSurface s(cat.snapshot());
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-9.9, 9.9);
  for (int i = 0; i < 200; ++i) {
    const double lat = u(rng), lon = u(rng);
    const topo::SurfaceSample ref =
        own.surface({lat, lon}, topo::Interpolation::Bilinear, topo::NormalFrame::BodyFixed);
    const ComposedSample c = s.surface(lat, lon, topo::NormalFrame::BodyFixed);
    ASSERT_EQ(c.status, QueryStatus::Ok);
    EXPECT_EQ(c.height, ref.height);
    EXPECT_EQ(c.contributors, 1U);
    EXPECT_NEAR(glm::length(c.normal - ref.normal), 0.0, 1e-12);
  }
  EXPECT_EQ(s.height(40.0, 0.0).status, QueryStatus::OutsideGrid);
}

TEST(ComposedSurface, HeightGivesTheGeneralPathsBitsWhereOneDatasetIsACandidate) {
  // height() and heights() answer a point whose 1° cell has one candidate dataset straight
  // from it, and one where the top tier's one member covers the point fully from that
  // member (ComposedSurface.cpp); surface() always takes the general path. Same statuses,
  // contributor counts and height bits, on one dataset, on the global grid beside a feathered
  // regional one (cells with one and with two candidates), on the regional grid's own cells and
  // outside every grid. height() also leaves a planet grid's quality unevaluated where the
  // grid is alone in its tier (surface() evaluates every one): the third catalogue adds a
  // much finer feathered grid, a tier of its own over the tier of the other two.
  TwoPlanets t([](double lat, double lon) { return 100.0 + 3.0 * lat - 0.7 * lon; },
               [](double lat, double lon) { return 250.0 - 2.0 * lat + 1.3 * lon; }, 60e3);
  TwoPlanets three([](double lat, double lon) { return 100.0 + 3.0 * lat - 0.7 * lon; },
                   [](double lat, double lon) { return 250.0 - 2.0 * lat + 1.3 * lon; }, 60e3);
  three.catalogue.add(
      Dataset::planet(planetPyramid(kMoon, 4.95, -4.95, 0.1, 100, 100,
                                    [](double lat, double lon) { return 180.0 + lat * lon; }),
                      named("fine", 40e3)));
  // Nested grids without feathers (a 0.1° grid in a 0.5° one in the global grid): the top
  // tier's one member covers fully where it answers, so height() answers from it alone.
  TwoPlanets nested([](double lat, double lon) { return 100.0 + 3.0 * lat - 0.7 * lon; },
                    [](double lat, double lon) { return 250.0 - 2.0 * lat + 1.3 * lon; });
  nested.catalogue.add(
      Dataset::planet(planetPyramid(kMoon, 4.95, -4.95, 0.1, 100, 100,
                                    [](double lat, double lon) { return 180.0 + lat * lon; }),
                      named("fine")));
  Catalogue only(kMoon);
  only.add(Dataset::planet(
      planetPyramid(kMoon, 9.75, -9.75, 0.5, 40, 40, [](double lat, double) { return 10.0 * lat; }),
      named("only")));
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> lat(-30.0, 30.0), lon(-40.0, 40.0), unit(0.0, 1.0);
  // Two coarse grids of priority 1 that share a tier over a finer one of priority 0: the
  // top tier covers fully, but the weights are relative to the finest member, so the fine
  // grid below must still be read (spacings not a power of 2 apart: the weights' scale
  // would cancel exactly).
  Catalogue priority(kMoon);
  priority.add(Dataset::planet(
      globalPlanet(kMoon, 1.0, [](double la, double lo) { return 50.0 + la - 0.3 * lo; }),
      named("coarse", 0.0, 1)));
  priority.add(
      Dataset::planet(planetPyramid(kMoon, 39.25, -49.25, 1.5, 54, 67,
                                    [](double la, double lo) { return 70.0 - 0.5 * la + lo; }),
                      named("coarser", 0.0, 1)));
  // A twin of the coarse grid's spacing, over part of it: one quality serves both.
  priority.add(
      Dataset::planet(planetPyramid(kMoon, 29.5, -29.5, 1.0, 50, 60,
                                    [](double la, double lo) { return 60.0 + 0.2 * la * lo; }),
                      named("coarse twin", 0.0, 1)));
  priority.add(
      Dataset::planet(planetPyramid(kMoon, 19.85, -19.85, 0.3, 133, 133,
                                    [](double la, double lo) { return 10.0 * std::sin(la) * lo; }),
                      named("fine below")));
  // Blends without feathers (ComposedSurface::topTierHeight() and blendHeight()): two regional
  // grids of 0.5° and 0.7° that overlap each other, a 0.5° twin of the first over part of it (one
  // quality serves both) and the 1° global grid, one tier (tier ratio 4: 1° <= 4 · 0.5°) of two to
  // four members; and (FinestWins) tiers of equal spacings. A coarse grid of higher priority over
  // part of it puts a tier of one above them.
  Catalogue blend(kMoon);
  blend.add(Dataset::planet(
      globalPlanet(kMoon, 1.0, [](double la, double lo) { return 30.0 + 0.4 * la - 0.2 * lo; }),
      named("base")));
  blend.add(
      Dataset::planet(planetPyramid(kMoon, 14.75, -19.75, 0.5, 60, 60,
                                    [](double la, double lo) { return 80.0 + la * 0.3 * lo; }),
                      named("half")));
  blend.add(Dataset::planet(planetPyramid(kMoon, 4.65, -4.65, 0.7, 40, 50,
                                          [](double la, double lo) { return 55.0 - la + lo; }),
                            named("seven tenths")));
  blend.add(Dataset::planet(planetPyramid(kMoon, 9.75, -9.75, 0.5, 30, 30,
                                          [](double la, double lo) { return 66.0 + la * la - lo; }),
                            named("half twin")));
  // Pixels of another shape (0.8° by 0.5°): another quality, which the blend evaluates
  // (members of one pixel shape leave theirs out of the weights).
  topo::GridPyramid oblong = planetPyramid(
      kMoon, 0.0, 0.0, 0.5, 16, 9, [](double la, double lo) { return 44.0 + la - 2.0 * lo; });
  oblong.levels[0].grid = topo::TopoGrid(16, 9, -12.0, -6.25, 0.8, 0.5);
  blend.add(Dataset::planet(oblong, named("oblong")));
  blend.add(Dataset::planet(planetPyramid(kMoon, 24.5, 15.5, 1.0, 20, 20,
                                          [](double la, double lo) { return 5.0 * la - lo; }),
                            named("priority", 0.0, 2)));
  // Where a complete tier covers the point fully, a height reads no dataset below it
  // (composeGeneral()): the fine grid's interior, and (FinestWins: one tier per spacing) the
  // regional grid's.
  std::size_t single = 0, several = 0, threeTiers = 0, topAlone = 0, blended = 0, twinned = 0,
              shapes = 0, band = 0;
  const std::shared_ptr<const Snapshot> blendSnapshot = blend.snapshot();
  const std::shared_ptr<const Snapshot> tSnapshot = t.catalogue.snapshot();
  for (const auto& [snapshot, policy] :
       {std::pair{tSnapshot, Policy::Weighted}, std::pair{only.snapshot(), Policy::Weighted},
        std::pair{three.catalogue.snapshot(), Policy::Weighted},
        std::pair{tSnapshot, Policy::FinestWins},
        std::pair{three.catalogue.snapshot(), Policy::FinestWins},
        std::pair{priority.snapshot(), Policy::Weighted},
        std::pair{nested.catalogue.snapshot(), Policy::Weighted},
        std::pair{nested.catalogue.snapshot(), Policy::FinestWins},
        std::pair{blendSnapshot, Policy::Weighted}, std::pair{blendSnapshot, Policy::FinestWins}}) {
    const ComposedSurface s(snapshot, Rules{policy, 2.0});
    for (int i = 0; i < 3600; ++i) {
      // Every sixth point in the oblong grid.
      const bool inOblong = i % 6 == 0;
      const double la = inOblong ? -14.0 + 8.0 * unit(rng) : lat(rng);
      const double lo = inOblong ? -12.4 + 7.2 * unit(rng) : lon(rng);
      const topo::HeightSample h = s.height(la, lo);
      const ComposedSample g = s.surface(la, lo, topo::NormalFrame::BodyFixed);
      ASSERT_EQ(h.status, g.status) << la << ", " << lo;
      if (g.status != QueryStatus::Ok) continue;
      ASSERT_EQ(std::bit_cast<std::uint64_t>(h.height), std::bit_cast<std::uint64_t>(g.height))
          << la << ", " << lo << ": " << h.height << " against " << g.height;
      double hb = 0.0;
      QueryStatus sb = QueryStatus::OutsideGrid;
      std::uint32_t cb = 0;
      s.heights(std::span(&la, 1), std::span(&lo, 1), std::span(&hb, 1), std::span(&sb, 1),
                std::span(&cb, 1));
      ASSERT_EQ(sb, QueryStatus::Ok);
      ASSERT_EQ(std::bit_cast<std::uint64_t>(hb), std::bit_cast<std::uint64_t>(g.height));
      ASSERT_EQ(cb, g.contributors) << la << ", " << lo;
      const bool one = snapshot->cellCandidates(la, lo).size() == 1;
      ++(one ? single : several);
      threeTiers += g.contributors == 3 ? 1U : 0U;
      blended += snapshot == blendSnapshot && policy == Policy::Weighted && g.contributors >= 2;
      twinned += snapshot == blendSnapshot && policy == Policy::FinestWins && g.contributors == 2;
      // In the feathered regional grid's band over the global grid: two tiers of one under
      // FinestWins (featheredTopHeight()); Weighted puts 0.5° and 1° in one tier.
      band += snapshot == tSnapshot && policy == Policy::FinestWins && g.contributors == 2;
      // In the oblong grid (-12.4…-5.2° east, -14…-6° north), with "half" and "base".
      shapes += snapshot == blendSnapshot && policy == Policy::Weighted && g.contributors >= 2 &&
                lo > -12.4 && lo < -5.2 && la > -14.0 && la < -6.0;
      topAlone += !one && g.contributors == 1 ? 1U : 0U;
    }
  }
  EXPECT_GT(single, 1000U);
  EXPECT_GT(several, 100U);
  EXPECT_GT(threeTiers, 10U);  // points in the fine grid's feather, where all three blend
  EXPECT_GT(topAlone, 100U);
  EXPECT_GT(blended, 300U);  // points where blendHeight() answers
  EXPECT_GT(twinned, 100U);  // of those, the twins' plain mean (one spacing per tier)
  EXPECT_GT(shapes, 100U);   // blends of two qualities, weighed by them
  EXPECT_GT(band, 100U);     // a feathered top composited over the grid below
}

TEST(ComposedSurface, WeightedBlendFollowsResolutionAndQuality) {
  TwoPlanets t([](double, double) { return 100.0; }, [](double, double) { return 200.0; });
  const ComposedSurface s = t.surface(Policy::Weighted);
  for (double lat : {0.3, 5.0, -8.0}) {
    const double lon = 2.2;
    // Both grids are square in degrees: at latitude φ a pixel is R·cos φ·Δ by R·Δ, nominal
    // R·Δ on the equator (a sphere).
    const double q = projectionQuality(std::cos(lat * kDeg), 1.0, 1.0, kQualityN);
    const double wFine = q * 1.0, wCoarse = q * std::pow(0.5 / 1.0, 2.0);
    const double expected = (wFine * 200.0 + wCoarse * 100.0) / (wFine + wCoarse);
    const topo::HeightSample h = s.height(lat, lon);
    ASSERT_EQ(h.status, QueryStatus::Ok);
    EXPECT_NEAR(h.height, expected, 1e-3) << "lat " << lat;
  }
  EXPECT_NEAR(s.height(0.3, 2.2).height, 180.0, 1e-2);   // 200·1 + 100·¼ over 1¼
  EXPECT_DOUBLE_EQ(s.height(30.0, 50.0).height, 100.0);  // only the global grid
}

TEST(ComposedSurface, FinestWinsInsideAndFeathersAcrossTheBorder) {
  const double feather = 50e3;
  TwoPlanets t([](double, double) { return 100.0; }, [](double, double) { return 200.0; }, feather);
  const ComposedSurface s = t.surface(Policy::FinestWins);
  EXPECT_DOUBLE_EQ(s.height(0.0, 0.0).height, 200.0);
  EXPECT_DOUBLE_EQ(s.height(0.0, 30.0).height, 100.0);
  const double east = 10.0;  // the regional grid's pixel-extent edge
  for (double d : {0.0, 5e3, 12.5e3, 25e3, 40e3, 49e3, 60e3}) {
    const double lon = east - d / (kR * kDeg);
    const double c = testing::smoothstep(d / feather);
    EXPECT_NEAR(s.height(0.0, lon).height, c * 200.0 + (1.0 - c) * 100.0, 1e-6) << "d " << d;
  }
  // No hard step anywhere across the border: along a line through it, neighbouring heights
  // 100 m apart differ by at most the feather's steepest slope (1.5 × 100 m / 50 km).
  double prev = s.height(0.0, east - 0.2).height;
  for (int i = 1; i <= 400; ++i) {
    const double lon = east - 0.2 + 0.4 * i / 400.0;
    const double h = s.height(0.0, lon).height;
    const double step = 0.4 / 400.0 * kDeg * kR;
    EXPECT_LE(std::abs(h - prev), 1.5 * 100.0 / feather * step * 1.01 + 1e-9);
    prev = h;
  }
}

TEST(ComposedSurface, SharesSumToOneAndRebuildTheHeight) {
  TwoPlanets t([](double lat, double) { return 100.0 + lat; },
               [](double, double lon) { return 200.0 + lon; }, 80e3);
  for (Policy p : {Policy::Weighted, Policy::FinestWins}) {
    const ComposedSurface s = t.surface(p);
    for (double lon : {0.0, 9.0, 9.8}) {
      const auto shares = s.weights(1.0, lon);
      ASSERT_EQ(shares.size(), 2U);
      double sum = 0.0, h = 0.0;
      for (const Share& sh : shares) {
        sum += sh.weight;
        h += sh.weight * sh.height;
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_NEAR(h, s.height(1.0, lon).height, 1e-9);
    }
  }
}

TEST(ComposedSurface, MuchFinerDataCompositesOverWithItsFeather) {
  // A 1 km regional grid's feather over a 1° (30 km) global grid: 30 times finer, so under
  // Weighted (tierRatio 4) it is a tier of its own and its coverage is its alpha. With
  // tierRatio = ∞ the two blend by weight alone, and (1/30)² squeezes the feather.
  Catalogue cat(kMoon);
  cat.add(Dataset::planet(globalPlanet(kMoon, 1.0, [](double, double) { return 100.0; }),
                          named("global")));
  const double step = 1000.0 / (kR * kDeg);  // 1 km in degrees
  cat.add(Dataset::planet(planetPyramid(kMoon, 2.0 - 0.5 * step, -2.0 + 0.5 * step, step,
                                        static_cast<std::size_t>(std::lround(4.0 / step)),
                                        static_cast<std::size_t>(std::lround(4.0 / step)),
                                        [](double, double) { return 200.0; }),
                          named("fine", 40e3)));
  const double east = -2.0 + static_cast<double>(std::lround(4.0 / step)) * step;
  const ComposedSurface tiered(cat.snapshot());
  Rules flat;
  flat.tierRatio = std::numeric_limits<double>::infinity();
  const ComposedSurface blended(cat.snapshot(), flat);
  for (double d : {5e3, 20e3, 35e3}) {
    const double lon = east - d / (kR * kDeg);
    const double c = testing::smoothstep(d / 40e3);
    EXPECT_NEAR(tiered.height(0.0, lon).height, c * 200.0 + (1.0 - c) * 100.0, 1e-6) << d;
    // The pure blend: w_fine = c·q·1, w_global = 1·q·(1/30.3)²: nearly 200 long before the
    // feather ends.
    const double wg = std::pow(1000.0 / (kR * kDeg), 2.0);
    const double q = projectionQuality(1.0, 1.0, 1.0, kQualityN);  // both square on the equator
    EXPECT_NEAR(blended.height(0.0, lon).height,
                (c * q * 200.0 + wg * q * 100.0) / (c * q + wg * q), 1e-3)
        << d;
  }
  EXPECT_THROW(ComposedSurface(cat.snapshot(), Rules{Policy::Weighted, 2.0, 0.5}), InvalidArgument);
}

TEST(ComposedSurface, AHigherPriorityTierHidesALowerOne) {
  // The coarse global grid is priority 0, the regional one −1: the global one wins although
  // it is coarser, because tiers composite over each other.
  TwoPlanets t([](double, double) { return 100.0; }, [](double, double) { return 200.0; }, 0.0, -1);
  EXPECT_DOUBLE_EQ(t.surface(Policy::Weighted).height(0.0, 0.0).height, 100.0);
  EXPECT_DOUBLE_EQ(t.surface(Policy::FinestWins).height(0.0, 0.0).height, 100.0);
}

TEST(ComposedSurface, NormalIsTheGradientOfTheComposedHeightAcrossAFeather) {
  // Sloped datasets and a feathered border: the composed normal must be the normal of the
  // composed height field, which a brute-force central difference of height() gives.
  TwoPlanets t([](double lat, double lon) { return 30.0 * lon + 10.0 * lat; },
               [](double lat, double) { return 200.0 + 20.0 * lat; }, 100e3);
  for (Policy p : {Policy::Weighted, Policy::FinestWins}) {
    const ComposedSurface s = t.surface(p);
    for (double lon : {5.0, 8.0, 8.9, 9.5, 9.99, 10.02}) {
      const double lat = 1.3;
      const ComposedSample c = s.surface(lat, lon);
      ASSERT_EQ(c.normalStatus, QueryStatus::Ok) << lon;
      const double step = 1.0;  // metres
      const double dLon = step / (kR * std::cos(lat * kDeg) * kDeg), dLat = step / (kR * kDeg);
      const double dhde =
          (s.height(lat, lon + dLon).height - s.height(lat, lon - dLon).height) / (2 * step);
      const double dhdn =
          (s.height(lat + dLat, lon).height - s.height(lat - dLat, lon).height) / (2 * step);
      const glm::dvec3 ref = glm::normalize(glm::dvec3(-dhde, -dhdn, 1.0));
      EXPECT_NEAR(glm::length(c.normal - ref), 0.0, 2e-6) << policyName(p) << " lon " << lon;
    }
  }
}

TEST(ComposedSurface, PoleIsOneHeightWhateverTheLongitude) {
  // A global grid (poor at the pole) and a polar-stereographic cap, feathered.
  auto g = [](double lat, double lon) {
    return 100.0 + 50.0 * std::sin(lon * kDeg) * std::cos(lat * kDeg);
  };
  Catalogue cat(kMoon);
  cat.add(Dataset::planet(globalPlanet(kMoon, 1.0, g), named("global")));
  const auto ps = topo::PolarStereographic::withTrueScaleLatitude(
      kMoon, topo::PolarStereographic::Pole::North, 90.0, 0.0);
  cat.add(Dataset::dem(
      demPyramid(500.0, 401, 401, [](double x, double y) { return 120.0 + 1e-4 * x - 2e-4 * y; }),
      topo::Placement(kMoon, ps), named("north cap", 20e3)));
  for (Policy p : {Policy::Weighted, Policy::FinestWins}) {
    const ComposedSurface s(cat.snapshot(), Rules{p, 2.0});
    const double h0 = s.height(90.0, 0.0).height;
    // The cap's quality is 1 there and the global grid's kMinQuality: the cap all but wins.
    EXPECT_NEAR(h0, 120.0, 1e-4);
    for (double lon : {-180.0, -45.0, 90.0, 180.0, 359.0}) {
      EXPECT_NEAR(s.height(90.0, lon).height, h0, 1e-6) << lon;
      const ComposedSample c = s.surface(90.0, lon, topo::NormalFrame::BodyFixed);
      ASSERT_EQ(c.normalStatus, QueryStatus::Ok);
      EXPECT_NEAR(glm::length(c.normal), 1.0, 1e-12);
    }
    // Continuous towards the pole.
    EXPECT_NEAR(s.height(89.99999, 10.0).height, h0, 1e-2);
  }
}

TEST(ComposedSurface, SeamDoesNotSplitADatasetAcross180) {
  Catalogue cat(kMoon);
  cat.add(Dataset::planet(globalPlanet(kMoon, 1.0, [](double, double) { return 100.0; }),
                          named("global")));
  // A regional grid over longitudes 170…190, with height continuous across 180.
  cat.add(Dataset::planet(
      planetPyramid(kMoon, 9.75, 170.25, 0.5, 40, 40,
                    [](double, double lon) { return 300.0 + 10.0 * (lon - 180.0); }),
      named("across the seam")));
  const ComposedSurface s(cat.snapshot(), Rules{Policy::FinestWins, 2.0});
  EXPECT_NEAR(s.height(0.0, 180.0).height, 300.0, 1e-4);
  EXPECT_NEAR(s.height(0.0, -180.0).height, 300.0, 1e-4);
  EXPECT_NEAR(s.height(0.0, -175.0).height, 350.0, 1e-4);
  EXPECT_NEAR(s.height(0.0, 185.0).height, 350.0, 1e-4);
  EXPECT_NEAR(s.height(0.0, 175.0).height, 250.0, 1e-4);
}

TEST(ComposedSurface, TangentPlaneDemHeightsAreAlongTheBodyNormal) {
  // A tangent-plane DEM stores heights along its plane's normal; the composed height is
  // along the body's. Oracle: a sample's body-fixed position, converted by the body.
  const topo::LocalTangentPlane ltp(kMoon, {10.0, 20.0, 0.0}, 30.0);
  auto f = [](double x, double y) { return 50.0 + 0.02 * x + 0.01 * y; };
  auto pyr = demPyramid(10.0, 201, 201, f);
  const topo::TopoDem dem(pyr.levels[0].grid, topo::Placement(ltp), pyr.levels[0].source);
  Catalogue cat(kMoon);
  cat.add(Dataset::dem(pyr, topo::Placement(ltp), named("plane")));
  const ComposedSurface s(cat.snapshot());
  for (std::size_t r : {0UL, 37UL, 100UL, 199UL}) {
    for (std::size_t c : {3UL, 100UL, 180UL}) {
      const topo::Geodetic g = kMoon.toGeodetic(dem.samplePosition(r, c));
      const topo::HeightSample h = s.height(g.latDeg, g.lonDeg);
      ASSERT_EQ(h.status, QueryStatus::Ok);
      EXPECT_NEAR(h.height, g.height, 1e-5) << r << "," << c;
    }
  }
}

TEST(ComposedSurface, HeightOffsetShiftsADatasetInItsOwnConvention) {
  // A planet grid: +25 m along the body normal. A tangent-plane DEM: +25 m along its plane's
  // normal, so the point (x, y, DEM + 25) must lie on the composed surface.
  auto f = [](double lat, double lon) { return 100.0 + 3.0 * lat - 2.0 * lon; };
  auto planet = planetPyramid(kMoon, 9.75, -9.75, 0.5, 40, 40, f);
  DatasetOptions o = named("shifted");
  o.heightOffset = 25.0;
  Catalogue cat(kMoon);
  cat.add(Dataset::planet(planet, o));
  const ComposedSurface s(cat.snapshot());
  const topo::TopoPlanet own(planet.levels[0].grid, kMoon, topo::LatitudeType::Planetodetic,
                             planet.levels[0].source);
  EXPECT_DOUBLE_EQ(s.height(1.3, 2.7).height, own.height({1.3, 2.7}).height + 25.0);

  const topo::LocalTangentPlane ltp(kMoon, {10.0, 20.0, 0.0}, 30.0);
  auto dem =
      demPyramid(10.0, 201, 201, [](double x, double y) { return 50.0 + 0.02 * x + 0.01 * y; });
  const topo::TopoDem plain(dem.levels[0].grid, topo::Placement(ltp), dem.levels[0].source);
  Catalogue cat2(kMoon);
  cat2.add(Dataset::dem(dem, topo::Placement(ltp), o));
  const ComposedSurface s2(cat2.snapshot());
  for (std::size_t r : {10UL, 100UL, 190UL}) {
    const glm::dvec2 xy = dem.levels[0].grid.sampleCentre(static_cast<double>(r), 60.0);
    const double h = plain.height(xy.x, xy.y).height + 25.0;
    const topo::Geodetic g = kMoon.toGeodetic(ltp.toBodyFixed({xy.x, xy.y, h}));
    EXPECT_NEAR(s2.height(g.latDeg, g.lonDeg).height, g.height, 1e-5) << r;
  }
}

TEST(ComposedSurface, BatchGivesEachPointItsOwnStatus) {
  TwoPlanets t([](double, double) { return 100.0; }, [](double, double) { return 200.0; });
  const ComposedSurface s = t.surface(Policy::FinestWins);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> lats{0.0, nan, 95.0, 45.0, 0.0};
  const std::vector<double> lons{0.0, 0.0, 0.0, 400.0, std::numeric_limits<double>::infinity()};
  std::vector<double> h(5);
  std::vector<QueryStatus> st(5);
  s.heights(lats, lons, h, st);
  EXPECT_EQ(st[0], QueryStatus::Ok);
  EXPECT_DOUBLE_EQ(h[0], 200.0);
  EXPECT_EQ(st[1], QueryStatus::OutsideGrid);
  EXPECT_TRUE(std::isnan(h[1]));
  EXPECT_EQ(st[2], QueryStatus::OutsideGrid);
  EXPECT_EQ(st[3], QueryStatus::Ok);  // 400° is 40°E
  EXPECT_DOUBLE_EQ(h[3], 100.0);
  EXPECT_EQ(st[4], QueryStatus::OutsideGrid);
  std::vector<double> shortOut(4);
  EXPECT_THROW(s.heights(lats, lons, shortOut, st), InvalidArgument);
  // Each bad coordinate is named (the checks run out of line, after one test on the path).
  const double inf = std::numeric_limits<double>::infinity();
  const auto message = [&](double lat, double lon) -> std::string {
    try {
      (void)s.height(lat, lon);
    } catch (const InvalidArgument& e) {
      return e.what();
    }
    return "no error";
  };
  for (const auto& [lat, lon, field] :
       {std::tuple{nan, 0.0, "latitude"}, std::tuple{-inf, 0.0, "latitude"},
        std::tuple{0.0, nan, "longitude"}, std::tuple{0.0, inf, "longitude"},
        std::tuple{91.0, 0.0, "latitude"}, std::tuple{-1e300, 0.0, "latitude"}}) {
    const std::string m = message(lat, lon);
    EXPECT_NE(m.find("compose::ComposedSurface::height()"), std::string::npos) << m;
    EXPECT_NE(m.find(field), std::string::npos) << m;
    EXPECT_NE(m.find(std::isfinite(lat) && std::isfinite(lon) ? "within -90 .. 90" : "finite"),
              std::string::npos)
        << m;
  }
  EXPECT_THROW((void)s.heightAt(91.0, 0.0, 10.0), InvalidArgument);
  EXPECT_THROW((void)s.surface(0.0, nan), InvalidArgument);
}

TEST(ComposedSurface, NodataFallsThroughToTheDatasetBelow) {
  Catalogue cat(kMoon);
  cat.add(Dataset::planet(globalPlanet(kMoon, 1.0, [](double, double) { return 100.0; }),
                          named("global")));
  // The regional grid has a hole (NaN) in its middle.
  cat.add(Dataset::planet(planetPyramid(kMoon, 9.75, -9.75, 0.5, 40, 40,
                                        [](double lat, double lon) {
                                          return std::abs(lat) < 2.0 && std::abs(lon) < 2.0
                                                     ? std::numeric_limits<double>::quiet_NaN()
                                                     : 200.0;
                                        }),
                          named("holed")));
  const ComposedSurface s(cat.snapshot(), Rules{Policy::FinestWins, 2.0});
  EXPECT_DOUBLE_EQ(s.height(0.0, 0.0).height, 100.0);
  EXPECT_DOUBLE_EQ(s.height(6.0, 6.0).height, 200.0);
  // Alone, the holed grid answers Nodata in its hole.
  Catalogue alone(kMoon);
  alone.add(cat.snapshot()->entries()[1].dataset);
  EXPECT_EQ(ComposedSurface(alone.snapshot()).height(0.0, 0.0).status, QueryStatus::Nodata);
}

TEST(ComposedSurface, RefusesBadRules) {
  Catalogue cat(kMoon);
  EXPECT_THROW(ComposedSurface(nullptr), InvalidArgument);
  try {
    (void)ComposedSurface(cat.snapshot(), Rules{Policy::Weighted, -1.0});
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("resolutionPower"), std::string::npos) << e.what();
  }
  // An empty catalogue composes nothing.
  EXPECT_EQ(ComposedSurface(cat.snapshot()).height(0.0, 0.0).status, QueryStatus::OutsideGrid);
}

}  // namespace
}  // namespace regolith::compose
