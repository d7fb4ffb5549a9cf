#pragma once
/// \file
/// Draws a scene graph's render list: terrains (clipmaps) and small meshes, each in its own
/// frame, with DEMs that win over the planet they sit on.

#include <regolith/clod/Camera.hpp>
#include <regolith/clod/ClipmapOptions.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/scenegraph/RenderList.hpp>

#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <vector>

namespace regolith::gl {
class Program;
class RenderTarget;
}  // namespace regolith::gl

namespace regolith::farfield {
class FarField;
class HeightLayers;
struct PgmOptions;
}  // namespace regolith::farfield

namespace regolith::clod {
class ClipmapTerrain;  // <regolith/clod/ClipmapTerrain.hpp>: this header needs no GL header
}  // namespace regolith::clod

namespace regolith::render {

/// A mesh vertex in its item's frame (metres, float: meshes are small, e.g. a rover).
struct MeshVertex {
  glm::vec3 position{0.0F};
  glm::vec3 normal{0.0F, 0.0F, 1.0F};
};

/// The 36 vertices (12 triangles, outward normals) of the box [lo, hi], appended to `out`.
void appendBox(std::vector<MeshVertex>& out, const glm::vec3& lo, const glm::vec3& hi);
/// Where a rover model's wheels are, in metres: the defaults are rover::RoverGeometry's
/// (Curiosity-like), so the wheels drawn stand where a traverse's wheel contacts (and the
/// tracks pressed from them) are.
struct RoverShape {
  std::array<float, 3> axleOffsets{1.10F, 0.0F, -1.00F};  ///< front, middle, rear (forward)
  float trackWidth = 2.20F;                               ///< between wheel centres
  float wheelWidth = 0.40F, wheelRadius = 0.25F;
};

/// A rover model in the rover frame (x forward, y left, z up; origin on the ground under the
/// body centre): body, mast and head, six wheels at `shape`'s positions.
[[nodiscard]] std::vector<MeshVertex> roverMesh(const RoverShape& shape = {});

/// Camera intrinsics and the viewport a render list is drawn into. The camera's pose comes
/// from the render list (GL eye convention).
struct SceneView {
  double fovYDegrees = 45.0;
  double near = 0.1;                            ///< metres
  int x = 0, y = 0, width = 640, height = 480;  ///< viewport in the bound framebuffer (GL: y up)
  /// Towards the light, in the render list's focus frame (normalised when used).
  glm::dvec3 lightInFocus{0.4, -0.3, 0.866};
  /// Where prepare() centres the clipmaps, in the focus frame (a look-at point on the
  /// ground, as `regolith render` and clod::renderImage() do); unset: the camera's position.
  /// Clamped onto a plane DEM's grid either way.
  std::optional<glm::dvec3> clipmapCentreInFocus;
};

/// How SceneRenderer::prepare() loads the terrains' windows. Either way the reads run on the
/// clipmaps' executors (ClipmapOptions::executor), never on the calling thread.
enum class Loading {
  /// Waits until every terrain of the list has its windows for the view: the frame drawn next
  /// is the same however fast the machine reads (headless renders, tests).
  Wait,
  /// Asks for the windows and returns at once, uploading what has arrived since the last
  /// call; draw() shows the levels that are resident and a coarser one where a finer has not
  /// caught up (ClipmapTerrain::requestFocus()). For a frame loop.
  Background,
};

/// What one draw() did.
struct SceneFrame {
  std::size_t terrainsDrawn = 0, meshesDrawn = 0;
  std::size_t itemsUnknown = 0;       ///< render-list items with a key nothing is registered for
  std::size_t texelsUploaded = 0;     ///< by the prepare() calls since the previous draw()
  std::size_t vertices = 0;           ///< the far fields' PGM grids (as drawn) included
  std::size_t farFieldsPgm = 0;       ///< far fields drawn by PGM
  std::size_t farFieldsImpostor = 0;  ///< far fields drawn by the ray-cast impostor
  /// Far fields with nothing to draw: the near field had covered the target
  /// (farfield::FarFieldMode::Covered; one depth-only pass each).
  std::size_t farFieldsCovered = 0;
};

/// Draws render lists (scenegraph::SceneGraph::renderList). Each item is drawn in its own frame:
/// the camera's pose relative to the item (double, from the render list) becomes a clod
/// Camera in that frame, so a terrain's clipmap sends the GPU only camera-relative floats,
/// whatever the focus. A mesh gets its item → camera pose, made in double, cast to float.
///
/// Cut-outs: a DEM drawn over a planet (addCutOut) makes the planet's fragments vanish where
/// the DEM has data (a cell mask of the DEM's finest level, tested per fragment in the DEM's
/// grid frame), and a skirt hangs from the DEM's data border, down and inward, below both
/// surfaces, so no gap opens along the border whatever the two surfaces' heights and
/// whatever clipmap level each draws.
///
/// Needs a current GL 4.5 context; belongs to its thread. Not copyable.
class SceneRenderer {
 public:
  SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;
  ~SceneRenderer();

