// Fuzz target: the CSV point parser of `regolith query` (tools/PointsCsv.hpp). Every input is
// read as stdin would be, in the coordinates its first byte picks, and as one 'a,b'
// argument. Only regolith::Error may come out; every point read must be finite, and a
// longitude/latitude point's latitude within ±90°.
#include "FuzzSupport.hpp"
#include "PointsCsv.hpp"

#include <cmath>
#include <sstream>
#include <string>
#include <string_view>

using regolith::tools::Coords;

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_csv_points: %s\n", what);
    std::abort();
  }
}

void checkPoint(const regolith::tools::Point& p, Coords coords) {
  check(std::isfinite(p.a) && std::isfinite(p.b), "a point read is not finite");
  check(coords != Coords::LonLat || std::abs(p.b) <= 90.0, "a latitude read is beyond 90 deg");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto coords = static_cast<Coords>(data[0] % 3);
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  regolith::fuzz::expectOnlyRegolithErrors([&] {
    std::istringstream in(text);
    for (const auto& p : regolith::tools::readPoints(in, "stdin", coords)) checkPoint(p, coords);
  });
  regolith::fuzz::expectOnlyRegolithErrors([&] {
    checkPoint(regolith::tools::parsePoint(std::string_view(text), "point 1", coords), coords);
  });
  return 0;
}
