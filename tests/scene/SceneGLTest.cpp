// Scenes rendered: pixels checked against the scene's geometry (the height colour of the DEM
// under the camera, the sky above it), and the demo's scene, written as a file and read back,
// drawing the demo's pixels.
#include <regolith/clod/Camera.hpp>
#include <regolith/clod/Effects.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneDescription.hpp>
#include <regolith/scenegraph/Pose.hpp>
#include <regolith/store/Generate.hpp>

#include "gl/GlContext.hpp"
#include "support/CountingExecutor.hpp"
#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace regolith::scene {
namespace {

constexpr const char* kScene = R"({
  "version": 1,
  "bodies": [{"name": "mars", "heights": [{"generate": "mars-planet", "rows": 180, "seed": 3}]}],
  "dems": [{"name": "victoria", "body": "mars",
            "heights": {"generate": "victoria", "size": 301, "spacing": 4, "seed": 3},
            "placement": {"lat": -2.05, "lon": -5.5, "height": "surface"},
            "colour": [0.55, 0.75, 0.45]},
           {"name": "coloured", "body": "mars",
            "heights": {"generate": "victoria", "size": 301, "spacing": 4, "seed": 5},
            "placement": {"lat": -2.3, "lon": -5.5, "height": "surface"},
            "effects": {"heightColours": {"min": -80, "max": 20}}}],
  "objects": [{"name": "rover", "dem": "victoria", "pose": {"x": 0, "y": -395, "heading": 30}}],
  "cameras": [],
  "light": {"frame": "victoria", "elevation": 40, "azimuth": 100}
})";

/// The scene above with one camera in `frame` (eye, look-at, up) of 160 × 120 pixels.
SceneDescription withCamera(const std::string& frame, glm::dvec3 eye, glm::dvec3 at,
                            glm::dvec3 up) {
  SceneDescription d = parseScene(kScene, "gl.json", "/nowhere");
  Camera c;
  c.name = "view";
  c.frame = frame;
  c.eye = {eye.x, eye.y, eye.z};
  c.lookAt = {at.x, at.y, at.z};
  c.up = {up.x, up.y, up.z};
  c.width = 160;
  c.height = 120;
  c.near = 1.0;
  d.cameras.push_back(c);
  return d;
}

TEST(SceneGL, HeightColoursUnderTheCameraAreTheDemsHeight) {
  test::glContext();
  // Straight down from 300 m over a point of the coloured DEM: the centre pixel shows the
  // height colour (unlit) of the DEM's height there, computed on the CPU in double.
  for (const glm::dvec2 p :
       {glm::dvec2{-200.0, 130.0}, glm::dvec2{0.0, 0.0}, glm::dvec2{380.0, -20.0}}) {
    const Scene s(withCamera("coloured", {p.x, p.y, 300.0}, {p.x, p.y, 0.0}, {0.0, 1.0, 0.0}));
    const double h = s.demHeight("coloured", p.x, p.y);
    const gl::RgbaImage image = s.render("view");
    test::savePng("scene_height_colours_" + std::to_string(static_cast<int>(p.x)), image);
    const glm::vec3 want = clod::heightColour(clod::HeightColours{-80.0F, 20.0F, false}, h);
    const std::uint8_t* got = image.pixel(80, 60);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(static_cast<double>(got[k]), 255.0 * static_cast<double>(want[k]), 3.0)
          << "channel " << k << " at (" << p.x << ", " << p.y << "), height " << h;
    }
  }
}

