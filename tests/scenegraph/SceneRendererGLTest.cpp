// render::SceneRenderer drawing the paper's scene (the demo's scene file, demo::buildScene()): the
// DEM wins over the planet with no gap at the border, sits at its geodetic place and height, two
// DEMs on one planet, several cameras, and a focus switch that changes nothing on screen.
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scenegraph/SitePose.hpp>
#include <regolith/topo/Projection.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

namespace regolith::scenegraph {
namespace {

// The demo scene is this test's fixture until the scene-rendering layer has one of its own.
using demo::flyoverCamera;
using demo::MarsVictoriaOptions;

constexpr int kDrawMars = 0;  // scene::Scene's keys: the bodies first, in their order

/// The demo scene as scene::Scene builds it from its description (demo::buildScene()), with
/// the paper layout's cameras (demo::paperCameras()) and, for the focus switch, a frame
/// Earth's distance away (a node of its own, apart from the scene's Earth): what this test
/// needs of it.
class PaperScene {
 public:
  struct Nodes {
    NodeId mars = 0, victoria = 0, secondDem = 0, rover = 0, far = 0, root = 0;
    NodeId orbitCamera = 0, mastCamera = 0, chaseCamera = 0;
  };
  struct Layout {
    topo::Body mars = topo::Body::marsEllipsoid();
    topo::Geodetic victoriaOrigin, secondDemOrigin;
  };

  explicit PaperScene(const MarsVictoriaOptions& o) : scene_(demo::buildScene(o)) {
    SceneGraph& g = scene_.graph();
    n_.root = g.root();
    n_.mars = g.at("mars");
    n_.victoria = g.at("victoria");
    n_.secondDem = g.at("second_dem");
    n_.rover = g.at("rover");
    const demo::DemoCameras c = demo::paperCameraNodes(scene_);
    n_.orbitCamera = c.orbit;
    n_.mastCamera = c.mast;
    n_.chaseCamera = c.chase;
    Pose earth;
    earth.translation = {1.2e11, -0.4e11, 0.3e11};
    n_.far = g.add(g.root(), "earth_distance", earth);
    for (const scene::SceneTerrain& t : scene_.terrains()) {
      if (t.name == "mars") layout_.mars = *t.pyramid->body();
      if (t.name == "victoria") layout_.victoriaOrigin = t.origin;
      if (t.name == "second_dem") layout_.secondDemOrigin = t.origin;
    }
  }
  SceneGraph& graph() { return scene_.graph(); }
  [[nodiscard]] const Nodes& nodes() const { return n_; }
  [[nodiscard]] const Layout& layout() const { return layout_; }
  [[nodiscard]] double demHeight(double x, double y) const {
    return scene_.demHeight("victoria", x, y);
  }
  void placeRover(double x, double y, double headingDeg) {
    scene_.graph().setLocal(n_.rover, roverPose({x, y, demHeight(x, y)}, headingDeg));
  }
  [[nodiscard]] glm::dvec3 lightInFocus(NodeId focus) const {
    return scene_.lightIn(scene_.graph().node(focus).name);
  }
  void registerWith(render::SceneRenderer& r) const { scene_.registerWith(r); }
  [[nodiscard]] std::shared_ptr<const clod::HeightPyramid> mars() const { return pyramid("mars"); }
  [[nodiscard]] std::shared_ptr<const clod::HeightPyramid> victoria() const {
    return pyramid("victoria");
  }

 private:
  [[nodiscard]] std::shared_ptr<const clod::HeightPyramid> pyramid(const std::string& name) const {
    for (const scene::SceneTerrain& t : scene_.terrains())
      if (t.name == name) return t.pyramid;
    return nullptr;
  }
  scene::Scene scene_;
  Nodes n_;
  Layout layout_;
};

constexpr glm::vec4 kMagenta{1.0F, 0.0F, 1.0F, 1.0F};

// Full: the fly-over's scene (demo::renderFlyover's defaults: planet 0.5° samples,
// Victoria 601 × 601 at 2 m, a second DEM 201 × 201 at 2 m), for the border tests, so they
// look at what the demo shows. Small (1° planet, 4 m DEMs) for the rest, to keep the suite
// fast under sanitizers.
MarsVictoriaOptions sceneOptions(bool full) {
  MarsVictoriaOptions o;
  if (full) return o;
  o.planetRows = 180;
  o.demSize = 301;
  o.demSpacing = 4.0;
  o.secondDemSize = 101;
  o.secondDemSpacing = 4.0;
  o.clipmapSize = 63;
  return o;
}

// One scene and renderer per suite (GL objects on the shared test context).
template <bool Full>
class SceneGLTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    test::glContext();
    scene_ = std::make_unique<PaperScene>(sceneOptions(Full));
    renderer_ = std::make_unique<render::SceneRenderer>();
    scene_->registerWith(*renderer_);
    auto& g = scene_->graph();
    camInMars_ = g.add(scene_->nodes().mars, "test_camera_mars", Pose{}, NodeKind::Camera);
    camInDem_ = g.add(scene_->nodes().victoria, "test_camera_dem", Pose{}, NodeKind::Camera);
  }
  static void TearDownTestSuite() {
    test::glContext();
    renderer_.reset();
    scene_.reset();
  }

