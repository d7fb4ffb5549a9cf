// The traverse on real stores paged through a budgeted cache and on in-memory DEMs: contacts
// against direct TopoDem queries, the chassis on analytic planes, an analytic in-memory DEM
// with no store at all (and the ruts its wheels press), the cache budget, and bad options.
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/rover/TrackPresser.hpp>
#include <regolith/rover/Traverse.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <support/StoreScratch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::rover;

constexpr double kDeg = std::numbers::pi / 180.0;

/// The default Victoria-like crater at 4 m spacing (1204 m square, like the 1 m default), in
/// 64×64 patches; written once per test process.
const std::filesystem::path& victoriaStore() {
  static const std::filesystem::path path = [] {
    auto p = test::scratchFile("rover", "victoria.h5");
    store::VictoriaOptions o;
    o.size = 302;
    o.spacing = 4.0;
    o.write.patchRows = o.write.patchCols = 64;
    store::VictoriaGenerator(o).write(p);
    return p;
  }();
  return path;
}

/// A plane h = gx·x + gy·y + h0 on a 201×201 grid at 1 m centred on (0, 0), 64×64 patches.
std::filesystem::path planeStore(const std::string& name, double gx, double gy, double h0) {
  auto path = test::scratchFile("rover", name);
  store::GridSource g;
  g.info.name = "plane";
  g.info.rows = g.info.cols = 201;
  g.info.x0 = -100.0;
  g.info.y0 = 100.0;
  g.info.placement.originLatDeg = -2.05;
  g.info.placement.originLonDeg = -5.5;
  g.samples = topo::InMemorySamples::fromFunction(201, 201, [&](std::size_t r, std::size_t c) {
    const double x = -100.0 + static_cast<double>(c), y = 100.0 - static_cast<double>(r);
    return static_cast<float>(gx * x + gy * y + h0);
  });
  store::WriteOptions w;
  w.patchRows = w.patchCols = 64;
  store::writeStore(path, std::span(&g, 1), w);
  return path;
}

TraverseOptions victoriaOptions() {
  TraverseOptions o;
  o.path = defaultVictoriaPath();
  o.speed = 100.0;  // 10 cm per 1 ms step: about 11,400 steps over the 1,138 m path
  return o;
}

/// A store's DEM grid paged through a cache of `cacheBytes` that the test owns and reads.
struct Paged {
  std::shared_ptr<const store::Store> file;
  std::shared_ptr<store::PatchCache> cache;
  topo::TopoDem dem;
};

Paged paged(const std::filesystem::path& path, const std::string& grid = "victoria",
            std::size_t cacheBytes = std::size_t{64} << 20) {
  auto file = std::make_shared<const store::Store>(store::Store::open(path));
  auto cache = std::make_shared<store::PatchCache>(cacheBytes);
  const store::Pager pager(file, cache);
  return {file, cache, pager.dem(grid)};
}

TEST(TraverseTest, WheelContactsEqualDirectTopoDemQueries) {
  // An independent pager and cache over the same file: the oracle.
  auto file = std::make_shared<const store::Store>(store::Store::open(victoriaStore()));
  const store::Pager pager(file, std::make_shared<store::PatchCache>(std::size_t{64} << 20));
  const topo::TopoDem dem = pager.dem("victoria");
  const store::VictoriaShape shape = store::VictoriaGenerator(store::VictoriaOptions{}).shape();
  const Rover rover;
  std::size_t checked = 0;
  double worstShape = 0.0;
  const Paged traverse = paged(victoriaStore());
  const TraverseResult r = runTraverse(traverse.dem, victoriaOptions(), [&](const StepState& s) {
    const auto wheels = rover.wheelPositions(s.ground);
    for (std::size_t i = 0; i < kWheels; ++i) {
      const WheelContact& c = s.wheels[i];
      EXPECT_EQ(c.x, wheels[i].x);
      EXPECT_EQ(c.y, wheels[i].y);
      const topo::SurfaceSample q = dem.surface(c.x, c.y);
      EXPECT_EQ(c.status, topo::QueryStatus::Ok);
      EXPECT_EQ(c.height, q.height);
      EXPECT_EQ(c.normal, q.normal);
      worstShape = std::max(worstShape, std::abs(c.height - shape.height(c.x, c.y)));
      ++checked;
    }
    return true;
  });
  EXPECT_EQ(checked, r.queries);
  EXPECT_EQ(r.queries, 6 * r.steps);
  // The path: 147.6 m to (−430, −20), on to 170° on a 430 m circle, then six chords of 20°.
  const double length =
      std::hypot(130.0, 70.0) +
      std::hypot(-430.0 - 430.0 * std::cos(170.0 * kDeg), -20.0 - 430.0 * std::sin(170.0 * kDeg)) +
      12.0 * 430.0 * std::sin(10.0 * kDeg);
  EXPECT_EQ(r.steps, static_cast<std::size_t>(std::floor(length / 0.1)) + 1);
  EXPECT_NEAR(r.distance, length, 0.1);
  // Outside oracle: the analytic crater. Bilinear interpolation of 4 m samples of the
  // gentle ejecta blanket the path drives on stays within a few centimetres.
  EXPECT_LT(worstShape, 0.1);
  const store::CacheStats cache = traverse.cache->stats();
  EXPECT_GT(cache.loads, 0U);
  EXPECT_EQ(cache.loads, traverse.file->counters().reads);
  EXPECT_GT(traverse.file->counters().bytesRead, 0U);
}