TEST(SceneGL, AlbedoFromAGeneratorDarkensWhereItsHeightsAreLow) {
  test::glContext();
  // The green DEM's albedo from the same generator as its heights, mapped over the crater's
  // depth: straight down from 400 m at the crater floor (low: dark) and at the plains beyond
  // the rim (high: bright), with the light the same. Oracle: the mapped value the CPU
  // computes from the DEM's own heights (origin height 0 for the texture, the surface for
  // the DEM: the same relief, shifted).
  SceneDescription d = parseScene(kScene, "gl.json", "/nowhere");
  DrapedSource a;
  a.data = d.dems[0].heights;
  a.range = std::array<double, 2>{-60.0, 10.0};
  d.dems[0].look.effects.albedo = a;
  const auto shoot = [&](glm::dvec2 p) {
    SceneDescription v = d;
    Camera c;
    c.name = "view";
    c.frame = "victoria";
    c.eye = {p.x, p.y, 400.0};
    c.lookAt = {p.x, p.y, 0.0};
    c.up = {0.0, 1.0, 0.0};
    c.width = 160;
    c.height = 120;
    c.near = 1.0;
    v.cameras.push_back(c);
    const Scene s(v);
    const gl::RgbaImage image = s.render("view");
    test::savePng("scene_generated_albedo_" + std::to_string(static_cast<int>(p.y)), image);
    return std::array<int, 3>{image.pixel(80, 60)[0], image.pixel(80, 60)[1],
                              image.pixel(80, 60)[2]};
  };
  const std::array<int, 3> floor = shoot({0.0, 0.0}), plains = shoot({0.0, -560.0});
  const Scene plain(withCamera("victoria", {0.0, 0.0, 400.0}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}));
  const double origin = plain.demHeight("victoria", 0.0, 0.0) -
                        plain.demHeight("victoria", 0.0, -560.0);  // floor below the plains
  ASSERT_LT(origin, -20.0) << "the floor lies below the plains";
  for (std::size_t k = 0; k < 3; ++k) EXPECT_LT(floor[k] + 20, plains[k]) << "channel " << k;
}

TEST(SceneGL, DemAlbedoBelowAndSkyAbove) {
  test::glContext();
  // Down at the green DEM's plains (lit): green above red. Up from the plains: the clear
  // colour (0.02, 0.02, 0.04) everywhere, no terrain and no far field.
  const Scene down(
      withCamera("victoria", {-500.0, 500.0, 200.0}, {-500.0, 500.0, 0.0}, {0.0, 1.0, 0.0}));
  const gl::RgbaImage a = down.render("view");
  test::savePng("scene_dem_below", a);
  EXPECT_GT(a.pixel(80, 60)[1], a.pixel(80, 60)[0] + 20);
  const Scene up(
      withCamera("victoria", {-500.0, 500.0, 50.0}, {-500.0, 500.0, 500.0}, {0.0, 1.0, 0.0}));
  const gl::RgbaImage b = up.render("view");
  test::savePng("scene_sky_above", b);
  for (int y = 0; y < b.height; y += 7)
    for (int x = 0; x < b.width; x += 7) ASSERT_TRUE(b.is(x, y, 5, 5, 10)) << x << ", " << y;
  // From 40 km over the planet beside the DEMs, looking at Mars: the planet's colour, red
  // above green (the planet's albedo 0.80, 0.52, 0.38).
  const Scene planet(
      withCamera("victoria", {0.0, 60000.0, 40000.0}, {0.0, 60000.0, 0.0}, {0.0, 1.0, 0.0}));
  const gl::RgbaImage c = planet.render("view");
  test::savePng("scene_planet_below", c);
  EXPECT_GT(c.pixel(80, 60)[0], c.pixel(80, 60)[1] + 20);
}

