#pragma once
/// \file
/// A scene built from its description: stores opened and paged, generators run, the scene
/// graph built, traverses driven (their tracks pressed), and cameras rendered headless.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/rover/Rover.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/scene/SceneDescription.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace regolith::scene {

/// A body or DEM as render() draws it (Scene::terrains()), for other front ends.
struct SceneTerrain {
  std::string name;
  bool planet = false;  ///< a body's surface (else a DEM on `body`)
  std::string body;     ///< DEMs: the body they sit on
  int drawable = -1;    ///< its key in the render list
  scenegraph::NodeId node = 0;
  std::shared_ptr<const clod::HeightPyramid> pyramid;
  clod::ClipmapOptions options;  ///< the look and the declared effects
  /// Bodies drawn beyond their clipmap by the far field (null: none).
  std::shared_ptr<const farfield::HeightLayers> farField;
  /// Bodies: the composed surface of their datasets (null unless several heights datasets
  /// or `composeDems`).
  std::shared_ptr<const compose::ComposedSurface> composed;
  /// DEMs: the planetodetic origin of their tangent plane (height included) and its heading
  /// (degrees clockwise from north).
  topo::Geodetic origin{};
  double headingDeg = 0.0;
};

/// An object (a rover) as render() draws it.
struct SceneObject {
  std::string name;
  int drawable = -1;
  scenegraph::NodeId node = 0;
  glm::vec3 colour{0.8F};
};

struct SceneOptions {
  /// Budget of the patch cache every store of the scene is paged through.
  std::size_t cacheBytes = std::size_t{256} << 20;
  /// Wheel tracks a caller already pressed (its own traverse, e.g. `regolith demo`'s), by
  /// DEM name: a DEM that declares `tracks` draws this layer instead of a new, empty one
  /// (and the traverses of the scene's objects on it press into it too). InvalidArgument
  /// when the scene is built if the name is no DEM of the scene or the DEM declares no tracks.
  std::map<std::string, std::shared_ptr<rover::TrackLayer>> tracks;
  /// Traverses a caller already drove, by object name (`regolith demo` drives its rover's
  /// itself, through a patch cache of its own budget, and reports on it): the object stands
  /// where that run stopped (its last chassis pose: x, y, heading) and the scene does not
  /// drive the traverse again, so one run serves both. The run's wheel tracks come through
  /// `tracks`. The caller vouches that the run drove the object's traverse (its waypoints,
  /// speed and step) over the DEM's heights. InvalidArgument when the scene is built if the
  /// name is no object with a traverse, or if its DEM declares tracks and `tracks` gives that
  /// DEM no layer.
  std::map<std::string, rover::ChassisPose> driven;
  /// Where the scene's terrains load in the background: every store pyramid's hints and the
  /// windows its clipmap levels read (store::Pager::pyramid()), and each clipmap's moving
  /// windows, texture layers and probes (ClipmapOptions::executor). Null: the scene makes one
  /// core::ThreadPool of availableCores() − 1 threads (at least 1), shared by all its
  /// terrains, so a scene of N terrains loads on that pool and not on 2N threads of its own.
  std::shared_ptr<core::Executor> loader;
};

/// A built scene. Building needs no GL; render() does (and makes an EGL context if none is
/// current). Node names are the description's (bodies, DEMs, objects, cameras) under the
/// root frame (SceneDescription::root, "root" unless the file names it); each body's frame is
/// body-fixed, each DEM's its local tangent plane (x east, y north at heading 0, z up), each
/// rover's x forward, y left, z up.
///
/// Not thread-safe; render() from the thread that owns the GL context.
class Scene {
 public:
  /// Throws InvalidArgument naming the key for what the description's checks cannot see
  /// (a store grid of the wrong kind, radii that differ from the store's, more than 4 DEMs
  /// on a body), StoreError for bad stores, and what the generators and traverses throw.
  explicit Scene(SceneDescription description, const SceneOptions& options = {});
  /// readScene() then Scene().
  static Scene load(const std::filesystem::path& path, const SceneOptions& options = {});
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  ~Scene();

  [[nodiscard]] const SceneDescription& description() const noexcept;
  [[nodiscard]] const scenegraph::SceneGraph& graph() const noexcept;
  /// The graph for a front end that adds its own nodes (the viewer's free cameras).
  [[nodiscard]] scenegraph::SceneGraph& graph() noexcept;
  /// What render() draws: every body and DEM, and every object, in the description's order.
  [[nodiscard]] std::vector<SceneTerrain> terrains() const;
  [[nodiscard]] std::vector<SceneObject> objects() const;
  /// A camera's node in graph() (InvalidArgument for an unknown name).
  [[nodiscard]] scenegraph::NodeId cameraNode(const std::string& camera) const;
  /// The patch cache every store of the scene is paged through.
  [[nodiscard]] std::shared_ptr<const store::PatchCache> cache() const noexcept;
  /// The executor every terrain of the scene loads on (SceneOptions::loader, or the scene's).
  [[nodiscard]] std::shared_ptr<core::Executor> loader() const noexcept;
  /// The heights drawn for a body or DEM (composed for a body with several datasets).
  [[nodiscard]] const clod::HeightPyramid& terrain(const std::string& name) const;
  /// The clipmap options render() registers for a body or DEM (effects included).
  [[nodiscard]] const clod::ClipmapOptions& terrainOptions(const std::string& name) const;
  /// A DEM's surface height at grid (x, y), bilinear in its finest level.
  [[nodiscard]] double demHeight(const std::string& dem, double x, double y) const;
  /// Where an object stands, in its DEM's frame (x, y, height on the surface), and its
  /// heading (degrees clockwise from +y).
  [[nodiscard]] glm::dvec4 objectPose(const std::string& object) const;
  /// How many traverses building the scene drove (those not given by SceneOptions::driven).
  [[nodiscard]] std::size_t traversesDriven() const noexcept;
  /// The direction towards the light in the frame of node `frame` (unit): the light's
  /// direction, or, for a light `from` a frame (a sun), towards that frame's origin.
  [[nodiscard]] glm::dvec3 lightIn(const std::string& frame) const;
  /// The render list's focus for a camera (its `focus`, or its frame's terrain).
  [[nodiscard]] std::string focusOf(const std::string& camera) const;

  /// Renders camera `camera` (its size, viewport, intrinsics): every terrain and object, and
  /// the far field of each body that has one. Throws InvalidArgument for an unknown camera
  /// (listing the scene's cameras); GlError without GL.
  [[nodiscard]] gl::RgbaImage render(const std::string& camera) const;
  /// Renders any camera node of graph() (e.g. one a front end added) with `focus` as the
  /// render list's origin, into a `width` × `height` image cleared to the background, as
  /// render() does: `view` gives the intrinsics and viewport; its light is replaced by the
  /// scene's light in `focus`'s frame. Needs a current GL context or makes one.
  [[nodiscard]] gl::RgbaImage render(scenegraph::NodeId camera, scenegraph::NodeId focus,
                                     render::SceneView view, int width, int height) const;
  /// Registers what render() draws with a renderer a caller keeps across frames (the
  /// fly-over): every terrain with its options, the cut-outs of the DEMs in their bodies,
  /// the objects' meshes, and each body's far field (drawn by SceneRenderer::draw() when it
  /// is given the render target).
  void registerWith(render::SceneRenderer& renderer) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace regolith::scene
