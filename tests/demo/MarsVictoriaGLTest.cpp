// The demo scene (demo::sceneDescription() built by scene::Scene, demo::buildScene()) and
// demo::renderFlyover(): the fly-over writes readable PNGs from Mars whole down to the rover,
// switching the focus on the way.
#include <regolith/core/Error.hpp>
#include <regolith/demo/MarsVictoria.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/scene/Scene.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace regolith::demo {
namespace {

using scenegraph::Pose;

MarsVictoriaOptions small() {
  MarsVictoriaOptions o;
  o.planetRows = 180;
  o.demSize = 301;
  o.demSpacing = 4.0;
  o.secondDem = false;
  o.clipmapSize = 63;
  return o;
}

/// A five-frame fly-over of small() into a fresh temporary folder.
FlyoverOptions fiveFrames(const char* folder, int width, int height) {
  test::glContext();
  FlyoverOptions o;
  o.outputDir = std::filesystem::path(::testing::TempDir()) / folder;
  std::filesystem::remove_all(o.outputDir);
  o.frames = 5;
  o.width = width;
  o.height = height;
  o.scene = small();
  return o;
}

TEST(MarsVictoriaGLTest, FlyoverGoesFromMarsWholeToTheRover) {
  FlyoverOptions o = fiveFrames("regolith_flyover_test", 96, 64);
  const std::filesystem::path dir = o.outputDir;
  int calls = 0;
  o.progress = [&](int done, int all, const std::filesystem::path& p) {
    ++calls;
    EXPECT_EQ(done, calls);
    EXPECT_EQ(all, 5);
    EXPECT_TRUE(std::filesystem::exists(p));
  };
  const FlyoverSummary s = renderFlyover(o);
  EXPECT_EQ(calls, 5);
  ASSERT_EQ(s.files.size(), 6U);  // 5 frames and multiview.png
  EXPECT_GT(s.focusSwitchFrame, 0);
  EXPECT_LT(s.focusSwitchFrame, 5);
  EXPECT_NEAR(s.startDistance, 8.0e6, 1.0);
  EXPECT_NEAR(s.endDistance, 6.0, 0.5);
  const gl::RgbaImage first = gl::readPng(s.files.front().string());
  const gl::RgbaImage last = gl::readPng(s.files[4].string());
  EXPECT_EQ(first.width, 96);
  EXPECT_EQ(first.height, 64);
  // First frame: Mars whole, in the middle, with space in the corners.
  const auto* centre = first.pixel(48, 32);
  EXPECT_GT(centre[0], 60);
  EXPECT_TRUE(first.is(0, 0, 5, 5, 10));  // the background (0.02, 0.02, 0.04)
  // Last frame: the rover (grey: r = g = b) in the middle of the view.
  const auto* rover = last.pixel(48, 32);
  EXPECT_NEAR(rover[0], rover[1], 8);
  EXPECT_NEAR(rover[1], rover[2], 8);
  // Its surroundings are the DEM (green over red).
  const auto* ground = last.pixel(48, 60);
  EXPECT_GT(ground[1], ground[0]);
  std::filesystem::remove_all(dir);
}

// The approach from 16 Mars radii (FlyoverOptions::approachFrom): the first frame is beyond
// PGM's reach and draws Mars as the ray-cast impostor, a disc of the size the ellipsoid
// subtends from there; the frames after it are PGM's and the clipmaps'.
TEST(MarsVictoriaGLTest, AnApproachFromFarDrawsMarsAsTheImpostorFirst) {
  FlyoverOptions o = fiveFrames("regolith_flyover_approach", 384, 256);
  const std::filesystem::path dir = o.outputDir;
  o.multiView = false;
  o.overPole = true;
  const topo::Body mars = topo::Body::marsEllipsoid();
  o.approachFrom = 16.0 * mars.equatorialRadius();
  const FlyoverSummary s = renderFlyover(o);
  std::printf("approach: impostor %d, PGM %d, covered %d of 5 frames; pole frame %d\n",
              s.impostorFrames, s.farFieldFrames, s.coveredFrames, s.poleFrame);
  EXPECT_EQ(s.impostorFrames, 1);  // 5 frames: the approach is frame 0
  EXPECT_GE(s.farFieldFrames, 1);
  EXPECT_EQ(s.impostorFrames + s.farFieldFrames + s.coveredFrames, 5);
  EXPECT_GE(s.poleFrame, 1);  // the pole pass comes after the approach
  // Frame 0: Mars's disc against the ellipsoid's apparent size from 16 a (the mean of its
  // radii; relief and flattening move the area by under 2 %), within the limb's pixels.
  const gl::RgbaImage first = gl::readPng(s.files.front().string());
  int disc = 0;
  for (int y = 0; y < first.height; ++y) {
    for (int x = 0; x < first.width; ++x) disc += first.is(x, y, 5, 5, 10) ? 0 : 1;
  }
  const double r = 0.5 * (mars.equatorialRadius() + mars.polarRadius());
  const double focal = 0.5 * o.height / std::tan(22.5 * 3.14159265358979 / 180.0);
  const double radiusPx = focal * std::tan(std::asin(r / o.approachFrom));
  const double expected = 3.14159265358979 * radiusPx * radiusPx;
  std::printf("approach frame 0: %d disc pixels, %.0f expected (radius %.1f px)\n", disc, expected,
              radiusPx);
  EXPECT_NEAR(disc, expected, 2.0 * 3.14159265358979 * radiusPx);  // one limb's width
  std::filesystem::remove_all(dir);
}

TEST(MarsVictoriaGLTest, ApproachFromMustBeADistance) {
  FlyoverOptions o;
  o.scene = small();
  for (const double bad : {-1.0, std::nan("")}) {
    o.approachFrom = bad;
    try {
      (void)renderFlyover(o);
      ADD_FAILURE() << "no error for " << bad;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("renderFlyover(): approachFrom"), std::string::npos)
          << e.what();
    }
  }
}