TEST(SceneGL, DemoSceneFileDrawsTheDemosPixels) {
  test::glContext();
  // renderSceneView() with the demo's generated data, and the same view through the scene
  // file the demo's description writes.
  demo::SceneViewOptions view;
  view.width = 320;
  view.height = 180;
  view.roverX = 10.0;
  view.roverY = -390.0;
  view.roverHeadingDeg = 20.0;
  const glm::dvec3 eye{60.0, -470.0, 30.0}, at{0.0, -380.0, 0.0}, up{0.0, 0.0, 1.0};
  view.camera = scenegraph::Pose::lookAt(eye, at, up);
  const gl::RgbaImage drawn = demo::renderSceneView(view);
  test::savePng("scene_demo_drawn", drawn);

  SceneDescription d =
      demo::sceneDescription(view.scene, {view.roverX, view.roverY, view.roverHeadingDeg, {}});
  Camera c;
  c.name = "view";
  c.frame = "victoria";
  c.eye = {eye.x, eye.y, eye.z};
  c.lookAt = {at.x, at.y, at.z};
  c.up = {up.x, up.y, up.z};
  c.fovY = view.fovYDegrees;
  c.near = view.near;
  c.width = view.width;
  c.height = view.height;
  d.cameras.push_back(c);
  const auto file = test::scratchFile("scene_gl", "demo_scene.json");
  writeScene(d, file);
  const gl::RgbaImage again = Scene::load(file).render("view");
  test::savePng("scene_demo_again", again);
  ASSERT_EQ(again.rgba.size(), drawn.rgba.size());
  int differing = 0, largest = 0;
  for (std::size_t i = 0; i < drawn.rgba.size(); ++i) {
    const int diff = std::abs(static_cast<int>(drawn.rgba[i]) - static_cast<int>(again.rgba[i]));
    differing += diff > 0 ? 1 : 0;
    largest = std::max(largest, diff);
  }
  EXPECT_EQ(differing, 0) << "largest difference " << largest;

  // renderSceneView() and the file now share one code path (the demo scene is its
  // description), so the comparison above guards the file's round trip only. The pixels
  // themselves against the view's geometry: the rover (grey, drawn in its own colour) where
  // its body projects through the camera (clod::Camera in double), the DEM (greener than the
  // planet, kDemAlbedo) around it, and sky above the horizon of this low view.
  const Scene built(d);
  const glm::dvec4 rover = built.objectPose("rover");
  EXPECT_NEAR(rover.x, view.roverX, 1e-9);
  EXPECT_NEAR(rover.y, view.roverY, 1e-9);
  EXPECT_EQ(rover.z, built.demHeight("victoria", view.roverX, view.roverY));
  render::SceneView sv;
  sv.width = view.width;
  sv.height = view.height;
  sv.fovYDegrees = view.fovYDegrees;
  sv.near = view.near;
  const clod::Camera camera = render::cameraInItem(view.camera, sv);
  const glm::dvec3 body = camera.project({rover.x, rover.y, rover.z + 0.8});
  const auto* r = drawn.pixel(static_cast<int>(body.x), static_cast<int>(body.y));
  EXPECT_NEAR(r[0], r[1], 12) << body.x << ", " << body.y;
  EXPECT_NEAR(r[1], r[2], 12) << body.x << ", " << body.y;
  const glm::dvec3 ground = camera.project({at.x, at.y, built.demHeight("victoria", at.x, at.y)});
  const auto* g = drawn.pixel(static_cast<int>(ground.x), static_cast<int>(ground.y));
  EXPECT_GT(g[1], g[0]) << "the DEM is greener than the planet";
  EXPECT_TRUE(drawn.is(view.width / 2, 1, 5, 5, 10)) << "sky at the top";
}

TEST(SceneGL, TheDemosEarthIsDrawnWhereThePapersLayoutPutsIt) {
  test::glContext();
  // Earth's centre in Mars's body-fixed frame, worked by hand from the paper's layout
  // (demo/PaperScene.hpp): both heliocentric, Mars tilted by 25.19° about x, spun 120°.
  constexpr double kDeg = std::numbers::pi / 180.0;
  const glm::dvec3 earthSun =
      1.496e11 * glm::dvec3(std::cos(75.0 * kDeg), std::sin(75.0 * kDeg), 0.0);
  const glm::dvec3 marsSun =
      2.279e11 * glm::dvec3(std::cos(30.0 * kDeg), std::sin(30.0 * kDeg), 0.0);
  const glm::dvec3 d = earthSun - marsSun;
  const double ob = 25.19 * kDeg, sp = 120.0 * kDeg;
  // Rz(spin)ᵀ Rx(obliquity)ᵀ d.
  const glm::dvec3 tilted{d.x, std::cos(ob) * d.y + std::sin(ob) * d.z,
                          -std::sin(ob) * d.y + std::cos(ob) * d.z};
  const glm::dvec3 earth{std::cos(sp) * tilted.x + std::sin(sp) * tilted.y,
                         -std::sin(sp) * tilted.x + std::cos(sp) * tilted.y, tilted.z};
  // From 4 Earth radii on Mars's side, looking at Earth's centre: a disc of asin(1/4) =
  // 14.5° around the image centre (37 pixels of this 160 × 120 view), blue, and black sky
  // beyond it.
  demo::MarsVictoriaOptions o;
  o.planetRows = 90;
  o.demSize = 101;
  o.secondDem = false;
  SceneDescription s = demo::sceneDescription(o);
  Camera c;
  c.name = "earthward";
  c.frame = "mars";
  c.focus = "earth";
  const glm::dvec3 eye = earth - 4.0 * 6378137.0 * glm::normalize(earth);
  c.eye = {eye.x, eye.y, eye.z};
  c.lookAt = {earth.x, earth.y, earth.z};
  c.width = 160;
  c.height = 120;
  c.near = 1000.0;
  s.cameras.push_back(c);
  const gl::RgbaImage image = Scene(s).render("earthward");
  test::savePng("scene_demo_earth", image);
  for (const auto& [x, y] : {std::pair{80, 60}, {80 + 30, 60}, {80 - 30, 60}, {80, 60 + 30}}) {
    const auto* p = image.pixel(x, y);
    EXPECT_GT(p[2], p[0] + 8) << "Earth's blue at " << x << ", " << y;
  }
  for (const auto& [x, y] : {std::pair{80 + 45, 60}, {80 - 45, 60}, {80, 60 - 45}, {3, 3}})
    EXPECT_TRUE(image.is(x, y, 5, 5, 10)) << "sky at " << x << ", " << y;
}

