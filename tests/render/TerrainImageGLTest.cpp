// render::renderTerrain(): one terrain drawn through the scene renderer (`regolith render`).
// Oracles: clod::renderImage() (the clipmap alone, drawn without a scene graph) for a DEM,
// pixel for pixel; the planet's disc seen from 3 radii (angular radius asin(1/3)) for the
// far field.
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/render/TerrainImage.hpp>
#include <regolith/topo/Body.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include "clod/TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

namespace regolith::render {
namespace {

using clod::HeightPyramid;

/// Pixels whose colour differs by more than one level in some channel.
int differing(const gl::RgbaImage& a, const gl::RgbaImage& b) {
  int n = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const auto* p = a.pixel(x, y);
      const auto* q = b.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        if (std::abs(static_cast<int>(p[c]) - static_cast<int>(q[c])) > 1) {
          ++n;
          break;
        }
      }
    }
  }
  return n;
}

std::string messageOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

// A 1025 m square of hills seen obliquely from one corner at a point near the other: small
// clipmap windows (63 vertices), so where the clipmap is centred shows in the image.
struct HillsView {
  std::shared_ptr<const HeightPyramid> pyramid =
      test::planePyramid(test::centredGrid(1025, 1025, 1.0), test::hills);
  clod::RenderRequest request;
  HillsView() {
    request.clipmap.size = 63;
    request.clipmap.effects.heightColours = clod::HeightColours{-1480.0, -1370.0, true};
    const glm::dvec3 target{250.0, 250.0, test::hills(250.0, 250.0)};
    request.camera.position = {-400.0, -400.0, -1100.0};
    request.camera.target = target;
    request.camera.up = {0.0, 0.0, 1.0};
    request.camera.fovYDegrees = 40.0;
    request.camera.width = 320;
    request.camera.height = 240;
    request.camera.near = 0.5;
  }
};

TEST(RenderTerrainGL, ADemLooksAsClodDrawsItCentredOnTheLookAtPointWithItsLegend) {
  test::glContext();
  const HillsView v;
  const gl::RgbaImage clodImage = clod::renderImage(v.pyramid, v.request);
  const TerrainImage drawn = renderTerrain(v.pyramid, v.request);
  test::savePng("render_terrain_dem", drawn.image);
  ASSERT_EQ(drawn.image.width, 320);
  ASSERT_EQ(drawn.image.height, 240);
  // The scene renderer draws the same clipmap from the same camera: at most a few pixels
  // apart (the camera's frame is rebuilt from its pose, in double).
  EXPECT_LE(differing(drawn.image, clodImage), 320 * 240 / 1000);
  ASSERT_TRUE(drawn.legend.has_value());
  EXPECT_FALSE(drawn.legend->empty());
  // Centred under the camera instead (the scene renderer's default), the ground around the
  // look-at point is drawn from coarser levels: a different image, so the centre is
  // honoured.
  clod::RenderRequest underCamera = v.request;
  underCamera.focus = v.request.camera.position;
  const TerrainImage other = renderTerrain(v.pyramid, underCamera);
  EXPECT_GT(differing(other.image, drawn.image), 320 * 240 / 50);
  // Without the legend in the image, the legend is still returned, and the corner differs.
  clod::RenderRequest noLegend = v.request;
  noLegend.legendInImage = false;
  const TerrainImage bare = renderTerrain(v.pyramid, noLegend);
  EXPECT_TRUE(bare.legend.has_value());
  EXPECT_GT(differing(bare.image, drawn.image), 100);
}

