// Effects by name for the command line and Python: names, defaults, ranges and messages.
#include <regolith/clod/EffectList.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace regolith::clod {

namespace {

std::string knownNames() {
  std::string s;
  for (const std::string_view n : kEffectNames) {
    if (!s.empty()) s += ", ";
    s += n;
  }
  return s;
}

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

[[noreturn]] void refuse(std::string_view op, std::string_view field, const std::string& value,
                         std::string_view expected) {
  throw InvalidArgument(core::format({op, {}, field, value, expected}));
}

/// A parameter given for an effect the request does not name.
void refuseOrphan(bool given, bool declared, std::string_view op, std::string_view option,
                  std::string_view effect, std::string_view effectsOption) {
  if (!given || declared) return;
  std::string msg(op);
  msg += ": ";
  msg += option;
  msg += " sets a parameter of ";
  msg += effect;
  msg += ", which ";
  msg += effectsOption;
  msg += " does not name";
  throw InvalidArgument(msg);
}

std::string inRange(double lo, double hi) {
  return "finite and within [" + core::number(lo) + ", " + core::number(hi) + "]";
}

}  // namespace

std::string EffectRequest::names() const {
  std::string s;
  const std::array<bool, 4> on{tracks, heightColours, latLon, noise};
  for (std::size_t i = 0; i < on.size(); ++i) {
    if (!on[i]) continue;
    if (!s.empty()) s += ',';
    s += kEffectNames[i];
  }
  return s;
}

void addEffectName(EffectRequest& request, std::string_view name, std::string_view op,
                   const EffectOptionNames& spelling) {
  if (name == kEffectNames[0]) {
    request.tracks = true;
  } else if (name == kEffectNames[1]) {
    request.heightColours = true;
  } else if (name == kEffectNames[2]) {
    request.latLon = true;
  } else if (name == kEffectNames[3]) {
    request.noise = true;
  } else {
    std::string msg(op);
    msg += ": ";
    msg += spelling.effects;
    msg += " '";
    msg += name;
    msg += "' is not an effect, expected one of ";
    msg += knownNames();
    throw InvalidArgument(msg);
  }
}

