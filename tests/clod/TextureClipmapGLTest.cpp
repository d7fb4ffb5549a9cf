// The texture clipmap: an albedo store 16K wide (twice the 8K limit the paper's GPUs had)
// drawn through 512² windows at the resolution each view needs.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/TextureClipmap.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>

#include "EffectFixtures.hpp"
#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"
#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace regolith::clod {
namespace {

constexpr std::size_t kCols = 16384, kRows = 256;
constexpr double kTexel = 0.25;                  // metres
constexpr double kWest = -0.5 * kCols * kTexel;  // −2048 m
constexpr double kNorth = 0.5 * kRows * kTexel;  // 32 m

// Albedo: a ramp from west to east plus stripes 1 m apart (4 texels), which average out at
// any level coarser than level 1.
double ramp(double x) { return 0.15 + 0.6 * (x - kWest) / (kCols * kTexel); }
double albedo(double x) { return ramp(x) + 0.2 * std::sin(2.0 * std::numbers::pi * x); }

std::shared_ptr<const HeightPyramid> albedoStore() {
  store::GridInfo info;
  info.name = "albedo";
  info.rows = kRows;
  info.cols = kCols;
  info.x0 = kWest + 0.5 * kTexel;
  info.y0 = kNorth - 0.5 * kTexel;
  info.spacingX = info.spacingY = kTexel;
  info.units = "1";
  const auto samples =
      topo::InMemorySamples::fromFunction(kRows, kCols, [&](std::size_t, std::size_t c) {
        return static_cast<float>(albedo(info.x0 + static_cast<double>(c) * kTexel));
      });
  const auto path = test::scratchFile("TextureClipmapGLTest", "albedo16k.h5");
  const store::GridSource src{info, samples};
  store::WriteOptions w;
  w.threads = 2;
  store::writeStore(path, std::span(&src, 1), w);
  auto st = std::make_shared<const store::Store>(store::Store::open(path));
  auto cache = std::make_shared<store::PatchCache>(std::size_t{64} << 20);
  const store::Pager pager(st, cache);
  const store::GridInfo& stored = st->grid("albedo");
  std::vector<HeightPyramid::Level> levels;
  for (std::size_t l = 0; l < stored.levels; ++l)
    levels.push_back({store::topoGridOf(stored, l), pager.source("albedo", l)});
  return std::make_shared<const HeightPyramid>(std::move(levels), SurfaceKind::Plane);
}

// Level-0 bilinear filtering of the stored samples: what the finest level draws.
double bilinearAlbedo(double x) {
  const double f = (x - (kWest + 0.5 * kTexel)) / kTexel;
  const double c = std::floor(f), t = f - c;
  const auto at = [](double col) {
    return static_cast<double>(static_cast<float>(albedo(kWest + (col + 0.5) * kTexel)));
  };
  return (1.0 - t) * at(c) + t * at(c + 1.0);
}

TEST(TextureClipmapGLTest, AnAlbedoStore16KWideIsDrawnAtTheResolutionTheViewNeeds) {
  test::glContext();
  const auto texture = albedoStore();
  ASSERT_EQ(texture->level(0).grid.cols(), kCols);
  GLint maxSize = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxSize);
  // Flat ground under the whole strip, heights 8 m apart.
  const auto ground =
      test::planePyramid(test::centredGrid(17, 513, 8.0), [](double, double) { return 0.0; });
  ClipmapOptions opt;
  opt.size = 63;
  opt.lightDirection = {0.0F, 0.0F, 1.0F};  // straight down: colour = albedo
  opt.ambient = 0.0F;
  opt.effects.albedo = DrapedTexture{{texture}, 512, 1.0F};
  ClipmapTerrain terrain(ground, opt);

  // Close up near the east end (column ~15600, beyond any 8K texture): level 0, bilinear.
  const double x = 1850.0;
  Camera cam = test::downCamera({x, 0.0, 0.0}, 5.0, 160, 120, 40.0);
  terrain.setFocus(cam.target);
  const test::Shot close = test::renderShot(terrain, cam);
  test::savePng("texture_clipmap_16k_close", close.color);
  int sampled = 0;
  double worst = 0.0;
  for (int py = 10; py < cam.height - 10; py += 7)
    for (int px = 2; px < cam.width - 2; px += 3) {
      const auto g = test::groundAt(close, cam, px, py);
      ASSERT_TRUE(g);
      const double expected = bilinearAlbedo(g->x);
      worst = std::max(worst, std::abs(close.color.pixel(px, py)[0] / 255.0 - expected));
      ++sampled;
    }
  EXPECT_GT(sampled, 500);
  EXPECT_LT(worst, 0.03);  // 8-bit texels and framebuffer, float interpolation

