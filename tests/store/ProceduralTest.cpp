// proceduralMars() / proceduralPager(): every level against stores the generator writes (bit
// for bit), the coarse levels against the store's 2×2 pyramid (within the detail a coarser
// planet leaves out), pole heights against an in-memory TopoPlanet, and a 2^20-row planet
// (2^20 × 2^21 samples) paged with no disk: samples at the poles, on the ±180° seam and at
// random points against the generator's point function in double, the cache within its
// budget, and the memory an open takes independent of the grid's size.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Procedural.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "support/StoreScratch.hpp"
#include "support/WorkScale.hpp"

#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kSmallRows = 256;  // a 512 × 256 planet
constexpr std::size_t kSmallPatch = 64;  // four levels: 256, 128, 64 and 32 rows

MarsPlanetOptions smallPlanet(std::size_t rows) {
  MarsPlanetOptions o;
  o.rows = rows;
  o.seed = 11;
  o.write.patchRows = kSmallPatch;
  o.write.patchCols = kSmallPatch;
  return o;
}

ProceduralMarsOptions proceduralOf(const MarsPlanetOptions& planet, std::size_t patch) {
  ProceduralMarsOptions o;
  o.planet = planet;
  o.patchRows = patch;
  o.patchCols = patch;
  return o;
}

std::vector<float> readAll(const topo::SampleSource& s) {
  std::vector<float> v(s.rows() * s.cols());
  s.readWindow(0, 0, s.rows(), s.cols(), v);
  return v;
}

bool bitwiseEqual(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// A store written by the generator (what `regolith generate planet` writes), once per size.
fs::path generatedStore(std::size_t rows) {
  const fs::path path = test::scratchFile("procedural", "mars-" + std::to_string(rows) + ".h5");
  if (!fs::exists(path)) MarsPlanetGenerator(smallPlanet(rows)).write(path);
  return path;
}

/// Resident set size of this process, bytes (/proc/self/statm, second field).
std::size_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

}  // namespace

TEST(Procedural, GridIsTheGeneratorsWithTheWritersLevels) {
  const auto src = proceduralMars(proceduralOf(smallPlanet(kSmallRows), kSmallPatch));
  const Store store = Store::open(generatedStore(kSmallRows));
  const GridInfo& a = src->grid("mars");
  const GridInfo& b = store.grid("mars");
  EXPECT_EQ(src->gridNames(), std::vector<std::string>{"mars"});
  EXPECT_EQ(a.kind, GridKind::Planet);
  EXPECT_EQ(a.rows, b.rows);
  EXPECT_EQ(a.cols, b.cols);
  EXPECT_EQ(a.levels, b.levels);
  EXPECT_EQ(a.levels, 4U);
  EXPECT_EQ(a.patchRows, b.patchRows);
  EXPECT_EQ(a.patchCols, b.patchCols);
  EXPECT_EQ(a.bodyName, b.bodyName);
  EXPECT_EQ(a.equatorialRadius, b.equatorialRadius);
  EXPECT_EQ(a.polarRadius, b.polarRadius);
  for (std::size_t k = 0; k < a.levels; ++k) {
    const topo::TopoGrid ga = topoGridOf(a, k), gb = topoGridOf(b, k);
    EXPECT_EQ(ga.rows(), gb.rows());
    EXPECT_EQ(ga.cols(), gb.cols());
    EXPECT_EQ(ga.x0(), gb.x0());
    EXPECT_EQ(ga.y0(), gb.y0());
    EXPECT_EQ(ga.spacingX(), gb.spacingX());
    EXPECT_EQ(ga.spacingY(), gb.spacingY());
  }
  EXPECT_EQ(src->name(), "procedural Mars (seed 11, 256 rows)");
}

TEST(Procedural, Level0IsTheGeneratedStoreBitForBit) {
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Pager stored(std::make_shared<const Store>(Store::open(generatedStore(kSmallRows))), cache);
  const Pager computed = proceduralPager(proceduralOf(smallPlanet(kSmallRows), kSmallPatch), cache);
  EXPECT_FALSE(computed.hasStore());
  EXPECT_TRUE(stored.hasStore());
  const auto a = readAll(*computed.pyramid("mars").levels[0].source);
  const auto b = readAll(*stored.pyramid("mars").levels[0].source);
  EXPECT_TRUE(bitwiseEqual(a, b));
  // And sample by sample through the cache's patches, against the generator's point
  // function in double (an outside oracle for both).
  const MarsPlanetGenerator gen(smallPlanet(kSmallRows));
  const GridInfo info = gen.gridInfo();
  const auto src = computed.source("mars", 0);
  for (std::size_t r = 0; r < info.rows; r += 7) {
    for (std::size_t c = 0; c < info.cols; c += 5) {
      const double lat = info.y0 - static_cast<double>(r) * info.spacingY;
      const double lon = info.x0 + static_cast<double>(c) * info.spacingX;
      ASSERT_EQ(src->sample(r, c), static_cast<float>(gen.height(lat, lon))) << r << ", " << c;
    }
  }
}

