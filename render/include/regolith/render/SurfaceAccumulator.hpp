#pragma once
/// \file
/// Colour composition on the GPU: Kooima's surface-map accumulation (thesis §3.4.3, §4.1,
/// §4.2) of the albedo and overlay datasets of a catalogue snapshot over a drawn frame
/// (docs/colour-composition.md).

#include <regolith/clod/Camera.hpp>
#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace regolith::render {

/// Settings of a SurfaceAccumulator.
struct AccumulatorOptions {
  /// Largest window of a dataset's pyramid level uploaded per frame, texels per side
  /// (64..8192). A view that needs more reads a coarser level.
  int maxWindow = 2048;
  /// Kooima's quality coefficient n of α = 1 − |log k| / log n (> 1): a texel that maps to
  /// an n × 1 shape on the screen has quality 0 (then compose::kMinQuality).
  double qualityN = compose::kQualityN;
  /// Rays per side of the screen lattice that finds each dataset's visible window (≥ 3).
  int lattice = 17;
  /// Normalisation: the terrain's colour is multiplied by albedo × albedoGain where albedo
  /// datasets cover it (faded in by their coverage), and kept where none does.
  float albedoGain = 1.0F;
  /// Overlays are drawn over the albedo-modulated colour through a blue-yellow-red ramp of
  /// [overlayMin, overlayMax] with this opacity times their coverage.
  float overlayOpacity = 0.6F;
  float overlayMin = 0.0F, overlayMax = 1.0F;
};

/// What one accumulate() did.
struct AccumulationFrame {
  std::size_t visible = 0;         ///< albedo and overlay datasets the frustum query returned
  std::size_t drawn = 0;           ///< of those, passes drawn (a window on screen)
  std::size_t texelsUploaded = 0;  ///< value and mask texels uploaded this frame
};

/// Where one dataset's pass read its values (for tests and the demo's summary).
struct DatasetWindow {
  compose::DatasetId id = 0;
  std::size_t level = 0;            ///< pyramid level read
  std::int64_t row0 = 0, col0 = 0;  ///< window origin at that level (columns may wrap)
  int rows = 0, cols = 0;
};

/// Composes the colour datasets (roles Albedo and Overlay) of a catalogue snapshot over a
/// frame whose terrain is already drawn into a gl::RenderTarget, by Kooima's surface-map
/// accumulation:
///
/// 1. accumulate(): one geodetic pass turns each pixel's depth back into a latitude,
///    longitude and height (Kooima's deferred texturing, §3.4.2); then, for each colour
///    dataset whose bounds the camera's frustum meets (Snapshot::visible), one screen pass
///    (scissored to the projection of its bounds) maps each pixel through the dataset's
///    placement to its grid, reads a window of the pyramid level that matches the pixel
///    footprint (an R32F texture, NaN = no data) and adds (w·value, w) into an RGBA32F
///    accumulation target with w = coverage × α: coverage as compose::Dataset defines it
///    (border feather × mask), α = 1 − |log k / log n| with k from the screen derivatives of
///    the dataset's texture coordinates (§4.1). Albedo adds into (r, g), overlays into
///    (b, a); a second target multiplies (1 − coverage) per role.
/// 2. normalise(): value = Σ w·v / Σ w where Σ w > 0, blended into the target's colour:
///    terrain × (1 + (albedo·gain − 1) × albedo coverage), then the overlay ramp over it.
///
/// Precision: the shaders work in float on offsets from reference points (the frame's,
/// under the screen's centre, and each dataset's, at the centre of its window) whose own
/// coordinates the CPU computes in double, with difference formulas for the geodetic
/// latitude and the projections, so an error is a fraction of the view's extent (~1e-7 of
/// it), never of the body's radius.
///
/// Supported placements: planet latitude/longitude grids (either latitude type), local
/// tangent planes, polar stereographic and equirectangular maps. accumulate() throws
/// InvalidArgument for a colour dataset in another placement, before drawing anything.
///
/// Needs a current GL 4.5 context; belongs to its thread. Keeps each dataset's window
/// texture between frames (re-read when the view leaves it).
class SurfaceAccumulator {
 public:
  /// Throws InvalidArgument for options out of range.
  explicit SurfaceAccumulator(AccumulatorOptions options = {});
  ~SurfaceAccumulator();
  SurfaceAccumulator(const SurfaceAccumulator&) = delete;
  SurfaceAccumulator& operator=(const SurfaceAccumulator&) = delete;

  [[nodiscard]] const AccumulatorOptions& options() const noexcept { return options_; }

  /// Clears the accumulation and draws one pass per visible colour dataset. `camera` is in
  /// body-fixed metres of `snapshot`'s body and has the target's size. Reads the target's
  /// depth; leaves its colour alone. Throws InvalidArgument for a camera whose size is not
  /// the target's, or a colour dataset whose placement is not supported.
  AccumulationFrame accumulate(const gl::RenderTarget& target, const clod::Camera& camera,
                               const compose::Snapshot& snapshot);
  /// Blends the normalised accumulation into the target's colour (see the class comment).
  void normalise(const gl::RenderTarget& target) const;

  /// The accumulation of the last frame, row 0 at the top: (Σ w·albedo, Σ w over albedo
  /// datasets, Σ w·overlay, Σ w over overlays) per pixel.
  [[nodiscard]] std::vector<glm::vec4> readAccumulation() const;
  /// The coverage products of the last frame, row 0 at the top: (Π (1 − c) over albedo
  /// datasets, Π (1 − c) over overlays).
  [[nodiscard]] std::vector<glm::vec2> readCoverage() const;
  /// The windows the last accumulate() read, one per drawn pass.
  [[nodiscard]] const std::vector<DatasetWindow>& windows() const noexcept { return windows_; }

  /// Throws InvalidArgument naming `operation` and the dataset unless the accumulator can
  /// map the dataset's placement.
  static void requireSupported(const compose::Dataset& dataset, const char* operation);

 private:
  struct Cached;
  struct Pass;
  void resize(int width, int height);
  Cached* window(const compose::CatalogueEntry& entry, const clod::Camera& camera,
                 std::array<double, 2> heights, AccumulationFrame& frame);

  AccumulatorOptions options_;
  gl::Program geodetic_;
  gl::Program accumulate_;
  gl::Program normalise_;
  gl::VertexArray vao_;
  gl::Framebuffer fbo_;
  gl::Texture sums_{0};
  gl::Texture cover_{0};
  gl::Texture geo_{0};
  gl::Framebuffer geoFbo_{0};
  int width_ = 0, height_ = 0;
  std::vector<std::unique_ptr<Cached>> cache_;
  std::vector<DatasetWindow> windows_;
  std::uint64_t frame_ = 0;
};

}  // namespace regolith::render
