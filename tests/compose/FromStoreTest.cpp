// Datasets from stores and catalogue files: a store's grids, paged, compose exactly as the
// same samples in memory do; bad catalogue files are refused with the file and the key.

#include <regolith/compose/FromStore.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/store/Store.hpp>

#include "compose/ComposeFixtures.hpp"

#include <gtest/gtest.h>
#include <support/CountingExecutor.hpp>
#include <support/StoreScratch.hpp>

#include <cmath>
#include <fstream>
#include <memory>
#include <random>
#include <string>

namespace regolith::compose {
namespace {

using testing::named;

const topo::Body kMoon = topo::Body::moon();

struct Stored {
  std::filesystem::path path;
  std::shared_ptr<topo::InMemorySamples> planet, dem;
};

/// A store on the Moon: a 2° global grid and a 200 × 200 tangent-plane DEM at 100 m.
const Stored& stored() {
  static const Stored s = [] {
    Stored out;
    out.path = regolith::test::scratchFile("compose", "moon.h5");
    store::GridSource planet;
    planet.info.name = "global";
    planet.info.kind = store::GridKind::Planet;
    planet.info.rows = 90;
    planet.info.cols = 180;
    planet.info.x0 = -179.0;
    planet.info.y0 = 89.0;
    planet.info.spacingX = planet.info.spacingY = 2.0;
    planet.info.bodyName = "Moon";
    planet.info.equatorialRadius = planet.info.polarRadius = kMoon.equatorialRadius();
    out.planet = topo::InMemorySamples::fromFunction(90, 180, [](std::size_t r, std::size_t c) {
      return static_cast<float>(100.0 * std::sin(0.1 * static_cast<double>(r)) +
                                0.5 * static_cast<double>(c));
    });
    planet.samples = out.planet;
    store::GridSource dem;
    dem.info.name = "site";
    dem.info.rows = dem.info.cols = 200;
    dem.info.x0 = -9950.0;
    dem.info.y0 = 9950.0;
    dem.info.spacingX = dem.info.spacingY = 100.0;
    dem.info.bodyName = "Moon";
    dem.info.equatorialRadius = dem.info.polarRadius = kMoon.equatorialRadius();
    dem.info.placement.kind = store::PlacementInfo::Kind::LocalTangentPlane;
    dem.info.placement.originLatDeg = 10.0;
    dem.info.placement.originLonDeg = 20.0;
    out.dem = topo::InMemorySamples::fromFunction(200, 200, [](std::size_t r, std::size_t c) {
      return static_cast<float>(300.0 + 0.3 * static_cast<double>(r) -
                                0.2 * static_cast<double>(c));
    });
    dem.samples = out.dem;
    const store::GridSource grids[] = {planet, dem};
    store::WriteOptions w;
    w.patchRows = w.patchCols = 32;
    store::writeStore(out.path, grids, w);
    return out;
  }();
  return s;
}

std::filesystem::path writeText(const std::string& name, const std::string& text) {
  const auto p = stored().path.parent_path() / name;
  std::ofstream(p) << text;
  return p;
}

TEST(FromStore, CatalogueFileComposesAsTheSameSamplesInMemory) {
  const auto file = writeText("moon.json", R"({"policy": "finest", "datasets": [
      {"store": "moon.h5", "grid": "global"},
      {"store": "moon.h5", "grid": "site", "feather_m": 3000, "priority": 0}]})");
  const CatalogueFile cf = readCatalogueFile(file);
  ASSERT_EQ(cf.ids.size(), 2U);
  EXPECT_EQ(cf.rules.policy, Policy::FinestWins);
  const ComposedSurface paged(cf.catalogue->snapshot(), cf.rules);

  // The same samples, in memory, with the geometry the store records.
  Catalogue mem(kMoon);
  topo::GridPyramid pp;
  pp.levels.push_back({topo::TopoGrid(90, 180, -179.0, 89.0, 2.0, 2.0), stored().planet});
  pp.planetBody = kMoon;
  mem.add(Dataset::planet(pp, named("global")));
  topo::GridPyramid dp;
  dp.levels.push_back({topo::TopoGrid(200, 200, -9950.0, 9950.0, 100.0, 100.0), stored().dem});
  mem.add(Dataset::dem(dp, topo::Placement(topo::LocalTangentPlane(kMoon, {10.0, 20.0, 0.0})),
                       named("site", 3000.0)));
  const ComposedSurface inMemory(mem.snapshot(), cf.rules);

