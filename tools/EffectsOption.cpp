#include "EffectsOption.hpp"

#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/rover/TrackPresser.hpp>
#include <regolith/rover/Traverse.hpp>

#include "FiniteRange.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>
#include <string_view>
#include <system_error>

namespace regolith::tools {

namespace {

constexpr const char* kOp = "render";

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

std::optional<double> parseNumber(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty() || !std::isfinite(v))
    return std::nullopt;
  return v;
}

}  // namespace

void addEffectOptions(CLI::App& cmd, EffectOptions& o) {
  using L = clod::EffectLimits;
  const std::string group = "Effects (docs/overlays.md)";
  cmd.add_option("--effects", o.effects,
                 "Effects to draw, comma separated: tracks (needs --traverse), height-colours, "
                 "latlon (a planet, or a DEM placed on one), noise. Without it, none: the bare "
                 "terrain")
      ->group(group);
  cmd.add_option("--height-range", o.heightRange,
                 "height-colours: 'low,high' heights in metres of the ramp's first and last "
                 "colour (default: the grid's lowest and highest height)")
      ->delimiter(',')
      ->expected(2)
      ->check(FiniteRange(-L::kMaxAbsHeight, L::kMaxAbsHeight))
      ->group(group);
  cmd.add_option("--latlon-spacing", o.latLonSpacing,
                 "latlon: degrees between lines, 0 adapts to the view (default 0)")
      ->check(FiniteRange(0.0, L::kMaxLatLonSpacing))
      ->group(group);
  cmd.add_option("--noise-amplitude", o.noiseAmplitude,
                 "noise: height of the bumps in metres (default: a quarter of the grid spacing)")
      ->check(FiniteRange(0.0, L::kMaxNoiseAmplitude))
      ->group(group);
  cmd.add_option("--noise-wavelength", o.noiseWavelength,
                 "noise: wavelength of the coarsest octave in grid units, metres on a DEM and "
                 "degrees on a planet (default: 4 grid spacings)")
      ->check(FiniteRange(L::kMinNoiseWavelength, L::kMaxNoiseWavelength))
      ->group(group);
  cmd.add_option("--noise-octaves", o.noiseOctaves, "noise: octaves, 1 to 8 (default 4)")
      ->check(CLI::Range(1, L::kMaxNoiseOctaves))
      ->group(group);
  cmd.add_option("--traverse", o.traverse,
                 "tracks: a CSV of waypoints 'x,y' in the DEM's grid metres, one a line; the "
                 "rover drives them and its six wheels press ruts (0.40 m wide, 3 cm deep)")
      ->group(group);
}

std::vector<glm::dvec2> readWaypoints(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw InvalidArgument(core::format({kOp, path, "--traverse file", "not readable",
                                        "a readable CSV file of waypoints 'x,y' (metres)"}));
  }
  std::vector<glm::dvec2> points;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string_view text = trim(line);
    if (text.empty() || text.front() == '#') continue;
    const std::size_t comma = text.find(',');
    const auto x =
        comma == std::string_view::npos ? std::nullopt : parseNumber(text.substr(0, comma));
    const auto y =
        comma == std::string_view::npos ? std::nullopt : parseNumber(text.substr(comma + 1));
    if (x && y) {
      points.emplace_back(*x, *y);
      continue;
    }
    if (points.empty() && number == 1 && text == "x,y") continue;  // the header
    throw InvalidArgument(
        core::format({kOp, path, "--traverse line " + std::to_string(number),
                      "'" + std::string(text) + "'", "'x,y': two finite numbers (grid metres)"}));
  }
  if (in.bad())
    throw InvalidArgument(
        core::format({kOp, path, "--traverse file", "not readable to its end", "a readable file"}));
  if (points.size() < 2) {
    throw InvalidArgument(core::format(
        {kOp, path, "--traverse waypoints", std::to_string(points.size()), "at least 2"}));
  }
  return points;
}

bool namesLatLon(const EffectOptions& o) {
  clod::EffectRequest request;
  for (const std::string& list : o.effects)
    clod::addEffectList(request, list, kOp, clod::kCommandLineEffectOptions);
  return request.latLon;
}

