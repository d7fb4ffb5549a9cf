// The scene file: every class of error word for word, round trips, relative paths, and what
// a built scene declares.
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/demo/PaperScene.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/scene/SceneDescription.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/topo/Body.hpp>

#include "support/StoreScratch.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <tuple>

namespace regolith::scene {
namespace {

using nlohmann::json;

/// A small valid scene: generated Mars (90 rows), a Victoria-like DEM, a rover, two cameras.
json baseScene() {
  return json::parse(R"({
    "version": 1,
    "bodies": [{"name": "mars", "heights": [{"generate": "mars-planet", "rows": 90, "seed": 3}]}],
    "dems": [{"name": "victoria", "body": "mars",
              "heights": {"generate": "victoria", "size": 201, "spacing": 4, "seed": 3},
              "placement": {"lat": -2.05, "lon": -5.5, "height": "surface"},
              "effects": {"tracks": true, "heightColours": {"min": -60, "max": 10}}}],
    "objects": [{"name": "rover", "dem": "victoria", "pose": {"x": 0, "y": -360}}],
    "cameras": [{"name": "above", "frame": "victoria", "eye": [0, 0, 900], "lookAt": [0, 0, 0],
                 "up": [0, 1, 0]},
                {"name": "chase", "frame": "rover", "eye": [-8, 0, 3], "lookAt": [0, 0, 0.5]}],
    "light": {"frame": "victoria", "elevation": 35, "azimuth": 90}
  })");
}

SceneDescription parse(const json& j) { return parseScene(j.dump(), "t.json", "/nowhere"); }

std::string errorOf(const json& j) {
  try {
    (void)parse(j);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(SceneFile, ReadsTheBaseScene) {
  const SceneDescription s = parse(baseScene());
  ASSERT_EQ(s.bodies.size(), 1U);
  EXPECT_EQ(s.bodies[0].heights[0].generate, "mars-planet");
  EXPECT_EQ(s.bodies[0].heights[0].rows, 90U);
  EXPECT_EQ(s.bodies[0].heights[0].seed, 3U);
  ASSERT_EQ(s.dems.size(), 1U);
  EXPECT_TRUE(s.dems[0].placement->surfaceHeight);
  EXPECT_EQ(s.dems[0].look.effects.declared(),
            (std::vector<std::string>{"tracks", "heightColours"}));
  EXPECT_TRUE(s.bodies[0].look.effects.declared().empty());
  ASSERT_EQ(s.cameras.size(), 2U);
  EXPECT_EQ(s.cameras[1].fovY, 45.0);  // default
  EXPECT_EQ(s.cameras[1].up, (std::array<double, 3>{0.0, 0.0, 1.0}));
}

TEST(SceneFile, UnknownKeysNameTheAllowedOnes) {
  json j = baseScene();
  j["cameras"][1]["fov"] = 60;
  EXPECT_EQ(errorOf(j),
            "t.json: /cameras/1/fov: unknown key, expected one of: name, frame, eye, lookAt, up, "
            "fovY, near, width, height, viewport, focus");
  j = baseScene();
  j["dems"][0]["effects"]["heightColors"] = json::object();
  EXPECT_EQ(errorOf(j),
            "t.json: /dems/0/effects/heightColors: unknown key, expected one of: tracks, "
            "heightColours, latLon, noise, albedo, overlay");
  j = baseScene();
  j["bodies"][0]["effects"] = {{"tracks", true}};  // tracks are for DEMs
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/0/effects/tracks: unknown key, expected one of: heightColours, "
            "latLon, noise, albedo, overlay");
  j = baseScene();
  j["bodies"][0]["heights"][0]["size"] = 5;  // a victoria option on mars-planet
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/0/heights/0/size: unknown key, expected one of: generate, seed, "
            "rows, ellipsoid, craterDensity, featherMetres");
}

TEST(SceneFile, TypesRangesAndFiniteNumbers) {
  json j = baseScene();
  j["cameras"][1]["fovY"] = 190;
  EXPECT_EQ(errorOf(j), "t.json: /cameras/1/fovY: 190 is not in (0, 180)");
  j["cameras"][1]["fovY"] = "wide";
  EXPECT_EQ(errorOf(j), "t.json: /cameras/1/fovY: expected a number, got a string");
  j = baseScene();
  j["cameras"][0]["near"] = 0;
  EXPECT_EQ(errorOf(j), "t.json: /cameras/0/near: 0 is not in > 0");
  j = baseScene();
  j["cameras"][0]["eye"] = {0, 0};
  EXPECT_EQ(errorOf(j),
            "t.json: /cameras/0/eye: expected an array of 3 numbers, got an array of 2");
  j = baseScene();
  j["cameras"][0]["width"] = 2.5;
  EXPECT_EQ(errorOf(j), "t.json: /cameras/0/width: expected an integer, got 2.5");
  j = baseScene();
  j["dems"][0]["effects"]["heightColours"]["max"] = -70;
  EXPECT_EQ(errorOf(j), "t.json: /dems/0/effects/heightColours/max: -70 is not > min (-60)");
  j = baseScene();
  j["dems"][0]["placement"]["lat"] = 91;
  EXPECT_EQ(errorOf(j), "t.json: /dems/0/placement/lat: 91 is not in [-90, 90]");
  j = baseScene();
  j["dems"][0]["placement"]["height"] = "ground";
  EXPECT_EQ(errorOf(j),
            "t.json: /dems/0/placement/height: \"ground\" is not a number or \"surface\"");
  // JSON has no NaN or infinity; a number too large for a double is refused as it is read.
  const std::string huge = R"({"version": 1, "bodies": [{"name": "mars", "heights": [
      {"generate": "mars-planet"}], "colour": [0.5, 1e999, 0.5]}]})";
  try {
    (void)parseScene(huge, "t.json", "/nowhere");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "t.json: not JSON (number overflow parsing '1e999')");
  }
  j = baseScene();
  j["version"] = 2;
  EXPECT_EQ(errorOf(j), "t.json: /version: 2 is not in [1, 1]");
  j = baseScene();
  j.erase("version");
  EXPECT_EQ(errorOf(j), "t.json: /version: missing, expected 1");
  j = baseScene();
  j["bodies"][0].erase("name");
  EXPECT_EQ(errorOf(j), "t.json: /bodies/0/name: missing, expected a string");
  j = baseScene();
  j["bodies"][0]["heights"][0]["generate"] = "venus";
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/0/heights/0/generate: \"venus\" is not one of: mars-planet, "
            "mars-cap, mars-strip, victoria");
  j = baseScene();
  j["objects"][0]["traverse"] = {{"waypoints", {{0, 0}, {1, 1}}}};
  EXPECT_EQ(errorOf(j), "t.json: /objects/0: expected exactly one of \"pose\" and \"traverse\"");
  EXPECT_THROW((void)parseScene("{\"version\": 1,", "t.json", "/"), InvalidArgument);
}

