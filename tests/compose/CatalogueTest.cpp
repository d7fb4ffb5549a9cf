// The catalogue's spatial index against brute force: every dataset that covers a point (or
// that a view can see) is found, and a query visits O(log N) nodes, not N.

#include <regolith/compose/Catalogue.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/topo/Projection.hpp>

#include "compose/ComposeFixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <random>
#include <set>
#include <thread>
#include <tuple>
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

// cellCandidates() (the table of 1° cells that composed point queries use) holds, for every
// point, every dataset covering() returns there and so every dataset that contains it:
// checked at random points, at cell corners and edges, at the poles and across the ±180°
// seam (longitudes given as -180, 180 and beyond), from four threads at once, with each
// cell's list built by whichever thread asks first. A cell names its first candidate in tier
// order (higher priority, then finer spacing, then the lower index; a composed query's
// shortcut), an empty cell none; a look-up in the table taken once gives the very cell the
// plain look-up does.
TEST(Catalogue, CellCandidatesHoldEveryCoveringDataset) {
  Catalogue cat(kMars);
  auto dems = scatteredDems(300, 23);
  std::vector<std::array<double, 2>> points;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // DEMs astride the seam and at both poles, where the cells are narrowest.
  const auto pyr = demPyramid(50.0, 41, 41, [](double x, double y) { return 0.001 * x * y; });
  for (const topo::Geodetic site :
       {topo::Geodetic{0.0, 180.0, 0.0}, topo::Geodetic{89.99, 0.0, 0.0},
        topo::Geodetic{-89.99, 45.0, 0.0}, topo::Geodetic{12.0, -179.995, 0.0}}) {
    DatasetOptions o = named("edge");
    o.heightRange = std::array<double, 2>{-500.0, 500.0};
    dems.push_back(
        Dataset::dem(pyr, topo::Placement(topo::LocalTangentPlane(kMars, site, 30.0)), o));
  }
  // A flat DEM 400 km across on the north pole: its plane stands up to 12 km above the
  // ellipsoid at its corners, far outside its own height range [0, 1] (and its box, flat
  // along z, is as thin); the catalogue still finds it there.
  {
    DatasetOptions o = named("wide");
    o.heightRange = std::array<double, 2>{0.0, 1.0};
    dems.push_back(
        Dataset::dem(demPyramid(4000.0, 101, 101, [](double, double) { return 0.0; }),
                     topo::Placement(topo::LocalTangentPlane(kMars, {90.0, 0.0, 0.0}, 0.0)), o));
    EXPECT_GT(dems.back()->ellipsoidHeightRange()[1], 10000.0);
    EXPECT_LT(dems.back()->ellipsoidHeightRange()[0], 0.0);
    for (int j = 0; j < 400; ++j) {
      points.push_back(
          {90.0 - 4.0 * std::abs(u(rng)), 180.0 * u(rng)});  // to its corners and beyond
    }
  }
  // Last (the highest index), a coarse DEM of priority 1 on the north pole: the first in tier
  // order in every cell it reaches, before the finer and earlier DEMs there.
  {
    DatasetOptions o = named("priority");
    o.priority = 1;
    o.heightRange = std::array<double, 2>{0.0, 1.0};
    dems.push_back(
        Dataset::dem(demPyramid(2000.0, 41, 41, [](double, double) { return 0.0; }),
                     topo::Placement(topo::LocalTangentPlane(kMars, {90.0, 0.0, 0.0}, 0.0)), o));
  }
  // A tangent plane's point on the far side of the body is not in the DEM, though its foot
  // on the plane is (the north pole's foot on a south-polar plane is the plane's origin).
  EXPECT_TRUE(dems[302]->contains(-89.99, 45.0));
  EXPECT_FALSE(dems[302]->contains(89.99, -135.0));
  EXPECT_FALSE(dems[301]->contains(-89.99, 180.0));
  for (const auto& d : dems) cat.add(d);
  const auto snap = cat.snapshot();
  for (std::uint32_t k = 0; k < snap->size(); ++k) {  // around each dataset's origin
    const auto& o = snap->entries()[k].dataset->placement()->localTangentPlane()->origin();
    for (int j = 0; j < 8; ++j) {
      points.push_back(
          {std::clamp(o.latDeg + 0.02 * u(rng), -90.0, 90.0), o.lonDeg + 0.03 * u(rng)});
    }
  }
  for (int j = 0; j < 2000; ++j) points.push_back({90.0 * u(rng), 540.0 * u(rng)});
  for (const double lat : {-90.0, -89.5, -1.0, 0.0, 1.0, 89.0, 90.0}) {
    for (const double lon : {-540.0, -180.0, -179.0, 0.0, 179.0, 180.0, 181.0}) {
      points.push_back({lat, lon});
    }
  }
  std::atomic<std::size_t> missing{0}, missingExact{0}, contained{0}, longest{0};
  std::atomic<std::size_t> badTop{0}, soles{0}, otherCell{0};
  auto check = [&](std::size_t begin, std::size_t step) {
    std::vector<std::uint32_t> found;
    for (std::size_t i = begin; i < points.size(); i += step) {
      const auto [lat, lon] = points[i];
      const auto cell = snap->cellCandidates(lat, lon);
      const Snapshot::Cell& whole = snap->cell(snap->cellTable(Role::Height), lat, lon);
      otherCell += whole.candidates.data() != cell.data() ? 1U : 0U;
      const auto first =
          std::min_element(cell.begin(), cell.end(), [&](std::uint32_t ia, std::uint32_t ib) {
            const Dataset& a = *snap->entries()[ia].dataset;
            const Dataset& b = *snap->entries()[ib].dataset;
            return std::tuple(-a.options().priority, a.groundSpacing(), ia) <
                   std::tuple(-b.options().priority, b.groundSpacing(), ib);
          });
      const Dataset* top = first == cell.end() ? nullptr : snap->entries()[*first].dataset.get();
      badTop += whole.top != top || (top != nullptr && whole.topEntry != *first) ? 1U : 0U;
      soles += cell.size() == 1 ? 1U : 0U;
      found.clear();
      snap->covering(lat, lon, found);
      for (const std::uint32_t e : found) {
        if (!std::binary_search(cell.begin(), cell.end(), e)) ++missing;
      }
      std::sort(found.begin(), found.end());
      for (std::uint32_t k = 0; k < snap->size(); ++k) {
        if (snap->entries()[k].dataset->contains(lat, lon)) {
          ++contained;
          if (!std::binary_search(cell.begin(), cell.end(), k)) ++missing;
          if (!std::binary_search(found.begin(), found.end(), k)) ++missingExact;
        }
      }
      std::size_t seen = longest.load();
      while (cell.size() > seen && !longest.compare_exchange_weak(seen, cell.size())) {
      }
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 4; ++t) threads.emplace_back(check, t, 4);
  for (auto& t : threads) t.join();
  EXPECT_EQ(missing.load(), 0U);
  EXPECT_EQ(missingExact.load(), 0U);
  EXPECT_EQ(badTop.load(), 0U);
  EXPECT_EQ(otherCell.load(), 0U);
  EXPECT_GT(soles.load(), 100U);  // both kinds of cell were seen
  EXPECT_GT(points.size() - soles.load(), 100U);
  EXPECT_GT(contained.load(), 2000U);  // the points do land in datasets
  // The lists stay short: a cell holds the few datasets near it, not the catalogue.
  EXPECT_LE(longest.load(), 12U);
  // Role filter: no height dataset is an albedo candidate.
  EXPECT_TRUE(snap->cellCandidates(0.0, 180.0, Role::Albedo).empty());
  // An empty catalogue and a non-finite point have none.
  EXPECT_TRUE(Catalogue(kMars).snapshot()->cellCandidates(0.0, 0.0).empty());
  EXPECT_TRUE(snap->cellCandidates(std::nan(""), 0.0).empty());
  // A finite latitude beyond the poles (no query passes one; the call is public) is the
  // last cell's, without converting a huge value to an integer (undefined behaviour, which
  // the sanitizer jobs would report).
  for (const double lat : {1e300, 90.5, -1e300, -91.0}) {
    const auto beyond = snap->cellCandidates(lat, 10.0);
    const auto edge = snap->cellCandidates(lat > 0.0 ? 90.0 : -90.0, 10.0);
    EXPECT_TRUE(std::equal(beyond.begin(), beyond.end(), edge.begin(), edge.end())) << lat;
  }
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
