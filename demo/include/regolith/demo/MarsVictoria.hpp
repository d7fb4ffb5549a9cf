#pragma once
/// \file
/// The paper's example scene with data (generated or stored Mars, Victoria-like DEMs, a
/// rover) as a scene description (docs/scene-format.md) built by scene::Scene, and the
/// headless fly-over from orbit down to the rover.

#include <regolith/clod/Effects.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneDescription.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::demo {

/// Sizes of the generated data (small by default so tests and the demo stay fast).
struct MarsVictoriaOptions {
  /// store::MarsPlanetGenerator rows (latitude samples pole to pole) on the IAU ellipsoid.
  std::size_t planetRows = 360;
  /// store::VictoriaGenerator grid: samples per side and spacing (m).
  std::size_t demSize = 601;
  double demSpacing = 2.0;
  /// A second, smaller Victoria-like DEM (another seed) on Mars near the first.
  bool secondDem = true;
  std::size_t secondDemSize = 201;
  double secondDemSpacing = 2.0;
  std::uint64_t seed = 1;
  /// Clipmap vertices per level side for every terrain.
  int clipmapSize = 127;
  /// Stores to draw instead of generating Mars and Victoria in memory: a planet grid and a
  /// DEM grid (kind dem, local tangent plane placement), paged through one patch cache of
  /// `cacheBytes`. The DEM sits at its store's placement origin and heading; the planet's
  /// body is its store's. Both empty: generate (planetRows, demSize, demSpacing, seed).
  /// One given without the other: InvalidArgument.
  std::filesystem::path marsStore, victoriaStore;
  std::string marsGrid = "mars", victoriaGrid = "victoria";
  std::size_t cacheBytes = std::size_t{256} << 20;
  /// The DEMs' albedo; unset: kDemAlbedo (greener than the planet, so
  /// tests can tell the two apart).
  std::optional<glm::vec3> demAlbedo;
  /// Effects declared on the Victoria DEM (e.g. the wheel tracks of a traverse); none by
  /// default (the bare pipeline).
  clod::Effects victoriaEffects;
  /// Compose Mars, the DEMs and `extraDatasets` into one surface (docs/composition.md) and
  /// draw that everywhere: each terrain keeps its own lattice, but its samples are the
  /// composed heights there, so the planet shows the DEMs (at its resolution) and each DEM
  /// blends into the planet over its feather instead of meeting it at a step.
  bool composition = false;
  /// Border feather of the Victoria-like DEMs in the composition, metres.
  double demFeatherMetres = 60.0;
  /// Further datasets of the composition (with composition on): store grids, e.g. the
  /// generated polar caps and an inclined strip, paged through the scene's cache.
  struct StoreDataset {
    std::filesystem::path store;
    std::string grid;
    double featherMetres = 0.0;
    /// > 0: a coverage mask feathered over this many samples from the grid's nodata border
    /// (compose::featherMask(), in memory).
    double featherNodataSamples = 0.0;
  };
  std::vector<StoreDataset> extraDatasets;
  /// Draw Mars beyond its clipmap with the far field (docs/far-field.md): the planet's
  /// clipmap keeps only the levels whose window spans at most 180° (a wider one reaches
  /// over a pole onto ground it already covers), and PGM draws the rest of the planet around
  /// it. Off: the clipmap draws every level, as before the far field existed.
  bool farField = true;
};

/// The albedos of the demo's terrains: the DEMs are drawn greener than the planet so tests
/// can tell them apart.
inline constexpr glm::vec3 kPlanetAlbedo{0.80F, 0.52F, 0.38F};
inline constexpr glm::vec3 kDemAlbedo{0.55F, 0.75F, 0.45F};