// The far field draws Mars beyond the planet clipmap, which keeps only its levels of at most
// 180°: frame by frame the planet covers the same pixels as when the clipmap drew every level
// (but at the limb, where PGM's grid and the clipmap's lattice cut it differently), and PGM
// drew in the frames where the planet is seen whole.
TEST(MarsVictoriaGLTest, FarFieldDrawsMarsBeyondTheClipmapWithoutGaps) {
  test::glContext();
  const auto dir = std::filesystem::path(::testing::TempDir()) / "regolith_farfield_flyover";
  std::filesystem::remove_all(dir);
  FlyoverOptions o;
  o.frames = 5;
  o.width = 192;
  o.height = 128;
  o.multiView = false;
  o.scene = small();
  o.outputDir = dir / "with";
  const FlyoverSummary with = renderFlyover(o);
  o.scene.farField = false;
  o.outputDir = dir / "without";
  const FlyoverSummary without = renderFlyover(o);
  EXPECT_GE(with.farFieldFrames, 2);
  EXPECT_EQ(without.farFieldFrames, 0);
  // Every frame either drew the far field or had it skipped, the view filled.
  std::printf("far field: PGM %d, impostor %d, covered %d of 5 frames\n", with.farFieldFrames,
              with.impostorFrames, with.coveredFrames);
  EXPECT_EQ(with.farFieldFrames + with.impostorFrames + with.coveredFrames, 5);
  EXPECT_EQ(without.coveredFrames, 0);
  for (std::size_t f = 0; f < 5; ++f) {
    const gl::RgbaImage a = gl::readPng(with.files[f].string());
    const gl::RgbaImage b = gl::readPng(without.files[f].string());
    const auto background = [](const gl::RgbaImage& img, int x, int y) {
      return img.is(x, y, 5, 5, 10);
    };
    int differ = 0, planet = 0;
    for (int y = 1; y + 1 < o.height; ++y) {
      for (int x = 1; x + 1 < o.width; ++x) {
        planet += background(b, x, y) ? 0 : 1;
        if (background(a, x, y) == background(b, x, y)) continue;
        // A pixel within one pixel of the limb (one of its 8 neighbours differs in the
        // reference) may go either way.
        bool limb = false;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            limb = limb || background(b, x + dx, y + dy) != background(b, x, y);
          }
        }
        if (!limb) {
          ++differ;
          ADD_FAILURE() << "frame " << f << ": pixel (" << x << ", " << y << ") differs";
        }
      }
    }
    EXPECT_EQ(differ, 0) << "frame " << f << " (" << planet << " planet pixels)";
  }
  std::filesystem::remove_all(dir);
}

