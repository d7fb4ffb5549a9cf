#pragma once
// `regolith render`'s effect options (docs/cli.md, "Effects"): --effects and the parameters
// of each effect, checked by clod::effectsOf() (the same rules and messages as Python's
// render(effects=...)), and the tracks a --traverse stamps.

#include <regolith/clod/EffectList.hpp>
#include <regolith/clod/Effects.hpp>
#include <regolith/topo/TopoDem.hpp>

#include <CLI/CLI.hpp>
#include <glm/vec2.hpp>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace regolith::clod {
class HeightPyramid;
}

namespace regolith::tools {

/// The effect options as given on the command line.
struct EffectOptions {
  std::vector<std::string> effects;  // --effects, each a comma-separated list
  std::vector<double> heightRange;   // low, high
  std::optional<double> latLonSpacing;
  std::optional<double> noiseAmplitude;
  std::optional<double> noiseWavelength;
  std::optional<int> noiseOctaves;
  std::string traverse;  // waypoints CSV
};

/// Adds --effects, --height-range, --latlon-spacing, --noise-amplitude, --noise-wavelength,
/// --noise-octaves and --traverse to `cmd`.
void addEffectOptions(CLI::App& cmd, EffectOptions& o);

/// Whether --effects names latlon (a DEM is then drawn placed on its body). Throws as
/// declareEffects() for an unknown name.
[[nodiscard]] bool namesLatLon(const EffectOptions& o);

/// What the render needs to know of its terrain to declare the effects.
struct EffectTerrain {
  const clod::HeightPyramid* pyramid = nullptr;
  /// The terrain's height range (a store's level-0 statistics if it has them).
  std::function<std::optional<std::array<double, 2>>()> heightRange;
  /// The DEM a traverse drives on (empty: no DEM, tracks are refused with `what`).
  std::function<topo::TopoDem()> dem;
  std::string what;       // "grid 'g' of x.h5", for messages
  glm::dvec2 focus{0.0};  // the clipmap focus, grid coordinates
  double metresPerUnit = 1.0;
};

/// The effects declared, ready for ClipmapOptions.
struct DeclaredEffects {
  clod::Effects effects;
  int trackWindow = 2048;  // ClipmapOptions::trackWindow
  std::string summary;     // one line for the command's report ("" without effects)
};

/// Checks the options and builds the effects: tracks from the rover driving the --traverse
/// waypoints over the DEM (ruts as the main demo presses them, rover::RoverRuts), with a
/// track window that holds the traverse around the focus (at most 4096 texels). Throws
/// InvalidArgument("render: ...") naming the option.
[[nodiscard]] DeclaredEffects declareEffects(const EffectOptions& o, const EffectTerrain& t);

/// The waypoints of a traverse file: "x,y" lines (grid metres; blanks around fields, blank
/// lines, '#' comments and an "x,y" header line allowed). Throws InvalidArgument naming the
/// file and the line.
[[nodiscard]] std::vector<glm::dvec2> readWaypoints(const std::string& path);

}  // namespace regolith::tools
