// The catalogue's spatial index against brute force: every dataset that covers a point (or
// that a view can see) is found, and a query visits O(log N) nodes, not N.

#include <regolith/compose/Catalogue.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/topo/Projection.hpp>

#include "compose/ComposeFixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <set>
#include <thread>
#include <vector>

namespace regolith::compose {
namespace {

using testing::demPyramid;
using testing::named;

const topo::Body kMars = topo::Body::marsEllipsoid();

/// `n` small tangent-plane DEMs (2 km across, 50 m spacing) at random places on Mars.
std::vector<std::shared_ptr<const Dataset>> scatteredDems(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> lat(-80.0, 80.0), lon(-180.0, 180.0), head(0.0, 360.0);
  // One pyramid shared by all: the heights do not matter here, the placements do.
  const auto pyr = demPyramid(50.0, 41, 41, [](double x, double y) { return 0.001 * x * y; });
  std::vector<std::shared_ptr<const Dataset>> out;
  for (std::size_t i = 0; i < n; ++i) {
    DatasetOptions o = named("dem");
    o.heightRange = std::array<double, 2>{-500.0, 500.0};
    out.push_back(Dataset::dem(
        pyr, topo::Placement(topo::LocalTangentPlane(kMars, {lat(rng), lon(rng), 0.0}, head(rng))),
        o));
  }
  return out;
}

TEST(Catalogue, CoveringFindsEveryDatasetThatContainsThePoint) {
  Catalogue cat(kMars);
  const auto dems = scatteredDems(1000, 7);
  for (const auto& d : dems) cat.add(d);
  const auto snap = cat.snapshot();
  ASSERT_EQ(snap->size(), 1000U);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::uint32_t> found;
  std::size_t hits = 0;
  for (int i = 0; i < 4000; ++i) {
    // Half the points near a dataset's centre (so there is something to find), half anywhere.
    double lat = 0.0, lon = 0.0;
    if (i % 2 == 0) {
      const auto& e = snap->entries()[static_cast<std::size_t>(i / 2) % snap->size()];
      const auto& o = e.dataset->placement()->localTangentPlane()->origin();
      lat = o.latDeg + 0.02 * u(rng);
      lon = o.lonDeg + 0.02 * u(rng);
    } else {
      lat = 90.0 * u(rng);
      lon = 180.0 * u(rng);
    }
    found.clear();
    snap->covering(lat, lon, found);
    const std::set<std::uint32_t> got(found.begin(), found.end());
    for (std::uint32_t k = 0; k < snap->size(); ++k) {
      if (snap->entries()[k].dataset->contains(lat, lon)) {
        ++hits;
        EXPECT_TRUE(got.count(k)) << "dataset " << k << " contains " << lat << ", " << lon;
      }
    }
    // The index answers few extra candidates: its boxes are tight.
    EXPECT_LE(found.size(), 4U);
  }
  EXPECT_GT(hits, 1000U);
}

TEST(Catalogue, QueriesVisitLogarithmicallyManyNodes) {
  // The mean number of BVH nodes a point query visits grows like log N: compare N = 100
  // and N = 10000 (a linear scan would visit 100 times more).
  std::vector<double> perQuery;
  for (std::size_t n : {100UL, 10000UL}) {
    Catalogue cat(kMars);
    cat.add(scatteredDems(n, 11));
    const auto snap = cat.snapshot();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> lat(-80.0, 80.0), lon(-180.0, 180.0);
    std::vector<std::uint32_t> found;
    std::size_t visited = 0;
    constexpr int kQueries = 2000;
    for (int i = 0; i < kQueries; ++i) {
      found.clear();
      visited += snap->covering(lat(rng), lon(rng), found);
    }
    perQuery.push_back(static_cast<double>(visited) / kQueries);
  }
  EXPECT_LT(perQuery[1], 4.0 * perQuery[0]) << perQuery[0] << " -> " << perQuery[1];
  EXPECT_LT(perQuery[1], 200.0);
}

TEST(Catalogue, VisibleMatchesBruteForceBoxTests) {
  Catalogue cat(kMars);
  for (const auto& d : scatteredDems(500, 13)) cat.add(d);
  const auto snap = cat.snapshot();
  // A box-shaped "frustum" around a point on the surface, and a half-space.
  const glm::dvec3 p = kMars.toBodyFixed({20.0, 30.0, 0.0});
  for (double half : {5e4, 5e5, 2e6}) {
    const std::vector<glm::dvec4> planes{{1, 0, 0, -(p.x - half)}, {-1, 0, 0, p.x + half},
                                         {0, 1, 0, -(p.y - half)}, {0, -1, 0, p.y + half},
                                         {0, 0, 1, -(p.z - half)}, {0, 0, -1, p.z + half}};
    std::vector<std::uint32_t> found;
    snap->visible(planes, found);
    std::set<std::uint32_t> expected;
    for (std::uint32_t k = 0; k < snap->size(); ++k) {
      const auto& b = snap->entries()[k].dataset->bounds();
      bool overlaps = true;
      for (int a = 0; a < 3; ++a) overlaps &= b[0][a] <= p[a] + half && b[1][a] >= p[a] - half;
      if (overlaps) expected.insert(k);
    }
    EXPECT_EQ(std::set<std::uint32_t>(found.begin(), found.end()), expected) << half;
  }
}

TEST(Catalogue, BoundsHoldEverySampleOfTheDataset) {
  const auto ps = topo::PolarStereographic::withTrueScaleLatitude(
      kMars, topo::PolarStereographic::Pole::South, -90.0, 0.0);
  const auto pyr = demPyramid(2000.0, 301, 301, [](double x, double) { return 1e-3 * x; });
  const auto d = Dataset::dem(pyr, topo::Placement(kMars, ps), named("south cap"));
  const topo::TopoDem dem(pyr.levels[0].grid, topo::Placement(kMars, ps), pyr.levels[0].source);
  for (std::size_t r = 0; r < 301; r += 10) {
    for (std::size_t c = 0; c < 301; c += 10) {
      const glm::dvec3 q = dem.samplePosition(r, c);
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(q[a], d->bounds()[0][a]);
        EXPECT_LE(q[a], d->bounds()[1][a]);
      }
    }
  }
  // The measured height range is exact for a one-level pyramid.
  EXPECT_NEAR(d->heightRange()[0], -300.0, 1e-3);
  EXPECT_NEAR(d->heightRange()[1], 300.0, 1e-3);
}

TEST(Catalogue, AddAndRemoveWhileOtherThreadsQuery) {
  Catalogue cat(kMars);
  const auto dems = scatteredDems(64, 17);
  const auto fixed = dems.front();
  const DatasetId keep = cat.add(fixed);
  const auto& o = fixed->placement()->localTangentPlane()->origin();
  std::atomic<bool> stop{false};
  std::atomic<int> misses{0}, queries{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 2; ++t) {
    readers.emplace_back([&] {
      std::vector<std::uint32_t> found;
      while (!stop.load()) {
        const auto snap = cat.snapshot();
        found.clear();
        snap->covering(o.latDeg, o.lonDeg, found);
        const bool ok = std::any_of(found.begin(), found.end(),
                                    [&](std::uint32_t k) { return snap->entries()[k].id == keep; });
        if (!ok) misses.fetch_add(1);
        queries.fetch_add(1);
      }
    });
  }
  std::vector<DatasetId> ids;
  for (int round = 0; round < 20; ++round) {
    for (std::size_t i = 1; i < dems.size(); ++i) ids.push_back(cat.add(dems[i]));
    for (DatasetId id : ids) EXPECT_TRUE(cat.remove(id));
    ids.clear();
  }
  stop.store(true);
  for (auto& r : readers) r.join();
  EXPECT_EQ(misses.load(), 0);
  EXPECT_GT(queries.load(), 0);
  EXPECT_FALSE(cat.remove(9999));
  EXPECT_EQ(cat.snapshot()->size(), 1U);
}

TEST(Catalogue, RefusesADatasetOfAnotherBody) {
  Catalogue cat(topo::Body::moon());
  const auto d = scatteredDems(1, 1).front();
  try {
    cat.add(d);
    FAIL() << "a Mars dataset entered a Moon catalogue";
  } catch (const InvalidArgument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("compose::Catalogue::add()"), std::string::npos) << m;
    EXPECT_NE(m.find("Moon"), std::string::npos) << m;
  }
  EXPECT_THROW(cat.add(nullptr), InvalidArgument);
}

}  // namespace
}  // namespace regolith::compose