// With a rover position given (where a traverse stopped), the fly-over ends there: the ruts
// pressed only around that position show in the last frame, which they could not if the
// camera descended on the layout's rover 250 m away.
TEST(MarsVictoriaGLTest, FlyoverEndsAtTheGivenRoverWithItsTracks) {
  test::glContext();
  const auto dir = std::filesystem::path(::testing::TempDir()) / "regolith_flyover_rover_test";
  std::filesystem::remove_all(dir);
  auto tracks = std::make_shared<rover::TrackLayer>(0.05);
  std::array<rover::WheelImprint, 6> step;
  for (double y = -253.0; y <= -225.0; y += 0.05) {  // northwards, under the rover and ahead
    for (std::size_t w = 0; w < 6; ++w)
      step[w] = {{120.0 + (w % 2 == 0 ? -1.1 : 1.1), y + 1.1 - 1.05 * static_cast<double>(w / 2)},
                 0.4,
                 0.05};
    tracks->step(step);
  }
  FlyoverOptions o;
  o.frames = 3;
  o.width = 96;
  o.height = 64;
  o.multiView = false;
  o.scene = small();
  o.rover = glm::dvec3{120.0, -250.0, 0.0};
  o.outputDir = dir / "plain";
  const FlyoverSummary plain = renderFlyover(o);
  o.outputDir = dir / "tracks";
  o.scene.victoriaEffects.tracks = tracks;
  const FlyoverSummary tracked = renderFlyover(o);
  ASSERT_EQ(plain.files.size(), 3U);
  ASSERT_EQ(tracked.files.size(), 3U);
  EXPECT_NEAR(tracked.endDistance, 6.0, 0.5);
  const gl::RgbaImage a = gl::readPng(plain.files.back().string());
  const gl::RgbaImage b = gl::readPng(tracked.files.back().string());
  const auto* centre = a.pixel(48, 32);  // the rover, grey
  EXPECT_NEAR(centre[0], centre[1], 8);
  EXPECT_NEAR(centre[1], centre[2], 8);
  int darker = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) darker += b.pixel(x, y)[1] + 4 < a.pixel(x, y)[1] ? 1 : 0;
  EXPECT_GT(darker, 20);  // the ruts, darker than the bare ground
  o.rover = glm::dvec3{std::nan(""), 0.0, 0.0};
  EXPECT_THROW((void)renderFlyover(o), InvalidArgument);
  std::filesystem::remove_all(dir);
}

TEST(MarsVictoriaGLTest, FlyoverCameraEndsLookingAtTheRover) {
  const glm::dvec3 rover{0.0, -395.0, 5.0};
  for (const double t : {0.0, 0.5, 1.0}) {
    const Pose cam = flyoverCamera(t, rover);
    const glm::dvec3 inEye = cam.inverse().apply(rover + glm::dvec3(0.0, 0.0, 0.8));
    EXPECT_NEAR(inEye.x, 0.0, 1e-6 * glm::length(inEye));
    EXPECT_NEAR(inEye.y, 0.0, 1e-6 * glm::length(inEye));
    EXPECT_LT(inEye.z, 0.0);
  }
}

