// `regolith info` on damaged stores (tools::printInfo(), the subcommand's body), issue 17:
// tests/fuzz/fuzz_info_json found that a provenance attribute that is not JSON made `info
// --json` print `<discarded>`; reading the same code for the fix found that strings that are
// not UTF-8 and provenance fields of the wrong type made nlohmann::json throw type_error out
// of the command. The JSON is checked with nlohmann::json's strict parser, the text line by
// line.
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include "Commands.hpp"
#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sstream>
#include <string>

namespace {

using namespace regolith;

/// A store of one 4 × 4 DEM with the given body name and provenance text.
std::filesystem::path writeStore(const std::string& name, const std::string& body,
                                 const std::string& provenance) {
  store::GridInfo g;
  g.name = "g";
  g.rows = g.cols = 4;
  g.bodyName = body;
  g.provenance = provenance;
  const store::GridSource src{
      g, topo::InMemorySamples::fromFunction(4, 4, [](std::size_t, std::size_t) { return 1.0f; })};
  store::WriteOptions o;
  o.patchRows = o.patchCols = 4;
  o.threads = 1;
  const auto path = test::scratchFile("InfoCommand", name);
  store::writeStore(path, std::span<const store::GridSource>(&src, 1), o);
  return path;
}

std::string info(const std::filesystem::path& path, bool json) {
  std::ostringstream out;
  tools::printInfo(path.string(), json, out);
  return out.str();
}

/// The line of `text` that starts with `key`.
std::string lineOf(const std::string& text, const std::string& key) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) == 0) return line;
  }
  return "(no line '" + key + "')";
}

TEST(InfoCommand, JsonOfAProvenanceThatIsNotJsonHoldsItsTextAsAString) {
  const auto path = writeStore("not_json.h5", "Mars", "{\"sources\": [tru");
  const nlohmann::json j = nlohmann::json::parse(info(path, true), nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << info(path, true);
  EXPECT_EQ(j["grids"][0]["provenance"], "{\"sources\": [tru");
  EXPECT_EQ(lineOf(info(path, false), "  provenance:"),
            "  provenance:     recorded, but not JSON (a damaged store?)");
}

TEST(InfoCommand, JsonOfStringsThatAreNotUtf8ReplacesTheirBadBytes) {
  const auto path = writeStore("latin1.h5", "Mars\xe9", "{\"gdal_driver\": \"PDS\xff\"}");
  const nlohmann::json j = nlohmann::json::parse(info(path, true), nullptr, false);
  ASSERT_FALSE(j.is_discarded());
  EXPECT_EQ(j["grids"][0]["body"]["name"], "Mars\xef\xbf\xbd");  // U+FFFD
  // Not JSON (its string is not UTF-8), so kept as the text, with the bad byte replaced.
  EXPECT_EQ(j["grids"][0]["provenance"], "{\"gdal_driver\": \"PDS\xef\xbf\xbd\"}");
}

TEST(InfoCommand, TextOfProvenanceFieldsOfTheWrongTypesPrintsThemAsJson) {
  const auto path = writeStore(
      "wrong_types.h5", "Mars",
      R"({"sources": [{"file": 7, "bytes": "many", "sha256": null}, 3], "gdal_version": [3],)"
      R"( "gdal_driver": "GTiff", "label": {"": 1, "_type": "x", "A": {"value": "v", "unit": 5},)"
      R"( "B": {"value": 2}}})");
  const std::string text = info(path, false);
  EXPECT_EQ(lineOf(text, "  sources:"), "  sources:        7, many bytes, sha256 null");
  // An entry that is no object has no digest either (said so since digests became optional).
  EXPECT_EQ(lineOf(text, "                  ,"), "                  ,  bytes, no digest recorded");
  EXPECT_EQ(lineOf(text, "  made with:"), "  made with:      GDAL [3], driver GTiff");
  EXPECT_EQ(lineOf(text, "  label:"), "  label:           = 1; A = \"v\" <5>; B = 2");
}

}  // namespace
