#pragma once
// Locates the real-data fixtures: the environment variable REGOLITH_FIXTURES_DIR if set and
// non-empty, else the CMake cache variable of the same name (default: tests/data/dem).

#include <cstdlib>
#include <string>

namespace regolith::test {

inline std::string fixturesDir() {
  if (const char* env = std::getenv("REGOLITH_FIXTURES_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return REGOLITH_FIXTURES_DIR;
}

inline std::string fixture(const std::string& name) { return fixturesDir() + "/" + name; }

}  // namespace regolith::test
