#pragma once
/// \file
/// The heights the far field samples on the GPU: a body's surface resampled once into a
/// global equirectangular layer and two polar stereographic caps (planetary PGM §6–§7,
/// docs/far-field.md).

#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstddef>
#include <functional>
#include <vector>

namespace regolith::core {
class Executor;
}
namespace regolith::compose {
class ComposedSurface;
}

namespace regolith::farfield {

/// Sizes of the layers.
struct LayerOptions {
  /// Texels around the equator of the equirectangular layer (its height is half): 64..16384,
  /// even. 4096 is 5.2 km per texel on Mars.
  int equirectWidth = 2048;
  /// Texels per side of each polar cap (16..8192).
  int capSize = 512;
  /// The caps take over poleward of this latitude (degrees, 30..85), blended in over
  /// `blendDegrees` (0.5..10): the equirectangular layer's texels shrink to slivers there.
  double capLatitude = 60.0;
  double blendDegrees = 5.0;
  /// Runs the resampling; a pool of core::availableCores() threads if null.
  core::Executor* executor = nullptr;
  /// Called with the fraction done (0..1) as rows finish, from the calling thread.
  std::function<void(double)> progress;
};

/// A body's heights as three float layers, in the form the GPU reads them.
///
/// - Equirectangular: texel (i, j) has its centre at longitude −180° + (i + ½)·360°/W and
///   planetodetic latitude −90° + (j + ½)·180°/H (row 0 in the south); longitude wraps.
/// - North and south caps: texel (i, j) has its centre at the polar stereographic
///   coordinates (p, q) = −R + ((i, j) + ½)·2R/N of farfield::polarStereographic() (the
///   unit-sphere form applied to the ellipsoid's normal, so the GPU evaluates it without
///   trigonometry), R the cap's half-side: the coordinate of capLatitude − blendDegrees − 1°.
///
/// Heights are metres above the body along its normal; where the source has no value the
/// texel is 0 (counted by missing()). Immutable after construction; thread-safe to read.
class HeightLayers {
 public:
  /// A height source: planetodetic latitude and longitude in degrees, and the ground spacing
  /// in metres the layer texel stands for (a composed surface reads the pyramid level that
  /// serves it). NaN: no data.
  using HeightFunction = std::function<double(double latDeg, double lonDeg, double metres)>;

  /// Resamples `height` at every texel centre. Throws InvalidArgument naming the option for
  /// options out of range.
  static HeightLayers build(const topo::Body& body, const HeightFunction& height,
                            const LayerOptions& options = {});
  /// Resamples a composed surface: every covering dataset of the catalogue, by the
  /// composition rule (compose::ComposedSurface::heightAt at the texel's spacing).
  static HeightLayers fromSurface(const compose::ComposedSurface& surface,
                                  const LayerOptions& options = {});

  /// Resamples a planet latitude/longitude grid (x longitude, y latitude of `latitudeType`,
  /// degrees), read whole with one readWindow() (a paged or generated source computes or
  /// loads its blocks once, not once per texel), bilinear, longitudes wrapping where the
  /// grid covers a whole turn; NaN samples count as no data. Pick a pyramid level of at most
  /// a few thousand samples a side: throws InvalidArgument above 2^26 samples.
  static HeightLayers fromPlanetGrid(const topo::Body& body, const topo::TopoGrid& grid,
                                     const topo::SampleSource& source,
                                     topo::LatitudeType latitudeType,
                                     const LayerOptions& options = {});

  [[nodiscard]] const topo::Body& body() const noexcept { return body_; }
  [[nodiscard]] const LayerOptions& options() const noexcept { return options_; }
  [[nodiscard]] int equirectWidth() const noexcept { return options_.equirectWidth; }
  [[nodiscard]] int equirectHeight() const noexcept { return options_.equirectWidth / 2; }
  [[nodiscard]] int capSize() const noexcept { return options_.capSize; }
  /// The caps' half-side R in polar stereographic units.
  [[nodiscard]] double capRadius() const noexcept { return capRadius_; }
  [[nodiscard]] const std::vector<float>& equirect() const noexcept { return equirect_; }
  [[nodiscard]] const std::vector<float>& north() const noexcept { return north_; }
  [[nodiscard]] const std::vector<float>& south() const noexcept { return south_; }
  /// Lowest and highest height over all texels (0 if there are none with data).
  [[nodiscard]] double minHeight() const noexcept { return minHeight_; }
  [[nodiscard]] double maxHeight() const noexcept { return maxHeight_; }
  /// Texels with no data (set to 0).
  [[nodiscard]] std::size_t missing() const noexcept { return missing_; }

  /// The height the GPU reads at full resolution: bilinear in the equirectangular layer,
  /// blended by smoothstep over [capLatitude, capLatitude + blendDegrees] with the cap's
  /// bilinear value. The renderer's surface, in double, for oracles and tests.
  [[nodiscard]] double heightAt(double latDeg, double lonDeg) const noexcept;

 private:
  HeightLayers(topo::Body body, LayerOptions options);

  topo::Body body_;
  LayerOptions options_;
  double capRadius_ = 0.0;
  std::vector<float> equirect_, north_, south_;
  double minHeight_ = 0.0, maxHeight_ = 0.0;
  std::size_t missing_ = 0;
};

}  // namespace regolith::farfield