TEST(MarsVictoriaGLTest, SceneFromStoresEqualsTheGeneratedScene) {
  // The same Mars and Victoria written as stores (as `regolith demo` writes them) and drawn
  // paged: same placement, same heights, and the same fly-over frames as the scene that
  // generates them in memory.
  test::glContext();
  const MarsVictoriaOptions mem = small();
  const scene::Scene generated = buildScene(mem);
  const auto originOf = [](const scene::Scene& s) {
    for (const scene::SceneTerrain& t : s.terrains())
      if (t.name == "victoria") return t.origin;
    ADD_FAILURE() << "no DEM victoria";
    return topo::Geodetic{};
  };
  const auto dir = std::filesystem::path(::testing::TempDir()) / "regolith_scene_stores";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  store::MarsPlanetOptions po;
  po.rows = mem.planetRows;
  po.seed = mem.seed;
  po.ellipsoid = true;
  po.write.levels = 7;  // the in-memory pyramid goes on down to 2 × 2; the clipmap's
                        // coarsest usable level is the same either way
  store::MarsPlanetGenerator(po).write(dir / "mars.h5");
  store::VictoriaOptions vo;
  vo.size = mem.demSize;
  vo.spacing = mem.demSpacing;
  vo.seed = mem.seed;
  vo.originHeight = originOf(generated).height;
  vo.write.levels = 6;
  store::VictoriaGenerator(vo).write(dir / "victoria.h5");

  MarsVictoriaOptions fromStores = mem;
  fromStores.marsStore = dir / "mars.h5";
  fromStores.victoriaStore = dir / "victoria.h5";
  const scene::Scene paged = buildScene(fromStores);
  const topo::Geodetic a = originOf(generated), b = originOf(paged);
  EXPECT_NEAR(a.latDeg, b.latDeg, 1e-12);
  EXPECT_NEAR(a.lonDeg, b.lonDeg, 1e-12);
  EXPECT_EQ(a.height, b.height);
  const topo::Body& ga = *generated.terrain("mars").body();
  const topo::Body& pa = *paged.terrain("mars").body();
  EXPECT_EQ(ga.equatorialRadius(), pa.equatorialRadius());
  EXPECT_EQ(ga.polarRadius(), pa.polarRadius());
  for (const glm::dvec2 p :
       {glm::dvec2{0.0, 0.0}, glm::dvec2{-395.5, 12.25}, glm::dvec2{300, -410}})
    EXPECT_EQ(generated.demHeight("victoria", p.x, p.y), paged.demHeight("victoria", p.x, p.y))
        << p.x << ", " << p.y;

  FlyoverOptions o;
  o.frames = 4;
  o.width = 96;
  o.height = 64;
  o.multiView = false;
  o.outputDir = dir / "generated";
  o.scene = mem;
  const FlyoverSummary s1 = renderFlyover(o);
  o.outputDir = dir / "paged";
  o.scene = fromStores;
  const FlyoverSummary s2 = renderFlyover(o);
  ASSERT_EQ(s1.files.size(), s2.files.size());
  for (std::size_t i = 0; i < s1.files.size(); ++i) {
    const gl::RgbaImage x = gl::readPng(s1.files[i].string());
    const gl::RgbaImage y = gl::readPng(s2.files[i].string());
    double diff = 0.0;
    for (std::size_t k = 0; k < x.rgba.size(); ++k)
      diff += std::abs(static_cast<int>(x.rgba[k]) - static_cast<int>(y.rgba[k]));
    EXPECT_LT(diff / static_cast<double>(x.rgba.size()), 1.0) << "frame " << i;
  }
  // A DEM given as the planet is refused, naming the grid, the file and both kinds.
  MarsVictoriaOptions swapped = fromStores;
  swapped.marsStore = dir / "victoria.h5";
  swapped.marsGrid = swapped.victoriaGrid;
  try {
    const scene::Scene s = buildScene(swapped);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()), "Scene: /bodies/0/heights/0: grid '" + swapped.victoriaGrid +
                                         "' is not a planet grid");
  }
  std::filesystem::remove_all(dir);

  MarsVictoriaOptions half = mem;
  half.marsStore = dir / "mars.h5";
  EXPECT_THROW((void)buildScene(half), InvalidArgument);
}

TEST(MarsVictoriaGLTest, FlyoverOverABuiltSceneNeedsTheDemoNames) {
  // A scene without the rover: refused before anything is drawn, naming what is missing.
  scene::SceneDescription d = sceneDescription(small());
  d.objects.clear();
  d.cameras.clear();  // the paper's cameras: two of them ride on the rover
  scene::Scene s(d);
  FlyoverOptions o;
  o.frames = 2;
  o.outputDir = std::filesystem::path(::testing::TempDir()) / "regolith_flyover_names";
  try {
    (void)renderFlyover(s, o);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(
        std::string(e.what()),
        "renderFlyover(): the scene's object 'rover' is missing, expected the demo scene's body "
        "\"mars\", DEM \"victoria\" and object \"rover\" (demo::sceneDescription())");
  }
  try {
    (void)paperCameraNodes(s);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              "demo::paperCameraNodes(): the scene's camera 'orbit_camera' is missing, expected "
              "the paper's cameras (demo::paperCameras(), declared by demo::sceneDescription())");
  }
  EXPECT_FALSE(std::filesystem::exists(o.outputDir));
}

TEST(MarsVictoriaGLTest, RejectsBadOptions) {
  FlyoverOptions o;
  o.frames = 1;
  EXPECT_THROW(renderFlyover(o), InvalidArgument);
  o.frames = 2;
  o.width = 0;
  EXPECT_THROW(renderFlyover(o), InvalidArgument);
}

}  // namespace
}  // namespace regolith::demo
