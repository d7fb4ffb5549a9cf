#pragma once
// CLI11's Range() and PositiveNumber accept "nan" (every comparison with NaN is false), and
// Range() accepts "inf" for an unbounded side: FiniteRange checks that a number option is a
// finite number within its bounds (each element of a delimited list).
#include <CLI/CLI.hpp>

#include <limits>

namespace regolith::tools {

/// A validator: the value parses as a finite double in [min, max]; else CLI11's usage error
/// "<option>: Value nan is not a finite number in [min, max]".
[[nodiscard]] CLI::Validator FiniteRange(double min = -std::numeric_limits<double>::max(),
                                         double max = std::numeric_limits<double>::max());

/// FiniteRange() for numbers > 0.
[[nodiscard]] CLI::Validator FinitePositive();

}  // namespace regolith::tools