TEST(TraverseTest, AnInMemoryDemDrivesExactlyAsThePagedStore) {
  // The same samples, read whole into memory: every contact and pose is bit-identical.
  const Paged stored = paged(victoriaStore());
  const topo::TopoGrid& g = stored.dem.grid();
  std::vector<float> all(g.rows() * g.cols());
  stored.file->readWindow("victoria", 0, 0, 0, g.rows(), g.cols(), all);
  const topo::TopoDem memory(g, stored.dem.placement(),
                             std::make_shared<topo::InMemorySamples>(g.rows(), g.cols(), all));
  TraverseOptions o = victoriaOptions();
  o.maxSteps = 3000;
  std::vector<StepState> fromStore;
  (void)runTraverse(stored.dem, o, [&](const StepState& s) {
    fromStore.push_back(s);
    return true;
  });
  std::size_t k = 0;
  const TraverseResult r = runTraverse(memory, o, [&](const StepState& s) {
    const StepState& t = fromStore.at(k++);
    for (std::size_t i = 0; i < kWheels; ++i) {
      EXPECT_EQ(s.wheels[i].height, t.wheels[i].height) << "step " << s.step << " wheel " << i;
      EXPECT_EQ(s.wheels[i].normal, t.wheels[i].normal) << "step " << s.step << " wheel " << i;
    }
    EXPECT_EQ(s.chassis.position, t.chassis.position) << "step " << s.step;
    return true;
  });
  EXPECT_EQ(r.steps, 3000U);
  EXPECT_EQ(k, fromStore.size());
}

TEST(TraverseTest, ChassisMatchesATiltedPlane) {
  // h = 0.125·x − 0.0625·y: exact in float at integer x, y, and bilinear is exact on planes.
  const Paged plane = paged(planeStore("tilted.h5", 0.125, -0.0625, 3.0), "plane");
  TraverseOptions o;
  o.path = {{-80.0, -70.0}, {60.0, 50.0}, {60.0, -60.0}};
  o.speed = 50.0;
  const glm::dvec3 n = glm::normalize(glm::dvec3(-0.125, 0.0625, 1.0));
  std::size_t steps = 0;
  (void)runTraverse(plane.dem, o, [&](const StepState& s) {
    const ChassisPose& p = s.chassis;
    const glm::dvec3 f{std::sin(s.ground.heading), std::cos(s.ground.heading), 0.0};
    const glm::dvec3 l{-f.y, f.x, 0.0};
    // The slope along the heading gives the pitch. Rolling by φ about the pitched forward
    // axis turns the up axis towards −left by φ, and the left axis stays horizontal, so the
    // plane's normal has n·l = −sin φ.
    const double pitch = std::atan(0.125 * f.x - 0.0625 * f.y);
    const double roll = std::asin(-glm::dot(n, l));
    EXPECT_NEAR(p.pitch, pitch, 1e-12);
    EXPECT_NEAR(p.roll, roll, 1e-12);
    EXPECT_NEAR(p.height, 0.125 * s.ground.x - 0.0625 * s.ground.y + 3.0, 1e-9);
    EXPECT_NEAR(glm::distance(p.up, n), 0.0, 1e-12);
    EXPECT_NEAR(p.residual, 0.0, 1e-9);
    ++steps;
    return true;
  });
  EXPECT_EQ(steps, 5888U);  // ⌊294.39 m / 5 cm⌋ + 1
}

