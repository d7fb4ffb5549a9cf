#pragma once
/// \file
/// Planetary projective grid mapping on the GPU (../shared/papers/planetary-pgm.txt,
/// docs/far-field.md): the far field beyond the clipmaps.

#include <regolith/clod/Camera.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmMath.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <cstddef>
#include <vector>

namespace regolith::farfield {

/// How the primary sphere's radius (the minimum visible radius of the previous frame, §4) is
/// read back from the GPU.
enum class PrimaryReadback {
  Fixed,   ///< no reduction: the body's lowest radius every frame
  Stall,   ///< reduce, then read at once (the GPU finishes the frame first)
  Lagged,  ///< reduce, read the result a frame later through a fence (no stall)
};

/// Settings of a PgmRenderer.
struct PgmOptions {
  /// The projective grid, set independently of the screen (§6): 8..4096 points per side.
  int gridWidth = 256, gridHeight = 256;
  /// The blend threshold ζ of eq. 1 (0.05..1): rays below ζ·τ₀ use the primary sphere only.
  double zeta = 0.9;
  PrimaryReadback readback = PrimaryReadback::Lagged;
  /// The primary radius is lowered by this fraction of the body's relief (max − min
  /// radius) below the last minimum, so terrain that comes into view this frame is not
  /// shrunk away (§4, "shrinking").
  double primaryMargin = 0.02;
  /// Spread the grid's rays for an even screen-space error (RaySpread, docs/far-field.md):
  /// the paper's grid is even in the sampling camera's image plane and coarsest on the
  /// ground at the limb; the spread moves its rows towards the limb and the horizon. Off:
  /// the paper's even grid. A frame whose sampling frustum did not hold the nadir would be
  /// drawn without it (the spread keeps the grid's coverage only about a nadir it holds);
  /// the sampling camera includes the nadir, and no view tested has left it out.
  bool evenError = true;
  /// Mip bias of the height lookups (0: one layer texel per grid step).
  float lodBias = 0.0F;
  /// Colour: a height ramp from `low` to `high` over the layers' height range, or one
  /// colour when `heightColours` is false. Lambert shading with this ambient term.
  bool heightColours = true;
  glm::vec3 low{0.42F, 0.26F, 0.16F}, high{0.93F, 0.80F, 0.62F};
  float ambient = 0.12F;
  /// Time each pass with GL timer queries (read at the end of draw(), which then waits for
  /// the GPU): PgmFrame::gridMs, meshMs and reduceMs. For benchmarks.
  bool timePasses = false;
  /// Cull the mesh's clockwise triangles: where the grid folds back over itself (the ground
  /// behind the limb that the occluded-area sampling reaches) its triangles turn clockwise
  /// on screen and are hidden by the surface in front. Off draws them too, for the test that
  /// shows culling changes no pixel and for the benchmark of what it saves.
  bool cullFolds = true;
  /// A smaller grid when the body covers few pixels: the grid's side is halved
  /// (n → (n − 1)/2 + 1, over the same sampling frustum, down to 8 points) while its cells,
  /// at their largest on the screen, span fewer than this many pixels. On llvmpipe the mesh
  /// pass costs about one fragment-shader run per 4 × 4 pixel block each triangle touches,
  /// so small cells cost several times their area and sub-pixel cells many times
  /// (docs/far-field.md, "The mesh pass"). The default, 1, thins only a grid whose cells
  /// are all under a pixel; 0: always the full grid.
  double minCellPixels = 1.0;
  /// FarField only: draw the impostor instead of PGM while the body's relief (the largest
  /// |height| of the layers), seen from the eye at the nearest distance the body can have,
  /// spans at most this many pixels: the impostor's ellipsoid is then within that screen
  /// error of the terrain. 0 (the default): PGM until r_s ≤ 0.
  double impostorReliefPixels = 0.0;
};

/// What one draw() did.
struct PgmFrame {
  /// False if the view is too far for PGM (no secondary sphere, r_s ≤ 0): nothing was drawn
  /// and the body should be drawn as an impostor (RayCastGlobe).
  bool drawn = false;
  ReferenceSpheres spheres;
  SamplingCamera sampling;
  /// The minimum visible radius read back this frame (metres from the centre), or NaN if
  /// none arrived yet (Lagged: the previous frame's; Fixed: never).
  double minVisibleRadius = 0.0;
  /// GPU time of the grid pass (the PGM step proper: rays, spheres, heights), the mesh pass
  /// and the reduction, in milliseconds (PgmOptions::timePasses; else 0).
  double gridMs = 0.0, meshMs = 0.0, reduceMs = 0.0;
  /// The spread of the grid's rays this frame (inactive: the even grid).
  RaySpread spread;
  /// The grid drawn: the options' size, or smaller under PgmOptions::minCellPixels.
  int gridWidth = 0, gridHeight = 0;
  /// The grid's largest cell on the screen (pixels) at the options' size (0 unless
  /// minCellPixels is set).
  double cellPixels = 0.0;
};

/// Draws a body's surface by PGM into a render target:
///
/// 1. The grid pass (one full-screen pass over a grid-sized target): each grid point's eye
///    ray from the sampling camera (§5); its normal angle γ from the ray–circle reduction and
///    the blend of the two reference spheres (§3, §4); its sphere normal ŝ and its position
///    relative to the eye, (d − r_p + 2r_p·sin²(γ/2))·n̂ + r_p·sin γ·k̂, then the height
///    from the layers (§6, §7: the equirectangular layer and the polar stereographic caps
///    evaluated from the normal, with no radius) and the displaced point
///    P + (ρ(ŝ) − r_p)·ŝ + h·n̂_geodetic, all as small differences: no planetary-magnitude
///    world position is formed on the GPU.
/// 2. The mesh pass: the grid as triangle strips, each vertex fetched from the grid pass,
///    through the camera's reversed-Z projection (float depth with an infinite far plane;
///    the paper's near/far two-pass rasterisation is not needed, docs/far-field.md). It also
///    writes each fragment's radius into a screen-sized buffer.
/// 3. The reduction: a compute shader takes that buffer's minimum, the next frame's primary
///    radius (PrimaryReadback).
///
/// The camera is in body-fixed metres (the body's centre at the origin). Needs a current
/// GL 4.5 context; belongs to its thread.
class PgmRenderer {
 public:
  /// Uploads the layers (mipmapped). Throws InvalidArgument for options out of range.
  PgmRenderer(const HeightLayers& layers, PgmOptions options = {});
  ~PgmRenderer();
  PgmRenderer(const PgmRenderer&) = delete;
  PgmRenderer& operator=(const PgmRenderer&) = delete;

