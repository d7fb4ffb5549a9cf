// How `info` and `query` tell a catalogue file from a store and a raster
// (tools::isCatalogueFile()), and `info` of a catalogue through tools::printInfo(): the JSON is
// checked with nlohmann::json's strict parser against the grid the store was written with.
#include <regolith/core/Error.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>

#include "CatalogueInfo.hpp"
#include "Commands.hpp"
#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

using namespace regolith;

std::filesystem::path writeText(const std::string& name, const std::string& text) {
  const auto path = test::scratchFile("CatalogueInfo", name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// A store of one 6 × 8 planet grid at 5° (lon -20..20, lat 15..45) on the Moon, heights 7 m.
void writePlanetStore() {
  store::GridInfo g;
  g.name = "patch";
  g.kind = store::GridKind::Planet;
  g.rows = 6;
  g.cols = 8;
  g.x0 = -17.5;
  g.y0 = 42.5;
  g.spacingX = g.spacingY = 5.0;
  g.bodyName = "Moon";
  g.equatorialRadius = g.polarRadius = 1737400.0;
  const store::GridSource src{
      g, topo::InMemorySamples::fromFunction(6, 8, [](std::size_t, std::size_t) { return 7.0f; })};
  store::WriteOptions o;
  o.patchRows = o.patchCols = 8;
  o.threads = 1;
  const auto path = test::scratchFile("CatalogueInfo", "patch.h5");
  store::writeStore(path, std::span<const store::GridSource>(&src, 1), o);
}

TEST(CatalogueInfo, ACatalogueIsATextFileThatStartsAJsonObject) {
  EXPECT_TRUE(tools::isCatalogueFile(writeText("plain.json", "{\"datasets\": []}")));
  // White space and a UTF-8 byte-order mark before the brace.
  EXPECT_TRUE(tools::isCatalogueFile(writeText("bom.json", "\xEF\xBB\xBF \r\n\t{")));
  EXPECT_FALSE(tools::isCatalogueFile(writeText("array.json", "[{\"datasets\": []}]")));
  EXPECT_FALSE(tools::isCatalogueFile(writeText("empty.json", "")));
  EXPECT_FALSE(tools::isCatalogueFile(writeText("blank.json", "  \n ")));
  EXPECT_FALSE(tools::isCatalogueFile(writeText("points.csv", "lon,lat\n1,2\n")));
  writePlanetStore();
  EXPECT_FALSE(tools::isCatalogueFile(test::scratchFile("CatalogueInfo", "patch.h5")));
  EXPECT_FALSE(tools::isCatalogueFile(test::scratchFile("CatalogueInfo", "absent.json")));
  EXPECT_FALSE(tools::isCatalogueFile(test::scratchFile("CatalogueInfo", "")));  // a folder
  const auto loop = test::scratchFile("CatalogueInfo", "loop.json");
  std::filesystem::remove(loop);
  std::filesystem::create_symlink(loop, loop);
  EXPECT_FALSE(tools::isCatalogueFile(loop));  // Store::open() then names the loop
}

TEST(CatalogueInfo, JsonListsTheDatasetAsTheStoreRecordsIt) {
  writePlanetStore();  // patch.h5, beside the catalogue file
  const auto file = writeText(
      "one.json", R"({"policy": "weighted", "resolution_power": 1.5, "tier_ratio": 6, "datasets": [
          {"store": "patch.h5", "grid": "patch", "feather_m": 1000, "priority": 3}]})");
  std::ostringstream out;
  tools::printInfo(file.string(), true, out);
  const nlohmann::json j = nlohmann::json::parse(out.str(), nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << out.str();
  EXPECT_EQ(j["path"], file.string());
  EXPECT_EQ(j["body"]["name"], "Moon");
  EXPECT_EQ(j["policy"], "weighted");
  EXPECT_EQ(j["resolution_power"], 1.5);
  EXPECT_EQ(j["tier_ratio"], 6.0);
  ASSERT_EQ(j["datasets"].size(), 1U);
  const nlohmann::json& d = j["datasets"][0];
  EXPECT_EQ(d["name"], "patch");
  EXPECT_EQ(d["kind"], "planet");
  EXPECT_TRUE(d["placement"].is_null());
  EXPECT_EQ(d["priority"], 3);
  EXPECT_EQ(d["feather_m"], 1000.0);
  EXPECT_EQ(d["rows"], 6);
  EXPECT_EQ(d["cols"], 8);
  EXPECT_EQ(d["extent"]["west"], -20.0);
  EXPECT_EQ(d["extent"]["east"], 20.0);
  EXPECT_EQ(d["extent"]["south"], 15.0);
  EXPECT_EQ(d["extent"]["north"], 45.0);
  EXPECT_EQ(d["centre"]["lat"], 30.0);
  EXPECT_EQ(d["centre"]["lon"], 0.0);
  EXPECT_EQ(d["height_range"][0], 7.0);
  EXPECT_EQ(d["height_range"][1], 7.0);
}

TEST(CatalogueInfo, ABadCatalogueGivesTheLibrarysError) {
  const auto file = writeText("typo.json", R"({"dataset": []})");
  try {
    std::ostringstream out;
    tools::printInfo(file.string(), false, out);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              "compose::readCatalogueFile(): " + file.string() +
                  ": key 'dataset' is [], expected one of policy, resolution_power, tier_ratio, "
                  "datasets");
  }
}

}  // namespace