  struct Shot {
    gl::RgbaImage color;
    gl::DepthImage depth;
    clod::Camera marsCamera;  // the camera in Mars's body-fixed frame (double)
  };

  // Renders `camera` (its pose set by the caller) with `focus` into a w × h target.
  static Shot shoot(NodeId camera, NodeId focus, int w, int h, double fov = 45.0,
                    double near = 0.5) {
    test::glContext();
    gl::RenderTarget target(w, h);
    target.clear(kMagenta);
    render::SceneView view;
    view.width = w;
    view.height = h;
    view.fovYDegrees = fov;
    view.near = near;
    view.lightInFocus = scene_->lightInFocus(focus);
    const RenderList list = scene_->graph().renderList(focus, camera);
    renderer_->prepare(list, view);
    const render::SceneFrame f = renderer_->draw(list, view);
    EXPECT_EQ(f.itemsUnknown, 0U);
    Shot s{target.readColor(), target.readDepth(),
           render::cameraInItem(list.findDrawable(kDrawMars)->cameraInItem(), view)};
    return s;
  }

  static bool isDem(const gl::RgbaImage& im, int x, int y) {
    const auto* p = im.pixel(x, y);
    return p[1] > p[0] && !(p[0] == 255 && p[2] == 255);
  }
  static bool isPlanet(const gl::RgbaImage& im, int x, int y) {
    const auto* p = im.pixel(x, y);
    return p[0] > p[1] && p[2] < 200;
  }
  static std::size_t count(const gl::RgbaImage& im, bool (*pred)(const gl::RgbaImage&, int, int)) {
    std::size_t n = 0;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) n += pred(im, x, y) ? 1U : 0U;
    return n;
  }
  static std::size_t magenta(const gl::RgbaImage& im) {
    std::size_t n = 0;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) n += im.is(x, y, 255, 0, 255) ? 1U : 0U;
    return n;
  }

  static inline std::unique_ptr<PaperScene> scene_;
  static inline std::unique_ptr<render::SceneRenderer> renderer_;
  static inline NodeId camInMars_ = 0, camInDem_ = 0;
};

using SceneRendererGLTest = SceneGLTest<false>;
using SceneRendererBorderGLTest = SceneGLTest<true>;

