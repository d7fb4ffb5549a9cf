#pragma once
// The points `regolith query` reads: 'a,b' arguments and CSV lines on stdin (docs/cli.md).
// Apart from the command so that the tests and the fuzz target (tests/fuzz/) link it.

#include <istream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace regolith::tools {

/// The coordinates a query's points are given in.
enum class Coords { LonLat, Grid, Xy };

/// Column names of the two input coordinates, in input order.
[[nodiscard]] std::pair<const char*, const char*> coordNames(Coords c);

/// One input point: its two coordinates as given.
struct Point {
  double a = 0.0, b = 0.0;
};

/// Parses "a,b" (spaces and tabs around the fields allowed, a leading '+' accepted) into a
/// point of finite numbers, a latitude within ±90° for lonlat; throws
/// InvalidArgument("query: <where>: ...") naming the field.
[[nodiscard]] Point parsePoint(std::string_view text, const std::string& where, Coords coords);

/// Appends the shortest text that reads back as the same double (std::to_chars); "nan" for
/// NaN. The numbers `query` prints.
void appendCsvNumber(std::string& out, double v);

/// Every point of CSV lines read from `in` (`source` names it in messages, e.g. "stdin"):
/// blank lines and lines starting with '#' skipped, an optional first header line naming
/// the columns in order. Throws InvalidArgument naming the line of the first bad one.
[[nodiscard]] std::vector<Point> readPoints(std::istream& in, const std::string& source,
                                            Coords coords);

}  // namespace regolith::tools
