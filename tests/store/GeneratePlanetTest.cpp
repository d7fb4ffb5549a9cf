// MarsPlanetGenerator: the store it writes (read back with Store, not through the generator)
// against its point function; determinism across seeds, patch sizes and threads; continuity
// across the ±180° seam and at both poles; craters (power law, bowl, rim, ejecta); errors.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Pager.hpp>

#include "support/StoreScratch.hpp"

#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numbers>
#include <numeric>
#include <span>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) { return test::scratchFile("genplanet", name); }

MarsPlanetOptions smallPlanet(std::uint64_t seed = 7) {
  MarsPlanetOptions o;
  o.rows = 90;
  o.seed = seed;
  o.write.patchRows = 32;
  o.write.patchCols = 32;
  return o;
}

using test::readLevel0;

bool bitwiseEqual(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

double rms(const std::vector<double>& v) {
  double s = 0.0;
  for (const double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

}  // namespace

TEST(GeneratePlanet, GridCoversTheWholePlanetWithBothPoles) {
  const MarsPlanetGenerator g(smallPlanet());
  const GridInfo info = g.gridInfo();
  EXPECT_EQ(info.kind, GridKind::Planet);
  EXPECT_EQ(info.name, "mars");
  EXPECT_EQ(info.rows, 90U);
  EXPECT_EQ(info.cols, 180U);
  EXPECT_DOUBLE_EQ(info.spacingX, 2.0);
  EXPECT_DOUBLE_EQ(info.spacingY, 2.0);
  const topo::TopoGrid grid = topoGridOf(info);
  EXPECT_DOUBLE_EQ(grid.west(), -180.0);
  EXPECT_DOUBLE_EQ(grid.east(), 180.0);
  EXPECT_DOUBLE_EQ(grid.north(), 90.0);
  EXPECT_DOUBLE_EQ(grid.south(), -90.0);
  EXPECT_EQ(info.latitudeType, topo::LatitudeType::Planetocentric);
  EXPECT_EQ(info.bodyName, "Mars");
  EXPECT_DOUBLE_EQ(info.equatorialRadius, 3396190.0);
  EXPECT_DOUBLE_EQ(info.polarRadius, 3396190.0);

  MarsPlanetOptions e = smallPlanet();
  e.ellipsoid = true;
  const GridInfo ei = MarsPlanetGenerator(e).gridInfo();
  EXPECT_DOUBLE_EQ(ei.equatorialRadius, 3396190.0);
  EXPECT_DOUBLE_EQ(ei.polarRadius, 3376200.0);
  EXPECT_EQ(ei.latitudeType, topo::LatitudeType::Planetocentric);
}

TEST(GeneratePlanet, StoredSamplesEqualThePointFunctionAtSampleCentres) {
  MarsPlanetOptions o = smallPlanet();
  o.write.levels = 3;
  const MarsPlanetGenerator g(o);
  const fs::path path = scratch("points.h5");
  g.write(path);
  const std::vector<float> v = readLevel0(path, "mars");
  const topo::TopoGrid grid = topoGridOf(g.gridInfo());
  std::size_t mismatches = 0;
  for (std::size_t r = 0; r < grid.rows(); ++r) {
    for (std::size_t c = 0; c < grid.cols(); ++c) {
      const glm::dvec2 p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      const auto expected = static_cast<float>(g.height(p.y, p.x));
      if (std::memcmp(&expected, &v[r * grid.cols() + c], sizeof(float)) != 0) ++mismatches;
    }
  }
  EXPECT_EQ(mismatches, 0U);
  const Store s = Store::open(path);
  EXPECT_EQ(s.grid("mars").levels, 3U);
  EXPECT_EQ(s.grid("mars").patchRows, 32U);
}

TEST(GeneratePlanet, SameSeedIsBitIdenticalWhateverThePatchesAndThreads) {
  MarsPlanetOptions a = smallPlanet(11);
  a.threads = 1;
  MarsPlanetOptions b = smallPlanet(11);
  b.write.patchRows = 90;  // windows of 90 x 100 samples: split over threads
  b.write.patchCols = 100;
  b.threads = 3;
  MarsPlanetOptions c = smallPlanet(11);
  c.write.patchRows = 45;
  c.write.patchCols = 17;
  MarsPlanetGenerator(a).write(scratch("a.h5"));
  MarsPlanetGenerator(b).write(scratch("b.h5"));
  MarsPlanetGenerator(c).write(scratch("c.h5"));
  const std::vector<float> va = readLevel0(scratch("a.h5"), "mars");
  EXPECT_TRUE(bitwiseEqual(va, readLevel0(scratch("b.h5"), "mars")));
  EXPECT_TRUE(bitwiseEqual(va, readLevel0(scratch("c.h5"), "mars")));
  // Samples one by one agree with the windows too.
  const auto source = MarsPlanetGenerator(b).samples();
  for (std::size_t r = 0; r < 90; r += 7) {
    for (std::size_t col = 0; col < 180; col += 11) {
      EXPECT_EQ(source->sample(r, col), va[r * 180 + col]);
    }
  }

  MarsPlanetGenerator(smallPlanet(12)).write(scratch("d.h5"));
  const std::vector<float> vc = readLevel0(scratch("d.h5"), "mars");
  std::size_t differ = 0;
  for (std::size_t i = 0; i < va.size(); ++i) differ += va[i] != vc[i] ? 1U : 0U;
  EXPECT_GT(differ, va.size() * 99 / 100);
}

TEST(GeneratePlanet, SeamColumnsAreContinuous) {
  const MarsPlanetGenerator g(smallPlanet());
  const fs::path path = scratch("seam.h5");
  g.write(path);
  const std::vector<float> v = readLevel0(path, "mars");
  const std::size_t rows = 90, cols = 180;
  // Across the seam (last column to first) the step is like any step between neighbours.
  std::vector<double> seam, interior;
  for (std::size_t r = 0; r < rows; ++r) {
    seam.push_back(static_cast<double>(v[r * cols] - v[r * cols + cols - 1]));
    for (std::size_t c = 0; c + 1 < cols; ++c) {
      interior.push_back(static_cast<double>(v[r * cols + c + 1] - v[r * cols + c]));
    }
  }
  EXPECT_LT(rms(seam), 2.0 * rms(interior));
  EXPECT_GT(rms(seam), 0.0);
  // The function itself: a micro-degree either side of ±180° differs by centimetres at most.
  for (double lat = -89.0; lat <= 89.0; lat += 7.0) {
    EXPECT_NEAR(g.height(lat, 180.0 - 1e-6), g.height(lat, -180.0 + 1e-6), 0.05) << lat;
    EXPECT_NEAR(g.height(lat, 180.0 - 1e-6), g.height(lat, 180.0 + 1e-6), 0.05) << lat;
    // Longitudes in any range name the same point.
    EXPECT_NEAR(g.height(lat, 10.0), g.height(lat, 370.0), 1e-6);
    EXPECT_NEAR(g.height(lat, -100.0), g.height(lat, 260.0), 1e-6);
  }
}

TEST(GeneratePlanet, HeightsNearEachPoleAgreeAcrossLongitudes) {
  const MarsPlanetGenerator g(smallPlanet());
  for (const double pole : {90.0, -90.0}) {
    std::vector<double> at, near;
    for (double lon = -180.0; lon < 180.0; lon += 10.0) {
      at.push_back(g.height(pole, lon));
      near.push_back(g.height(pole - std::copysign(1e-7, pole), lon));
    }
    const auto spread = [](const std::vector<double>& x) {
      const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
      return *hi - *lo;
    };
    EXPECT_LT(spread(at), 1e-6) << pole;
    EXPECT_LT(spread(near), 0.01) << pole;  // points 2e-7 degrees (1.2 cm) apart at most
    // A degree from the pole the terrain does vary with longitude (the test can fail).
    std::vector<double> far;
    for (double lon = -180.0; lon < 180.0; lon += 10.0) {
      far.push_back(g.height(pole - std::copysign(10.0, pole), lon));
    }
    EXPECT_GT(spread(far), 10.0) << pole;
  }
  // In the store, the rows nearest the poles vary far less along the row than a row does.
  const fs::path path = scratch("poles.h5");
  g.write(path);
  const std::vector<float> v = readLevel0(path, "mars");
  const std::size_t rows = 90, cols = 180;
  const auto rowSpread = [&](std::size_t r) {
    const auto [lo, hi] = std::minmax_element(v.begin() + static_cast<long>(r * cols),
                                              v.begin() + static_cast<long>((r + 1) * cols));
    return static_cast<double>(*hi - *lo);
  };
  EXPECT_LT(rowSpread(0), 0.25 * rowSpread(rows / 2));
  EXPECT_LT(rowSpread(rows - 1), 0.25 * rowSpread(rows / 2));
  // Paged through topo, the planet has both polar caps and one height at each pole.
  auto store = std::make_shared<const Store>(Store::open(path));
  const Pager pager(store, std::make_shared<PatchCache>(std::size_t{8} << 20));
  const topo::TopoPlanet planet = pager.planet("mars");
  EXPECT_TRUE(planet.isGlobalInLongitude());
  EXPECT_TRUE(planet.hasNorthCap());
  EXPECT_TRUE(planet.hasSouthCap());
  for (const double lon : {-170.0, -20.0, 45.0, 135.0}) {
    EXPECT_DOUBLE_EQ(planet.height({90.0, lon}).height, planet.northPoleHeight());
    EXPECT_DOUBLE_EQ(planet.height({-90.0, lon}).height, planet.southPoleHeight());
  }
}

TEST(GeneratePlanet, APagedPlanetOpensWithoutReadingAndFindsItsPolesOutsideTheCache) {
  MarsPlanetOptions o = smallPlanet(5);
  o.rows = 256;  // 512 columns: a row of 16 patches of 32 × 32
  const fs::path path = scratch("lazy_poles.h5");
  MarsPlanetGenerator(o).write(path);
  const std::size_t rows = 256, cols = 512;
  const std::vector<float> v = readLevel0(path, "mars");
  ASSERT_EQ(v.size(), rows * cols);
  const auto rowMean = [&](std::size_t r) {  // the rule: valid samples, column order, double
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t c = 0; c < cols; ++c) {
      if (!std::isnan(v[r * cols + c])) {
        sum += static_cast<double>(v[r * cols + c]);
        ++n;
      }
    }
    return sum / static_cast<double>(n);
  };
  auto cache = std::make_shared<PatchCache>(std::size_t{8} << 20);
  const Pager pager(std::make_shared<const Store>(Store::open(path)), cache);
  const topo::TopoPlanet planet = pager.planet("mars");
  EXPECT_EQ(cache->stats().loads, 0U) << "opening a planet reads no patch";
  // A bilinear query in the north cap loads its stencil's patch or two, not the pole row's 16:
  // the pole's mean is read outside the cache.
  ASSERT_TRUE(planet.height({89.9, 30.0}).valid());
  EXPECT_GE(cache->stats().loads, 1U);
  EXPECT_LE(cache->stats().loads, 2U);
  EXPECT_EQ(planet.northPoleHeight(), rowMean(0));
  EXPECT_EQ(planet.height({90.0, 12.0}).height, rowMean(0));
  ASSERT_TRUE(planet.height({-89.9, -100.0}).valid());
  EXPECT_LE(cache->stats().loads, 4U);
  EXPECT_EQ(planet.southPoleHeight(), rowMean(rows - 1));
  // The caps answer exactly as the same samples in memory, read sample by sample, do.
  const GridInfo& info = pager.grid("mars");
  const topo::TopoPlanet mem(topoGridOf(info), bodyOf(info), info.latitudeType,
                             std::make_shared<topo::InMemorySamples>(rows, cols, v));
  for (const double lat : {89.9, 89.99, 90.0, -89.8, -90.0}) {
    for (const double lon : {-179.5, 0.0, 30.0, 123.4}) {
      for (const topo::Interpolation k :
           {topo::Interpolation::Nearest, topo::Interpolation::Bilinear,
            topo::Interpolation::Bicubic}) {
        const topo::SurfaceSample a = mem.surface({lat, lon}, k);
        const topo::SurfaceSample b = planet.surface({lat, lon}, k);
        ASSERT_EQ(a.status, b.status) << lat << "," << lon;
        EXPECT_EQ(a.height, b.height) << lat << "," << lon;
        EXPECT_EQ(a.normal, b.normal) << lat << "," << lon;
      }
    }
  }
}

TEST(GeneratePlanet, CratersFollowAPowerLawAndHaveBowlRimAndEjecta) {
  MarsPlanetOptions o = smallPlanet(3);
  o.rows = 720;
  o.craterDensity = 8.0;
  const MarsPlanetGenerator g(o);
  ASSERT_EQ(g.craterBands(), 4U);  // 600–1200 km down to 75–150 km at 14.8 km spacing
  const std::vector<GeneratedCrater> all = g.craters();
  // Cumulative counts N(>D) at D = 1200/2^k: log-log slope −2 (fitted over k = 1…4).
  std::vector<double> logD, logN;
  for (std::size_t k = 1; k <= 4; ++k) {
    const double d = 1200.0 / std::pow(2.0, static_cast<double>(k));
    const auto n = std::count_if(all.begin(), all.end(),
                                 [&](const GeneratedCrater& c) { return c.diameterKm > d; });
    ASSERT_GT(n, 0);
    logD.push_back(std::log(d));
    logN.push_back(std::log(static_cast<double>(n)));
  }
  const double mx = std::accumulate(logD.begin(), logD.end(), 0.0) / 4.0;
  const double my = std::accumulate(logN.begin(), logN.end(), 0.0) / 4.0;
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    sxy += (logD[i] - mx) * (logN[i] - my);
    sxx += (logD[i] - mx) * (logD[i] - mx);
  }
  EXPECT_NEAR(sxy / sxx, -2.0, 0.2);
  for (const GeneratedCrater& c : all) {
    const double lo = 1200.0 / std::pow(2.0, static_cast<double>(c.band + 1));
    EXPECT_GE(c.diameterKm, lo * (1 - 1e-12));
    EXPECT_LE(c.diameterKm, 2.0 * lo * (1 + 1e-12));
    EXPECT_GT(c.depth, 0.0);
    EXPECT_GT(c.rim, 0.0);
  }
}