TEST(RenderTerrainGL, ThePngAndTheLegendAreWrittenBeside) {
  test::glContext();
  const HillsView v;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("regolith_render_terrain_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "dem.png").string();
  renderTerrainToPng(v.pyramid, v.request, std::nullopt, path);
  const gl::RgbaImage back = gl::readPng(path);
  EXPECT_EQ(differing(back, renderTerrain(v.pyramid, v.request).image), 0);
  EXPECT_TRUE(std::filesystem::exists(path + ".legend.json"));
  std::filesystem::remove_all(dir);
}

TEST(RenderTerrainGL, APlanetsFarFieldDrawsTheDiscWholeBeyondItsClipmap) {
  test::glContext();
  // A 0.2° Mars: its clipmap levels whose window spans at most 180° reach about 102° around
  // the point under the camera, less than the 141° of ground seen from 3 radii, so the
  // clipmap alone leaves the disc's rim empty; the far field fills it.
  const topo::Body mars = topo::Body::marsSphere();
  const topo::TopoGrid grid(900, 1800, -179.9, 89.9, 0.2, 0.2);
  const auto samples =
      topo::InMemorySamples::fromFunction(900, 1800, [](std::size_t r, std::size_t c) {
        return static_cast<float>(2000.0 * std::sin(0.02 * static_cast<double>(r)) *
                                  std::cos(0.01 * static_cast<double>(c)));
      });
  const auto pyramid = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, clod::SurfaceKind::Planet, mars));
  clod::RenderRequest request;
  request.clipmap.size = 255;
  std::size_t levels = 0;
  while (levels < pyramid->levelCount() &&
         254.0 * std::abs(pyramid->level(levels).grid.spacingY()) <= 180.0) {
    ++levels;
  }
  request.clipmap.levels = levels;
  request.background = {0.02F, 0.02F, 0.04F, 1.0F};
  const double radius = mars.equatorialRadius();
  request.camera.position = {3.0 * radius, 0.0, 0.0};
  request.camera.target = {0.0, 0.0, 0.0};
  request.camera.up = {0.0, 0.0, 1.0};
  request.camera.fovYDegrees = 45.0;
  request.camera.width = 160;
  request.camera.height = 120;
  request.camera.near = 1000.0;
  request.focus = pyramid->position(0.0, 0.0, 0.0);  // the ground under the camera
  const TerrainFarField far{
      std::make_shared<const farfield::HeightLayers>(farfield::HeightLayers::fromPlanetGrid(
          mars, grid, *pyramid->level(0).source, topo::LatitudeType::Planetocentric)),
      {}};
  const double disc =
      60.0 * std::tan(std::asin(1.0 / 3.0)) / std::tan(22.5 * std::numbers::pi / 180.0);
  const auto count = [&](const gl::RgbaImage& im, bool sky, double lo, double hi) {
    int n = 0;
    for (int y = 0; y < im.height; ++y) {
      for (int x = 0; x < im.width; ++x) {
        const double r = std::hypot(x + 0.5 - 80.0, y + 0.5 - 60.0);
        n += r >= lo * disc && r < hi * disc && im.is(x, y, 5, 5, 10) == sky ? 1 : 0;
      }
    }
    return n;
  };
  const TerrainImage nearOnly = renderTerrain(pyramid, request);
  test::savePng("render_terrain_planet_near_only", nearOnly.image);
  EXPECT_GT(count(nearOnly.image, true, 0.0, 0.95), 50) << "the clipmap alone leaves a rim";
  const TerrainImage whole = renderTerrain(pyramid, request, far);
  test::savePng("render_terrain_planet_far_field", whole.image);
  EXPECT_EQ(count(whole.image, true, 0.0, 0.95), 0) << "sky inside the disc";
  EXPECT_EQ(count(whole.image, false, 1.15, 10.0), 0) << "planet beyond the disc";
  EXPECT_FALSE(whole.legend.has_value());  // nothing declared
}

TEST(RenderTerrainGL, BadRequestsAreRefusedByName) {
  test::glContext();
  const HillsView v;
  EXPECT_EQ(messageOf([&] { (void)renderTerrain(nullptr, v.request); }),
            "render::renderTerrain(): pyramid is null");
  clod::RenderRequest bad = v.request;
  bad.camera.fovYDegrees = 0.0;
  EXPECT_EQ(messageOf([&] { (void)renderTerrain(v.pyramid, bad); }),
            "render::renderTerrain(): field of view is 0 deg, expected inside (0, 180)");
  bad = v.request;
  bad.camera.position = {0.0, 0.0, -1500.0};  // below the hills
  EXPECT_NE(messageOf([&] {
              (void)renderTerrain(v.pyramid, bad);
            }).find("render::renderTerrain(): camera position is (0, 0, -1500) m"),
            std::string::npos);
  const topo::Body mars = topo::Body::marsSphere();
  const topo::TopoGrid coarse(90, 180, -179.0, 89.0, 2.0, 2.0);
  const TerrainFarField far{
      std::make_shared<const farfield::HeightLayers>(farfield::HeightLayers::fromPlanetGrid(
          mars, coarse, topo::InMemorySamples(90, 180, std::vector<float>(90 * 180, 0.0F)),
          topo::LatitudeType::Planetocentric)),
      {}};
  EXPECT_NE(messageOf([&] { (void)renderTerrain(v.pyramid, v.request, far); })
                .find("render::renderTerrain(): a far field was given for a terrain not drawn "
                      "body-fixed"),
            std::string::npos);
}

}  // namespace
}  // namespace regolith::render