  /// Terrain drawn for render-list items with key `drawable`. Its scene frame (grid frame
  /// for a Plane pyramid, body-fixed for a Planet or placed DEM) is the item's frame.
  /// Throws InvalidArgument if the key is taken.
  void addTerrain(int drawable, std::shared_ptr<const clod::HeightPyramid> pyramid,
                  const clod::ClipmapOptions& options = {});
  /// A mesh in its item's frame for key `drawable`, flat-lit with `albedo`.
  void addMesh(int drawable, const std::vector<MeshVertex>& vertices, const glm::vec3& albedo);
  /// DEM `dem` (a Plane pyramid, registered with addTerrain) wins over planet `planet` (a
  /// Planet pyramid) where the DEM has data. At most 4 DEMs per planet. Throws
  /// InvalidArgument for unknown keys, wrong kinds, or a fifth DEM.
  void addCutOut(int planet, int dem);
  /// The far field of planet terrain `planet` (registered with addTerrain, a Planet
  /// pyramid, or a placed one drawn body-fixed: a polar cap's stereographic grid): a
  /// farfield::FarField (PGM, and the ray-cast impostor for views too far for it) over
  /// `layers` with `options`, drawn by draw() beyond the clipmap, wherever the near field
  /// left the target empty. Throws InvalidArgument for an unknown key, a terrain not drawn
  /// body-fixed, or a planet that has one already.
  void addFarField(int planet, std::shared_ptr<const farfield::HeightLayers> layers,
                   const farfield::PgmOptions& options);

  /// Views drawn in turn each take a slot below this (prepare(), draw()).
  static constexpr std::size_t kMaxSlots = 16;

  /// Loads what draw() needs for `list` seen through `view` in view slot `slot`: moves each
  /// terrain's clipmap of that slot to its focus (view.clipmapCentreInFocus or else the
  /// camera's position, in the terrain's frame, clamped onto a plane DEM's grid), reads on
  /// the executors as `loading` says, uploads what has arrived, and starts reading the planet
  /// samples under the DEMs that cut it (the border skirts' depth). Call it before each
  /// draw() of a list whose camera or items moved. Returns the texels uploaded. A read error
  /// of the loader (a store I/O error) is rethrown here. Throws InvalidArgument for a view
  /// draw() would refuse, or a slot of kMaxSlots or more.
  ///
  /// Each slot has clipmaps of its own (made on its first prepare(); slot 0's by
  /// addTerrain()), so views drawn in turn, such as split viewports, do not move one
  /// another's clipmap windows and reload them every frame.
  std::size_t prepare(const scenegraph::RenderList& list, const SceneView& view,
                      Loading loading = Loading::Wait, std::size_t slot = 0);
  /// Draws `list` into the bound framebuffer within view's viewport (depth state: reversed
  /// Z, as RenderTarget sets it), with what prepare() left resident: draw() reads no terrain
  /// source, moves no clipmap and waits for no read (a terrain never prepared draws nothing;
  /// a DEM's border skirt waits for a frame in which the planet's sample under it is in).
  ///
  /// The clipmaps drawn are those of view `slot` (prepare()); a slot never prepared draws no
  /// terrain. With `target` (the render target bound, which the view must cover whole: PGM's
  /// passes are the target's size), draw() then draws the far fields (addFarField) of the
  /// list's planets. Each slot has far fields of its own too: PGM's primary sphere comes from
  /// the previous frame of the same view, so views drawn in turn (viewports, cameras) each
  /// take a slot. Without `target` no far field is drawn. Throws InvalidArgument for a view
  /// draw() cannot draw (a far field's view not covering the target included) or a slot of
  /// kMaxSlots or more.
  SceneFrame draw(const scenegraph::RenderList& list, const SceneView& view,
                  const gl::RenderTarget* target = nullptr, std::size_t slot = 0);

  /// Draws the DEM border skirts (default on). Off only to show what they prevent: the
  /// planet's cut edge and the DEM's border then leave gaps wherever their heights differ.
  void setBorderSkirts(bool on) noexcept { skirts_ = on; }

  /// The clipmap of a terrain key in view slot 0 (nullptr if none).
  [[nodiscard]] const clod::ClipmapTerrain* terrain(int drawable) const;

 private:
  struct Terrain;
  struct Mesh;
  struct Skirt;
  struct FarFields;
  void drawFarFields(const scenegraph::RenderList& list, const SceneView& view,
                     const gl::RenderTarget& target, std::size_t slot, SceneFrame& frame);
  std::map<int, std::unique_ptr<Terrain>> terrains_;
  std::map<int, std::unique_ptr<Mesh>> meshes_;
  std::map<int, std::unique_ptr<FarFields>> farFields_;
  std::unique_ptr<gl::Program> meshProgram_;
  bool skirts_ = true;
  std::size_t preparedTexels_ = 0;  // uploaded by prepare() since the last draw()
};

/// The clod Camera for drawing an item whose camera pose (camera → item frame) is `pose`.
[[nodiscard]] clod::Camera cameraInItem(const scenegraph::Pose& pose, const SceneView& view);

}  // namespace regolith::render
