#pragma once
/// \file
/// Geometry-clipmap terrain over a plane (DEM) or a spheroid (planet).

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapOptions.hpp>
#include <regolith/clod/CutOut.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Program.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace regolith::clod {

class ClipmapLevel;

/// A DEM that wins over a planet terrain where it has data (render::SceneRenderer::addCutOut): its
/// cell mask (an R8 texture, one texel per cell of render::CellMask, r > 0.5 with data) and this
/// frame's map from eye coordinates to those cells (render::cutOutTransform()).
struct ClipmapCutOut {
  const gl::Texture* mask = nullptr;  ///< not null; must outlive the draw() calls that use it
  CutOutTransform transform;
};

/// What one draw() did.
struct ClipmapFrame {
  std::size_t firstLevel = 0;    ///< innermost level drawn (it draws its centre)
  std::size_t levelsDrawn = 0;   ///< levels drawn, from firstLevel outward
  std::size_t levelsCulled = 0;  ///< active levels left out as out of view (cullLevels)
  std::size_t vertices = 0;      ///< vertices submitted (indices drawn)
  std::size_t textureBinds = 0;  ///< glBindTextureUnit calls (one per level without effects)
};

/// Geometry clipmaps (Losasso & Hoppe 2004; Asirvatham & Hoppe, GPU Gems 2 ch. 2): nested
/// n × n grids centred on the focus, level k at the spacing of pyramid level k.
///
/// - The CPU builds one mesh once (grid, centre hole of the coarser levels, skirts) that
///   every level shares.
/// - Each level keeps a toroidally addressed RGBA32F texture: xyz the scene position of a
///   sample relative to the level's anchor (computed in double on the CPU; small floats
///   only), w its height or NaN over nodata. Moving the focus uploads only the rows and
///   columns that enter a level's window.
/// - Coarser levels leave out a centre hole a little smaller than the finer level's extent
///   (the two overlap by a few cells) and each level hangs a skirt below its outer border,
///   deep enough to reach below both its own and the next level's lowest sample, so no
///   gap opens between levels.
/// - A geometry shader drops triangles that touch a nodata sample; the fragment shader
///   lights with a light direction, an albedo and the normal from neighbouring samples.
///
/// Planets: windows wrap in longitude on global grids and continue over a pole (the rows
/// beyond it are the rows on the other side, half a turn of longitude away), so neither the
/// ±180° meridian nor a pole is an edge.
///
/// Needs a current GL 4.5 context; belongs to its thread. The pyramid must outlive it.
class ClipmapTerrain {
 public:
  /// Throws InvalidArgument for a size that is even or out of range, or more levels than
  /// the pyramid has.
  /// Effects: throws InvalidArgument for lat/lon lines on a plane without placement, tracks
  /// on a planet (their grid is not metric), a track window outside 256..8192, or a draped
  /// texture TextureClipmap rejects.
  ClipmapTerrain(std::shared_ptr<const HeightPyramid> pyramid, ClipmapOptions options = {});
  ClipmapTerrain(const ClipmapTerrain&) = delete;
  ClipmapTerrain& operator=(const ClipmapTerrain&) = delete;
  ~ClipmapTerrain();

  /// Centres every level on the scene point `focus` (its grid point: x, y for a plane;
  /// longitude, latitude for a planet) and uploads what enters the windows. Returns the
  /// number of texels uploaded. Reads the pyramid's sources on the calling thread.
  std::size_t setFocus(const glm::dvec3& focus);
  /// Background loading: sets the focus the levels should move to and returns at once. A
  /// task on the options' executor reads and prepares the new rows and columns, coarsest
  /// level first;
  /// update() uploads what is ready. Until a level has caught up, draw() leaves it (and any
  /// finer one) out and the next coarser consistent level draws its centre, so a frame
  /// never waits for I/O and never shows a gap.
  void requestFocus(const glm::dvec3& focus);
  /// Uploads finished background work (height rows and columns, and the windows of draped
  /// textures) and schedules more (render thread). With
  /// `wait` it first blocks until some job finishes, if one is running (tests, tools; a
  /// frame loop passes false). Returns the texels uploaded. An error the loader met while
  /// reading (a store I/O error) is rethrown here; that level is then asked again.
  std::size_t update(bool wait = false);
  /// True while background jobs are queued or running.
  [[nodiscard]] bool loading() const;
  /// Runs update(true) until nothing is loading; returns the texels uploaded.
  std::size_t finishLoading();
  /// Levels with data resident (a level is resident once its first window is uploaded).
  [[nodiscard]] std::vector<bool> residentLevels() const;

  /// Draws into the bound framebuffer (depth state: useReversedZ()).
  ClipmapFrame draw(const Camera& camera) const;