  // From 2.5 km up a pixel spans ~9 m: a coarse level draws, the 1 m stripes average out,
  // and every pixel shows the ramp (level 0 would alias them into ±0.2 noise).
  Camera high = test::downCamera({0.0, 0.0, 0.0}, 2500.0, 200, 60, 40.0);
  high.near = 10.0;
  terrain.setFocus(high.target);
  const test::Shot far = test::renderShot(terrain, high);
  test::savePng("texture_clipmap_16k_far", far.color);
  worst = 0.0;
  sampled = 0;
  for (int px = 2; px < high.width - 2; px += 2) {
    const auto g = test::groundAt(far, high, px, high.height / 2);
    if (!g || std::abs(g->x) > 2040.0) continue;  // the view is wider than the strip
    worst = std::max(worst, std::abs(far.color.pixel(px, high.height / 2)[0] / 255.0 - ramp(g->x)));
    ++sampled;
  }
  EXPECT_GT(sampled, 60);
  EXPECT_LT(worst, 0.04);

  // The GPU holds 512² windows, never the 16K source.
  TextureClipmap direct(DrapedTexture{{texture}, 512, 1.0F}, "albedo");
  EXPECT_EQ(direct.update({x, 0.0}),
            std::size_t{512} * 512 * static_cast<std::size_t>(direct.levels()));
  GLint w = 0;
  glGetTextureLevelParameteriv(direct.texture(), 0, GL_TEXTURE_WIDTH, &w);
  EXPECT_EQ(w, 512);
  EXPECT_LT(w, maxSize);
  EXPECT_EQ(direct.update({x + 10.0, 0.0}), 0U);   // a small move: no window moves
  EXPECT_GT(direct.update({x - 100.0, 0.0}), 0U);  // 400 texels: level 0 (and 1) follow

  // Background loading: requestFocus() returns before the texture windows are read; until
  // they are uploaded the old windows draw; finishLoading() gives the same frame as a
  // synchronous setFocus().
  const Camera west = test::downCamera({-1500.0, 0.0, 0.0}, 5.0, 160, 120, 40.0);
  terrain.setFocus(cam.target);
  terrain.requestFocus(west.target);
  EXPECT_TRUE(terrain.loading());
  terrain.finishLoading();
  EXPECT_FALSE(terrain.loading());
  const test::Shot background = test::renderShot(terrain, west);
  ClipmapTerrain direct2(ground, opt);
  direct2.setFocus(west.target);
  const test::Shot sync = test::renderShot(direct2, west);
  EXPECT_EQ(background.color.rgba, sync.color.rgba);
  // And it shows the albedo of that place, not the old window's edge.
  const auto g = test::groundAt(sync, west, 80, 60);
  ASSERT_TRUE(g);
  EXPECT_NEAR(sync.color.pixel(80, 60)[0] / 255.0, bilinearAlbedo(g->x), 0.03);
}

TEST(TextureClipmapGLTest, AColourOverlayBlendsOverTheLitTerrainWhereItHasData) {
  test::glContext();
  const auto ground =
      test::planePyramid(test::centredGrid(65, 65, 1.0), [](double, double) { return 0.0; });
  // A science map with data west of x = 0 only (NaN east of it): RGB (0.1, 0.8, 0.3).
  DrapedTexture map;
  for (double v : {0.1, 0.8, 0.3})
    map.channels.push_back(test::planePyramid(
        test::centredGrid(128, 128, 0.5),
        [v](double x, double) { return x < 0.0 ? v : std::numeric_limits<double>::quiet_NaN(); }));
  map.window = 64;
  map.opacity = 0.5F;
  ClipmapOptions opt;
  opt.size = 31;
  opt.lightDirection = {0.0F, 0.0F, 1.0F};
  opt.ambient = 0.0F;
  opt.effects.overlay = map;
  ClipmapTerrain terrain(ground, opt);
  const Camera cam = test::downCamera({0.0, 0.0, 0.0}, 40.0, 120, 80, 40.0);
  terrain.setFocus(cam.target);
  const test::Shot shot = test::renderShot(terrain, cam);
  test::savePng("overlay_science_map", shot.color);
  const glm::vec3 lit = opt.albedo, ov{0.1F, 0.8F, 0.3F};
  int west = 0, east = 0;
  for (int y = 5; y < cam.height - 5; y += 5)
    for (int x = 2; x < cam.width - 2; x += 3) {
      const auto g = test::groundAt(shot, cam, x, y);
      ASSERT_TRUE(g);
      if (std::abs(g->x) < 1.0 || std::abs(g->x) > 30.0 || std::abs(g->y) > 30.0) continue;
      const glm::vec3 want = g->x < 0.0 ? 0.5F * lit + 0.5F * ov : lit;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(shot.color.pixel(x, y)[c] / 255.0, static_cast<double>(want[c]), 2.5 / 255.0)
            << x << "," << y;
      (g->x < 0.0 ? west : east) += 1;
    }
  EXPECT_GT(west, 100);
  EXPECT_GT(east, 100);
}