// Views across the DEM's border; counts of magenta pixels and of pixels that see through
// the planet (further than 100 km) summed over them.
TEST_F(SceneRendererBorderGLTest, BorderBetweenDemAndPlanetHasNoGapOrCrack) {
  // Views across the DEM's border from outside, from inside, along an edge and at a corner,
  // all looking down enough that terrain fills the image: any gap shows the magenta
  // background or the planet's far side (thousands of km away).
  struct View {
    glm::dvec3 eye, target;
  };
  const View views[] = {
      {{-900.0, -900.0, 250.0}, {-600.0, -600.0, 0.0}},  // outside the SW corner
      {{0.0, 400.0, 120.0}, {0.0, 650.0, 0.0}},          // inside, looking out over the N edge
      {{700.0, -700.0, 150.0}, {600.0, -500.0, 0.0}},    // along the E edge
      {{0.0, -1500.0, 400.0}, {0.0, -600.0, 0.0}},       // outside, the S edge from afar
      {{-610.0, 0.0, 3000.0}, {-600.0, 0.0, 0.0}},       // over the W edge, looking down
      {{0.0, -160.0, 8000.0}, {0.0, 0.0, 0.0}},          // nearly straight down, from 8 km
      {{0.0, -4000.0, 6000.0}, {0.0, -600.0, 0.0}},      // the S edge from the fly-over's way
  };
  // And the fly-over's own camera where a crack once showed (frames 26–29 of 48).
  std::vector<Pose> poses;
  for (const View& v : views) poses.push_back(Pose::lookAt(v.eye, v.target, {0.0, 0.0, 1.0}));
  const glm::dvec3 rover =
      scene_->graph().relative(scene_->nodes().victoria, scene_->nodes().rover).translation;
  for (const int frame : {26, 28}) poses.push_back(flyoverCamera(frame / 47.0, rover));
  int i = 0;
  for (const Pose& pose : poses) {
    scene_->graph().setLocal(camInDem_, pose);
    const Shot s = shoot(camInDem_, scene_->nodes().victoria, 200, 150);
    test::savePng("scene_border_" + std::to_string(i++), s.color);
    EXPECT_EQ(magenta(s.color), 0U) << "view " << i - 1;
    std::size_t far = 0;
    for (int y = 0; y < s.depth.height; ++y)
      for (int x = 0; x < s.depth.width; ++x) {
        const float d = s.depth.at(x, y);
        if (d > 0.0F && 0.5 / static_cast<double>(d) > 100e3) {
          if (far < 5)
            std::printf("view %d: pixel (%d, %d) sees %.0f m away\n", i - 1, x, y,
                        0.5 / static_cast<double>(d));
          ++far;
        }
      }
    EXPECT_EQ(far, 0U) << "view " << i - 1 << ": pixels see through the planet";
    // The view does show the border: both surfaces are in the image.
    EXPECT_GT(count(s.color, isDem), 200U) << "view " << i - 1;
    EXPECT_GT(count(s.color, isPlanet), 200U) << "view " << i - 1;
  }
}

TEST_F(SceneRendererGLTest, WithoutBorderSkirtsTheSameViewsShowGaps) {
  // The control for the test above: the views do look where a crack would show.
  renderer_->setBorderSkirts(false);
  std::size_t magentaPixels = 0, far = 0;
  for (const auto& [eye, target] :
       {std::pair{glm::dvec3(-900.0, -900.0, 250.0), glm::dvec3(-600.0, -600.0, 0.0)},
        {glm::dvec3(700.0, -700.0, 150.0), glm::dvec3(600.0, -500.0, 0.0)}}) {
    scene_->graph().setLocal(camInDem_, Pose::lookAt(eye, target, {0.0, 0.0, 1.0}));
    const Shot s = shoot(camInDem_, scene_->nodes().victoria, 200, 150);
    magentaPixels += magenta(s.color);
    for (float d : s.depth.depth) far += d > 0.0F && 0.5 / static_cast<double>(d) > 100e3 ? 1U : 0U;
  }
  renderer_->setBorderSkirts(true);
  std::printf("without skirts: %zu magenta pixels, %zu seeing through the planet\n", magentaPixels,
              far);
  EXPECT_GT(magentaPixels + far, 100U);
}