TEST(SceneFile, DuplicateNamesAndDanglingReferences) {
  json j = baseScene();
  j["dems"][0]["name"] = "mars";
  EXPECT_EQ(errorOf(j), "t.json: /dems/0/name: \"mars\" is already the name of /bodies/0/name");
  j = baseScene();
  j["cameras"][1]["name"] = "rover";
  EXPECT_EQ(errorOf(j),
            "t.json: /cameras/1/name: \"rover\" is already the name of /objects/0/name");
  j = baseScene();
  j["cameras"][1]["frame"] = "rovr";
  EXPECT_EQ(errorOf(j),
            "t.json: /cameras/1/frame: \"rovr\" names no body, DEM or object (there are: mars, "
            "victoria, rover)");
  j = baseScene();
  j["objects"][0]["dem"] = "mars";
  EXPECT_EQ(errorOf(j), "t.json: /objects/0/dem: \"mars\" names no DEM (there are: victoria)");
  j = baseScene();
  j["dems"][0]["body"] = "earth";
  EXPECT_EQ(errorOf(j), "t.json: /dems/0/body: \"earth\" names no body (there are: mars)");
}

TEST(SceneFile, StoresMustExist) {
  json j = baseScene();
  j["bodies"][0]["heights"].push_back({{"store", "caps.h5"}, {"grid", "north_cap"}});
  EXPECT_EQ(errorOf(j), "t.json: /bodies/0/heights/1/store: no such file");
}

TEST(SceneFile, RoundTripAndRelativePaths) {
  // A DEM store beside the scene, named relative to it.
  const auto dir = test::scratchFile("scene", "round_trip");
  std::filesystem::create_directories(dir / "data");
  std::filesystem::create_directories(dir / "elsewhere");
  store::VictoriaOptions vo;
  vo.size = 65;
  vo.spacing = 8.0;
  vo.write.levels = 2;
  store::VictoriaGenerator(vo).write(dir / "data" / "v.h5");
  json j = baseScene();
  j["dems"].push_back({{"name", "stored"},
                       {"body", "mars"},
                       {"heights", {{"store", "data/v.h5"}, {"grid", "victoria"}}}});
  j["cameras"][0]["viewport"] = {10, 20, 300, 200};
  j["light"] = {{"frame", "rover"}, {"direction", {0.5, -0.25, 1.0}}};
  { std::ofstream(dir / "scene.json") << j.dump(2); }
  const SceneDescription a = readScene(dir / "scene.json");
  EXPECT_EQ(a.resolve(a.dems[1].heights.store), dir / "data" / "v.h5");
  writeScene(a, dir / "copy.json");
  const SceneDescription b = readScene(dir / "copy.json");
  EXPECT_EQ(a, b);
  EXPECT_EQ(sceneJson(a, dir), sceneJson(b, dir));
  // Written into another folder: the relative path is rewritten to reach the same file.
  writeScene(a, dir / "elsewhere" / "moved.json");
  const SceneDescription c = readScene(dir / "elsewhere" / "moved.json");
  EXPECT_EQ(c.dems[1].heights.store, "../data/v.h5");
  EXPECT_EQ(std::filesystem::weakly_canonical(c.resolve(c.dems[1].heights.store)),
            std::filesystem::weakly_canonical(dir / "data" / "v.h5"));
  // A scene that no longer reads back is not written.
  SceneDescription bad = a;
  bad.cameras[0].fovY = 190.0;
  try {
    writeScene(bad, dir / "bad.json");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "bad.json").string() + ": /cameras/0/fovY: 190 is not in (0, 180)");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.json"));
}

/// baseScene() with Earth: WGS84 radii, no heights (a body without relief), placed 1.5e11 m
/// from the root's origin and tilted by 23.44°.
json withEarth() {
  json j = baseScene();
  j["bodies"].push_back(
      {{"name", "earth"},
       {"radii", {6378137.0, 6356752.314245179}},
       {"pose", {{"position", {1.0e11, -1.1e11, 2.5e9}}, {"obliquity", 23.44}, {"spin", 40}}},
       {"colour", {0.3, 0.45, 0.8}},
       {"clipmapSize", 31},
       {"farField", false}});
  return j;
}