TEST(SceneGL, TheRenderersFarFieldDrawsThePlanetWholeInEachViewSlot) {
  test::glContext();
  // Mars from 3 body radii out on the x axis, through a render::SceneRenderer the scene
  // registers with: the far field comes with the render target only, and fills the disc
  // (of angular radius asin(1/3)) whole. A 0.2° planet: its clipmap's levels that span at
  // most 180° of latitude reach 102° around the point under the camera, less than the 141°
  // of the ground seen from 3 radii, so the clipmap alone leaves the disc's rim empty.
  SceneDescription fine =
      withCamera("mars", {3.0 * 3396190.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0});
  ASSERT_EQ(fine.bodies.at(0).heights.at(0).rows, 180U);
  fine.bodies[0].heights[0].rows = 900;
  const Scene s(fine);
  const scenegraph::NodeId mars = s.graph().at("mars");
  const scenegraph::NodeId camera = s.cameraNode("view");
  render::SceneView view;
  view.width = 160;
  view.height = 120;
  view.near = 1000.0;
  view.lightInFocus = s.lightIn("mars");
  const scenegraph::RenderList list = s.graph().renderList(mars, camera);
  const auto frameOf = [&](render::SceneRenderer& r, const gl::RenderTarget* target,
                           std::size_t slot) {
    r.prepare(list, view);
    return r.draw(list, view, target, slot);
  };
  const auto planetPixels = [](const gl::RgbaImage& im) {
    int n = 0;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) n += im.is(x, y, 5, 5, 10) ? 0 : 1;
    return n;
  };
  gl::RenderTarget target(view.width, view.height);
  render::SceneRenderer near;
  s.registerWith(near);
  target.clear({0.02F, 0.02F, 0.04F, 1.0F});
  const render::SceneFrame withoutTarget = frameOf(near, nullptr, 0);
  EXPECT_EQ(withoutTarget.farFieldsPgm + withoutTarget.farFieldsImpostor, 0U);
  const gl::RgbaImage nearImage = target.readColor();
  test::savePng("scene_renderer_near_only", nearImage);
  const int nearOnly = planetPixels(nearImage);
  const double disc =
      60.0 * std::tan(std::asin(1.0 / 3.0)) / std::tan(22.5 * std::numbers::pi / 180.0);
  const auto skyInside = [&](const gl::RgbaImage& im, double fraction) {
    int n = 0;
    for (int y = 0; y < im.height; ++y) {
      for (int x = 0; x < im.width; ++x) {
        const double r = std::hypot(x + 0.5 - 80.0, y + 0.5 - 60.0);
        n += r < fraction * disc && im.is(x, y, 5, 5, 10) ? 1 : 0;
      }
    }
    return n;
  };
  EXPECT_GT(skyInside(nearImage, 0.95), 50) << "the clipmap alone leaves the disc's rim empty";

  render::SceneRenderer whole;
  s.registerWith(whole);
  target.clear({0.02F, 0.02F, 0.04F, 1.0F});
  const render::SceneFrame withTarget = frameOf(whole, &target, 0);
  EXPECT_EQ(withTarget.farFieldsPgm + withTarget.farFieldsImpostor, 1U);
  // The scene's 512² grid, thinned while its cells span under 2 px (planetFarFieldOptions()):
  // on this disc of about 100 px the grid drawn is at most 64² points.
  ASSERT_EQ(withTarget.farFieldsPgm, 1U);
  EXPECT_GT(withTarget.vertices, withoutTarget.vertices);
  EXPECT_LE(withTarget.vertices - withoutTarget.vertices, 64U * 64U);
  const gl::RgbaImage drawn = target.readColor();
  test::savePng("scene_renderer_far_field", drawn);
  EXPECT_GE(planetPixels(drawn), nearOnly);
  // The disc: 60 · tan(asin(1/3)) / tan(22.5°) ≈ 51 pixels; inside 0.95 of it every pixel
  // is the planet, beyond 1.15 of it every one is sky.
  EXPECT_EQ(skyInside(drawn, 0.95), 0);
  int planetBeyond = 0;
  for (int y = 0; y < drawn.height; ++y) {
    for (int x = 0; x < drawn.width; ++x) {
      const double r = std::hypot(x + 0.5 - 80.0, y + 0.5 - 60.0);
      planetBeyond += r > 1.15 * disc && !drawn.is(x, y, 5, 5, 10) ? 1 : 0;
    }
  }
  EXPECT_EQ(planetBeyond, 0);

  // A view slot is a view's own: slot 0 drawn twice from one camera gives the same image
  // whether or not another view is drawn in slot 1 between the two (PGM's primary sphere
  // lags a frame within its slot).
  const Scene closer(
      withCamera("mars", {1.3 * 3396190.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}));
  const auto secondFrame = [&](bool between) {
    render::SceneRenderer r;
    s.registerWith(r);
    target.clear({0.02F, 0.02F, 0.04F, 1.0F});
    (void)frameOf(r, &target, 0);
    if (between) {
      const scenegraph::RenderList l2 =
          closer.graph().renderList(closer.graph().at("mars"), closer.cameraNode("view"));
      target.clear({0.02F, 0.02F, 0.04F, 1.0F});
      r.prepare(l2, view);
      (void)r.draw(l2, view, &target, 1);
    }
    target.clear({0.02F, 0.02F, 0.04F, 1.0F});
    (void)frameOf(r, &target, 0);
    return target.readColor();
  };
  const gl::RgbaImage alone = secondFrame(false), interleaved = secondFrame(true);
  EXPECT_TRUE(alone.rgba == interleaved.rgba);

  // Straight down from 200 km the clipmap fills the view: the far field has no pixel to
  // fill and draws nothing (counted as covered); the image is the clipmap's alone.
  const double up = 3396190.0 + 200.0e3;
  const Scene low(withCamera("mars", {up, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}));
  const scenegraph::RenderList lowList =
      low.graph().renderList(low.graph().at("mars"), low.cameraNode("view"));
  render::SceneView lowView = view;
  lowView.lightInFocus = low.lightIn("mars");
  const auto lowFrame = [&](const gl::RenderTarget* t) {
    render::SceneRenderer r;
    low.registerWith(r);
    target.clear({0.02F, 0.02F, 0.04F, 1.0F});
    r.prepare(lowList, lowView);
    const render::SceneFrame f = r.draw(lowList, lowView, t, 0);
    return std::pair{f, target.readColor()};
  };
  const auto [lowNear, lowNearImage] = lowFrame(nullptr);
  const auto [lowBoth, lowBothImage] = lowFrame(&target);
  EXPECT_EQ(planetPixels(lowNearImage), view.width * view.height);
  EXPECT_EQ(lowBoth.farFieldsCovered, 1U);
  EXPECT_EQ(lowBoth.farFieldsPgm + lowBoth.farFieldsImpostor, 0U);
  EXPECT_EQ(lowBoth.vertices, lowNear.vertices);
  EXPECT_TRUE(lowBothImage.rgba == lowNearImage.rgba);
  EXPECT_EQ(withTarget.farFieldsCovered, 0U);  // the whole planet: the rim was empty

  // Refused, naming the call and what was expected.
  render::SceneRenderer r;
  s.registerWith(r);
  const SceneTerrain planet = s.terrains().front();
  ASSERT_TRUE(planet.planet);
  const auto message = [&](auto&& call) {
    try {
      call();
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { r.addFarField(planet.drawable, planet.farField, {}); })
                .find("SceneRenderer::addFarField(): planet is " + std::to_string(planet.drawable) +
                      ", expected a planet without a far field yet"),
            std::string::npos);  // registered by registerWith() already
  EXPECT_NE(message([&] { r.addFarField(9999, planet.farField, {}); }).find("9999"),
            std::string::npos);
  const SceneTerrain dem = s.terrains().at(1);
  ASSERT_FALSE(dem.planet);
  EXPECT_NE(message([&] {
              r.addFarField(dem.drawable, planet.farField, {});
            }).find("expected a terrain drawn body-fixed"),
            std::string::npos);
  render::SceneView part = view;
  part.width = 80;
  EXPECT_NE(message([&] { (void)r.draw(list, part, &target, 0); }).find("the whole target"),
            std::string::npos);
}