TEST_F(SceneRendererGLTest, DemCentreIsAtItsGeodeticPositionAndHeight) {
  const auto& layout = scene_->layout();
  const topo::Body& mars = layout.mars;
  const topo::Geodetic site = layout.victoriaOrigin;
  const double hc = scene_->demHeight(0.0, 0.0);
  // The oracle: topo's geodesy, independent of the scene graph's poses.
  const glm::dvec3 expected = mars.toBodyFixed({site.latDeg, site.lonDeg, site.height + hc});
  const glm::dmat3 enu = mars.enuFrame(site.latDeg, site.lonDeg);
  const topo::LocalTangentPlane plane(mars, site, 0.0);
  for (const double pitch : {90.0, 55.0}) {
    // 1 km from the crater centre, from the south, looking at it `pitch` degrees down.
    const double p = pitch * std::numbers::pi / 180.0;
    const glm::dvec3 eye = expected + 1000.0 * (std::cos(p) * -enu[1] + std::sin(p) * enu[2]);
    scene_->graph().setLocal(camInMars_, Pose::lookAt(eye, expected, enu[1] + enu[2]));
    const Shot s = shoot(camInMars_, scene_->nodes().victoria, 240, 180);
    test::savePng("scene_centre_pitch" + std::to_string(static_cast<int>(pitch)), s.color);
    const glm::dvec3 px = s.marsCamera.project(expected);
    const int ix = static_cast<int>(std::floor(px.x)), iy = static_cast<int>(std::floor(px.y));
    ASSERT_TRUE(isDem(s.color, ix, iy));
    // The rendered surface point under that pixel's centre, back to geodetic, then into the
    // DEM's tangent plane (topo's geodesy: independent of the scene graph's poses).
    const float d = s.depth.at(ix, iy);
    ASSERT_GT(d, 0.0F);
    const glm::dvec3 ray = s.marsCamera.ray(ix + 0.5, iy + 0.5);
    const double dist =
        s.marsCamera.viewDistance(static_cast<double>(d)) / glm::dot(ray, s.marsCamera.forward());
    const glm::dvec3 rendered = s.marsCamera.position + ray * dist;
    const glm::dvec3 local = plane.forward(mars.toGeodetic(rendered));
    // Metres per pixel on the ground there; the pixel centre is at most 0.71 px from the
    // projected centre, so the rendered point lies within 1 px of it on the ground.
    const double mPerPx = glm::length(eye - expected) / s.marsCamera.focalPixels();
    const double ground = glm::length(glm::dvec2(local.x, local.y)) / (mPerPx / std::sin(p));
    // Height: the rendered surface is the DEM's (bilinear in its samples, 4 m spacing) at
    // the rendered point's plane position.
    const double dh = local.z - scene_->demHeight(local.x, local.y);
    std::printf(
        "pitch %.0f°: rendered point %.3f px from the DEM centre on the ground, "
        "%.3f m off the DEM surface (%.2f m/px)\n",
        pitch, ground, dh, mPerPx);
    EXPECT_LT(ground, 1.0);
    // A coarser clipmap level may draw here (2×2 means over the dunes): allow a quarter of
    // a pixel, as if the error were seen side-on.
    EXPECT_LT(std::abs(dh), 0.25 * mPerPx);
  }
  // Straight down from 3 km: the DEM's footprint (a square, its edges at the same height to
  // a metre) is centred on the projected centre to within a pixel.
  scene_->graph().setLocal(camInMars_, Pose::lookAt(expected + 3000.0 * enu[2], expected, enu[1]));
  const Shot s = shoot(camInMars_, scene_->nodes().victoria, 240, 180);
  const glm::dvec3 px = s.marsCamera.project(expected);
  int x0 = s.color.width, x1 = -1, y0 = s.color.height, y1 = -1;
  for (int y = 0; y < s.color.height; ++y)
    for (int x = 0; x < s.color.width; ++x)
      if (isDem(s.color, x, y)) {
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
  ASSERT_GT(x0, 0);  // the whole DEM is in the image
  ASSERT_LT(x1, s.color.width - 1);
  EXPECT_NEAR(0.5 * (x0 + x1 + 1), px.x, 1.0);
  EXPECT_NEAR(0.5 * (y0 + y1 + 1), px.y, 1.0);
}

TEST_F(SceneRendererGLTest, TwoDemsOnOnePlanetEachAtItsPlace) {
  const auto& layout = scene_->layout();
  const topo::Body& mars = layout.mars;
  const glm::dvec3 a = mars.toBodyFixed(layout.victoriaOrigin);
  const glm::dvec3 b = mars.toBodyFixed(layout.secondDemOrigin);
  const glm::dvec3 mid = 0.5 * (a + b);
  const glm::dvec3 up = glm::normalize(mid);
  scene_->graph().setLocal(camInMars_,
                           Pose::lookAt(mid + up * 20e3, mid, glm::dvec3(0.0, 0.0, 1.0)));
  const Shot s = shoot(camInMars_, scene_->nodes().mars, 240, 180, 45.0, 10.0);
  test::savePng("scene_two_dems", s.color);
  for (const glm::dvec3& c : {a, b}) {
    const glm::dvec3 px = s.marsCamera.project(c);
    EXPECT_TRUE(isDem(s.color, static_cast<int>(px.x), static_cast<int>(px.y)));
  }
  const glm::dvec3 pm = s.marsCamera.project(mid);
  EXPECT_TRUE(isPlanet(s.color, static_cast<int>(pm.x), static_cast<int>(pm.y)));
  EXPECT_EQ(magenta(s.color), 0U);
}

TEST_F(SceneRendererGLTest, OrbitAndMastCamerasRenderTheSameSceneAsViewports) {
  const auto& n = scene_->nodes();
  scene_->placeRover(0.0, -395.0, 0.0);
  test::glContext();
  gl::RenderTarget target(320, 120);
  target.clear(kMagenta);
  for (const auto& [camera, x] : {std::pair{n.orbitCamera, 0}, {n.mastCamera, 160}}) {
    render::SceneView view;
    view.x = x;
    view.width = 160;
    view.height = 120;
    view.near = camera == n.orbitCamera ? 100.0 : 0.05;
    view.lightInFocus = scene_->lightInFocus(n.victoria);
    const RenderList list = scene_->graph().renderList(n.victoria, camera);
    renderer_->prepare(list, view);
    renderer_->draw(list, view);
  }
  const gl::RgbaImage im = target.readColor();
  test::savePng("scene_two_viewports", im);
  // Orbit view (left): Victoria in the middle, planet around it.
  EXPECT_TRUE(isDem(im, 80, 60));
  EXPECT_TRUE(isPlanet(im, 5, 5));
  // Mast view (right): the DEM's ground fills the lower half; the upper part is sky or
  // terrain beyond the rim, never a hole in the ground.
  std::size_t holes = 0, dem = 0;
  for (int y = 60; y < 120; ++y)
    for (int x = 160; x < 320; ++x) {
      holes += im.is(x, y, 255, 0, 255) ? 1U : 0U;
      dem += isDem(im, x, y) ? 1U : 0U;
    }
  EXPECT_EQ(holes, 0U);
  EXPECT_GT(dem, 160U * 50U);
}

TEST_F(SceneRendererGLTest, SwitchingTheFocusMovesNothingOnScreen) {
  const auto& n = scene_->nodes();
  scene_->placeRover(0.0, -395.0, 30.0);
  const Shot ref = shoot(n.chaseCamera, n.victoria, 160, 120, 45.0, 0.05);
  test::savePng("scene_focus_victoria", ref.color);
  ASSERT_GT(count(ref.color, isDem), 1000U);
  // Victoria → Mars → rover → back: the camera's pose in each item's frame is exact to
  // double rounding of small numbers, so the frames are identical. Through a frame at Earth's
  // distance, 1e11 m offsets cancel and leave ~1e-4 m: a few edge pixels may flip, nothing
  // moves. (The scene's root is Mars's centre.)
  for (const NodeId focus : {n.mars, n.rover, n.victoria, n.far, n.root, n.victoria}) {
    const Shot s = shoot(n.chaseCamera, focus, 160, 120, 45.0, 0.05);
    std::size_t differ = 0;
    for (std::size_t k = 0; k < ref.color.rgba.size(); ++k)
      differ += std::abs(int{ref.color.rgba[k]} - int{s.color.rgba[k]}) > 2 ? 1U : 0U;
    const bool far = focus == n.far;
    EXPECT_LE(differ, far ? 12U : 0U) << "focus " << scene_->graph().node(focus).name;
  }
}

TEST_F(SceneRendererGLTest, RoverStaysStillOnScreenWhileMovingInMillimetreSteps) {
  // On the GPU: the chase camera rides on the rover, so the rover must not move on screen
  // while it drives 1 mm per frame across the rim. Re-rooted, its pixels are identical
  // frame after frame (a Mars-rooted float pipeline would hop by tens of pixels, see
  // JitterTest).
  const auto& n = scene_->nodes();
  std::vector<std::uint8_t> first;
  std::size_t roverPixels = 0;
  for (int i = 0; i < 12; ++i) {
    const double y = -395.0 + 0.001 * i;
    scene_->graph().setLocal(n.rover, roverPose({0.0, y, scene_->demHeight(0.0, -395.0)}, 0.0));
    const Shot s = shoot(n.chaseCamera, n.victoria, 160, 120, 45.0, 0.05);
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(160 * 120));
    for (int yy = 0; yy < 120; ++yy)
      for (int x = 0; x < 160; ++x) {
        const auto* p = s.color.pixel(x, yy);
        mask[static_cast<std::size_t>(yy * 160 + x)] =
            std::abs(p[0] - p[1]) < 6 && p[0] > 60 ? 1 : 0;  // grey: the rover
      }
    if (i == 0) {
      first = mask;
      for (auto m : mask) roverPixels += m;
      continue;
    }
    std::size_t moved = 0;
    for (std::size_t k = 0; k < mask.size(); ++k) moved += mask[k] != first[k] ? 1U : 0U;
    EXPECT_EQ(moved, 0U) << "frame " << i;
  }
  std::printf("rover: %zu pixels, identical in 12 frames 1 mm apart\n", roverPixels);
  EXPECT_GT(roverPixels, 300U);  // the rover is in view
  scene_->placeRover(0.0, -395.0, 0.0);
}