  [[nodiscard]] std::size_t levelCount() const noexcept { return levels_.size(); }
  [[nodiscard]] int size() const noexcept { return options_.size; }
  [[nodiscard]] const ClipmapOptions& options() const noexcept { return options_; }
  void setOptions(const ClipmapOptions& options);
  /// Texels uploaded since construction.
  [[nodiscard]] std::size_t uploadedTexels() const noexcept { return uploaded_; }
  /// Window origin (row, col) of level k, in that pyramid level's sample indices.
  [[nodiscard]] std::pair<long long, long long> windowOrigin(std::size_t level) const;
  /// Levels that draw for this camera (first, count), without drawing.
  [[nodiscard]] std::pair<std::size_t, std::size_t> activeLevels(const Camera& camera) const;
  /// Grid cells in the centre hole of a coarser level (half-width, in that level's cells).
  [[nodiscard]] int holeHalfWidth() const noexcept { return hole_; }
  /// The pyramid drawn.
  [[nodiscard]] const HeightPyramid& pyramid() const noexcept { return *pyramid_; }
  /// The GL program: to inspect its active uniforms.
  [[nodiscard]] const gl::Program& program() const noexcept { return program_; }

  /// The DEMs that win over this terrain in the following draw() calls (at most 4; empty:
  /// none), drawn into a viewport whose lower-left corner is `viewportOrigin` (pixels in the
  /// bound framebuffer; the viewport's size and the projection come from draw()'s camera).
  /// Only for a terrain built with options().cutOuts (an assertion), as is the count.
  void setCutOuts(std::span<const ClipmapCutOut> cutOuts, const glm::ivec2& viewportOrigin);

  /// The sources the program was built from: the bare clipmap shaders plus one snippet per
  /// declared effect (identical to bareSources() when none is declared).
  [[nodiscard]] const gl::ShaderSources& programSources() const noexcept { return sources_; }
  /// The clipmap program without any effect: the pipeline before effects existed.
  [[nodiscard]] static gl::ShaderSources bareSources();
  /// The sources a terrain with these options compiles (effects, cut-outs).
  [[nodiscard]] static gl::ShaderSources programSourcesFor(const ClipmapOptions& options,
                                                           bool planet);
  /// The GPU work a frame does, in order: "terrain" always; "albedo-clipmap",
  /// "overlay-clipmap" (texture windows following the focus) and "track-upload" (new ruts)
  /// only when those effects are declared.
  [[nodiscard]] std::vector<std::string> passes() const;
  /// Degrees between lat/lon lines for this camera (LatLonLines::spacingDegrees if set, else
  /// adapted to the camera's height above the body). Throws InvalidArgument if lat/lon
  /// lines are not declared.
  [[nodiscard]] double latLonSpacing(const Camera& camera) const;
  /// The grid point the frame's effect coordinates are relative to (the last focus).
  [[nodiscard]] glm::dvec2 gridOrigin() const noexcept { return gridOrigin_; }

 private:
  void buildMesh();
  void schedule();
  /// Runs queued level reads, coarsest first, until the queue is empty (on the executor).
  void drainQueue();
  [[nodiscard]] int polarFor(const glm::dvec2& gridPoint) const;
  [[nodiscard]] std::size_t firstConsistent() const;

  struct Job;
  struct Loader;
  struct EffectState;
  void initEffects();
  void updateEffects(const glm::dvec3& focus, bool background = false);
  /// Lat/lon lines: reads the ground under a new focus (FocusGround), now or on the executor.
  void updateGround(bool background);
  std::size_t pollEffects(bool wait);
  [[nodiscard]] bool effectsLoading() const noexcept;
  void setEffectUniforms(const Camera& camera, ClipmapFrame& frame) const;
  void setLevelUniforms(std::size_t level) const;
  void setCutOutUniforms(const Camera& camera) const;

  std::shared_ptr<const HeightPyramid> pyramid_;
  ClipmapOptions options_;
  std::vector<std::unique_ptr<ClipmapLevel>> levels_;
  gl::ShaderSources sources_;
  gl::Program program_;
  gl::VertexArray vao_;
  gl::Buffer vertices_, indices_;
  std::size_t holeIndices_ = 0, ringIndices_ = 0, skirtIndices_ = 0;
  int hole_ = 0;
  std::size_t uploaded_ = 0;
  std::unique_ptr<Loader> loader_;
  std::unique_ptr<EffectState> effects_;  // null without effects
  glm::dvec2 gridOrigin_{0.0};
  std::vector<ClipmapCutOut> cutOuts_;  // setCutOuts(): applied by draw()
  glm::ivec2 cutViewportOrigin_{0};
};

}  // namespace regolith::clod
