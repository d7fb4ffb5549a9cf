#pragma once
/// \file
/// Effects by name, as the command line (`regolith render --effects ...`) and Python
/// (`render(effects=...)`) declare them: the names, their parameters as the user gave them,
/// and the checked clod::Effects they make (docs/overlays.md). One place for the names, the
/// defaults, the ranges and the messages, so both front ends say the same thing.
///
/// Thread-safety: pure functions and value types.

#include <regolith/clod/Effects.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace regolith::clod {

class HeightPyramid;

/// The effects a name can declare, in this order: wheel tracks (stamped by a traverse the
/// caller runs), height colours, latitude/longitude lines, structured noise.
inline constexpr std::array<std::string_view, 4> kEffectNames{"tracks", "height-colours", "latlon",
                                                              "noise"};

/// Ranges of the named effects' parameters (inclusive).
struct EffectLimits {
  static constexpr double kMaxAbsHeight = 1e6;         ///< height range ends, metres
  static constexpr double kMaxLatLonSpacing = 90.0;    ///< degrees (0: adaptive)
  static constexpr double kMinLatLonSpacing = 1e-6;    ///< degrees, when not 0
  static constexpr double kMaxNoiseAmplitude = 1e4;    ///< metres (0 allowed: albedo only)
  static constexpr double kMinNoiseWavelength = 1e-6;  ///< grid units
  static constexpr double kMaxNoiseWavelength = 1e7;   ///< grid units
  static constexpr int kMaxNoiseOctaves = 8;           ///< 1..8
};

/// How a front end spells the options, for messages.
struct EffectOptionNames {
  std::string_view effects, heightRange, latLonSpacing, noiseAmplitude, noiseWavelength,
      noiseOctaves;
};
/// `regolith render`'s options.
inline constexpr EffectOptionNames kCommandLineEffectOptions{
    "--effects",         "--height-range",     "--latlon-spacing",
    "--noise-amplitude", "--noise-wavelength", "--noise-octaves"};
/// Python's `render()` keywords.
inline constexpr EffectOptionNames kPythonEffectOptions{"effects",
                                                        "height_range",
                                                        "effects['latlon']['spacing']",
                                                        "effects['noise']['amplitude']",
                                                        "effects['noise']['wavelength']",
                                                        "effects['noise']['octaves']"};

/// What a user asked for: the named effects and their parameters as given (unset: the
/// default, see effectsOf()).
struct EffectRequest {
  bool tracks = false;
  bool heightColours = false;
  bool latLon = false;
  bool noise = false;
  std::optional<std::array<double, 2>> heightRange;  ///< low, high, metres
  std::optional<double> latLonSpacing;               ///< degrees; 0 adapts to the view
  std::optional<double> noiseAmplitude;              ///< metres
  std::optional<double> noiseWavelength;             ///< grid units (metres, or degrees)
  std::optional<int> noiseOctaves;

  [[nodiscard]] bool any() const noexcept { return tracks || heightColours || latLon || noise; }
  /// Names of the requested effects, comma separated, in kEffectNames order ("" if none).
  [[nodiscard]] std::string names() const;
};

/// Declares the effect called `name` (one of kEffectNames, exactly). Throws InvalidArgument
/// `<op>: <effects option> 'name' is not an effect, expected one of tracks, height-colours,
/// latlon, noise`.
void addEffectName(EffectRequest& request, std::string_view name, std::string_view op,
                   const EffectOptionNames& spelling);

/// Declares each effect of a comma-separated list ("tracks,latlon"; blanks around names
/// ignored). Throws InvalidArgument as addEffectName(), and for an empty name (",," or an
/// empty list).
void addEffectList(EffectRequest& request, std::string_view list, std::string_view op,
                   const EffectOptionNames& spelling);

/// What effectsOf() needs to know of the terrain for its defaults.
struct EffectDefaults {
  /// The terrain's height range (low, high metres), called only for height colours without
  /// a range; nullopt if the terrain has no valid height.
  std::function<std::optional<std::array<double, 2>>()> heightRange;
  /// Level-0 grid spacing in grid units (metres on a DEM, degrees on a planet): the noise's
  /// default wavelength is 4 spacings.
  double gridSpacing = 1.0;
  /// Metres per grid unit (1 on a DEM; a degree of the body's equator on a planet): the
  /// noise's default amplitude is a quarter of a spacing, in metres.
  double metresPerGridUnit = 1.0;
};

/// The checked effects of a request, tracks left null (the caller makes the TrackLayer a
/// traverse stamps). Defaults: height colours over the terrain's height range (a flat
/// terrain gets ±0.5 m around its height); adaptive lat/lon spacing; noise of 4 octaves, 4
/// spacings' wavelength, a quarter spacing's amplitude. Throws InvalidArgument naming the
/// option (in `spelling`) for a parameter of an effect that is not requested, a number that
/// is not finite or out of EffectLimits, a height range whose low end is not below its high
/// end (as floats, which the shader uses), or height colours on a terrain without a valid
/// height and no range.
[[nodiscard]] Effects effectsOf(const EffectRequest& request, const EffectDefaults& defaults,
                                std::string_view op, const EffectOptionNames& spelling);

/// The lowest and highest valid sample of the finest level of `pyramid` with at most
/// `maxSamples` samples (the coarsest level if none is that small); nullopt if it has no
/// valid sample. Coarse levels are 2×2 means, so the range can be a little narrower than
/// level 0's.
[[nodiscard]] std::optional<std::array<double, 2>> heightRangeOf(
    const HeightPyramid& pyramid, std::size_t maxSamples = std::size_t{1} << 22U);

/// A light direction given in a DEM's grid frame (x east, y north, z up; the default
/// ClipmapOptions::lightDirection) turned into the scene frame of `pyramid` at grid point
/// (x, y): the same for a plane, body-fixed for a placed DEM, so a DEM drawn placed (for
/// lat/lon lines) is lit as in its grid frame. Unit length.
[[nodiscard]] glm::vec3 gridLightInScene(const HeightPyramid& pyramid, glm::dvec2 gridPoint,
                                         glm::vec3 gridLight);

}  // namespace regolith::clod