TEST(SceneFile, ABodysPoseAndABodyWithoutReliefAreReadAsWritten) {
  // Read: the values of the hand-written file.
  const SceneDescription s = parse(withEarth());
  ASSERT_EQ(s.bodies.size(), 2U);
  EXPECT_FALSE(s.bodies[0].pose);  // mars: the root's frame
  const Body& earth = s.bodies[1];
  EXPECT_TRUE(earth.heights.empty());
  EXPECT_EQ(earth.radii, (std::array<double, 2>{6378137.0, 6356752.314245179}));
  ASSERT_TRUE(earth.pose);
  EXPECT_EQ(earth.pose->position, (std::array<double, 3>{1.0e11, -1.1e11, 2.5e9}));
  EXPECT_EQ(earth.pose->obliquity, 23.44);
  EXPECT_EQ(earth.pose->spin, 40.0);
  EXPECT_FALSE(earth.farField);
  // Spin defaults to 0, obliquity too.
  json j = withEarth();
  j["bodies"][1]["pose"] = {{"position", {1.0e11, 0, 0}}};
  const SceneDescription t = parse(j);
  EXPECT_EQ(t.bodies[1].pose->obliquity, 0.0);
  EXPECT_EQ(t.bodies[1].pose->spin, 0.0);

  // Written: the keys of the JSON the writer gives, read with nlohmann alone.
  const json w = json::parse(sceneJson(s, "/nowhere"));
  EXPECT_FALSE(w["bodies"][0].contains("pose"));
  EXPECT_FALSE(w["bodies"][1].contains("heights"));
  EXPECT_EQ(w["bodies"][1]["pose"]["position"], json({1.0e11, -1.1e11, 2.5e9}));
  EXPECT_EQ(w["bodies"][1]["pose"]["obliquity"], 23.44);
  EXPECT_EQ(w["bodies"][1]["pose"]["spin"], 40.0);
  EXPECT_EQ(w["bodies"][1]["radii"], json({6378137.0, 6356752.314245179}));

  // Round trip through a file: write → read gives the same description.
  const auto file = test::scratchFile("scene", "earth.json");
  writeScene(s, file);
  SceneDescription back = readScene(file);
  EXPECT_EQ(back.folder, file.parent_path());
  back.folder = s.folder;
  EXPECT_EQ(back, s);
  // And the writer refuses what JSON cannot carry, naming the key.
  SceneDescription bad = s;
  bad.bodies[1].pose->position[2] = std::numeric_limits<double>::quiet_NaN();
  const auto badFile = test::scratchFile("scene", "earth_nan.json");
  try {
    writeScene(bad, badFile);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              badFile.string() +
                  ": /bodies/1/pose/position: [1e+11, -1.1e+11, nan] is not finite, expected "
                  "metres");
  }
  EXPECT_FALSE(std::filesystem::exists(badFile));
}

TEST(SceneFile, BadBodyPosesAndBodiesWithoutHeightsAreNamed) {
  json j = withEarth();
  j["bodies"][1]["pose"].erase("position");
  EXPECT_EQ(errorOf(j), "t.json: /bodies/1/pose/position: missing, expected [x, y, z] in metres");
  j = withEarth();
  j["bodies"][1]["pose"]["position"] = {1.0e11, "far"};
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/1/pose/position: expected an array of 3 numbers, got an array of 2");
  j = withEarth();
  j["bodies"][1]["pose"]["position"][1] = "far";
  EXPECT_EQ(errorOf(j), "t.json: /bodies/1/pose/position/1: expected a number, got a string");
  j = withEarth();
  j["bodies"][1]["pose"]["obliquity"] = 200;
  EXPECT_EQ(errorOf(j), "t.json: /bodies/1/pose/obliquity: 200 is not in [-180, 180]");
  j = withEarth();
  j["bodies"][1]["pose"]["tilt"] = 3;
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/1/pose/tilt: unknown key, expected one of: position, obliquity, spin");
  // A position too large for a double is refused as the file is read.
  std::string text = withEarth().dump();
  text.replace(text.find("100000000000.0"), 14, "1e999");
  try {
    (void)parseScene(text, "t.json", "/nowhere");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("t.json: not JSON (", 0), 0U) << e.what();
  }
  // No heights: only with radii (the reference ellipsoid); an empty list is a mistake.
  j = withEarth();
  j["bodies"][1].erase("radii");
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/1/heights: missing, expected an array of datasets (or \"radii\": a "
            "body without relief)");
  j = withEarth();
  j["bodies"][1]["heights"] = json::array();
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/1/heights: empty, expected at least one dataset (leave it out, with "
            "\"radii\", for a body without relief)");
  // Inside another body: the reader sees it when both radii are given...
  j = withEarth();
  j["bodies"][0]["radii"] = {3396190.0, 3376200.0};
  j["bodies"][1]["pose"]["position"] = {0.0, 9.0e6, 0.0};
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/1/pose/position: [0, 9e+06, 0] puts \"earth\" 9e+06 m from the "
            "centre of \"mars\" (/bodies/0), inside it: expected at least 9774327 m (the sum of "
            "their equatorial radii)");
  // ...and just apart is fine.
  j["bodies"][1]["pose"]["position"] = {0.0, 9774327.0, 0.0};
  EXPECT_EQ(errorOf(j), "no error");
  // A body left at the root's origin, where another already is.
  j["bodies"][1].erase("pose");
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/1/pose: missing (the root's origin) puts \"earth\" 0 m from the "
            "centre of \"mars\" (/bodies/0), inside it: expected at least 9774327 m (the sum of "
            "their equatorial radii)");
}