DeclaredEffects declareEffects(const EffectOptions& o, const EffectTerrain& t) {
  clod::EffectRequest request;
  for (const std::string& list : o.effects)
    clod::addEffectList(request, list, kOp, clod::kCommandLineEffectOptions);
  if (o.heightRange.size() == 2) request.heightRange = {o.heightRange[0], o.heightRange[1]};
  request.latLonSpacing = o.latLonSpacing;
  request.noiseAmplitude = o.noiseAmplitude;
  request.noiseWavelength = o.noiseWavelength;
  request.noiseOctaves = o.noiseOctaves;
  if (!o.traverse.empty() && !request.tracks) {
    throw InvalidArgument(std::string(kOp) +
                          ": --traverse sets a parameter of tracks, which --effects does not name");
  }
  if (request.tracks && o.traverse.empty()) {
    throw InvalidArgument(std::string(kOp) +
                          ": --effects tracks needs --traverse FILE (waypoints 'x,y' in the "
                          "DEM's grid metres that the rover drives to press its tracks)");
  }
  const clod::HeightPyramid& pyramid = *t.pyramid;
  if (request.tracks && (!t.dem || pyramid.kind() == clod::SurfaceKind::Planet)) {
    throw InvalidArgument(std::string(kOp) + ": --effects tracks needs a DEM (a rover drives " +
                          "in metres), and " + t.what + " is not one");
  }
  if (request.latLon && pyramid.kind() == clod::SurfaceKind::Plane && !pyramid.placement()) {
    throw InvalidArgument(std::string(kOp) + ": --effects latlon needs a planet or a DEM " +
                          "placed on one, and " + t.what +
                          " has no placement (no latitude or longitude)");
  }
  clod::EffectDefaults defaults;
  defaults.heightRange = t.heightRange;
  defaults.gridSpacing = std::abs(pyramid.level(0).grid.spacingY());
  defaults.metresPerGridUnit = t.metresPerUnit;
  DeclaredEffects d;
  d.effects = clod::effectsOf(request, defaults, kOp, clod::kCommandLineEffectOptions);
  if (!request.any()) return d;

  std::ostringstream summary;
  summary << std::setprecision(6) << "  effects: " << request.names();
  if (d.effects.heightColours) {
    summary << "; height colours over [" << d.effects.heightColours->minHeight << ", "
            << d.effects.heightColours->maxHeight << "] m";
  }
  if (d.effects.latLon) {
    if (d.effects.latLon->spacingDegrees > 0.0)
      summary << "; lat/lon lines every " << d.effects.latLon->spacingDegrees << "°";
    else
      summary << "; lat/lon lines at an adaptive spacing";
  }
  if (d.effects.noise) {
    summary << "; noise " << d.effects.noise->amplitude << " m, wavelength "
            << d.effects.noise->wavelength << ", " << d.effects.noise->octaves << " octaves";
  }
  if (request.tracks) {
    const std::vector<glm::dvec2> path = readWaypoints(o.traverse);
    const topo::TopoDem dem = t.dem();
    using Ruts = rover::RoverRuts;
    auto tracks = std::make_shared<rover::TrackLayer>(Ruts::kTexelMetres);
    rover::TraverseOptions traverse;
    traverse.path = path;
    traverse.speed = 1.0;
    traverse.step = 0.01;                  // 1 cm a step; an imprint every 5 cm
    rover::TrackPresser presser(*tracks);  // RoverRuts
    const rover::TraverseResult r =
        rover::runTraverse(dem, traverse, [&](const rover::StepState& s) {
          (void)presser.press(s);
          return true;
        });
    d.effects.tracks = tracks;
    // The GPU window of ruts around the focus: the whole traverse if 4096 texels hold it.
    double reach = 0.0;
    for (const glm::dvec2& p : path)
      reach = std::max({reach, std::abs(p.x - t.focus.x), std::abs(p.y - t.focus.y)});
    reach += 2.0;  // the wheels beside the path, and a margin
    const double texels = std::ceil(2.0 * reach / Ruts::kTexelMetres);
    d.trackWindow = static_cast<int>(std::clamp(texels, 256.0, 4096.0));
    summary << "; tracks of " << r.distance << " m driven (" << presser.imprints()
            << " six-wheel imprints from " << o.traverse << ")";
    if (texels > 4096.0) {
      summary << ", drawn within " << 0.5 * 4096.0 * Ruts::kTexelMetres
              << " m of the look-at point";
    }
  }
  d.summary = summary.str();
  return d;
}

}  // namespace regolith::tools