TEST(TraverseTest, FlatPlaneIsLevel) {
  const Paged plane = paged(planeStore("flat.h5", 0.0, 0.0, -1400.25), "plane");
  TraverseOptions o;
  o.path = {{-80.0, 0.0}, {80.0, 30.0}};
  o.speed = 50.0;
  const TraverseResult r = runTraverse(plane.dem, o, [&](const StepState& s) {
    EXPECT_EQ(s.chassis.pitch, 0.0);
    EXPECT_EQ(s.chassis.roll, 0.0);
    EXPECT_EQ(s.chassis.height, -1400.25);
    for (const WheelContact& c : s.wheels) EXPECT_EQ(c.normal, glm::dvec3(0.0, 0.0, 1.0));
    return true;
  });
  EXPECT_EQ(r.maxTilt, 0.0);
}

/// h(x, y) = x²/64 + y/8 − 40 on a 401×401 grid at 0.5 m centred on (0, 0), in memory: no
/// store, no pager, no file. Its float samples are exact (multiples of 1/256 below 2^8).
topo::TopoDem parabolicTrough() {
  const topo::TopoGrid g(401, 401, -100.0, 100.0, 0.5, 0.5);
  auto samples = topo::InMemorySamples::fromFunction(401, 401, [](std::size_t r, std::size_t c) {
    const double x = -100.0 + 0.5 * static_cast<double>(c);
    const double y = 100.0 - 0.5 * static_cast<double>(r);
    return static_cast<float>(x * x / 64.0 + y / 8.0 - 40.0);
  });
  const topo::Placement mars(topo::LocalTangentPlane(topo::Body::marsSphere(), {-2.05, -5.5, 0.0}));
  return {g, mars, samples};
}

TEST(TraverseTest, RunsOnAnAnalyticInMemoryDemItIsHanded) {
  const topo::TopoDem dem = parabolicTrough();
  TraverseOptions o;
  o.path = {{0.0, -80.0}, {0.0, 60.0}, {70.0, 60.0}};  // north along the trough, then east
  o.speed = 50.0;                                      // 5 cm per 1 ms step
  TrackLayer tracks(RoverRuts::kTexelMetres);
  TrackPresser presser(tracks);
  std::size_t northSteps = 0;
  const TraverseResult r = runTraverse(dem, o, [&](const StepState& s) {
    // Oracle: bilinear interpolation of a function quadratic in x and linear in y is the
    // function plus (x − x₀)(x₁ − x)/64, x₀ ≤ x ≤ x₁ the sample columns around x; its
    // gradient is ((x₀ + x₁)/64, 1/8).
    for (const WheelContact& c : s.wheels) {
      const double x0 = -100.0 + 0.5 * std::floor((c.x + 100.0) / 0.5), x1 = x0 + 0.5;
      const double h = (c.x * c.x + (c.x - x0) * (x1 - c.x)) / 64.0 + c.y / 8.0 - 40.0;
      const glm::dvec3 n = glm::normalize(glm::dvec3(-(x0 + x1) / 64.0, -0.125, 1.0));
      EXPECT_EQ(c.status, topo::QueryStatus::Ok);
      EXPECT_NEAR(c.height, h, 1e-9) << "step " << s.step << " at (" << c.x << ", " << c.y << ")";
      EXPECT_NEAR(glm::distance(c.normal, n), 0.0, 1e-9) << "step " << s.step;
    }
    if (s.ground.heading == 0.0) {
      // Heading north along x = 0, the wheels stand at x = ±1.1 (track width 2.2 m), where
      // the interpolated trough is (1.21 + 0.1·0.4)/64 = 1.25/64 high on both sides: the
      // chassis pitches up the 1/8 slope, does not roll, and all six contacts lie in a plane.
      for (const WheelContact& c : s.wheels) EXPECT_DOUBLE_EQ(std::abs(c.x), 1.1);
      EXPECT_NEAR(s.chassis.pitch, std::atan(0.125), 1e-12);
      EXPECT_NEAR(s.chassis.roll, 0.0, 1e-12);
      EXPECT_NEAR(s.chassis.height, 1.25 / 64.0 + s.ground.y / 8.0 - 40.0, 1e-9);
      EXPECT_NEAR(s.chassis.residual, 0.0, 1e-9);
      ++northSteps;
    }
    (void)presser.press(s);
    return true;
  });
  EXPECT_EQ(r.steps, 4201U);     // ⌊210 m / 5 cm⌋ + 1
  EXPECT_EQ(northSteps, 2801U);  // 140 m north, the corner included
  EXPECT_EQ(r.queries, 6 * r.steps);
  EXPECT_NEAR(r.distance, 210.0, 1e-9);
  // The steepest pose is the last, on the trough's side at x = 70 (slope x/32) and the 1/8
  // slope; within 1e-3 rad, as six contacts on a curved surface fit a plane only roughly.
  EXPECT_NEAR(r.maxTilt, std::atan(std::hypot(70.0 / 32.0, 0.125)), 1e-3);
  // The ruts the wheels pressed on the way north: 5 cm texels centred 2.5 cm either side of
  // the wheels' paths at x = ±1.1, each 0.03·cos²(π·0.025 / 0.4) deep; none between the
  // wheels or beyond their 0.4 m width.
  const double rut =
      RoverRuts::kDepthMetres * std::pow(std::cos(std::numbers::pi * 0.025 / 0.4), 2.0);
  EXPECT_GT(presser.imprints(), 2000U);
  for (double y = -78.0; y < 55.0; y += 1.3) {
    EXPECT_NEAR(tracks.depthAt({-1.1, y}), rut, 1e-7) << y;
    EXPECT_NEAR(tracks.depthAt({1.1, y}), rut, 1e-7) << y;
    EXPECT_EQ(tracks.depthAt({0.0, y}), 0.0) << y;
    EXPECT_EQ(tracks.depthAt({1.5, y}), 0.0) << y;
  }
}