void addEffectList(EffectRequest& request, std::string_view list, std::string_view op,
                   const EffectOptionNames& spelling) {
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = list.find(',', start);
    const std::string_view item =
        trim(list.substr(start, comma == std::string_view::npos ? list.npos : comma - start));
    if (item.empty()) {
      std::string msg(op);
      msg += ": ";
      msg += spelling.effects;
      msg += " '";
      msg += list;
      msg += "' has an empty name, expected names separated by commas, each one of ";
      msg += knownNames();
      throw InvalidArgument(msg);
    }
    addEffectName(request, item, op, spelling);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

Effects effectsOf(const EffectRequest& r, const EffectDefaults& defaults, std::string_view op,
                  const EffectOptionNames& spelling) {
  using L = EffectLimits;
  refuseOrphan(r.heightRange.has_value(), r.heightColours, op, spelling.heightRange,
               kEffectNames[1], spelling.effects);
  refuseOrphan(r.latLonSpacing.has_value(), r.latLon, op, spelling.latLonSpacing, kEffectNames[2],
               spelling.effects);
  refuseOrphan(r.noiseAmplitude.has_value(), r.noise, op, spelling.noiseAmplitude, kEffectNames[3],
               spelling.effects);
  refuseOrphan(r.noiseWavelength.has_value(), r.noise, op, spelling.noiseWavelength,
               kEffectNames[3], spelling.effects);
  refuseOrphan(r.noiseOctaves.has_value(), r.noise, op, spelling.noiseOctaves, kEffectNames[3],
               spelling.effects);

  Effects e;
  if (r.heightColours) {
    std::array<double, 2> range{};
    if (r.heightRange) {
      range = *r.heightRange;
      const std::string given = core::number(range[0]) + "," + core::number(range[1]) + " m";
      for (const double v : range) {
        if (!(std::isfinite(v) && std::abs(v) <= L::kMaxAbsHeight))
          refuse(op, spelling.heightRange, given,
                 "low,high " + inRange(-L::kMaxAbsHeight, L::kMaxAbsHeight) + " m");
      }
      if (!(static_cast<float>(range[0]) < static_cast<float>(range[1])))
        refuse(op, spelling.heightRange, given, "low < high (as 32-bit floats)");
    } else {
      const std::optional<std::array<double, 2>> found =
          defaults.heightRange ? defaults.heightRange() : std::nullopt;
      if (!found) {
        std::string expected(spelling.heightRange);
        expected += " (the terrain has no valid height to take a range from)";
        refuse(op, kEffectNames[1], "", expected);
      }
      range = *found;
      if (!(static_cast<float>(range[0]) < static_cast<float>(range[1]))) {
        range = {range[0] - 0.5, range[0] + 0.5};  // a flat terrain: its one colour mid-ramp
      }
    }
    e.heightColours = HeightColours{static_cast<float>(range[0]), static_cast<float>(range[1])};
  }
  if (r.latLon) {
    LatLonLines lines;
    if (r.latLonSpacing) {
      const double s = *r.latLonSpacing;
      if (!(std::isfinite(s) &&
            (s == 0.0 || (s >= L::kMinLatLonSpacing && s <= L::kMaxLatLonSpacing)))) {
        refuse(op, spelling.latLonSpacing, core::number(s) + " deg",
               "0 (adapts to the view) or " + inRange(L::kMinLatLonSpacing, L::kMaxLatLonSpacing) +
                   " deg");
      }
      lines.spacingDegrees = s;
    }
    e.latLon = lines;
  }
  if (r.noise) {
    StructuredNoise n;
    const double spacing = std::abs(defaults.gridSpacing);
    n.wavelength = std::clamp(4.0 * spacing, L::kMinNoiseWavelength, L::kMaxNoiseWavelength);
    n.amplitude =
        std::clamp(0.25 * spacing * defaults.metresPerGridUnit, 0.0, L::kMaxNoiseAmplitude);
    if (r.noiseAmplitude) {
      const double a = *r.noiseAmplitude;
      if (!(std::isfinite(a) && a >= 0.0 && a <= L::kMaxNoiseAmplitude))
        refuse(op, spelling.noiseAmplitude, core::number(a) + " m",
               inRange(0.0, L::kMaxNoiseAmplitude) + " m");
      n.amplitude = a;
    }
    if (r.noiseWavelength) {
      const double w = *r.noiseWavelength;
      if (!(std::isfinite(w) && w >= L::kMinNoiseWavelength && w <= L::kMaxNoiseWavelength))
        refuse(op, spelling.noiseWavelength, core::number(w),
               inRange(L::kMinNoiseWavelength, L::kMaxNoiseWavelength) +
                   " grid units (metres on a DEM, degrees on a planet)");
      n.wavelength = w;
    }
    if (r.noiseOctaves) {
      const int o = *r.noiseOctaves;
      if (o < 1 || o > L::kMaxNoiseOctaves)
        refuse(op, spelling.noiseOctaves, core::number(o),
               "1 to " + core::number(L::kMaxNoiseOctaves));
      n.octaves = o;
    }
    e.noise = n;
  }
  return e;
}

std::optional<std::array<double, 2>> heightRangeOf(const HeightPyramid& pyramid,
                                                   std::size_t maxSamples) {
  if (pyramid.levelCount() == 0) return std::nullopt;
  std::size_t l = 0;
  while (l + 1 < pyramid.levelCount() &&
         pyramid.level(l).grid.rows() * pyramid.level(l).grid.cols() > maxSamples) {
    ++l;
  }
  const auto& level = pyramid.level(l);
  const std::size_t rows = level.grid.rows(), cols = level.grid.cols();
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  std::vector<float> row(cols);
  for (std::size_t r = 0; r < rows; ++r) {
    level.source->readWindow(r, 0, 1, cols, row);
    for (const float s : row) {
      if (std::isnan(s) || level.grid.isNodata(s)) continue;
      lo = std::min(lo, static_cast<double>(s));
      hi = std::max(hi, static_cast<double>(s));
    }
  }
  if (!(lo <= hi)) return std::nullopt;
  return std::array<double, 2>{lo, hi};
}

glm::vec3 gridLightInScene(const HeightPyramid& pyramid, glm::dvec2 g, glm::vec3 gridLight) {
  const glm::dvec3 l = glm::normalize(glm::dvec3(gridLight));
  if (!pyramid.placement()) return glm::vec3(l);
  const double d = std::abs(pyramid.level(0).grid.spacingX());
  const glm::dvec3 o = pyramid.position(g.x, g.y, 0.0);
  const glm::dvec3 up = pyramid.up(o);
  glm::dvec3 east = pyramid.position(g.x + d, g.y, 0.0) - o;
  east = glm::normalize(east - up * glm::dot(east, up));
  const glm::dvec3 north = glm::cross(up, east);
  return glm::vec3(glm::normalize(l.x * east + l.y * north + l.z * up));
}

}  // namespace regolith::clod
