#pragma once
/// \file
/// The far field of one body: PGM where it has a secondary sphere, an impostor beyond
/// (docs/far-field.md, "One zoom").

#include <regolith/clod/Camera.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/farfield/RayCastGlobe.hpp>
#include <regolith/gl/EmptyPixels.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <glm/vec3.hpp>

#include <memory>

namespace regolith::farfield {

/// What drew the body in one FarField::draw().
enum class FarFieldMode {
  Pgm,
  Impostor,
  /// Nothing to draw: with keepDrawn, the target had no empty pixel (the near field covered
  /// it), and neither PGM nor the impostor ran.
  Covered,
  None
};

/// What one FarField::draw() did.
struct FarFieldFrame {
  FarFieldMode mode = FarFieldMode::None;
  /// The PGM frame (mode Pgm; for Impostor its spheres are filled in, unless the impostor
  /// was chosen by impostorReliefPixels and PGM did not run).
  PgmFrame pgm;
  GlobeFrame globe;  ///< the impostor's frame (mode Impostor)
  /// The body's relief (largest |height|) seen at the nearest distance the body can have,
  /// in pixels: the bound on the impostor's screen error (PgmOptions::impostorReliefPixels).
  double reliefPixels = 0.0;
};

/// A body's far field: draws it by PGM while the view has a secondary sphere (r_s > 0) and
/// hands over to the ray-cast impostor beyond (or sooner, once the relief spans at most
/// PgmOptions::impostorReliefPixels), filling in around what the target already
/// shows (the near-field clipmaps drawn first). Where the target has no empty pixel left
/// (a near view whose clipmap fills the screen), it draws nothing and costs one depth-only
/// pass (FarFieldMode::Covered). The camera is body-fixed (the body's centre at the origin).
/// Needs a current GL 4.5 context; belongs to its thread.
///
/// The impostor is the body's ellipsoid (RayCastGlobe, polygon proxy) textured with PGM's
/// own albedo of the equirectangular layer (the height ramp or the flat albedo of
/// PgmOptions), so the switch changes the geometry by the relief only: at the distance where
/// r_s reaches 0 (about 10 radii for Mars) that is under a pixel or two.
class FarField {
 public:
  /// Keeps the layers (shared; they must describe `layers.body()`).
  FarField(std::shared_ptr<const HeightLayers> layers, PgmOptions options = {});
  ~FarField();
  FarField(const FarField&) = delete;
  FarField& operator=(const FarField&) = delete;

  [[nodiscard]] const HeightLayers& layers() const noexcept { return *layers_; }
  [[nodiscard]] PgmRenderer& pgm() noexcept { return pgm_; }
  [[nodiscard]] RayCastGlobe& globe() noexcept { return globe_; }

  /// Draws the body into `target` where it has no depth yet (keepDrawn) or over it by the
  /// depth test. `sun`: unit direction towards the light, body-fixed. With keepDrawn and no
  /// empty pixel in the target, draws nothing (mode Covered; PGM then restarts its primary
  /// sphere when it next draws, PgmRenderer::restart()).
  FarFieldFrame draw(const gl::RenderTarget& target, const clod::Camera& camera,
                     const glm::dvec3& sun, bool keepDrawn = true);

 private:
  std::shared_ptr<const HeightLayers> layers_;
  PgmRenderer pgm_;
  RayCastGlobe globe_;
  gl::Texture albedo_;
  gl::EmptyPixelTest emptyTest_;
  gl::Texture drawnDepth_{0};
  int depthWidth_ = 0, depthHeight_ = 0;
};

}  // namespace regolith::farfield