TEST(Procedural, CoarseLevelsAreThePlanetGeneratedAtTheirSize) {
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Pager computed = proceduralPager(proceduralOf(smallPlanet(kSmallRows), kSmallPatch), cache);
  const topo::GridPyramid p = computed.pyramid("mars");
  ASSERT_EQ(p.levels.size(), 4U);
  for (std::size_t k = 1; k < p.levels.size(); ++k) {
    const std::size_t rows = kSmallRows >> k;
    EXPECT_TRUE(
        bitwiseEqual(readAll(*p.levels[k].source), test::readLevel0(generatedStore(rows), "mars")))
        << "level " << k;
  }
}

namespace {

struct LevelDifference {
  double rmsDiff = 0.0, medianDiff = 0.0, maxDiff = 0.0;
  double rmsShift = 0.0;  // the store level against itself one column east
};

/// Level k of a generated store (2×2 means) against level k computed, for a planet.
std::vector<LevelDifference> pyramidDifferences(const MarsPlanetOptions& planet,
                                                const std::string& file) {
  const fs::path path = test::scratchFile("procedural", file);
  if (!fs::exists(path)) MarsPlanetGenerator(planet).write(path);
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Pager stored(std::make_shared<const Store>(Store::open(path)), cache);
  const Pager computed = proceduralPager(proceduralOf(planet, kSmallPatch), cache);
  const topo::GridPyramid ps = stored.pyramid("mars"), pc = computed.pyramid("mars");
  std::vector<LevelDifference> out(ps.levels.size());
  for (std::size_t k = 1; k < ps.levels.size(); ++k) {
    const auto s = readAll(*ps.levels[k].source), c = readAll(*pc.levels[k].source);
    const std::size_t rows = ps.levels[k].source->rows(), cols = ps.levels[k].source->cols();
    double diff2 = 0.0, shift2 = 0.0;
    std::vector<double> absDiff;
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t col = 0; col < cols; ++col) {
        const double d =
            static_cast<double>(s[r * cols + col]) - static_cast<double>(c[r * cols + col]);
        diff2 += d * d;
        absDiff.push_back(std::abs(d));
        const double e = static_cast<double>(s[r * cols + col]) -
                         static_cast<double>(s[r * cols + (col + 1) % cols]);
        shift2 += e * e;
      }
    }
    const auto n = static_cast<double>(rows * cols);
    LevelDifference& L = out[k];
    L.rmsDiff = std::sqrt(diff2 / n);
    L.rmsShift = std::sqrt(shift2 / n);
    L.maxDiff = *std::max_element(absDiff.begin(), absDiff.end());
    const auto mid = absDiff.begin() + static_cast<std::ptrdiff_t>(absDiff.size() / 2);
    std::nth_element(absDiff.begin(), mid, absDiff.end());
    L.medianDiff = *mid;
    std::printf(
        "%s level %zu: rms(store - computed) %.1f m, median %.1f m, max %.1f m; "
        "rms(one-column shift) %.1f m\n",
        file.c_str(), k, L.rmsDiff, L.medianDiff, L.maxDiff, L.rmsShift);
  }
  return out;
}

}  // namespace