TEST(SceneFile, TheRootIsNamedAndALightMayComeFromIt) {
  json j = withEarth();
  j["root"] = "sun";
  j["light"] = {{"from", "sun"}};
  const SceneDescription s = parse(j);
  EXPECT_EQ(s.root, "sun");
  EXPECT_EQ(s.light.from, "sun");
  EXPECT_EQ(parse(withEarth()).root, "root") << "unnamed, the root is \"root\"";
  const json w = json::parse(sceneJson(s, "/nowhere"));
  EXPECT_EQ(w["root"], "sun");
  EXPECT_EQ(w["light"], json({{"from", "sun"}}));
  EXPECT_FALSE(json::parse(sceneJson(parse(withEarth()), "/nowhere")).contains("root"));
  EXPECT_EQ(parseScene(sceneJson(s, "/nowhere"), "t.json", "/nowhere"), s);

  json bad = j;
  bad["light"]["elevation"] = 10;
  EXPECT_EQ(errorOf(bad),
            "t.json: /light: expected \"from\" alone (a light at a frame's origin has no "
            "direction of its own)");
  bad = j;
  bad["light"] = {{"from", "moon"}};
  EXPECT_EQ(errorOf(bad),
            "t.json: /light/from: \"moon\" names no root, body, DEM or object (there are: sun, "
            "mars, earth, victoria, rover)");
  bad = j;
  bad["root"] = "mars";
  EXPECT_EQ(errorOf(bad), "t.json: /bodies/0/name: \"mars\" is already the name of /root");
  bad = j;
  bad["root"] = "";
  EXPECT_EQ(errorOf(bad), "t.json: /root: empty, expected a non-empty string");
}

TEST(Scene, ALightFromTheSunComesFromTheRootsOriginInEveryFrame) {
  json j = withEarth();
  j["root"] = "sun";
  j["light"] = {{"from", "sun"}};
  j["bodies"][0]["pose"] = {
      {"position", {2.0e11, 1.0e11, 0.0}}, {"obliquity", 25.19}, {"spin", 120}};
  const Scene s(parse(j));
  EXPECT_EQ(s.graph().at("sun"), s.graph().root());
  // Towards the Sun from a body at p, in the body's frame, worked by hand:
  // Rz(spin)ᵀ Rx(obliquity)ᵀ (−p / |p|).
  constexpr double kDeg = std::numbers::pi / 180.0;
  const auto towardsSun = [&](glm::dvec3 p, double obliquity, double spin) {
    const glm::dvec3 d = -glm::normalize(p);
    const double ob = obliquity * kDeg, sp = spin * kDeg;
    const glm::dvec3 t{d.x, std::cos(ob) * d.y + std::sin(ob) * d.z,
                       -std::sin(ob) * d.y + std::cos(ob) * d.z};
    return glm::dvec3{std::cos(sp) * t.x + std::sin(sp) * t.y,
                      -std::sin(sp) * t.x + std::cos(sp) * t.y, t.z};
  };
  const glm::dvec3 mars = towardsSun({2.0e11, 1.0e11, 0.0}, 25.19, 120.0);
  const glm::dvec3 earth = towardsSun({1.0e11, -1.1e11, 2.5e9}, 23.44, 40.0);
  EXPECT_NEAR(glm::length(s.lightIn("mars") - mars), 0.0, 1e-15);
  EXPECT_NEAR(glm::length(s.lightIn("earth") - earth), 0.0, 1e-15);
  // Victoria sees the Sun from its own origin, 3.4e6 m from Mars's centre: within
  // 3.4e6 / 2.2e11 = 1.5e-5 rad of the direction at the centre, and not the same bits.
  const scenegraph::SceneGraph& g = s.graph();
  const glm::dvec3 atCentre = g.relative(g.at("victoria"), g.at("mars")).applyVector(mars);
  const double apart = glm::length(s.lightIn("victoria") - atCentre);
  EXPECT_LT(apart, 1.6e-5);
  EXPECT_GT(apart, 1e-9);
  // The same scene lit by a direction in Mars's frame instead: that direction, unchanged.
  j["light"] = {{"frame", "mars"}, {"direction", {0.0, 0.0, 1.0}}};
  EXPECT_EQ(Scene(parse(j)).lightIn("mars"), glm::dvec3(0.0, 0.0, 1.0));
}

TEST(Scene, ABodyInsideAnotherIsRefusedWhenBuilt) {
  // Mars's radii come from its generator: only building knows them.
  json j = withEarth();
  j["bodies"][1]["pose"]["position"] = {0.0, 0.0, 9.0e6};
  const SceneDescription d = parse(j);
  try {
    const Scene s(d);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "Scene: /bodies/1/pose/position: [0, 0, 9e+06] puts \"earth\" 9e+06 m from "
                 "the centre of \"mars\" (/bodies/0), inside it: expected at least 9774327 m "
                 "(the sum of their equatorial radii)");
  }
}

