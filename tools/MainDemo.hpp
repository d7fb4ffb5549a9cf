#pragma once
// The main job (`regolith demo`, the README's first command): default data, the rover
// traverse, and headless renders of the scene and of the rover's view with its tracks.

#include <cstddef>
#include <filesystem>
#include <iosfwd>

namespace regolith::tools {

struct MainDemoOptions {
  std::filesystem::path outDir = "out/demo";
  /// Where the default stores live; generated there when absent (empty: outDir/data).
  std::filesystem::path dataDir;
  /// The traverse's patch cache budget.
  std::size_t cacheMb = 2;
  /// Frames of the orbit-to-surface sequence, and the image size of every render.
  std::size_t frames = 24;
  int width = 960, height = 540;
  /// Smaller stores and images for a fast smoke run (tests).
  bool quick = false;
};

/// Runs the main job, printing progress and a summary to `out`. Throws on error.
void runMainDemo(const MainDemoOptions& options, std::ostream& out);

}  // namespace regolith::tools