// The store's coarse levels are 2×2 means of the level below; the computed ones are the
// planet sampled at the coarse resolution. They differ by what the coarser planet leaves
// out (its finest fBm octave, 1800·0.5^o m, and its finest crater band: at 256 rows craters
// 150–300 km across and kilometres deep) and by the box filter's smoothing, which at the
// shield volcanoes' summits and the craters' rims (slopes of tens of metres per km, cells
// 80 km wide) reaches kilometres in single samples (docs/scale.md gives the figures). So
// single samples are not bounded here; the bulk is. The test holds it against the relief
// between neighbouring samples of the same level (rms of a one-column shift), which a
// shifted, flipped or mixed-up level would show in full:
// - without craters (only octaves and smoothing differ): median |diff| below a quarter and
//   rms below half of it;
// - with craters: median below a quarter, rms below the whole of it.
TEST(Procedural, CoarseLevelsAgreeWithTheStoresPyramidWithinTheDetailTheyLeaveOut) {
  MarsPlanetOptions smooth = smallPlanet(kSmallRows);
  smooth.craterDensity = 0.0;
  const auto noCraters = pyramidDifferences(smooth, "mars-no-craters.h5");
  for (std::size_t k = 1; k < noCraters.size(); ++k) {
    EXPECT_LT(noCraters[k].medianDiff, 0.25 * noCraters[k].rmsShift) << "level " << k;
    EXPECT_LT(noCraters[k].rmsDiff, 0.5 * noCraters[k].rmsShift) << "level " << k;
  }
  const auto withCraters = pyramidDifferences(smallPlanet(kSmallRows), "mars-256.h5");
  for (std::size_t k = 1; k < withCraters.size(); ++k) {
    EXPECT_LT(withCraters[k].medianDiff, 0.25 * withCraters[k].rmsShift) << "level " << k;
    EXPECT_LT(withCraters[k].rmsDiff, withCraters[k].rmsShift) << "level " << k;
  }
}

TEST(Procedural, PlanetEqualsTheInMemoryPlanetPolesIncluded) {
  auto cache = std::make_shared<PatchCache>(std::size_t{64} << 20);
  const Pager computed = proceduralPager(proceduralOf(smallPlanet(kSmallRows), kSmallPatch), cache);
  const GridInfo& info = computed.grid("mars");
  for (std::size_t k = 0; k < info.levels; ++k) {
    const topo::TopoPlanet paged = computed.planet("mars", k);
    const topo::TopoPlanet inMemory(
        topoGridOf(info, k), bodyOf(info), info.latitudeType,
        std::make_shared<topo::InMemorySamples>(info.levelRows(k), info.levelCols(k),
                                                readAll(*computed.source("mars", k))));
    ASSERT_TRUE(paged.hasNorthCap() && paged.hasSouthCap());
    EXPECT_EQ(paged.northPoleHeight(), inMemory.northPoleHeight()) << "level " << k;
    EXPECT_EQ(paged.southPoleHeight(), inMemory.southPoleHeight()) << "level " << k;
    std::mt19937_64 rng(k + 1);
    std::uniform_real_distribution<double> lat(-90.0, 90.0), lon(-180.0, 180.0);
    std::vector<topo::LatLon> points{{90.0, 0.0},    {90.0, 123.0},   {-90.0, -45.0},
                                     {89.9, 180.0},  {-89.7, -180.0}, {0.0, 180.0},
                                     {12.0, -180.0}, {-3.0, 179.99}};
    for (int i = 0; i < 200; ++i) points.push_back({lat(rng), lon(rng)});
    for (const topo::LatLon& ll : points) {
      for (const auto interp : {topo::Interpolation::Bilinear, topo::Interpolation::Bicubic}) {
        const auto a = paged.height(ll, interp), b = inMemory.height(ll, interp);
        ASSERT_EQ(a.status, b.status);
        ASSERT_EQ(a.height, b.height) << ll.latDeg << ", " << ll.lonDeg;
      }
    }
  }
}

TEST(Procedural, RefusesLevelsTheRowsDoNotAllowAndUnknownGrids) {
  ProceduralMarsOptions o = proceduralOf(smallPlanet(96), 32);  // 96 = 3·2^5
  o.levels = 7;                                                 // would need 2^6 | 96
  EXPECT_THROW((void)proceduralMars(o), InvalidArgument);
  o.levels = 6;
  EXPECT_EQ(proceduralMars(o)->grid("mars").levels, 6U);
  o.levels = 0;  // the writer's rule: 96×192, 48×96, 24×48, then 12×24 fits one patch
  EXPECT_EQ(proceduralMars(o)->grid("mars").levels, 4U);
  o.patchRows = 0;
  EXPECT_THROW((void)proceduralMars(o), InvalidArgument);
  const auto src = proceduralMars(proceduralOf(smallPlanet(96), 32));
  try {
    (void)src->grid("moon");
    FAIL();
  } catch (const StoreError& e) {
    EXPECT_STREQ(e.what(),
                 "store::proceduralMars(): procedural Mars (seed 11, 96 rows): grid 'moon', "
                 "expected 'mars'");
  }
  std::vector<float> out(4);
  EXPECT_THROW(src->readWindow("mars", 0, 95, 0, 2, 2, out), StoreError);
  EXPECT_THROW(src->readWindow("mars", 4, 0, 0, 2, 2, out), StoreError);
}

