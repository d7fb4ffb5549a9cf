#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/render/TerrainImage.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>

#include <EGL/egl.h>

#include <utility>

namespace regolith::render {

namespace {
constexpr const char* kOp = "render::renderTerrain()";
constexpr int kTerrain = 0;  // the terrain's key with the renderer
}  // namespace

TerrainImage renderTerrain(std::shared_ptr<const clod::HeightPyramid> pyramid,
                           const clod::RenderRequest& request,
                           const std::optional<TerrainFarField>& farField) {
  if (!pyramid) throw InvalidArgument(std::string(kOp) + ": pyramid is null");
  const clod::Camera& cam = request.camera;
  clod::checkCamera(*pyramid, cam, kOp);
  if (farField && pyramid->kind() != clod::SurfaceKind::Planet && !pyramid->placement()) {
    throw InvalidArgument(std::string(kOp) +
                          ": a far field was given for a terrain not drawn body-fixed (a far "
                          "field draws a body beyond its clipmap: a Planet pyramid, or one "
                          "with a placement)");
  }
  std::unique_ptr<gl::HeadlessContext> context;
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) context = std::make_unique<gl::HeadlessContext>();
  TerrainImage out;
  {
    // The terrain at the root's origin: its scene frame is the focus frame, and the camera
    // stands where the request puts it.
    scenegraph::SceneGraph graph("scene");
    const scenegraph::NodeId terrain =
        graph.add(graph.root(), "terrain", scenegraph::Pose::identity(),
                  scenegraph::NodeKind::Terrain, kTerrain);
    const scenegraph::NodeId camera = graph.add(
        graph.root(), "camera", scenegraph::Pose::lookAt(cam.position, cam.target, cam.up),
        scenegraph::NodeKind::Camera);
    SceneRenderer renderer;
    renderer.addTerrain(kTerrain, std::move(pyramid), request.clipmap);
    if (farField) renderer.addFarField(kTerrain, farField->layers, farField->options);
    SceneView view;
    view.fovYDegrees = cam.fovYDegrees;
    view.near = cam.near;
    view.width = cam.width;
    view.height = cam.height;
    view.lightInFocus = glm::dvec3(request.clipmap.lightDirection);
    view.clipmapCentreInFocus = request.focus.value_or(cam.target);
    gl::RenderTarget target(cam.width, cam.height);
    target.clear(request.background);
    const scenegraph::RenderList list = graph.renderList(terrain, camera);
    renderer.prepare(list, view);  // waits: the image does not depend on how fast reads are
    renderer.draw(list, view, &target);
    out.image = target.readColor();
    // The legend of what was drawn, for the camera the renderer drew with.
    const clod::Legend legend = clod::Legend::of(
        *renderer.terrain(kTerrain), cameraInItem(list.items.front().cameraInItem(), view));
    if (!legend.empty()) {
      if (request.legendInImage) legend.drawInto(out.image);
      out.legend = legend;
    }
  }  // GL objects go before the context
  return out;
}

void renderTerrainToPng(std::shared_ptr<const clod::HeightPyramid> pyramid,
                        const clod::RenderRequest& request,
                        const std::optional<TerrainFarField>& farField, const std::string& path) {
  const TerrainImage drawn = renderTerrain(std::move(pyramid), request, farField);
  gl::writePng(path, drawn.image);
  if (drawn.legend) drawn.legend->writeJson(path + ".legend.json");
}

}  // namespace regolith::render