/// What the fly-over renders and where.
struct FlyoverOptions {
  std::filesystem::path outputDir = "mars_victoria_frames";
  int frames = 72;
  int width = 480, height = 270;
  MarsVictoriaOptions scene{};
  /// Where the fly-over ends: the rover at grid (x, y) on the Victoria DEM (on its surface),
  /// heading in degrees clockwise from +y, e.g. where a traverse stopped. Unset: the paper
  /// layout's rover on the southern rim. InvalidArgument if not finite.
  std::optional<glm::dvec3> rover;
  /// Also write a frame of the rover's mast camera and of the orbit camera (one PNG with
  /// both as viewports) after the fly-over.
  bool multiView = true;
  /// Begin over the north pole: the first 40% of the frames fly from 2000 km above the pole
  /// along Victoria's meridian to 2000 km above Victoria, then descend as without it.
  bool overPole = false;
  /// Begin with an approach from this far from Mars's centre (metres; 0: none): the first
  /// tenth of the frames (at least one, leaving at least two) fly in along the first pose's
  /// view, log-spaced in distance, to that pose. From beyond about 10.5 Mars radii, where
  /// PGM's secondary sphere vanishes, the first frame draws Mars as the ray-cast impostor,
  /// so the fly-over passes through all three of the far field's renderers: impostor, PGM,
  /// clipmaps (docs/far-field.md). InvalidArgument if negative or not finite.
  double approachFrom = 0.0;
  /// Called after each frame with (frames written, frames in all, path).
  std::function<void(int, int, const std::filesystem::path&)> progress;
};

struct FlyoverSummary {
  std::vector<std::filesystem::path> files;
  double seconds = 0.0;        ///< wall time of the whole run (scene build included)
  double renderSeconds = 0.0;  ///< drawing and reading back frames only
  /// The frame where the focus switched from Mars to Victoria (-1: never).
  int focusSwitchFrame = -1;
  /// With composition: how many datasets each frame's camera saw (its frustum against each
  /// dataset's bounds, compose::Snapshot::visible()), one entry per frame.
  std::vector<std::size_t> datasetsPerFrame;
  /// The frame where the camera passed closest to the north pole (overPole), and its
  /// latitude there (degrees; -1 and NaN without overPole).
  int poleFrame = -1;
  double poleLatitude = std::numeric_limits<double>::quiet_NaN();
  /// Camera distance to the rover at the first and last frame (m).
  double startDistance = 0.0, endDistance = 0.0;
  /// Frames in which the far field drew Mars by PGM around the clipmaps (options.scene.
  /// farField), by the impostor (too far for PGM), and frames in which it drew nothing
  /// because the clipmaps had filled the view (farfield::FarFieldMode::Covered).
  int farFieldFrames = 0;
  int impostorFrames = 0;
  int coveredFrames = 0;
};

/// Builds the demo scene (buildScene(options.scene) with the rover at options.rover) and
/// renders the fly-over over it headless: the camera starts far enough out to see Mars whole and
/// descends on a smooth logarithmic path to a few metres from the rover on Victoria's rim,
/// the focus switching from Mars to Victoria on the way. Writes frame_NNNN.png files (and
/// multiview.png) into outputDir, creating it. Creates an EGL context if none is current.
/// Throws InvalidArgument for fewer than 2 frames or an empty image, or if a frame would be
/// written over one of the scene's stores (core::refuseOverwritingInput()); GlError without
/// GL, regolith::Error if a PNG cannot be written.
FlyoverSummary renderFlyover(const FlyoverOptions& options);

/// The same fly-over over a scene already built (e.g. from the file `regolith demo` writes):
/// options.scene and options.rover are not used; the scene must hold a body "mars", a DEM
/// "victoria" on it and an object "rover" on that DEM, and for the multi-view the cameras of
/// paperCameras() (InvalidArgument naming what is missing). Adds its camera
/// ("flyover_camera") to the scene's graph, so a scene flies over once.
FlyoverSummary renderFlyover(scene::Scene& scene, const FlyoverOptions& options);