  [[nodiscard]] const PgmOptions& options() const noexcept { return options_; }
  /// The body's lowest and highest radius (ellipsoid and heights).
  [[nodiscard]] double minRadius() const noexcept { return minRadius_; }
  [[nodiscard]] double maxRadius() const noexcept { return maxRadius_; }
  /// The primary radius the next draw() will use.
  [[nodiscard]] double primaryRadius() const noexcept { return primary_; }
  /// Forgets what earlier frames measured: the next draw() takes the lowest radius as its
  /// primary sphere, as the first one does, and a read-back still in flight is dropped. For
  /// a caller that skips frames (FarField, while the near field covers the target): the
  /// minimum visible radius of a view long past may lie above the ground seen now.
  void restart() noexcept;

  /// Draws into `target` (which the caller cleared) with depth test and depth writes. The
  /// camera must have the target's size (InvalidArgument otherwise). `sun` is the unit
  /// direction towards the light, body-fixed.
  ///
  /// With `keepDrawn`, pixels the target already has depth for keep it: the far field
  /// fills in only around what is drawn (the hand-off from the near-field clipmaps, drawn
  /// first: no band where two surfaces of different resolution fight in the depth test).
  PgmFrame draw(const gl::RenderTarget& target, const clod::Camera& camera, const glm::dvec3& sun,
                bool keepDrawn = false);

  /// The grid pass's outputs of the last draw(), row-major from the grid's bottom row:
  /// (displaced point − eye, radius − r_p) and (lighting normal, height) per grid point.
  [[nodiscard]] std::vector<glm::vec4> readGridPositions() const;
  [[nodiscard]] std::vector<glm::vec4> readGridNormals() const;

 private:
  void setFrameUniforms(const clod::Camera& camera, const ReferenceSpheres& s,
                        const SamplingCamera& sc, const glm::dvec3& sun) const;
  /// The frame's spread (PgmOptions::evenError), uploaded to the grid pass; recomputed only
  /// when the reference spheres change.
  void setSpread(PgmFrame& frame, const glm::dvec3& nadir);
  void reduce(const gl::RenderTarget& target, PgmFrame& frame);
  /// The grid stride (1, 2, 4, …) for PgmOptions::minCellPixels; sets frame.cellPixels.
  int gridStride(const clod::Camera& camera, PgmFrame& frame) const;

  PgmOptions options_;
  LayerOptions layerOptions_;
  double capRadius_ = 0.0;
  double a_ = 0.0, b_ = 0.0, minHeight_ = 0.0, maxHeight_ = 0.0;
  double minRadius_ = 0.0, maxRadius_ = 0.0, primary_ = 0.0;
  gl::Program grid_;
  gl::Program mesh_;
  gl::Program reduce_;
  gl::VertexArray vao_;
  gl::Texture equirect_, north_, south_;
  gl::Texture gridPos_, gridNrm_;
  gl::Framebuffer gridFbo_;
  gl::Buffer indices_;
  int indexCount_ = 0;
  gl::Buffer thinIndices_{0};  ///< the strips of the thinned grid (minCellPixels)
  int thinIndexCount_ = 0;
  int thinWidth_ = 0, thinHeight_ = 0;
  gl::Texture radius_{0};
  gl::Texture drawnDepth_{0};  ///< copy of the target's depth for keepDrawn
  int radiusWidth_ = 0, radiusHeight_ = 0;
  std::array<gl::Buffer, 2> minBuffers_;
  // GLsync fences: opaque pointers, kept as void* so this header needs no GL header.
  std::array<void*, 2> fences_{nullptr, nullptr};
  std::array<double, 2> primaryOf_{0.0, 0.0};
  std::array<gl::Id, 3> timers_{0, 0, 0};  ///< r_p each buffer's frame drew with
  int frameIndex_ = 0;
  RaySpread spread_;                ///< the last spread computed,
  ReferenceSpheres spreadSpheres_;  ///< for these spheres
};

}  // namespace regolith::farfield
