#pragma once
// Rows of figures written as JSON in Google Benchmark's shape ({"context": {...},
// "benchmarks": [{"name": ..., <counter>: <number>, ...}]}), for the bench programs that are
// plain main()s (accuracy_table, cache_policies) so `regolith report` reads every program's
// output the same way (docs/accuracy-vs-time.md).

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace regolith::bench {

/// One named row: its counters in the order they were added.
struct JsonRow {
  std::string name;
  std::vector<std::pair<std::string, double>> counters;
  std::vector<std::pair<std::string, std::string>> labels;

  JsonRow& set(std::string key, double value) {
    counters.emplace_back(std::move(key), value);
    return *this;
  }
  JsonRow& label(std::string key, std::string value) {
    labels.emplace_back(std::move(key), std::move(value));
    return *this;
  }
};

/// Writes `rows` to `path` (names and labels are plain ASCII identifiers: no escaping).
/// Non-finite numbers are written as null. Throws std::runtime_error if the file cannot be
/// written.
inline void writeJsonRows(const std::string& path, const char* program,
                          const std::vector<JsonRow>& rows) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error(std::string(program) + ": cannot write " + path);
  std::fprintf(f, "{\n  \"context\": {\"executable\": \"%s\"},\n  \"benchmarks\": [", program);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const JsonRow& r = rows[i];
    std::fprintf(f, "%s\n    {\"name\": \"%s\", \"run_type\": \"iteration\"", i == 0 ? "" : ",",
                 r.name.c_str());
    for (const auto& [k, v] : r.labels) std::fprintf(f, ", \"%s\": \"%s\"", k.c_str(), v.c_str());
    for (const auto& [k, v] : r.counters) {
      if (std::isfinite(v)) {
        std::fprintf(f, ", \"%s\": %.9g", k.c_str(), v);
      } else {
        std::fprintf(f, ", \"%s\": null", k.c_str());
      }
    }
    std::fputs("}", f);
  }
  std::fputs("\n  ]\n}\n", f);
  if (std::fclose(f) != 0) {
    throw std::runtime_error(std::string(program) + ": cannot write " + path);
  }
}

}  // namespace regolith::bench
