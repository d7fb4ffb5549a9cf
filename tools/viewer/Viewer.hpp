#pragma once
// The interactive viewer of `regolith view` (docs/viewer.md): any ViewScene in one or two
// viewports, orbit and fly cameras, focus switching by re-rooting, effect toggles, picking,
// a HUD and screenshots. It draws into offscreen render targets, so the window (gl::Window)
// only shows its image and a script can drive it exactly as a user would.
#include <regolith/clod/Camera.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/gl/Window.hpp>
#include <regolith/render/SceneRenderer.hpp>

#include "Hud.hpp"
#include "ViewScene.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <ostream>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace regolith::tools::viewer {

/// What a pick found under a pixel.
struct Pick {
  bool hit = false;
  int x = 0, y = 0;  ///< window pixel (origin top-left)
  /// Longitude and latitude in degrees (the body grid's latitude convention), or grid x, y
  /// in metres for a scene without a body (lonLat false).
  bool lonLat = false;
  double a = 0.0, b = 0.0;
  double height = 0.0;       ///< metres above the body (or the DEM's grid z)
  std::string dataset;       ///< the terrain the point lies on
  double distance = 0.0;     ///< metres from the camera
  std::string text() const;  ///< one line, as printed
};

/// One viewport's camera: free (eye, target, up in its focus object's frame, double) or one
/// of the scene's cameras.
struct ViewportState {
  std::size_t object = 0;  ///< the focus: ViewScene::objects index
  glm::dvec3 eye{0.0}, target{0.0}, up{0.0, 0.0, 1.0};
  bool fly = false;
  int sceneCamera = -1;  ///< >= 0: shows ViewScene::cameras[sceneCamera]
};

/// Needs a current GL 4.5 context; belongs to its thread. Not copyable.
class Viewer {
 public:
  /// `log` receives one line per pick, focus switch, effect toggle and screenshot.
  /// `loading`: how the terrains load (render::SceneRenderer::prepare()). In the background (the
  /// default) a frame never waits for a read and shows coarser levels until the finer
  /// arrive; Wait for frames that must not depend on read speed (scripts with screenshots).
  /// Split viewports always wait: their two cameras move each terrain's clipmap twice a
  /// frame, and in the background neither view would settle.
  Viewer(ViewScene scene, int width, int height, std::ostream& log,
         render::Loading loading = render::Loading::Background);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  /// Input (window pixels, origin top-left).
  void handle(const gl::WindowEvent& event);
  /// Draws a frame at this window size into image().
  void draw(int width, int height);
  /// The last frame: viewports and HUD.
  [[nodiscard]] const gl::RenderTarget& image() const { return *image_; }
  /// Picks at window pixel (x, y) in the last frame; logs it and shows it in the HUD.
  Pick pick(double x, double y);
  /// Writes image() as a PNG (crash-safe) and logs it.
  void screenshot(const std::string& path);
  [[nodiscard]] bool quitRequested() const noexcept { return quit_; }
  /// The frame time the HUD shows (the caller measures whole frames, swap included).
  void setFrameMs(double ms) noexcept { frameMs_ = ms; }
  [[nodiscard]] std::size_t lastVertices() const noexcept { return vertices_; }
  [[nodiscard]] const std::vector<std::string>& hudLines() const noexcept { return hudLines_; }

 private:
  struct Viewport {
    ViewportState state;
    std::unique_ptr<gl::RenderTarget> target;
    int x = 0, width = 0, height = 0;  // in the window
  };
  void rebuild();
  void open(std::size_t viewport, const OpeningView& view);
  [[nodiscard]] scenegraph::NodeId cameraNode(std::size_t viewport);
  [[nodiscard]] glm::dvec3 upAt(std::size_t object, const glm::dvec3& p) const;
  void orbitBasis(std::size_t object, const glm::dvec3& at, glm::dvec3& e, glm::dvec3& n,
                  glm::dvec3& u) const;
  void setOrbit(ViewportState& s, double headingDeg, double elevationDeg, double distance);
  void orbitAngles(const ViewportState& s, double& headingDeg, double& elevationDeg) const;
  void moveTarget(ViewportState& s, const glm::dvec3& delta);
  void switchFocus(std::size_t viewport, std::size_t object);
  void toggleEffect(std::size_t index);
  void keyPressed(int code);
  void drag(double dx, double dy, int button);
  void stepHeldKeys();
  [[nodiscard]] std::size_t viewportAt(double x) const;
  [[nodiscard]] render::SceneView viewOf(std::size_t viewport) const;
  [[nodiscard]] scenegraph::NodeId shownCamera(std::size_t viewport);
  [[nodiscard]] glm::dvec3 lightIn(scenegraph::NodeId node) const;
  void lightBehind(std::size_t viewport);
  void updateHud();

  ViewScene scene_;
  std::ostream& log_;
  std::unique_ptr<render::SceneRenderer> renderer_;
  std::vector<std::set<std::string>> off_;                    // per terrain: effects off
  std::vector<std::pair<std::size_t, std::string>> toggles_;  // key 1..9 → (terrain, effect)
  std::vector<Viewport> viewports_;
  bool split_ = false;
  render::Loading loading_ = render::Loading::Background;
  std::size_t active_ = 0;
  std::map<std::pair<std::size_t, std::size_t>, scenegraph::NodeId> cameraNodes_;
  glm::dvec3 light_{0.0, 0.0, 1.0};  // towards the sun, in lightNode_'s frame
  scenegraph::NodeId lightNode_ = 0;
  std::unique_ptr<gl::RenderTarget> image_;
  Hud hud_;
  bool hudOn_ = true, quit_ = false;
  double cursorX_ = 0.0, cursorY_ = 0.0, pressX_ = 0.0, pressY_ = 0.0;
  int button_ = -1;
  bool dragged_ = false;
  std::set<int> held_, fresh_, released_;  // held down; pressed, released since the last frame
  std::vector<std::string> hudLines_;
  std::string pickLine_ = "CLICK TO PICK";
  double frameMs_ = 0.0;
  std::size_t vertices_ = 0;
  std::uint64_t loads_ = 0, loadsFrame_ = 0;
  int shots_ = 0;
};

}  // namespace regolith::tools::viewer
