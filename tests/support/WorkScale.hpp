#pragma once
// How much of its repeated work a long test does (its random points, rounds, samples).

#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace regolith::test {

/// `n` scaled by REGOLITH_TEST_WORK_SCALE, a number in (0, 1] (default 1: the whole work),
/// rounded up and at least `atLeast`. scripts/test-all.sh sets 0.25 for its sanitizer runs,
/// where the instrumented code runs 5–30 times slower: the tests that scale keep every
/// thread, path and assertion, over a quarter of the points. Any other value of the
/// variable throws std::invalid_argument (the test fails naming it).
inline std::size_t scaledWork(std::size_t n, std::size_t atLeast = 1) {
  const char* text = std::getenv("REGOLITH_TEST_WORK_SCALE");
  double scale = 1.0;
  if (text != nullptr && *text != '\0') {
    char* end = nullptr;
    scale = std::strtod(text, &end);
    if (end == text || *end != '\0' || !(scale > 0.0 && scale <= 1.0))
      throw std::invalid_argument(std::string("REGOLITH_TEST_WORK_SCALE: '") + text +
                                  "', expected a number in (0, 1]");
  }
  const auto scaled = static_cast<std::size_t>(std::ceil(static_cast<double>(n) * scale));
  return scaled < atLeast ? atLeast : scaled;
}

}  // namespace regolith::test
