#include "PointsCsv.hpp"

#include <regolith/core/Error.hpp>

#include <charconv>
#include <cmath>
#include <cstdlib>

namespace regolith::tools {

namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

[[noreturn]] void failHeader(const std::string& where, std::string_view line,
                             const std::string& header) {
  throw InvalidArgument("query: " + where + ": header '" + std::string(line) +
                        "' does not match the expected '" + header +
                        "' (--coords decides the columns and their order)");
}

}  // namespace

void appendCsvNumber(std::string& out, double v) {
  if (std::isnan(v)) {
    out += "nan";
    return;
  }
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

std::pair<const char*, const char*> coordNames(Coords c) {
  switch (c) {
    case Coords::LonLat: return {"lon", "lat"};
    case Coords::Grid: return {"row", "col"};
    case Coords::Xy: return {"x", "y"};
  }
  return {"a", "b"};
}

Point parsePoint(std::string_view text, const std::string& where, Coords coords) {
  const auto [nameA, nameB] = coordNames(coords);
  const std::vector<std::string_view> f = splitFields(text);
  if (f.size() != 2) {
    throw InvalidArgument("query: " + where + ": '" + std::string(trim(text)) + "' has " +
                          std::to_string(f.size()) + " field" + (f.size() == 1 ? "" : "s") +
                          ", expected 2 (" + nameA + "," + nameB + ")");
  }
  double v[2] = {0.0, 0.0};
  for (std::size_t i = 0; i < 2; ++i) {
    const std::string_view s = f[i];
    const char* name = i == 0 ? nameA : nameB;
    // from_chars takes no leading '+'; accept it as people write it.
    const std::string_view digits = !s.empty() && s[0] == '+' ? s.substr(1) : s;
    const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), v[i]);
    if (s.empty() || r.ec != std::errc() || r.ptr != digits.data() + digits.size()) {
      throw InvalidArgument("query: " + where + ": " + name + " '" + std::string(s) +
                            "' is not a number");
    }
    if (!std::isfinite(v[i])) {
      throw InvalidArgument("query: " + where + ": " + name + " '" + std::string(s) +
                            "' is not a finite number");
    }
  }
  if (coords == Coords::LonLat && std::abs(v[1]) > 90.0) {
    throw InvalidArgument("query: " + where + ": lat " + std::string(f[1]) +
                          " is outside -90 to 90 degrees");
  }
  return {v[0], v[1]};
}

std::vector<Point> readPoints(std::istream& in, const std::string& source, Coords coords) {
  const auto [nameA, nameB] = coordNames(coords);
  const std::string header = std::string(nameA) + "," + nameB;
  std::vector<Point> points;
  std::string line;
  std::size_t lineNo = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++lineNo;
    // A UTF-8 byte-order mark (spreadsheets write one) is not part of the first field.
    if (lineNo == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
    const std::string_view t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (first) {
      first = false;
      // An optional header naming the columns, in the order they are expected.
      const std::vector<std::string_view> f = splitFields(t);
      if (f.size() == 2 && f[0] == nameA && f[1] == nameB) continue;
      if (!f.empty() && (f[0] == nameB || (f.size() > 1 && f[1] == nameA))) {
        failHeader(source + " line " + std::to_string(lineNo), t, header);
      }
    }
    points.push_back(parsePoint(t, source + " line " + std::to_string(lineNo), coords));
  }
  if (in.bad()) throw InvalidArgument("query: cannot read " + source);
  return points;
}

}  // namespace regolith::tools
