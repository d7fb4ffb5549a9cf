#include "FiniteRange.hpp"

#include "ReportText.hpp"

#include <cmath>
#include <string>

namespace regolith::tools {

namespace {

CLI::Validator finiteWithin(double min, double max, bool positive, const std::string& bounds) {
  return {[=](std::string& s) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(s, v)) return "Value " + s + " is not a number";
            if (std::isfinite(v) && v >= min && v <= max && (!positive || v > 0.0)) return {};
            return "Value " + s + " is not a finite number" + (bounds.empty() ? "" : " " + bounds);
          },
          bounds.empty() ? "FINITE" : "FINITE " + bounds};
}

}  // namespace

CLI::Validator FiniteRange(double min, double max) {
  const bool bounded =
      min > -std::numeric_limits<double>::max() || max < std::numeric_limits<double>::max();
  return finiteWithin(
      min, max, false,
      bounded ? "in [" + shortestNumber(min) + ", " + shortestNumber(max) + "]" : std::string());
}

CLI::Validator FinitePositive() {
  return finiteWithin(0.0, std::numeric_limits<double>::max(), true, "> 0");
}

}  // namespace regolith::tools