TEST(TraverseTest, ResidentBytesNeverExceedTheBudget) {
  // Three 64×64 patches (16 KiB of samples each, plus overhead): the path crosses ~15.
  const std::size_t budget = std::size_t{3} * (64 * 64 * 4 + 1024);
  const Paged traverse = paged(victoriaStore(), "victoria", budget);
  std::size_t over = 0, sampledPeak = 0;
  (void)runTraverse(traverse.dem, victoriaOptions(), [&](const StepState&) {
    const store::CacheStats c = traverse.cache->stats();
    over += c.residentBytes > budget ? 1 : 0;
    sampledPeak = std::max(sampledPeak, c.residentBytes);
    EXPECT_EQ(c.capacityBytes, budget);
    return true;
  });
  const store::CacheStats c = traverse.cache->stats();
  EXPECT_LE(c.peakResidentBytes, budget);
  EXPECT_GE(c.peakResidentBytes, sampledPeak);  // the cache's own peak misses nothing
  EXPECT_GT(sampledPeak, 0U);
  EXPECT_GT(c.evictions, 0U);  // the budget did bind
  EXPECT_EQ(over, 0U);
}

TEST(TraverseTest, TheCallbackCanStopTheTraverse) {
  std::size_t seen = 0;
  const TraverseResult r =
      runTraverse(paged(victoriaStore()).dem, victoriaOptions(), [&](const StepState& s) {
        ++seen;
        return s.step < 99;
      });
  EXPECT_EQ(seen, 100U);
  EXPECT_EQ(r.steps, 100U);
}

std::string errorOf(const TraverseOptions& o) {
  try {
    (void)runTraverse(paged(victoriaStore()).dem, o);
  } catch (const regolith::Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(TraverseTest, BadOptionsGiveClearErrors) {
  const topo::TopoDem dem = paged(victoriaStore()).dem;
  TraverseOptions o = victoriaOptions();
  o.step = 0.0;
  EXPECT_EQ(errorOf(o), "rover::runTraverse(): step is 0 s, expected finite and > 0");
  EXPECT_THROW((void)runTraverse(dem, o), InvalidArgument);

  o = victoriaOptions();
  o.path[1].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(errorOf(o),
            "rover::runTraverse(): path waypoint 1 is (-430, nan), expected finite grid "
            "coordinates in metres");

  o = victoriaOptions();
  o.path.resize(1);
  EXPECT_EQ(errorOf(o), "rover::runTraverse(): path has 1 waypoints, expected at least 2");

  o = victoriaOptions();
  o.speed = -1.0;
  EXPECT_EQ(errorOf(o), "rover::runTraverse(): speed is -1 m/s, expected finite and > 0");

  // The grid's pixel extent is [−604, 604] m; the rover reaches 1.556 m from its centre.
  o = victoriaOptions();
  o.path.push_back({603.0, 0.0});
  const std::string e = errorOf(o);
  // Word for word, with core::number()'s shortest round-trip numbers.
  const double reach = RoverGeometry{}.reach();
  const topo::TopoGrid& g = dem.grid();
  EXPECT_EQ(e, "rover::runTraverse(): path waypoint 9 (603, 0) puts a wheel (reach " +
                   core::number(reach) + " m) outside the grid: x must lie in [" +
                   core::number(g.west() + reach) + ", " + core::number(g.east() - reach) +
                   "] and y in [" + core::number(g.south() + reach) + ", " +
                   core::number(g.north() - reach) + "]");
  EXPECT_DOUBLE_EQ(g.east(), 604.0);
  EXPECT_NEAR(reach, 1.5556, 1e-4);
}

}  // namespace