// A HiRISE-class DEM too large for a level-0 mask (8193 × 8193 at 0.25 m), its samples a
// function computed on demand (nothing held in memory).
class SlopeSamples final : public topo::SampleSource {
 public:
  SlopeSamples(std::size_t n, double spacing) : n_(n), spacing_(spacing) {}
  [[nodiscard]] std::size_t rows() const noexcept override { return n_; }
  [[nodiscard]] std::size_t cols() const noexcept override { return n_; }
  [[nodiscard]] float sample(std::size_t r, std::size_t c) const override {
    return static_cast<float>(0.002 * spacing_ * static_cast<double>(c) +
                              std::sin(0.01 * static_cast<double>(r)));
  }

 private:
  std::size_t n_;
  double spacing_;
};

TEST_F(SceneRendererGLTest, LargeDemCutsThePlanetThroughACoarserMask) {
  std::vector<clod::HeightPyramid::Level> levels;
  const std::size_t n0 = 8193;
  const double dx0 = 0.25, half = 0.5 * static_cast<double>(n0 - 1) * dx0;
  for (std::size_t k = 0; k < 4; ++k) {
    const std::size_t n = (n0 + (std::size_t{1} << k) - 1) >> k;
    const double dx = dx0 * static_cast<double>(std::size_t{1} << k);
    const double off = 0.5 * (dx - dx0);  // level k sample 0 at the mean of level k−1's
    levels.push_back({topo::TopoGrid(n, n, -half + off, half - off, dx, dx),
                      std::make_shared<SlopeSamples>(n, dx)});
  }
  auto dem =
      std::make_shared<const clod::HeightPyramid>(std::move(levels), clod::SurfaceKind::Plane);
  test::glContext();
  render::SceneRenderer r;
  clod::ClipmapOptions o;
  o.size = 63;
  o.albedo = demo::kPlanetAlbedo;
  r.addTerrain(0, scene_->mars(), o);
  o.albedo = demo::kDemAlbedo;
  r.addTerrain(1, dem, o);
  r.addCutOut(0, 1);  // level 0 and 1 exceed 4096 a side: the mask comes from level 2
  SceneGraph g("mars");
  const auto& layout = scene_->layout();
  const NodeId mars = g.add(g.root(), "planet", Pose{}, NodeKind::Terrain, 0);
  const NodeId d = g.add(mars, "dem", tangentPlanePose(layout.mars, layout.victoriaOrigin, 0.0),
                         NodeKind::Terrain, 1);
  const NodeId cam =
      g.add(d, "camera", Pose::lookAt({-1500.0, -1500.0, 1200.0}, {-900.0, -900.0, 0.0}, {0, 0, 1}),
            NodeKind::Camera);
  gl::RenderTarget target(200, 150);
  target.clear(kMagenta);
  render::SceneView view;
  view.width = 200;
  view.height = 150;
  view.near = 1.0;
  r.prepare(g.renderList(d, cam), view);
  r.draw(g.renderList(d, cam), view);
  const gl::RgbaImage im = target.readColor();
  test::savePng("scene_large_dem", im);
  EXPECT_EQ(magenta(im), 0U);
  std::size_t far = 0;
  for (float v : target.readDepth().depth)
    far += v > 0.0F && 1.0 / static_cast<double>(v) > 100e3 ? 1U : 0U;
  EXPECT_EQ(far, 0U);
  EXPECT_GT(count(im, isDem), 2000U);  // the view holds the DEM's corner and the planet
  EXPECT_GT(count(im, isPlanet), 2000U);
}

