#pragma once
// What `regolith view` shows, as a small interface a scene source fills: a scene graph, the
// terrains drawn in its nodes' frames with the effects each declares, meshes, the objects
// one can focus on and the scene's cameras. Today two sources fill it: a bare store
// (storeScene(): one terrain), the Mars/Victoria demo (demoScene()) and a scene file
// (sceneFileScene(): scene::Scene from scene.json); the viewer itself (Viewer.hpp) needs
// nothing else.
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/store/PatchCache.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::tools::viewer {

/// A terrain: a clipmap drawn in the frame of graph node `node` under key `drawable`.
struct ViewTerrain {
  std::string name;  ///< the dataset a pick names
  scenegraph::NodeId node = 0;
  int drawable = 0;
  std::shared_ptr<const clod::HeightPyramid> pyramid;
  /// The look and the declared effects (options.effects). The viewer toggles each declared
  /// effect on and off; an effect never declared is never built.
  clod::ClipmapOptions options;
  /// Drawables of DEMs that win over this planet where they have data (SceneRenderer::
  /// addCutOut()).
  std::vector<int> cutOuts;
  /// Planets: the far field drawn beyond the clipmap (farfield::FarField); null: none.
  std::shared_ptr<const farfield::HeightLayers> farField;
  /// Where two terrains hold a picked point (a DEM over its planet), the higher wins.
  int pickPriority = 0;
};

/// A small mesh (a rover) in the frame of the node whose drawable key is `drawable`.
struct ViewMesh {
  int drawable = 0;
  std::vector<render::MeshVertex> vertices;
  glm::vec3 albedo{0.8F};
};

/// Something to focus on: the view re-roots at `node` (its frame becomes the origin).
struct ViewObject {
  std::string name;
  scenegraph::NodeId node = 0;
  /// Its surface, if it is a terrain (the orbit's "up" and the framing height).
  std::shared_ptr<const clod::HeightPyramid> surface;
  double size = 1.0;  ///< metres across, for framing
};

/// A camera node of the scene, for the split viewports.
struct ViewCamera {
  std::string name;
  scenegraph::NodeId node = 0;
  double fovYDegrees = 45.0;
  double near = 0.1;
};

/// A viewport the viewer opens with: a free camera looking at `target` (in `object`'s
/// frame) from a heading, an elevation and a distance.
struct OpeningView {
  std::size_t object = 0;
  glm::dvec3 target{0.0};
  double headingDeg = 0.0, elevationDeg = 35.0, distance = 1000.0;
};

struct ViewScene {
  std::string title;
  /// The graph; the viewer adds its own camera nodes to it (one per object).
  std::shared_ptr<scenegraph::SceneGraph> graph;
  std::vector<ViewTerrain> terrains;
  std::vector<ViewMesh> meshes;
  std::vector<ViewObject> objects;
  std::vector<ViewCamera> cameras;
  std::vector<OpeningView> openings;  ///< at least one; two open split
  /// The planet grid whose longitude, latitude (in its own latitude convention) and height
  /// above its body picks report, and the node whose frame is its body-fixed frame. Null
  /// (a bare DEM): picks report the picked terrain's grid x, y and height.
  std::shared_ptr<const clod::HeightPyramid> bodyGrid;
  scenegraph::NodeId bodyNode = 0;
  /// The patch cache of paged data (HUD: resident against budget); null: all in memory.
  std::shared_ptr<const store::PatchCache> cache;
  std::shared_ptr<const void> keepAlive;  ///< stores, pagers, the demo scene
};

/// A store's grid as a one-terrain scene: a planet seen whole, or a DEM from above at 35°.
/// Declares height colours (over the grid's height range) and, where there is latitude,
/// lat/lon lines. Throws as store::Store::open() and chooseGrid() do.
ViewScene storeScene(const std::string& path, const std::string& grid, std::size_t cacheBytes,
                     int clipmapSize);

/// The Mars/Victoria demo scene (demo::sceneDescription() with generated data, built by
/// scene::Scene): Mars with its far field, the Victoria-like DEM and a second DEM, the rover
/// and the paper layout's cameras (demo::paperCameras()). Opens split:
/// Mars whole on the left, Victoria from above at 35° on the right.
ViewScene demoScene();

/// A scene file (docs/scene-format.md) as scene::Scene builds and renders it: its bodies
/// (with their far fields) and DEMs with the effects each declares, its rovers, its cameras.
/// Opens on the first body whole and, if there is a DEM, split with the first DEM from above
/// at 35°. Throws as scene::Scene::load() does (errors name the file and the key).
ViewScene sceneFileScene(const std::string& path, std::size_t cacheBytes);

}  // namespace regolith::tools::viewer
