#pragma once
/// \file
/// Effects a scene can declare for a ClipmapTerrain: only what is declared is compiled,
/// bound and drawn (docs/overlays.md).

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::rover {
class TrackLayer;
}  // namespace regolith::rover

namespace regolith::clod {

class HeightPyramid;

/// Colour-coded height: the terrain is coloured by its height through a fixed ramp
/// (heightColour()) from `minHeight` (first stop) to `maxHeight` (last stop), metres.
/// Unlit by default so colours read exactly as the legend shows them.
struct HeightColours {
  float minHeight = 0.0F;
  float maxHeight = 1.0F;
  bool shaded = false;  ///< multiply the ramp colour by the Lambert term
};

/// Longitude/latitude lines, for planets and for DEMs placed on a planet (a Plane pyramid
/// without placement has no latitude: ClipmapTerrain throws InvalidArgument).
struct LatLonLines {
  /// Degrees between lines; 0 adapts to the view: the smallest of 90, 60, 45, 30, 20, 15,
  /// 10, 5, 2, 1, 0.5, 0.2, 0.1, … whose lines lie at least `minPixelSpacing` pixels apart
  /// at the ground below the camera (ClipmapTerrain::latLonSpacing()).
  double spacingDegrees = 0.0;
  double minPixelSpacing = 80.0;
  glm::vec3 colour{1.0F, 1.0F, 1.0F};
  float widthPixels = 1.5F;  ///< line width on screen
};

/// Structured noise: fractal value noise that perturbs the normal and the albedo, a sense of
/// small-scale roughness on low-resolution terrain. Lengths in grid units (metres on a DEM,
/// degrees on a planet). Deterministic: the pattern is tied to the grid, not to the view.
struct StructuredNoise {
  double amplitude = 0.05;        ///< height of the bumps, metres
  double wavelength = 0.5;        ///< of the coarsest octave, grid units
  int octaves = 4;                ///< 1..8, each half the wavelength of the one before
  float albedoVariation = 0.15F;  ///< relative albedo change at full noise
  /// Grid rectangle (xmin, ymin, xmax, ymax) the noise applies to; everywhere if unset.
  std::optional<glm::dvec4> region;
};

/// A texture draped over the terrain in its grid frame, paged like the heights: one
/// HeightPyramid per channel (1: grey, 3: RGB, 4: RGBA; values in [0, 1]), all with the same
/// grids, in the terrain's grid coordinates. Drawn through a texture clipmap
/// (TextureClipmap): `window` × `window` texels per level around the focus, the level chosen
/// per pixel from the resolution the view needs. Larger than any GPU texture is fine.
struct DrapedTexture {
  std::vector<std::shared_ptr<const HeightPyramid>> channels;
  int window = 512;      ///< texels per side of each level's window (64..4096)
  float opacity = 1.0F;  ///< overlays: blend factor (times the alpha channel if any)
};

/// The effects of one terrain. An unset member is not simulated: no shader code, no
/// uniform, no texture, no pass (tested, docs/overlays.md).
struct Effects {
  /// Albedo texture: replaces ClipmapOptions::albedo (the default constant colour).
  std::optional<DrapedTexture> albedo;
  /// Wheel tracks, stamped by a traverse on the CPU (rover/TrackLayer.hpp); shared with
  /// whoever stamps them. ClipmapTerrain uploads the window around the focus.
  std::shared_ptr<rover::TrackLayer> tracks;
  std::optional<StructuredNoise> noise;
  std::optional<HeightColours> heightColours;
  std::optional<LatLonLines> latLon;
  /// A colour overlay (science map), blended over the lit terrain.
  std::optional<DrapedTexture> overlay;

  /// Names of the declared effects, in the order above ("albedo", "tracks", "noise",
  /// "heightColours", "latLon", "overlay").
  [[nodiscard]] std::vector<std::string> declared() const;
};

/// Names of the declared effects of any type with Effects' members (an unset optional or
/// null pointer is not declared), in Effects::declared()'s order: one list for clod and for
/// the scene file's description of the same effects (scene::EffectsDescription).
template <class AnyEffects>
[[nodiscard]] std::vector<std::string> declaredEffectNames(const AnyEffects& e) {
  std::vector<std::string> out;
  if (e.albedo) out.emplace_back("albedo");
  if (e.tracks) out.emplace_back("tracks");
  if (e.noise) out.emplace_back("noise");
  if (e.heightColours) out.emplace_back("heightColours");
  if (e.latLon) out.emplace_back("latLon");
  if (e.overlay) out.emplace_back("overlay");
  return out;
}

/// The height ramp's stops, first to last (a perceptual blue → green → yellow → red ramp).
inline constexpr std::array<glm::vec3, 5> kHeightRamp{
    glm::vec3{0.19F, 0.21F, 0.58F}, glm::vec3{0.13F, 0.57F, 0.55F}, glm::vec3{0.37F, 0.79F, 0.38F},
    glm::vec3{0.99F, 0.91F, 0.15F}, glm::vec3{0.85F, 0.16F, 0.12F}};

/// The colour HeightColours gives height h (clamped to the range), as the shader computes it.
[[nodiscard]] glm::vec3 heightColour(const HeightColours& colours, double h) noexcept;

}  // namespace regolith::clod