TEST(Scene, ABodysPoseIsItsFrameInTheRootsAndABodyWithoutReliefIsItsEllipsoid) {
  const Scene s(parse(withEarth()));
  const scenegraph::SceneGraph& g = s.graph();
  const scenegraph::Pose earth = g.inRoot(g.at("earth"));
  EXPECT_EQ(earth.translation, glm::dvec3(1.0e11, -1.1e11, 2.5e9));
  // The pole tilted by the obliquity about the root's x axis, then the prime meridian turned
  // by the spin about the pole: worked by hand with the rotation matrices Rx(23.44°) Rz(40°).
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double ob = 23.44 * kDeg, sp = 40.0 * kDeg;
  const glm::dvec3 pole = earth.applyVector({0.0, 0.0, 1.0});
  const glm::dvec3 meridian = earth.applyVector({1.0, 0.0, 0.0});
  EXPECT_NEAR(glm::length(pole - glm::dvec3(0.0, -std::sin(ob), std::cos(ob))), 0.0, 1e-15);
  EXPECT_NEAR(glm::length(meridian - glm::dvec3(std::cos(sp), std::sin(sp) * std::cos(ob),
                                                std::sin(sp) * std::sin(ob))),
              0.0, 1e-15);
  // Mars has no pose: the root's frame.
  EXPECT_EQ(g.inRoot(g.at("mars")).translation, glm::dvec3(0.0));
  // Earth without relief: the WGS84 radii given, every height 0 on 3° cells.
  const clod::HeightPyramid& p = s.terrain("earth");
  ASSERT_TRUE(p.body());
  EXPECT_EQ(p.body()->equatorialRadius(), 6378137.0);
  EXPECT_EQ(p.body()->polarRadius(), 6356752.314245179);
  EXPECT_NEAR(p.body()->flattening(), topo::Body::earthWgs84().flattening(), 1e-15);
  const auto& level = p.level(0);
  EXPECT_EQ(level.grid.rows(), 60U);
  EXPECT_EQ(level.grid.cols(), 120U);
  EXPECT_EQ(level.grid.spacingX(), 3.0);
  for (std::size_t r = 0; r < 60; r += 7)
    for (std::size_t c = 0; c < 120; c += 11) EXPECT_EQ(level.source->sample(r, c), 0.0F);
  EXPECT_EQ(s.terrainOptions("earth").size, 31);
  EXPECT_EQ(s.terrains()[1].farField, nullptr);
  // A DEM on a placed body keeps its place on the body: the body's pose does not enter.
  json j = baseScene();
  j["bodies"][0]["pose"] = {
      {"position", {2.0e11, 1.0e11, 0.0}}, {"obliquity", 25.19}, {"spin", 120}};
  const Scene placed(parse(j)), unplaced(parse(baseScene()));
  const scenegraph::Pose a =
      placed.graph().relative(placed.graph().at("mars"), placed.graph().at("rover"));
  const scenegraph::Pose b =
      unplaced.graph().relative(unplaced.graph().at("mars"), unplaced.graph().at("rover"));
  EXPECT_EQ(a.translation, b.translation);
  EXPECT_EQ(a.rotation, b.rotation);
}

TEST(Scene, TheDemoSceneDeclaresEarthWhereThePapersLayoutPutsIt) {
  // demo::sceneDescription() against demo::buildPaperScene(), the paper's layout as a bare
  // scene graph (both from demo::PaperSceneLayout through scenegraph::bodyPose()): Earth and
  // Mars where the layout puts them, and Mars's axes against the rotations written out here.
  demo::MarsVictoriaOptions o;
  o.planetRows = 90;
  o.demSize = 101;
  o.secondDem = false;
  const SceneDescription d = demo::sceneDescription(o);
  ASSERT_EQ(d.bodies.size(), 2U);
  EXPECT_EQ(d.bodies[0].name, "mars");  // first: the viewer and the fly-over's planet
  EXPECT_EQ(d.bodies[1].name, "earth");
  EXPECT_TRUE(d.bodies[1].heights.empty());
  EXPECT_EQ(d.bodies[1].look.colour, (std::array<double, 3>{0.3, 0.45, 0.8}));
  const Scene s(d);
  scenegraph::SceneGraph paper("sun");
  const demo::PaperSceneNodes n = demo::buildPaperScene(paper);
  const scenegraph::SceneGraph& g = s.graph();
  for (const auto& [name, node] : {std::pair{"mars", n.mars}, {"earth", n.earth}}) {
    const scenegraph::Pose want = paper.inRoot(node), got = g.inRoot(g.at(name));
    EXPECT_EQ(got.translation, want.translation) << name;
    EXPECT_NEAR(glm::length(got.applyVector({0.0, 0.0, 1.0}) - want.applyVector({0.0, 0.0, 1.0})),
                0.0, 1e-15)
        << name;
    EXPECT_NEAR(glm::length(got.applyVector({1.0, 0.0, 0.0}) - want.applyVector({1.0, 0.0, 0.0})),
                0.0, 1e-15)
        << name;
  }
  // Mars's frame, analytically: its pole tilted by the obliquity ε about the ecliptic's x
  // axis, (0, −sin ε, cos ε); its prime meridian turned by the spin σ about that pole, then
  // tilted, (cos σ, sin σ cos ε, sin σ sin ε); its centre at the heliocentric distance and
  // longitude.
  const demo::PaperSceneLayout layout;
  const double eps = layout.marsObliquityDeg * std::numbers::pi / 180.0;
  const double spin = layout.marsSpinDeg * std::numbers::pi / 180.0;
  const double lon = layout.marsLongitudeDeg * std::numbers::pi / 180.0;
  const scenegraph::Pose mars = g.inRoot(g.at("mars"));
  EXPECT_NEAR(glm::length(mars.applyVector({0.0, 0.0, 1.0}) -
                          glm::dvec3(0.0, -std::sin(eps), std::cos(eps))),
              0.0, 1e-15);
  EXPECT_NEAR(glm::length(mars.applyVector({1.0, 0.0, 0.0}) -
                          glm::dvec3(std::cos(spin), std::sin(spin) * std::cos(eps),
                                     std::sin(spin) * std::sin(eps))),
              0.0, 1e-15);
  EXPECT_NEAR(glm::length(mars.translation -
                          layout.marsDistance * glm::dvec3(std::cos(lon), std::sin(lon), 0.0)),
              0.0, 1e-3);
  // Earth seen from Mars, through the root: ~1.0e11 m away, as in the paper's graph.
  const glm::dvec3 fromMars = g.relative(g.at("mars"), g.at("earth")).translation;
  const glm::dvec3 paperFromMars = paper.relative(n.mars, n.earth).translation;
  EXPECT_NEAR(glm::length(fromMars - paperFromMars), 0.0, 1e-3);
  EXPECT_GT(glm::length(fromMars), 1.0e11);
  EXPECT_EQ(s.terrain("earth").body()->equatorialRadius(),
            topo::Body::earthWgs84().equatorialRadius());
}