TEST(GeneratePlanet, CratersHaveABowlARaisedRimAndEjecta) {
  // The difference between the planet with craters and the same planet without, around
  // craters that no other crater's ejecta reach: a bowl, a raised rim, ejecta thinning out
  // to nothing at 2.5 radii.
  MarsPlanetOptions o = smallPlanet(3);
  o.rows = 360;
  const MarsPlanetGenerator g(o);
  MarsPlanetOptions bare = o;
  bare.craterDensity = 0.0;
  const MarsPlanetGenerator flat(bare);
  EXPECT_EQ(flat.craterBands(), 0U);
  const std::vector<GeneratedCrater> all = g.craters();
  constexpr double kR = 3396.19;  // km
  const auto unit = [](double lat, double lon) {
    const double p = lat * std::numbers::pi / 180.0, l = lon * std::numbers::pi / 180.0;
    return std::array<double, 3>{std::cos(p) * std::cos(l), std::cos(p) * std::sin(l), std::sin(p)};
  };
  const auto angle = [&](const GeneratedCrater& a, const GeneratedCrater& b) {
    const auto u = unit(a.latDeg, a.lonDeg), v = unit(b.latDeg, b.lonDeg);
    return std::acos(std::clamp(u[0] * v[0] + u[1] * v[1] + u[2] * v[2], -1.0, 1.0));
  };
  std::size_t checked = 0;
  for (const GeneratedCrater& c : all) {
    if (std::abs(c.latDeg) > 60.0) continue;
    const double radius = 0.5 * c.diameterKm / kR;  // radians
    const bool isolated = std::all_of(all.begin(), all.end(), [&](const GeneratedCrater& d) {
      return &d == &c || angle(c, d) > 2.5 * (radius + 0.5 * d.diameterKm / kR) + 0.01;
    });
    if (!isolated) continue;
    // The point at `distance` radii from the centre along bearing az (great circle).
    const auto added = [&](double distance, double az) {
      const double d2r = std::numbers::pi / 180.0;
      const double p1 = c.latDeg * d2r, delta = distance * radius;
      const double p2 =
          std::asin(std::sin(p1) * std::cos(delta) + std::cos(p1) * std::sin(delta) * std::cos(az));
      const double dl = std::atan2(std::sin(az) * std::sin(delta) * std::cos(p1),
                                   std::cos(delta) - std::sin(p1) * std::sin(p2));
      const double lat = p2 / d2r, lon = c.lonDeg + dl / d2r;
      return g.height(lat, lon) - flat.height(lat, lon);
    };
    const double centre = added(0.0, 0.0);
    EXPECT_LT(centre, -0.6 * c.depth) << c.latDeg << " " << c.lonDeg;
    EXPECT_GT(centre, -1.01 * c.depth);
    for (int a = 0; a < 8; ++a) {
      const double az = a * std::numbers::pi / 4.0;
      const double rim = added(1.0, az), ejecta = added(1.6, az), beyond = added(2.55, az);
      EXPECT_NEAR(rim, c.rim, 0.01 * c.rim) << az;
      EXPECT_GT(ejecta, 0.1 * c.rim);
      EXPECT_LT(ejecta, 0.3 * c.rim);
      EXPECT_EQ(beyond, 0.0);
    }
    ++checked;
  }
  EXPECT_GE(checked, 3U);
}