// ---- a 2^20-row planet: 2^20 × 2^21 samples, no disk ------------------------------------------

namespace {

constexpr std::size_t kHugeRows = std::size_t{1} << 20;

ProceduralMarsOptions hugePlanet(std::size_t rows, std::size_t patch) {
  MarsPlanetOptions planet;
  planet.rows = rows;
  planet.seed = 3;
  return proceduralOf(planet, patch);
}

/// The generator's point function at sample (r, c) of level 0, in double (height() equals
/// the stored sample before its float cast there).
double oracle(const MarsPlanetGenerator& gen, const GridInfo& info, std::size_t r, std::size_t c) {
  return gen.height(info.y0 - static_cast<double>(r) * info.spacingY,
                    info.x0 + static_cast<double>(c) * info.spacingX);
}

}  // namespace

TEST(Procedural, HugePlanetAnswersAnywhereWithinItsCacheBudget) {
  constexpr std::size_t kPatch = 64;
  constexpr std::size_t kBudget = std::size_t{2} << 20;  // 2 MiB: about 120 patches of 64 × 64
  auto cache = std::make_shared<PatchCache>(kBudget);
  const Pager pager = proceduralPager(hugePlanet(kHugeRows, kPatch), cache);
  const GridInfo& info = pager.grid("mars");
  ASSERT_EQ(info.rows, kHugeRows);
  ASSERT_EQ(info.cols, 2 * kHugeRows);
  MarsPlanetOptions genOptions = hugePlanet(kHugeRows, kPatch).planet;
  genOptions.threads = 1;
  const MarsPlanetGenerator gen(genOptions);
  const auto src = pager.source("mars", 0);
  const std::size_t rows = info.rows, cols = info.cols;

  // Samples: the pole rows and the seam columns, and random ones, bit for bit.
  std::vector<std::pair<std::size_t, std::size_t>> samples{{0, 0},
                                                           {0, cols - 1},
                                                           {0, cols / 2},
                                                           {rows - 1, 0},
                                                           {rows - 1, cols - 1},
                                                           {rows - 1, 12345},
                                                           {rows / 2, 0},
                                                           {rows / 2, cols - 1},
                                                           {1, 0},
                                                           {rows - 2, cols - 1}};
  std::mt19937_64 rng(20);
  std::uniform_int_distribution<std::size_t> row(0, rows - 1), col(0, cols - 1);
  for (std::size_t i = 0, n = test::scaledWork(300); i < n; ++i)
    samples.emplace_back(row(rng), col(rng));
  std::size_t peak = 0;
  for (const auto& [r, c] : samples) {
    ASSERT_EQ(src->sample(r, c), static_cast<float>(oracle(gen, info, r, c))) << r << ", " << c;
    peak = std::max(peak, cache->stats().residentBytes);
  }

  // Queries through TopoPlanet: bilinear heights between samples (across the seam too)
  // against the four oracle samples around them, and the poles themselves.
  const topo::TopoPlanet planet = pager.planet("mars");
  const auto bilinear = [&](double latDeg, double lonDeg) {
    const double v = (info.y0 - latDeg) / info.spacingY;
    double u = (lonDeg - info.x0) / info.spacingX;
    u -= static_cast<double>(cols) * std::floor(u / static_cast<double>(cols));
    const auto r0 = static_cast<std::size_t>(std::floor(v));
    const auto c0 = static_cast<std::size_t>(std::floor(u));
    const double t = v - static_cast<double>(r0), s = u - static_cast<double>(c0);
    const std::size_t c1 = (c0 + 1) % cols;
    const auto f = [&](std::size_t r, std::size_t c) {
      return static_cast<double>(static_cast<float>(oracle(gen, info, r, c)));
    };
    return (1 - t) * ((1 - s) * f(r0, c0) + s * f(r0, c1)) +
           t * ((1 - s) * f(r0 + 1, c0) + s * f(r0 + 1, c1));
  };
  const double dx = info.spacingX;
  std::vector<topo::LatLon> points{
      {0.3, 180.0 - 0.25 * dx}, {0.3, -180.0 + 0.1 * dx}, {-45.0, 180.0},
      {-45.0, -180.0},          {10.0, 180.0 - 0.5 * dx}, {89.9, 179.9999999},
      {-89.9, -179.9999999},    {90.0 - 1.5 * dx, 17.0},  {-90.0 + 1.5 * dx, -17.0}};
  std::uniform_real_distribution<double> lat(-89.99, 89.99), lon(-180.0, 180.0);
  for (std::size_t i = 0, n = test::scaledWork(200); i < n; ++i)
    points.push_back({lat(rng), lon(rng)});
  for (const topo::LatLon& ll : points) {
    const auto h = planet.height(ll);
    ASSERT_TRUE(h.valid());
    const double expected = bilinear(ll.latDeg, ll.lonDeg);
    ASSERT_NEAR(h.height, expected, 1e-6 + 1e-12 * std::abs(expected))
        << ll.latDeg << ", " << ll.lonDeg;
    peak = std::max(peak, cache->stats().residentBytes);
  }
  // The poles: one height whatever the longitude, the mean of the row around the pole (a
  // circle 5 m across at this resolution). Oracle: the generator's heights at every 512th
  // sample of that row (heightsAt(): bit for bit the samples), whose mean a smooth periodic
  // function's full mean matches to far below the float rounding of the samples.
  for (const int pole : {1, -1}) {
    const std::size_t r = pole > 0 ? 0 : rows - 1;
    const double phi = (info.y0 - static_cast<double>(r) * info.spacingY) * std::numbers::pi / 180;
    std::vector<glm::dvec3> units;
    for (std::size_t c = 0; c < cols; c += 512) {
      const double lambda = (info.x0 + static_cast<double>(c) * dx) * std::numbers::pi / 180;
      units.emplace_back(std::cos(phi) * std::cos(lambda), std::cos(phi) * std::sin(lambda),
                         std::sin(phi));
    }
    std::vector<double> hs(units.size());
    gen.heightsAt(units, units.size(), hs);
    double sum = 0.0;
    for (const double x : hs) sum += static_cast<double>(static_cast<float>(x));
    const double mean = sum / static_cast<double>(hs.size());
    for (const double lonDeg : {-180.0, -90.0, 0.0, 45.0, 180.0}) {
      const auto h = planet.height({90.0 * pole, lonDeg});
      ASSERT_TRUE(h.valid());
      EXPECT_NEAR(h.height, mean, 1e-3) << "pole " << pole;
    }
  }

  const CacheStats stats = cache->stats();
  std::printf("2^20 planet: %llu patch loads, %llu evictions, peak resident %zu of %zu bytes\n",
              static_cast<unsigned long long>(stats.loads),
              static_cast<unsigned long long>(stats.evictions), stats.peakResidentBytes, kBudget);
  EXPECT_LE(stats.peakResidentBytes, kBudget);
  EXPECT_LE(peak, kBudget);
  EXPECT_GT(stats.evictions, 0U);  // the queries did not fit: the budget was enforced
}