TEST_F(SceneRendererGLTest, DemWinsWhereItHasDataEvenBelowThePlanet) {
  // Victoria sunk 500 m below the planet's surface: without the cut-out the planet hides
  // it; with it the DEM shows wherever it has data, and the planet around it, and the pit
  // between the DEM's border and the planet's cut edge above it has walls (the flanges):
  // no background, nothing seen through the planet.
  const auto& layout = scene_->layout();
  topo::Geodetic sunk = layout.victoriaOrigin;
  sunk.height -= 500.0;  // below the planet's chords too (1° cells sag ~130 m)
  SceneGraph g("mars");
  const NodeId mars = g.add(g.root(), "planet", Pose{}, NodeKind::Terrain, 0);
  const NodeId d =
      g.add(mars, "dem", tangentPlanePose(layout.mars, sunk, 0.0), NodeKind::Terrain, 1);
  const NodeId cam =
      g.add(d, "camera", Pose::lookAt({0.0, -1200.0, 2500.0}, {0.0, 0.0, 0.0}, {0, 0, 1}),
            NodeKind::Camera);
  test::glContext();
  std::size_t demPixels[2] = {0, 0};
  for (const bool cut : {false, true}) {
    render::SceneRenderer r;
    clod::ClipmapOptions o;
    o.size = 63;
    o.albedo = demo::kPlanetAlbedo;
    r.addTerrain(0, scene_->mars(), o);
    o.albedo = demo::kDemAlbedo;
    r.addTerrain(1, scene_->victoria(), o);
    if (cut) r.addCutOut(0, 1);
    gl::RenderTarget target(200, 150);
    target.clear(kMagenta);
    render::SceneView view;
    view.width = 200;
    view.height = 150;
    view.near = 1.0;
    r.prepare(g.renderList(d, cam), view);
    r.draw(g.renderList(d, cam), view);
    const gl::RgbaImage im = target.readColor();
    test::savePng(cut ? "scene_sunk_dem_cut" : "scene_sunk_dem_nocut", im);
    demPixels[cut ? 1 : 0] = count(im, isDem);
    EXPECT_EQ(magenta(im), 0U) << (cut ? "with" : "without") << " the cut-out";
    std::size_t far = 0;
    for (float v : target.readDepth().depth)
      far += v > 0.0F && 1.0 / static_cast<double>(v) > 100e3 ? 1U : 0U;
    EXPECT_EQ(far, 0U) << (cut ? "with" : "without") << " the cut-out";
    if (cut) {
      EXPECT_TRUE(isDem(im, 100, 75));  // the crater centre
      EXPECT_GT(count(im, isPlanet), 1000U);
    }
  }
  std::printf("DEM pixels: %zu without the cut-out, %zu with it\n", demPixels[0], demPixels[1]);
  EXPECT_LT(demPixels[0], 200U);
  EXPECT_GT(demPixels[1], 5000U);
}