TEST(GeneratePlanet, CoarserBandsAndReliefAreTheSameAtEveryResolution) {
  MarsPlanetOptions coarse = smallPlanet(5), fine = smallPlanet(5);
  fine.rows = 360;
  const MarsPlanetGenerator a(coarse), b(fine);
  EXPECT_LT(a.craterBands(), b.craterBands());
  EXPECT_LT(a.octaves(), b.octaves());
  const std::vector<GeneratedCrater> ca = a.craters(), cb = b.craters();
  std::size_t common = 0;
  for (const GeneratedCrater& c : ca) {
    const bool found = std::any_of(cb.begin(), cb.end(), [&](const GeneratedCrater& d) {
      return d.band == c.band && d.latDeg == c.latDeg && d.lonDeg == c.lonDeg &&
             d.diameterKm == c.diameterKm;
    });
    common += found ? 1U : 0U;
  }
  EXPECT_EQ(common, ca.size());
  EXPECT_GT(ca.size(), 0U);
}

TEST(GeneratePlanet, ReliefIsMarsLike) {
  MarsPlanetOptions o = smallPlanet(2);
  o.rows = 180;
  const MarsPlanetGenerator g(o);
  const fs::path path = scratch("relief.h5");
  g.write(path);
  const std::vector<float> v = readLevel0(path, "mars");
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  // Mars spans about 30 km from Hellas to Olympus Mons; the generator the same order.
  EXPECT_GT(static_cast<double>(*hi - *lo), 15000.0);
  EXPECT_LT(static_cast<double>(*hi - *lo), 40000.0);
  for (const float h : v) ASSERT_TRUE(std::isfinite(h));
}