TEST(Scene, BuildsOnlyWhatIsDeclared) {
  const Scene s(parse(baseScene()));
  EXPECT_EQ(s.terrainOptions("victoria").effects.declared(),
            (std::vector<std::string>{"tracks", "heightColours"}));
  EXPECT_TRUE(s.terrainOptions("mars").effects.declared().empty());
  json j = baseScene();
  j["dems"][0].erase("effects");
  j["bodies"][0]["effects"] = {{"latLon", {{"spacing", 10}}}, {"noise", json::object()}};
  const Scene t(parse(j));
  EXPECT_TRUE(t.terrainOptions("victoria").effects.declared().empty());
  EXPECT_EQ(t.terrainOptions("mars").effects.declared(),
            (std::vector<std::string>{"noise", "latLon"}));
  EXPECT_EQ(t.terrainOptions("mars").effects.latLon->spacingDegrees, 10.0);
}

TEST(Scene, GeneratorsAreDeterministicAndMatchTheGenerator) {
  const Scene a(parse(baseScene())), b(parse(baseScene()));
  store::VictoriaOptions vo;
  vo.size = 201;
  vo.spacing = 4.0;
  vo.seed = 3;
  const auto& level = a.terrain("victoria").level(0);
  // The DEM sits on the planet: the generator's origin height is the planet's there, and
  // its samples are the generator's with that origin height.
  vo.originHeight = 0.0;
  const auto direct = store::VictoriaGenerator(vo).samples();
  for (const auto& [r, c] : {std::pair<std::size_t, std::size_t>{0, 0}, {100, 100}, {37, 150}}) {
    EXPECT_EQ(level.source->sample(r, c), b.terrain("victoria").level(0).source->sample(r, c));
    EXPECT_EQ(level.source->sample(r, c), direct->sample(r, c)) << r << ", " << c;
  }
  EXPECT_EQ(a.objectPose("rover"), b.objectPose("rover"));
  EXPECT_EQ(a.objectPose("rover").z, a.demHeight("victoria", 0.0, -360.0));
  json j = baseScene();
  j["bodies"][0]["heights"][0]["seed"] = 4;
  const Scene c(parse(j));
  EXPECT_NE(c.terrain("mars").level(0).source->sample(40, 40),
            a.terrain("mars").level(0).source->sample(40, 40));
}

TEST(Scene, UnknownCameraListsTheCameras) {
  const Scene s(parse(baseScene()));
  try {
    (void)s.render("orbit");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "Scene::render(): no camera named 'orbit', expected one of: above, chase");
  }
  EXPECT_EQ(s.focusOf("chase"), "victoria");
  EXPECT_EQ(s.focusOf("above"), "victoria");
}

TEST(Scene, TraverseStopsAtItsEndAndPressesTracks) {
  json j = baseScene();
  j["objects"][0].erase("pose");
  j["objects"][0]["traverse"] = {{"waypoints", {{-100, -300}, {-100, -280}}}, {"step", 0.01}};
  const Scene s(parse(j));
  const glm::dvec4 p = s.objectPose("rover");
  EXPECT_NEAR(p.x, -100.0, 1e-6);
  EXPECT_NEAR(p.y, -280.0, 0.02);
  EXPECT_NEAR(p.w, 0.0, 1e-6);  // heading north
  EXPECT_GT(s.terrainOptions("victoria").effects.tracks->tiles(), 0U);
}

TEST(Scene, TheDemoScenesCamerasAreThePapersLayouts) {
  // The paper's cameras declared in demo::sceneDescription(), against demo::buildPaperScene()
  // (which takes them from demo::paperCameras() too, the orbit camera hung from Mars through
  // Victoria's pose): each in the frame it follows, the same pose, through the two graphs.
  demo::MarsVictoriaOptions o;
  o.planetRows = 90;
  o.demSize = 101;
  o.secondDem = false;
  const Scene s(demo::sceneDescription(o));
  scenegraph::SceneGraph paper("sun");
  const demo::PaperSceneNodes n = demo::buildPaperScene(paper);
  const demo::DemoCameras c = demo::paperCameraNodes(s);
  const scenegraph::SceneGraph& g = s.graph();
  EXPECT_EQ(c.orbit, s.cameraNode("orbit_camera"));
  for (const auto& [node, want, frame, tolerance] :
       {std::tuple{c.orbit, paper.relative(n.victoria, n.orbitCamera), "victoria", 1e-6},
        {c.mast, paper.relative(n.rover, n.mastCamera), "rover", 0.0},
        {c.chase, paper.relative(n.rover, n.chaseCamera), "rover", 0.0}}) {
    const scenegraph::Pose got = g.relative(g.at(frame), node);
    EXPECT_LE(glm::length(got.translation - want.translation), tolerance) << frame;
    for (const glm::dvec3& axis : {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)})
      EXPECT_LE(glm::length(got.applyVector(axis) - want.applyVector(axis)), 1e-12) << frame;
  }
  EXPECT_EQ(s.description().camera("orbit_camera")->near, 100.0);
  EXPECT_EQ(s.description().camera("mast_camera")->near, 0.05);
}