TEST_F(SceneRendererGLTest, RejectsBadRegistrations) {
  test::glContext();
  render::SceneRenderer r;
  EXPECT_THROW(r.addTerrain(1, nullptr), InvalidArgument);
  r.addTerrain(0, scene_->mars());
  r.addTerrain(1, scene_->victoria());
  EXPECT_THROW(r.addTerrain(1, scene_->victoria()), InvalidArgument);
  EXPECT_THROW(r.addCutOut(1, 0), InvalidArgument);  // a DEM is no planet
  EXPECT_THROW(r.addCutOut(0, 7), InvalidArgument);  // unknown
  EXPECT_THROW(r.addMesh(2, {render::MeshVertex{}}, {1, 1, 1}), InvalidArgument);
  render::SceneView bad;
  bad.width = 0;
  EXPECT_THROW(r.draw(RenderList{}, bad), InvalidArgument);
}

TEST_F(SceneRendererGLTest, OnlyAPlanetThatADemCutsCarriesTheCutOutTest) {
  // The cut-out test is shader code like an effect: a planet compiles it only once a DEM is
  // registered to win over it; until then (and for DEMs) the program is the bare one.
  test::glContext();
  render::SceneRenderer r;
  r.addTerrain(0, scene_->mars());
  r.addTerrain(1, scene_->victoria());
  const auto fragment = [&](int key) { return r.terrain(key)->programSources().fragment; };
  EXPECT_EQ(fragment(0), clod::ClipmapTerrain::bareSources().fragment);
  EXPECT_EQ(fragment(1), clod::ClipmapTerrain::bareSources().fragment);
  r.addCutOut(0, 1);
  EXPECT_NE(fragment(0).find("regolithCutOut"), std::string::npos);
  EXPECT_TRUE(r.terrain(0)->options().cutOuts);
  EXPECT_EQ(fragment(1), clod::ClipmapTerrain::bareSources().fragment);
}

}  // namespace
}  // namespace regolith::scenegraph
