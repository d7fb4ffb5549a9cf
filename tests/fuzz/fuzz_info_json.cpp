// Fuzz target: `regolith info FILE --json` (and the text form) on a store from bytes, run
// through the command's own CLI11 subcommand (tools/InfoCommand.cpp) with std::cout captured.
// Either the command fails with a regolith::Error, or what it printed with --json is valid
// JSON (RFC 8259, as nlohmann::json's parser accepts it) with the keys docs/cli.md lists.
// (A file that is not HDF5 is described as a raster GDAL reads, as the command does.)
// The text form must fail with a regolith::Error or succeed.
#include "Commands.hpp"
#include "FuzzSupport.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

/// What `regolith info <path> [--json]` writes to stdout.
std::string runInfo(const std::string& path, bool json) {
  CLI::App app{"fuzz"};
  regolith::tools::addInfoCommand(app);
  std::vector<std::string> args;  // CLI11 takes them in reverse order
  if (json) args.emplace_back("--json");
  args.push_back(path);
  args.emplace_back("info");
  std::ostringstream captured;
  std::streambuf* const old = std::cout.rdbuf(captured.rdbuf());
  try {
    app.parse(args);
  } catch (...) {
    std::cout.rdbuf(old);
    throw;
  }
  std::cout.rdbuf(old);
  return captured.str();
}

void checkJson(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  // A store: path, format_version, grids; a raster GDAL reads: path, raster, grid.
  const bool ok = !j.is_discarded() && j.is_object() && j.contains("path") &&
                  ((j.contains("grids") && j["grids"].is_array()) ||
                   (j.contains("raster") && j.contains("grid")));
  if (!ok) {
    std::fprintf(stderr, "fuzz_info_json: info --json printed invalid JSON:\n%s\n", text.c_str());
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  regolith::fuzz::keepHdf5FreeLists();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const regolith::fuzz::ScratchFile file("info.h5");
  if (!regolith::fuzz::globalHeapsConsistent(data, size)) return -1;  // known: see there
  file.write(data, size);
  regolith::fuzz::expectOnlyRegolithErrors([&] { checkJson(runInfo(file.path().string(), true)); });
  regolith::fuzz::expectOnlyRegolithErrors([&] { (void)runInfo(file.path().string(), false); });
  return 0;
}
