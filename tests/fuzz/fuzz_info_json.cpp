// Fuzz target: what `regolith info FILE --json` prints (tools::printInfo(), the subcommand's
// body), and the text form, for a store from bytes. Either it fails with a regolith::Error,
// or the --json output is valid JSON (RFC 8259, as nlohmann::json's parser accepts it) with
// the keys docs/cli.md lists; the text form must fail with a regolith::Error or succeed.
// (A file that is not HDF5 is described as a raster GDAL reads, as the command does.)
#include "Commands.hpp"
#include "FuzzSupport.hpp"

#include <nlohmann/json.hpp>

#include <sstream>
#include <string>

namespace {

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
  regolith::fuzz::quietSanitizerDeathsInForkedChildren();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const regolith::fuzz::ScratchFile file("info.h5");
  if (regolith::fuzz::globalHeapMayLoop(data, size)) return -1;  // known: see there
  file.write(data, size);
  for (const bool json : {true, false}) {
    regolith::fuzz::expectOnlyRegolithErrors([&] {
      std::ostringstream out;
      regolith::tools::printInfo(file.path().string(), json, out);
      if (json) checkJson(out.str());
    });
  }
  return 0;
}