TEST(SceneGL, EveryTerrainLoadsOnTheScenesOneLoader) {
  test::glContext();
  // Mars and Victoria as stores: every pyramid's hints and loads and every clipmap's reads
  // run on one executor, the one SceneOptions gives, not on threads of their own.
  const std::filesystem::path dir = test::scratchFile("scene_loader", "stores");
  std::filesystem::create_directories(dir);
  store::MarsPlanetOptions mo;
  mo.rows = 180;
  mo.seed = 3;
  store::MarsPlanetGenerator(mo).write(dir / "mars.h5");
  store::VictoriaOptions vo;
  vo.size = 301;
  vo.spacing = 4.0;
  vo.seed = 3;
  store::VictoriaGenerator(vo).write(dir / "victoria.h5");
  constexpr const char* kStores = R"({
    "version": 1,
    "bodies": [{"name": "mars", "heights": [{"store": "mars.h5", "grid": "mars"}]}],
    "dems": [{"name": "victoria", "body": "mars",
              "heights": {"store": "victoria.h5", "grid": "victoria"},
              "placement": {"lat": -2.05, "lon": -5.5, "height": "surface"}}],
    "cameras": [{"name": "view", "frame": "victoria", "eye": [60, -470, 30],
                 "lookAt": [0, -380, 0], "up": [0, 0, 1], "width": 160, "height": 120}]
  })";
  const SceneDescription d = parseScene(kStores, "stores.json", dir.string());

  const Scene own(d);
  ASSERT_NE(own.loader(), nullptr);
  for (const SceneTerrain& t : own.terrains())
    EXPECT_EQ(t.options.executor, own.loader()) << t.name << ": the scene's loader";

  SceneOptions options;
  const auto loader = std::make_shared<test::CountingExecutor>();
  options.loader = loader;
  const Scene s(d, options);
  EXPECT_EQ(s.loader(), loader);
  const std::vector<SceneTerrain> terrains = s.terrains();
  ASSERT_EQ(terrains.size(), 2U);
  for (const SceneTerrain& t : terrains)
    EXPECT_EQ(t.options.executor, loader) << t.name << ": the given loader";
  const int built = loader->submitted;
  const gl::RgbaImage image = s.render("view");
  test::savePng("scene_loader_view", image);
  EXPECT_FALSE(image.is(80, 100, 5, 5, 10)) << "the ground is drawn, not the sky";
  EXPECT_GE(loader->submitted - built, 2) << "each clipmap read its windows on the loader";
  EXPECT_GT(s.cache()->stats().loads, 0U);

  // A pyramid's hint is queued there too (its Prefetcher submits the loading task).
  const int before = loader->submitted;
  const topo::SampleSource::Window hint[] = {{0, 0, 180, 360}};
  s.terrain("mars").level(0).source->prefetch(hint);
  EXPECT_GT(loader->submitted, before) << "the planet's hint is a task on the loader";
}

}  // namespace
}  // namespace regolith::scene