// On a planet the grid is longitude/latitude: the albedo drapes in degrees, on the lat/lon
// lattice and on the polar lattice near a pole (grid point from the position there).
TEST(TextureClipmapGLTest, AnAlbedoDrapesOverAPlanetInLongitudeAndLatitude) {
  test::glContext();
  const double r = topo::Body::marsSphere().equatorialRadius();
  const topo::TopoGrid grid(90, 180, -179.0, 89.0, 2.0, 2.0);
  auto zero = std::make_shared<topo::InMemorySamples>(90, 180, std::vector<float>(90 * 180, 0.0F));
  const auto planet = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, zero, SurfaceKind::Planet, topo::Body::marsSphere()));
  // Albedo: waves 8° by 10° long, 0.2° samples (bilinear filtering is then exact to 0.001).
  const auto a = [](double lon, double lat) {
    return 0.5 + 0.35 * std::sin(2.0 * M_PI * lon / 8.0) * std::cos(2.0 * M_PI * lat / 10.0);
  };
  const topo::TopoGrid tgrid(900, 1800, -179.9, 89.9, 0.2, 0.2);
  auto samples =
      topo::InMemorySamples::fromFunction(900, 1800, [&](std::size_t row, std::size_t col) {
        const auto p = tgrid.sampleCentre(static_cast<double>(row), static_cast<double>(col));
        return static_cast<float>(a(p.x, p.y));
      });
  const auto texture = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(tgrid, samples, SurfaceKind::Plane));
  ClipmapOptions opt;
  opt.size = 31;
  opt.ambient = 1.0F;  // colour = albedo, whatever the normal
  opt.effects.albedo = DrapedTexture{{texture}, 256, 1.0F};
  ClipmapTerrain terrain(planet, opt);
  for (const auto& [lat, lon] : {std::pair{10.0, 30.0}, std::pair{70.0, -100.0}}) {
    SCOPED_TRACE(lat);
    const double la = lat * M_PI / 180.0, lo = lon * M_PI / 180.0;
    const glm::dvec3 u{std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la)};
    Camera cam;
    cam.position = u * (r + 600e3);
    cam.target = u * r;
    cam.up = {0.0, 0.0, 1.0};
    cam.width = cam.height = 96;
    cam.near = 100.0;
    terrain.setFocus(cam.target);
    const test::Shot shot = test::renderShot(terrain, cam);
    test::savePng("texture_clipmap_planet_" + std::to_string(static_cast<int>(lat)), shot.color);
    int sampled = 0;
    double worst = 0.0;
    for (int y = 4; y < cam.height - 4; y += 6)
      for (int x = 4; x < cam.width - 4; x += 6) {
        const auto p = test::groundAt(shot, cam, x, y);
        ASSERT_TRUE(p);
        const double plon = std::atan2(p->y, p->x) * 180.0 / M_PI;
        const double plat = std::asin(p->z / glm::length(*p)) * 180.0 / M_PI;
        worst = std::max(worst, std::abs(shot.color.pixel(x, y)[0] / 255.0 - a(plon, plat)));
        ++sampled;
      }
    EXPECT_GT(sampled, 150);
    // Lat/lon lattice: the grid point is linear across each cell. Polar lattice: it is
    // computed per fragment from the position (interpolated from the vertices of 2° cells it
    // was off by ~0.1° of longitude at 70°, 0.025 of this albedo).
    EXPECT_LT(worst, 0.01);
  }
}

TEST(TextureClipmapGLTest, RejectsBadTextures) {
  test::glContext();
  const auto a =
      test::planePyramid(test::centredGrid(64, 64, 1.0), [](double, double) { return 0.5; });
  const auto b =
      test::planePyramid(test::centredGrid(64, 32, 1.0), [](double, double) { return 0.5; });
  EXPECT_THROW(TextureClipmap(DrapedTexture{{a, b, a}, 512, 1.0F}, "overlay"), InvalidArgument);
  EXPECT_THROW(TextureClipmap(DrapedTexture{{a, nullptr, a}, 512, 1.0F}, "overlay"),
               InvalidArgument);
  EXPECT_THROW(TextureClipmap(DrapedTexture{{a}, 32, 1.0F}, "overlay"), InvalidArgument);
  EXPECT_THROW(TextureClipmap(DrapedTexture{{}, 512, 1.0F}, "overlay"), InvalidArgument);
}

}  // namespace
}  // namespace regolith::clod