TEST(GeneratePlanet, BadOptionsAreRefused) {
  MarsPlanetOptions o = smallPlanet();
  o.rows = 1;
  EXPECT_THROW(MarsPlanetGenerator{o}, InvalidArgument);
  o = smallPlanet();
  o.craterDensity = -1.0;
  EXPECT_THROW(MarsPlanetGenerator{o}, InvalidArgument);
  o = smallPlanet();
  o.gridName = "";
  EXPECT_THROW(MarsPlanetGenerator{o}, InvalidArgument);
  const MarsPlanetGenerator g(smallPlanet());
  EXPECT_THROW((void)g.height(91.0, 0.0), InvalidArgument);
  EXPECT_THROW((void)g.height(0.0, std::nan("")), InvalidArgument);
  // A write that fails leaves no file.
  o = smallPlanet();
  o.write.deflate = 12;
  const fs::path path = scratch("bad.h5");
  EXPECT_THROW(MarsPlanetGenerator(o).write(path), InvalidArgument);
  EXPECT_FALSE(fs::exists(path));
}

TEST(GeneratePlanet, HeightsAtUnitVectorsAreThePointFunctionWhateverTheWindow) {
  // heightsAt() on scattered points (both poles, the ±180° seam, a tight cluster, random
  // points: windows whose crater search spans every longitude or wraps the seam) equals
  // height() at each point's latitude and longitude, to the bit, whatever the grouping.
  MarsPlanetOptions o = smallPlanet(17);
  o.rows = 720;
  o.threads = 1;
  const MarsPlanetGenerator g(o);
  ASSERT_GT(g.craterBands(), 2U);
  std::vector<std::array<double, 2>> latLon{{90.0, 0.0},      {-90.0, 0.0},   {89.99, 179.99},
                                            {-89.9, -179.9},  {0.0, -180.0},  {10.0, 179.999},
                                            {10.0, -179.999}, {45.0, 45.0},   {45.001, 45.001},
                                            {44.999, 45.002}, {-60.0, 120.0}, {-60.01, 120.02}};
  std::uint64_t state = 99;
  const auto uniform = [&state] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11U) * 0x1.0p-53;
  };
  while (latLon.size() < 60) {
    latLon.push_back(
        {std::asin(2.0 * uniform() - 1.0) * 180.0 / std::numbers::pi, -180.0 + 360.0 * uniform()});
  }
  std::vector<glm::dvec3> units;
  for (const auto& [lat, lon] : latLon) {
    constexpr double kDegToRad = std::numbers::pi / 180.0;  // as the generator rounds it
    const double phi = lat * kDegToRad, lambda = lon * kDegToRad;
    units.emplace_back(std::cos(phi) * std::cos(lambda), std::cos(phi) * std::sin(lambda),
                       std::sin(phi));
  }
  std::vector<double> together(units.size()), asGrid(units.size());
  g.heightsAt(units, units.size(), together);  // one row
  g.heightsAt(units, 6, asGrid);               // 10 rows of 6
  for (std::size_t i = 0; i < units.size(); ++i) {
    const double expected = g.height(latLon[i][0], latLon[i][1]);
    double alone = 0.0;
    g.heightsAt(std::span(&units[i], 1), 1, std::span(&alone, 1));
    EXPECT_EQ(std::memcmp(&together[i], &expected, sizeof(double)), 0)
        << latLon[i][0] << ", " << latLon[i][1] << ": " << together[i] << " vs " << expected;
    EXPECT_EQ(std::memcmp(&asGrid[i], &expected, sizeof(double)), 0) << i;
    EXPECT_EQ(std::memcmp(&alone, &expected, sizeof(double)), 0) << i;
  }
}