  std::mt19937 rng(4);
  std::uniform_real_distribution<double> near(-0.4, 0.4), lat(-89.0, 89.0), lon(-180.0, 180.0);
  int both = 0;
  for (int i = 0; i < 500; ++i) {
    const double la = i % 2 ? lat(rng) : 10.0 + near(rng), lo = i % 2 ? lon(rng) : 20.0 + near(rng);
    const ComposedSample a = paged.surface(la, lo), b = inMemory.surface(la, lo);
    ASSERT_EQ(a.status, b.status);
    if (!a.valid()) continue;
    EXPECT_EQ(a.height, b.height) << la << ", " << lo;
    EXPECT_EQ(a.contributors, b.contributors);
    both += a.contributors == 2;
  }
  EXPECT_GT(both, 50);
}

TEST(FromStore, ACatalogueFilesDatasetsHintOnTheLoaderGiven) {
  // `regolith render` of a catalogue gives its datasets and its clipmap one loader thread.
  const auto file = writeText("moon-loader.json", R"({"datasets": [
      {"store": "moon.h5", "grid": "global"},
      {"store": "moon.h5", "grid": "site", "feather_m": 3000}]})");
  const auto loader = std::make_shared<test::CountingExecutor>();
  const CatalogueFile cf = readCatalogueFile(file, std::size_t{64} << 20, loader);
  const auto snapshot = cf.catalogue->snapshot();
  ASSERT_EQ(snapshot->entries().size(), 2U);
  for (const CatalogueEntry& e : snapshot->entries()) {
    const int before = loader->submitted;
    const topo::SampleSource::Window hint[] = {{0, 0, 8, 8}};
    e.dataset->level(0).source->prefetch(hint);
    EXPECT_GT(loader->submitted, before) << e.dataset->name() << "'s hint is a task on the loader";
  }
}

TEST(FromStore, BadCatalogueFilesNameTheFileAndTheKey) {
  auto messageOf = [](const std::string& name, const std::string& text) {
    const auto p = writeText(name, text);
    try {
      (void)readCatalogueFile(p);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = messageOf(
      "typo.json", R"({"datasets": [{"store": "moon.h5", "grid": "global", "feather": 5}]})");
  EXPECT_NE(m.find("typo.json"), std::string::npos) << m;
  EXPECT_NE(m.find("datasets[0] key 'feather'"), std::string::npos) << m;
  m = messageOf("policy.json",
                R"({"policy": "best", "datasets": [{"store": "moon.h5", "grid": "global"}]})");
  EXPECT_NE(m.find("weighted or finest"), std::string::npos) << m;
  m = messageOf("empty.json", R"({"datasets": []})");
  EXPECT_NE(m.find("non-empty array"), std::string::npos) << m;
  m = messageOf("notjson.json", "{datasets: ");
  EXPECT_NE(m.find("valid JSON"), std::string::npos) << m;
  // A number beyond double: nlohmann throws out_of_range, not parse_error (fuzz_info_json,
  // stop 31: it escaped as a non-Regolith exception).
  m = messageOf("overflow.json", R"({"tier_ratio": 1e999, "datasets": []})");
  EXPECT_NE(m.find("overflow.json"), std::string::npos) << m;
  EXPECT_NE(m.find("number overflow"), std::string::npos) << m;
  EXPECT_NE(m.find("valid JSON"), std::string::npos) << m;
  m = messageOf("nogrid.json", R"({"datasets": [{"store": "moon.h5", "grid": "nope"}]})");
  EXPECT_NE(m.find("nope"), std::string::npos) << m;
  m = messageOf("nostore.json", R"({"datasets": [{"store": "missing.h5", "grid": "g"}]})");
  EXPECT_NE(m.find("missing.h5"), std::string::npos) << m;
  m = messageOf("feather.json",
                R"({"datasets": [{"store": "moon.h5", "grid": "site", "feather_m": -1}]})");
  EXPECT_NE(m.find("datasets[0].feather_m"), std::string::npos) << m;
  EXPECT_THROW((void)readCatalogueFile(stored().path.parent_path() / "absent.json"), IoError);
}

}  // namespace
}  // namespace regolith::compose