/// One view of the scene, for a single image.
struct SceneViewOptions {
  MarsVictoriaOptions scene{};
  /// The rover on the Victoria DEM: grid x, y (on the surface) and heading (degrees
  /// clockwise from +y).
  double roverX = 0.0, roverY = -395.0, roverHeadingDeg = 0.0;
  /// The camera's pose in the Victoria DEM's frame (GL eye convention: it looks along its
  /// −z, e.g. scenegraph::Pose::lookAt()).
  scenegraph::Pose camera;
  int width = 960, height = 540;
  double fovYDegrees = 45.0, near = 0.05;
};

/// Renders one view of the demo scene (buildScene(options.scene) with the rover there)
/// headless (an EGL context is made if none is current), focus on Victoria. Throws InvalidArgument
/// for an empty image, a camera pose, near plane or rover that is not finite, or a field of view
/// outside (0, 180) degrees; GlError without GL.
gl::RgbaImage renderSceneView(const SceneViewOptions& options);

/// The fly-over camera's pose in the Victoria DEM frame at t ∈ [0, 1] for a rover at `rover`,
/// descending from `startDistance` metres (at t = 0) to 6 m (at t = 1).
[[nodiscard]] scenegraph::Pose flyoverCamera(double t, const glm::dvec3& rover,
                                             double startDistance = 8.0e6);

/// The paper layout's cameras (demo/PaperScene.hpp) as scene-file cameras, which
/// sceneDescription() declares: "orbit_camera" 20 km above Victoria's origin looking straight
/// down, north up (in the frame of the DEM "victoria", heading 0; near plane 100 m); the
/// rover's "mast_camera", 2.1 m up just ahead of the mast head of render::roverMesh(), looking
/// 15° down ahead; and "chase_camera" 8 m behind and 3 m above the rover (in the frame of the
/// object "rover"; near plane 0.05 m). Each 960 × 540, 45° vertical field of view.
[[nodiscard]] std::vector<scene::Camera> paperCameras();

/// The paper layout's camera nodes in a built demo scene.
struct DemoCameras {
  scenegraph::NodeId orbit = 0, mast = 0, chase = 0;
};

/// The nodes of the paper layout's cameras (paperCameras()) in a built demo scene.
/// InvalidArgument naming the first camera the scene does not declare.
[[nodiscard]] DemoCameras paperCameraNodes(const scene::Scene& scene);

/// Where the scene file's rover stands: at a pose on the Victoria DEM, or where a traverse of
/// these waypoints (grid frame) stops, its tracks pressed into the DEM.
struct SceneRover {
  double x = 0.0, y = -395.0, headingDeg = 0.0;
  std::vector<glm::dvec2> traverse;  ///< non-empty: replay this traverse instead
};

/// The Mars/Victoria scene of `options` as a scene description (docs/scene-format.md), with
/// the paper's cameras (paperCameras(); the caller adds its views, their frame "victoria" the
/// Victoria DEM's, as renderSceneView()'s camera): Mars ("mars") from its generator or store (with
/// the extra datasets and the DEMs composed into it under options.composition), Earth ("earth":
/// WGS84 without relief), both where the paper's layout puts them (PaperSceneLayout: heliocentric
/// poses), the Victoria DEM ("victoria") and the second DEM ("second_dem"), the rover
/// ("rover"), and the morning light over Victoria (35° up, from the east). This description is
/// the demo scene: every demo render (the fly-over, renderSceneView(), `regolith demo`'s rover
/// views) draws the scene::Scene built from it. Store paths are written as given (relative ones
/// resolve against the current folder). Effects other than tracks in options.victoriaEffects are
/// not carried over (InvalidArgument).
[[nodiscard]] scene::SceneDescription sceneDescription(const MarsVictoriaOptions& options,
                                                       const SceneRover& rover = {});

/// scene::Scene(sceneDescription(options, rover)) with the scene's patch cache of
/// options.cacheBytes and options.victoriaEffects.tracks (a layer the caller pressed) drawn on
/// the Victoria DEM. Throws as sceneDescription() and scene::Scene() do.
[[nodiscard]] scene::Scene buildScene(const MarsVictoriaOptions& options,
                                      const SceneRover& rover = {});

}  // namespace regolith::demo
