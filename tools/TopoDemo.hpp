#pragma once
// The main job until the rendering demo exists: a topo walkthrough on a Victoria-like
// crater DEM placed on Mars (see README).

#include <filesystem>
#include <iosfwd>

namespace regolith::tools {

struct TopoDemoOptions {
  std::size_t size = 1201;        // samples per side
  double spacing = 1.0;           // metres
  std::size_t queries = 2000000;  // for the throughput measurement
  std::filesystem::path outDir = "out/topo-demo";
};

/// Runs the demo, printing a report to `out`. Returns the process exit code.
int runTopoDemo(const TopoDemoOptions& options, std::ostream& out);

}  // namespace regolith::tools