// What opening a planet costs: the Pager, its pyramid (a source and a block table per level)
// and one query. The tables reserve address space for every patch of their level but are
// backed only where patches get published (store/BlockTable.hpp), and nothing else is sized
// by the grid; a table allocated whole would take 24 bytes per patch: 12 GiB at 2^20 rows
// in 64 × 64 patches.
TEST(Procedural, MemoryAtOpenDoesNotGrowWithTheGrid) {
  const auto openAndQuery = [](std::size_t rows) {
    auto cache = std::make_shared<PatchCache>(std::size_t{1} << 20);
    const std::size_t before = residentBytes();
    const Pager pager = proceduralPager(hugePlanet(rows, 64), cache);
    const topo::GridPyramid pyramid = pager.pyramid("mars");
    const auto& top = *pyramid.levels.back().source;
    const volatile float sink = pyramid.levels[0].source->sample(rows / 3, rows / 5) +
                                top.sample(top.rows() / 2, top.cols() / 2);
    (void)sink;
    const std::size_t after = residentBytes();
    return after > before ? after - before : std::size_t{0};
  };
  (void)openAndQuery(std::size_t{1} << 14);  // warm up: allocator arenas, thread records
  const std::size_t small = openAndQuery(std::size_t{1} << 14);
  const std::size_t mid = openAndQuery(std::size_t{1} << 17);
  const std::size_t huge = openAndQuery(kHugeRows);
  std::printf("RSS growth at open: 2^14 rows %zu KiB, 2^17 rows %zu KiB, 2^20 rows %zu KiB\n",
              small >> 10, mid >> 10, huge >> 10);
  constexpr std::size_t kBound = std::size_t{4} << 20;
  EXPECT_LT(mid, small + kBound);
  EXPECT_LT(huge, small + kBound);
}