TEST(Scene, ATraverseTheCallerDroveIsNotDrivenAgain) {
  json j = baseScene();
  j["objects"][0].erase("pose");
  j["objects"][0]["traverse"] = {{"waypoints", {{-100, -300}, {-100, -280}}}, {"step", 0.01}};
  const SceneDescription d = parse(j);
  // The scene drives the traverse itself: once.
  const Scene first(d);
  EXPECT_EQ(first.traversesDriven(), 1U);
  const glm::dvec4 end = first.objectPose("rover");
  const std::shared_ptr<rover::TrackLayer> pressed =
      first.terrainOptions("victoria").effects.tracks;
  const std::size_t tiles = pressed->tiles();
  ASSERT_GT(tiles, 0U);
  // A second scene given that run (its end and its tracks) drives nothing: the rover stands
  // where the run stopped, and the layer holds the run's tracks, pressed once.
  SceneOptions given;
  given.tracks["victoria"] = pressed;
  rover::ChassisPose last;
  last.x = end.x;
  last.y = end.y;
  last.heading = end.w * std::numbers::pi / 180.0;
  given.driven["rover"] = last;
  const Scene second(d, given);
  EXPECT_EQ(second.traversesDriven(), 0U);
  EXPECT_EQ(second.objectPose("rover").x, end.x);
  EXPECT_EQ(second.objectPose("rover").y, end.y);
  EXPECT_NEAR(second.objectPose("rover").w, end.w, 1e-12);
  EXPECT_EQ(second.terrainOptions("victoria").effects.tracks, pressed);
  EXPECT_EQ(pressed->tiles(), tiles);
  // Where the caller says the run stopped is where the rover stands (not where the
  // waypoints end): nothing is driven, nothing pressed into a fresh layer.
  given.tracks["victoria"] = std::make_shared<rover::TrackLayer>(rover::RoverRuts::kTexelMetres);
  last.x = 12.5;
  last.y = -300.25;
  last.heading = 0.5;
  given.driven["rover"] = last;
  const Scene elsewhere(d, given);
  EXPECT_EQ(elsewhere.traversesDriven(), 0U);
  EXPECT_EQ(elsewhere.objectPose("rover").x, 12.5);
  EXPECT_EQ(elsewhere.objectPose("rover").y, -300.25);
  EXPECT_EQ(elsewhere.objectPose("rover").z, elsewhere.demHeight("victoria", 12.5, -300.25));
  EXPECT_EQ(given.tracks["victoria"]->tiles(), 0U);
  // Misuse named: an object without a traverse, a name that is no object, no tracks layer
  // for a DEM that declares tracks.
  const auto errorOfBuild = [](const SceneDescription& desc, const SceneOptions& o) {
    try {
      const Scene s(desc, o);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  SceneOptions bad;
  bad.driven["rover"] = last;
  EXPECT_EQ(errorOfBuild(parse(baseScene()), bad),
            "Scene: SceneOptions::driven: 'rover' is not an object of the scene with a traverse");
  bad.driven.clear();
  bad.driven["rovr"] = last;
  EXPECT_EQ(errorOfBuild(d, bad),
            "Scene: SceneOptions::driven: 'rovr' is not an object of the scene with a traverse");
  bad.driven.clear();
  bad.driven["rover"] = last;
  EXPECT_EQ(errorOfBuild(d, bad),
            "Scene: /objects/0/traverse: driven by the caller (SceneOptions::driven), but "
            "SceneOptions::tracks gives no layer for its DEM 'victoria', which declares tracks");
}

TEST(SceneFile, DrapedDataFromAGeneratorNeedsItsRangeAndItsTerrainsKind) {
  const json victoria = {{"generate", "victoria"}, {"size", 201}, {"spacing", 4}, {"seed", 3}};
  json j = baseScene();
  j["dems"][0]["effects"]["albedo"] = {{"data", victoria}};
  EXPECT_EQ(errorOf(j),
            "t.json: /dems/0/effects/albedo/range: missing, expected [min, max]: the generator's "
            "heights (metres) that become 0 and 1");
  j["dems"][0]["effects"]["albedo"]["range"] = {10, 10};
  EXPECT_EQ(errorOf(j), "t.json: /dems/0/effects/albedo/range/1: 10 is not > min (10)");
  j["dems"][0]["effects"]["albedo"]["range"] = {-80, "high"};
  EXPECT_EQ(errorOf(j), "t.json: /dems/0/effects/albedo/range/1: expected a number, got a string");
  j["dems"][0]["effects"]["albedo"] = {{"data", {{"generate", "mars-planet"}, {"rows", 90}}},
                                       {"range", {-8000, 20000}}};
  EXPECT_EQ(errorOf(j),
            "t.json: /dems/0/effects/albedo/data/generate: \"mars-planet\" is not draped over a "
            "DEM, expected victoria");
  j = baseScene();
  j["bodies"][0]["effects"] = {{"overlay", {{"data", victoria}, {"range", {0, 1}}}}};
  EXPECT_EQ(errorOf(j),
            "t.json: /bodies/0/effects/overlay/data/generate: \"victoria\" is not draped over a "
            "body, expected mars-planet");
  j = baseScene();
  j["dems"][0]["effects"]["overlay"] = {{"data", {{"store", "x.h5"}, {"grid", "x"}}},
                                        {"range", {0, 1}}};
  EXPECT_EQ(errorOf(j),
            "t.json: /dems/0/effects/overlay/range: given for a store's data, expected it only "
            "with a generator (a store's values are drawn as they are, in [0, 1])");
  // Valid: written and read back with its range.
  j = baseScene();
  j["dems"][0]["effects"]["albedo"] = {{"data", victoria}, {"range", {-80, 20}}};
  j["bodies"][0]["effects"] = {{"overlay",
                                {{"data", {{"generate", "mars-planet"}, {"rows", 90}}},
                                 {"range", {-8000, 20000}},
                                 {"opacity", 0.5}}}};
  const SceneDescription d = parse(j);
  ASSERT_TRUE(d.dems[0].look.effects.albedo.has_value());
  EXPECT_EQ(d.dems[0].look.effects.albedo->range, (std::array<double, 2>{-80.0, 20.0}));
  const SceneDescription again = parseScene(sceneJson(d, "/nowhere"), "t.json", "/nowhere");
  EXPECT_EQ(again, d);
}

TEST(Scene, DrapedDataFromAGeneratorIsItsHeightsMappedOverTheRange) {
  // Oracle: store::VictoriaGenerator run here with the same options (origin height 0), and
  // the linear map with its clamp written out.
  json j = baseScene();
  j["dems"][0]["effects"]["albedo"] = {
      {"data", {{"generate", "victoria"}, {"size", 201}, {"spacing", 4}, {"seed", 5}}},
      {"range", {-60, 15}},
      {"window", 128}};
  const Scene s(parse(j));
  const auto& albedo = s.terrainOptions("victoria").effects.albedo;
  ASSERT_TRUE(albedo.has_value());
  ASSERT_EQ(albedo->channels.size(), 1U);
  EXPECT_EQ(albedo->window, 128);
  const clod::HeightPyramid& p = *albedo->channels[0];
  EXPECT_EQ(p.kind(), clod::SurfaceKind::Plane);
  store::VictoriaOptions vo;
  vo.size = 201;
  vo.spacing = 4.0;
  vo.seed = 5;
  vo.originHeight = 0.0;
  const auto truth = store::VictoriaGenerator(vo).samples();
  const auto& level0 = p.level(0);
  ASSERT_EQ(level0.grid.rows(), 201U);
  ASSERT_EQ(level0.grid.cols(), 201U);
  EXPECT_EQ(level0.grid.spacingX(), 4.0);
  std::size_t clamped = 0, inside = 0;
  for (std::size_t r = 0; r < 201; r += 5) {
    for (std::size_t c = 0; c < 201; c += 5) {
      const double h = truth->sample(r, c);
      const double v = std::min(1.0, std::max(0.0, (h + 60.0) / 75.0));
      EXPECT_NEAR(level0.source->sample(r, c), v, 1e-6) << r << ", " << c;
      (v == 0.0 || v == 1.0 ? clamped : inside) += 1;
    }
  }
  EXPECT_GT(inside, 100U);  // the range spans the crater's heights
}

TEST(Scene, GivenTracksAreDrawnAndPressedIntoAndCheckedByName) {
  // A caller's layer (its own traverse pressed it) is the one the DEM draws, and the scene's
  // traverses press into it too.
  auto mine = std::make_shared<rover::TrackLayer>(0.05);
  SceneOptions o;
  o.tracks["victoria"] = mine;
  const Scene plain(parse(baseScene()), o);
  EXPECT_EQ(plain.terrainOptions("victoria").effects.tracks, mine);
  EXPECT_EQ(mine->tiles(), 0U);
  json j = baseScene();
  j["objects"][0].erase("pose");
  j["objects"][0]["traverse"] = {{"waypoints", {{-100, -300}, {-100, -280}}}, {"step", 0.01}};
  const Scene driven(parse(j), o);
  EXPECT_EQ(driven.terrainOptions("victoria").effects.tracks, mine);
  EXPECT_GT(mine->tiles(), 0U);
  const auto errorOfBuild = [](const json& scene, const SceneOptions& options) {
    try {
      const Scene s(parse(scene), options);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  SceneOptions unknown;
  unknown.tracks["gale"] = mine;
  EXPECT_EQ(errorOfBuild(baseScene(), unknown),
            "Scene: SceneOptions::tracks: 'gale' is not a DEM of the scene");
  json untracked = baseScene();
  untracked["dems"][0]["effects"].erase("tracks");
  EXPECT_EQ(errorOfBuild(untracked, o),
            "Scene: /dems/0/effects/tracks: not declared, but SceneOptions::tracks gives a layer "
            "for 'victoria'");
  SceneOptions null;
  null.tracks["victoria"] = nullptr;
  EXPECT_EQ(errorOfBuild(baseScene(), null),
            "Scene: /dems/0/effects/tracks: SceneOptions::tracks gives a null layer");
}

TEST(Scene, TerrainsGiveTheDemsPlacementAndTheComposedSurface) {
  json j = baseScene();
  const Scene plain(parse(j));
  for (const SceneTerrain& t : plain.terrains()) {
    EXPECT_EQ(t.composed, nullptr) << t.name;
    if (t.name != "victoria") continue;
    EXPECT_EQ(t.origin.latDeg, -2.05);
    EXPECT_EQ(t.origin.lonDeg, -5.5);
    EXPECT_EQ(t.headingDeg, 0.0);
    // "surface": the planet's height there, which the DEM's frame sits at.
    const scenegraph::Pose p =
        plain.graph().relative(plain.graph().at("mars"), plain.graph().at("victoria"));
    EXPECT_NEAR(glm::length(p.translation - plain.terrain("mars").body()->toBodyFixed(t.origin)),
                0.0, 1e-6);
  }
  j["bodies"][0]["composeDems"] = true;
  j["bodies"][0]["farField"] = false;  // resampling the composed surface for it takes minutes
  const Scene composed(parse(j));
  EXPECT_NE(composed.terrains().front().composed, nullptr);
  EXPECT_EQ(composed.terrains().front().composed->snapshot().size(), 2U);  // mars, victoria
}

}  // namespace
}  // namespace regolith::scene
