// Image tests of the declared effects: height colours against the legend, lat/lon lines at
// their projected pixels, tracks exactly where the wheels touched, noise only where declared.
// PNGs go to $REGOLITH_TEST_PNG_DIR.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/Legend.hpp>
#include <regolith/clod/Render.hpp>
#include <regolith/rover/TrackLayer.hpp>
#include <regolith/topo/Placement.hpp>

#include "EffectFixtures.hpp"
#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace regolith::clod {
namespace {

// ---- Height colours ----------------------------------------------------------------------

TEST(EffectImagesGLTest, HeightColoursMatchTheLegendAtSampledPixels) {
  test::glContext();
  const auto grid = test::centredGrid(257, 257, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  ClipmapOptions opt;
  opt.size = 63;
  opt.effects.heightColours = HeightColours{-1460.0F, -1370.0F, false};
  ClipmapTerrain terrain(pyramid, opt);
  Camera cam;
  cam.position = {-60.0, -170.0, -1400.0 + 130.0};
  cam.target = {0.0, 0.0, -1420.0};
  cam.width = 256;
  cam.height = 192;
  cam.near = 1.0;
  terrain.setFocus(cam.target);
  test::Shot shot = test::renderShot(terrain, cam);
  const Legend legend = Legend::of(terrain, cam);
  ASSERT_FALSE(legend.empty());
  const gl::RgbaImage key = legend.image();
  const Legend::Bar bar = legend.bar();
  // Reads a pixel's height off the legend: the bar row of the nearest colour.
  const auto legendHeight = [&](const std::uint8_t* p) {
    int best = bar.y0;
    int bestD = std::numeric_limits<int>::max();
    for (int y = bar.y0; y < bar.y1; ++y) {
      const auto* q = key.pixel((bar.x0 + bar.x1) / 2, y);
      int d = 0;
      for (int c = 0; c < 3; ++c) d += (int{p[c]} - int{q[c]}) * (int{p[c]} - int{q[c]});
      if (d < bestD) {
        bestD = d;
        best = y;
      }
    }
    return legend.heightAtRow(best);
  };
  const double row = static_cast<double>(opt.effects.heightColours->maxHeight -
                                         opt.effects.heightColours->minHeight) /
                     static_cast<double>(bar.y1 - bar.y0);
  int sampled = 0;
  double worst = 0.0;
  for (int y = 4; y < cam.height - 4; y += 11)
    for (int x = 4; x < cam.width - 4; x += 13) {
      if (!shot.depth.smoothAt(x, y, cam.near, 0.01)) continue;
      const auto g = test::groundAt(shot, cam, x, y);
      if (!g) continue;
      const double h = test::hills(g->x, g->y);
      if (h < -1458.0 || h > -1372.0) continue;  // clamped ends of the ramp are ambiguous
      worst = std::max(worst, std::abs(legendHeight(shot.color.pixel(x, y)) - h));
      ++sampled;
    }
  EXPECT_GT(sampled, 150);
  // One bar row (0.7 m) of quantisation, plus the 8-bit colour and the clipmap's linear
  // interpolation between samples (1 m apart near the focus, coarser farther out).
  EXPECT_LT(worst, 2.0 * row + 1.5);
  legend.drawInto(shot.color);
  test::savePng("effects_height_colours", shot.color);
  test::savePng("effects_height_legend", key);
  // The legend beside the image: JSON with the range and the stops.
  const auto path = (std::filesystem::temp_directory_path() / "regolith_legend_test.json").string();
  legend.writeJson(path);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove(path);
  EXPECT_NE(text.str().find("\"min\": -1460"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("\"max\": -1370"), std::string::npos) << text.str();
}

TEST(EffectImagesGLTest, RenderToPngDrawsTheLegendAndWritesItBeside) {
  test::glContext();
  const auto pyramid = test::planePyramid(test::centredGrid(129, 129, 1.0), test::hills);
  RenderRequest req;
  req.camera = test::downCamera({0.0, 0.0, -1400.0}, 150.0, 320, 200, 50.0);
  req.clipmap.size = 31;
  req.clipmap.effects.heightColours = HeightColours{-1460.0F, -1370.0F, false};
  const auto path =
      (std::filesystem::temp_directory_path() / "regolith_legend_render.png").string();
  renderToPng(pyramid, req, path);
  const gl::RgbaImage img = gl::readPng(path);
  std::ifstream in(path + ".legend.json");
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove(path);
  std::filesystem::remove(path + ".legend.json");
  EXPECT_EQ(text.str(), Legend(req.clipmap.effects.heightColours, std::nullopt).json());
  // The legend sits in the top-right corner: its bar's top row is the ramp's last stop.
  const Legend legend(req.clipmap.effects.heightColours, std::nullopt);
  const gl::RgbaImage key = legend.image();
  const int x0 = img.width - key.width - 8, y0 = 8;
  const auto b = legend.bar();
  for (int y = b.y0; y < b.y1; y += 9) {
    const auto* want = key.pixel(b.x0 + 2, y);
    EXPECT_TRUE(img.is(x0 + b.x0 + 2, y0 + y, want[0], want[1], want[2])) << y;
  }
  test::savePng("effects_render_with_legend", img);
}

// ---- Lat/lon lines -----------------------------------------------------------------------

glm::dvec3 onSphere(double r, double latDeg, double lonDeg) {
  const double la = latDeg * M_PI / 180.0, lo = lonDeg * M_PI / 180.0;
  return r * glm::dvec3(std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la));
}

bool isLine(const gl::RgbaImage& img, int x, int y) { return img.is(x, y, 0, 255, 255); }
bool lineNear(const gl::RgbaImage& img, double px, double py) {
  const int x = static_cast<int>(std::floor(px)), y = static_cast<int>(std::floor(py));
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (isLine(img, x + dx, y + dy)) return true;
  return false;
}

TEST(EffectImagesGLTest, LatLonLinesFallAtTheirProjectedPixelsAndAdaptToZoom) {
  test::glContext();
  const double r = topo::Body::marsSphere().equatorialRadius();
  const topo::TopoGrid grid(90, 180, -179.0, 89.0, 2.0, 2.0);
  auto zero = std::make_shared<topo::InMemorySamples>(90, 180, std::vector<float>(90 * 180, 0.0F));
  const auto pyramid = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, zero, SurfaceKind::Planet, topo::Body::marsSphere()));
  ClipmapOptions opt;
  opt.size = 31;
  opt.effects.latLon = LatLonLines{5.0, 80.0, {0.0F, 1.0F, 1.0F}, 1.5F};
  opt.lightDirection = {1.0F, 0.0F, 0.0F};
  ClipmapTerrain terrain(pyramid, opt);
  Camera cam;
  cam.position = onSphere(r + 900e3, 0.0, 0.0);
  cam.target = {0.0, 0.0, 0.0};
  cam.up = {0.0, 0.0, 1.0};
  cam.fovYDegrees = 50.0;
  cam.width = 240;
  cam.height = 240;
  cam.near = 1000.0;
  terrain.setFocus(onSphere(r, 0.0, 0.0));
  const test::Shot shot = test::renderShot(terrain, cam);
  test::savePng("effects_latlon_planet", shot.color);
  int checked = 0;
  // Meridians, crossing the parallel at 2.5° (midway between two lines of latitude), and
  // the midpoints between them.
  for (double lon = -15.0; lon <= 15.0; lon += 5.0) {
    const glm::dvec3 on = cam.project(onSphere(r, 2.5, lon));
    const glm::dvec3 off = cam.project(onSphere(r, 2.5, lon + 2.5));
    if (on.x < 3 || on.x > cam.width - 3) continue;
    EXPECT_TRUE(lineNear(shot.color, on.x, on.y)) << "meridian " << lon << " at " << on.x;
    if (off.x > 3 && off.x < cam.width - 3) {
      EXPECT_FALSE(lineNear(shot.color, off.x, off.y)) << "between meridians at " << lon + 2.5;
    }
    ++checked;
  }
  for (double lat = -15.0; lat <= 15.0; lat += 5.0) {
    const glm::dvec3 on = cam.project(onSphere(r, lat, 2.5));
    const glm::dvec3 off = cam.project(onSphere(r, lat + 2.5, 2.5));
    if (on.y < 3 || on.y > cam.height - 3) continue;
    EXPECT_TRUE(lineNear(shot.color, on.x, on.y)) << "parallel " << lat << " at " << on.y;
    if (off.y > 3 && off.y < cam.height - 3) {
      EXPECT_FALSE(lineNear(shot.color, off.x, off.y)) << "between parallels at " << lat + 2.5;
    }
    ++checked;
  }
  EXPECT_GE(checked, 6);
  // Lines are thin: most of the disk is terrain.
  int lines = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) lines += isLine(shot.color, x, y) ? 1 : 0;
  EXPECT_LT(lines, cam.width * cam.height / 6);
  EXPECT_GT(lines, cam.width * 6);

  // Adaptive spacing: ten times closer, a tenth-ish of the spacing; the legend names it.
  ClipmapOptions adaptive = opt;
  adaptive.effects.latLon->spacingDegrees = 0.0;
  ClipmapTerrain zoomed(pyramid, adaptive);
  Camera close = cam;
  close.position = onSphere(r + 90e3, 0.0, 0.0);
  const double far = zoomed.latLonSpacing(cam), near = zoomed.latLonSpacing(close);
  EXPECT_LT(near, far / 4.0);
  // At least minPixelSpacing apart at the ground below the camera, but not 3 times more.
  const double degPerPixel = 90e3 / close.focalPixels() / r * 180.0 / M_PI;
  EXPECT_GE(near / degPerPixel, 80.0);
  EXPECT_LT(near / degPerPixel, 3.0 * 80.0);
  EXPECT_EQ(Legend::of(zoomed, close).latLonSpacing(), near);
  zoomed.setFocus(onSphere(r, 0.0, 0.0));
  gl::RgbaImage closeImage = test::renderShot(zoomed, close).color;
  Legend::of(zoomed, close).drawInto(closeImage);
  test::savePng("effects_latlon_planet_zoomed", closeImage);
}

TEST(EffectImagesGLTest, LatLonLinesOnADemPlacedOnAPlanet) {
  test::glContext();
  const topo::Body mars = topo::Body::marsSphere();
  const topo::LocalTangentPlane plane(mars, {0.0, 0.0, 0.0}, 0.0);
  const topo::Placement placement(plane);
  const auto grid = test::centredGrid(257, 257, 8.0);  // 2 km square at the equator
  auto zero =
      std::make_shared<topo::InMemorySamples>(257, 257, std::vector<float>(257 * 257, 0.0F));
  const auto pyramid =
      std::make_shared<const HeightPyramid>(HeightPyramid::fromSamples(grid, zero, placement));
  ClipmapOptions opt;
  opt.size = 63;
  opt.effects.latLon = LatLonLines{0.005, 80.0, {0.0F, 1.0F, 1.0F}, 1.5F};  // ≈ 296 m
  ClipmapTerrain terrain(pyramid, opt);
  Camera cam;
  cam.position = placement.toBodyFixed(0.0, 0.0, 2500.0);
  cam.target = placement.toBodyFixed(0.0, 0.0, 0.0);
  cam.up = placement.toBodyFixed(0.0, 1.0, 0.0) - cam.target;
  cam.width = 200;
  cam.height = 200;
  cam.near = 1.0;
  terrain.setFocus(cam.target);
  const test::Shot shot = test::renderShot(terrain, cam);
  test::savePng("effects_latlon_placed_dem", shot.color);
  int checked = 0;
  for (int k = -3; k <= 3; ++k) {
    const double d = 0.005 * k;
    const glm::dvec3 meridian = cam.project(onSphere(mars.equatorialRadius(), 0.0025, d));
    const glm::dvec3 parallel = cam.project(onSphere(mars.equatorialRadius(), d, 0.0025));
    const glm::dvec3 between = cam.project(onSphere(mars.equatorialRadius(), 0.0025, d + 0.0025));
    if (meridian.x > 3 && meridian.x < cam.width - 3) {
      EXPECT_TRUE(lineNear(shot.color, meridian.x, meridian.y)) << "meridian " << d;
      ++checked;
    }
    if (parallel.y > 3 && parallel.y < cam.height - 3) {
      EXPECT_TRUE(lineNear(shot.color, parallel.x, parallel.y)) << "parallel " << d;
      ++checked;
    }
    if (between.x > 3 && between.x < cam.width - 3) {
      EXPECT_FALSE(lineNear(shot.color, between.x, between.y)) << "between " << d;
    }
  }
  EXPECT_GE(checked, 8);
}

// ---- Tracks ------------------------------------------------------------------------------

double segmentDistance(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
  const glm::dvec2 ab = b - a;
  const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

TEST(EffectImagesGLTest, TracksAppearExactlyWhereTheWheelsTouched) {
  test::glContext();
  const auto grid = test::centredGrid(129, 129, 0.25);  // 32 m of flat ground
  const auto pyramid = test::planePyramid(grid, [](double, double) { return 0.0; });
  auto tracks = std::make_shared<rover::TrackLayer>(0.02);
  ClipmapOptions opt;
  opt.size = 63;
  opt.lightDirection = {0.8F, 0.1F, 0.35F};  // low sun from the east: ruts cast shading
  opt.trackWindow = 1024;
  ClipmapOptions plain = opt;
  opt.effects.tracks = tracks;
  ClipmapTerrain bare(pyramid, plain), terrain(pyramid, opt);
  const Camera cam = test::downCamera({0.0, 0.0, 0.0}, 9.0, 200, 200, 50.0);
  bare.setFocus(cam.target);
  terrain.setFocus(cam.target);
  const test::Shot before = test::renderShot(bare, cam);
  // No contact yet: the same picture as without the effect.
  const test::Shot empty = test::renderShot(terrain, cam);
  int emptyDiff = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      emptyDiff = std::max(emptyDiff, test::pixelDiff(before.color, empty.color, x, y));
  EXPECT_LE(emptyDiff, 1);
  // A rover drives north-east with a curve: three wheels a side, 0.3 m wide, 2.5 cm ruts.
  std::vector<std::pair<glm::dvec2, glm::dvec2>> paths;
  const double half = 0.6, width = 0.3;
  for (int step = 0; step < 40; ++step) {
    const auto centre = [](double s) { return glm::dvec2(-3.0 + 0.15 * s, -2.0 + 0.002 * s * s); };
    const glm::dvec2 c = centre(step);
    const glm::dvec2 dir = glm::normalize(centre(step + 1) - c);
    const glm::dvec2 side{-dir.y, dir.x};
    std::vector<rover::WheelImprint> wheels;
    for (double s : {-1.0, 1.0})
      for (double along : {-0.5, 0.0, 0.5})
        wheels.push_back({c + side * (s * half) + dir * along, width, 0.025});
    tracks->step(wheels);
  }
  // Where the ruts are, as line segments of the left and right wheel paths.
  for (double s : {-1.0, 1.0})
    for (int step = 0; step < 39; ++step)
      for (double along : {-0.5, 0.0, 0.5}) {
        const auto at = [&](int k) {
          const auto centre = [](double q) {
            return glm::dvec2(-3.0 + 0.15 * q, -2.0 + 0.002 * q * q);
          };
          const glm::dvec2 c = centre(k);
          const glm::dvec2 dir = glm::normalize(centre(k + 1) - c);
          return c + glm::dvec2(-dir.y, dir.x) * (s * half) + dir * along;
        };
        paths.emplace_back(at(step), at(step + 1));
      }
  const test::Shot after = test::renderShot(terrain, cam);
  test::savePng("effects_tracks", after.color);
  const double pixel = 2.0 * 9.0 * std::tan(25.0 * M_PI / 180.0) / cam.height;  // m per pixel
  int inside = 0, insideChanged = 0, outsideChanged = 0, rut = 0, rutChanged = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const auto g = test::groundAt(after, cam, x, y);
      ASSERT_TRUE(g);
      double d = 1e9;
      for (const auto& [a, b] : paths) {
        // Segments are 0.15 m long: those more than a metre away cannot be the nearest
        // within the distances below (a shortcut, for the sanitizer builds).
        if (std::abs(g->x - a.x) > 1.0 || std::abs(g->y - a.y) > 1.0) continue;
        d = std::min(d, segmentDistance({g->x, g->y}, a, b));
      }
      const bool changed = test::pixelDiff(before.color, after.color, x, y) > 2;
      // The rut's floor (flat: the darkening shows whatever the light); its walls tilt
      // towards or away from the sun, and where a wall faces the sun the brighter slope may
      // cancel the darkening, so only most of the rut must change.
      if (d < 0.1 * width) {
        ++inside;
        insideChanged += changed ? 1 : 0;
      }
      if (d < 0.35 * width) {  // at least a fifth of the full depth
        ++rut;
        rutChanged += changed ? 1 : 0;
      }
      // Beyond the rut's edge, a texel of filtering and a pixel: untouched.
      if (d > 0.5 * width + 0.04 + pixel && changed) ++outsideChanged;
    }
  EXPECT_GT(inside, 200);
  EXPECT_EQ(insideChanged, inside);
  EXPECT_GT(rutChanged, rut * 9 / 10);
  EXPECT_EQ(outsideChanged, 0);
}

TEST(EffectImagesGLTest, TracksPersistAlongTheTraverseAndFollowTheFocus) {
  test::glContext();
  const auto grid = test::centredGrid(129, 129, 0.5);  // 64 m of flat ground
  const auto pyramid = test::planePyramid(grid, [](double, double) { return 0.0; });
  auto tracks = std::make_shared<rover::TrackLayer>(0.02);
  ClipmapOptions opt;
  opt.size = 63;
  opt.lightDirection = {0.8F, 0.1F, 0.35F};
  ClipmapOptions plain = opt;
  opt.trackWindow = 256;  // 5.12 m: the window must follow the focus
  opt.effects.tracks = tracks;
  ClipmapTerrain bare(pyramid, plain), terrain(pyramid, opt);
  tracks->stampSegment({-25.0, 0.0}, {25.0, 0.0}, 0.3, 0.03);  // a 50 m traverse
  const auto changedPixels = [&](double x) {
    const Camera cam = test::downCamera({x, 0.0, 0.0}, 4.0, 80, 80, 50.0);
    bare.setFocus(cam.target);
    const test::Shot a = test::renderShot(bare, cam);
    const test::Shot b = test::renderShot(terrain, cam);
    int n = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int px = 0; px < cam.width; ++px) n += test::pixelDiff(a.color, b.color, px, y) > 2;
    return n;
  };
  terrain.setFocus({0.0, 0.0, 0.0});
  EXPECT_EQ(changedPixels(20.0), 0);     // 20 m from the focus: outside the track window
  for (double x : {20.0, -20.0, 0.0}) {  // the focus follows: the tracks are there
    terrain.setFocus({x, 0.0, 0.0});
    EXPECT_GT(changedPixels(x), 80 * 3) << x;  // a 0.3 m rut across an 3.7 m view
  }
}

TEST(EffectImagesGLTest, TracksOnADemPlacedOnAPlanetFollowItsGridFrame) {
  test::glContext();
  const topo::LocalTangentPlane plane(topo::Body::marsSphere(), {-14.6, 175.4, -2000.0}, 30.0);
  const topo::Placement placement(plane);
  const auto grid = test::centredGrid(65, 65, 0.5);
  auto zero = std::make_shared<topo::InMemorySamples>(65, 65, std::vector<float>(65 * 65, 0.0F));
  const auto pyramid =
      std::make_shared<const HeightPyramid>(HeightPyramid::fromSamples(grid, zero, placement));
  auto tracks = std::make_shared<rover::TrackLayer>(0.02);
  ClipmapOptions opt;
  opt.size = 31;
  opt.trackWindow = 512;
  // A low sun from the grid's east, in body-fixed coordinates.
  const glm::dvec3 o = placement.toBodyFixed(0.0, 0.0, 0.0);
  opt.lightDirection = glm::vec3(glm::normalize(0.8 * (placement.toBodyFixed(1.0, 0.0, 0.0) - o) +
                                                0.35 * (placement.toBodyFixed(0.0, 0.0, 1.0) - o)));
  ClipmapOptions plain = opt;
  opt.effects.tracks = tracks;
  ClipmapTerrain bare(pyramid, plain), terrain(pyramid, opt);
  const glm::dvec2 a{-3.0, -1.0}, b{3.0, 1.5};  // grid metres
  tracks->stampSegment(a, b, 0.3, 0.03);
  Camera cam;
  cam.position = placement.toBodyFixed(0.0, 0.0, 8.0);
  cam.target = o;
  cam.up = placement.toBodyFixed(0.0, 1.0, 0.0) - o;
  cam.width = cam.height = 120;
  cam.near = 0.1;
  bare.setFocus(o);
  terrain.setFocus(o);
  const test::Shot before = test::renderShot(bare, cam);
  const test::Shot after = test::renderShot(terrain, cam);
  test::savePng("effects_tracks_placed_dem", after.color);
  int floor = 0, floorChanged = 0, farChanged = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const auto p = test::groundAt(after, cam, x, y);
      ASSERT_TRUE(p);
      const glm::dvec3 g = placement.fromBodyFixed(*p);
      const double d = segmentDistance({g.x, g.y}, a, b);
      const bool changed = test::pixelDiff(before.color, after.color, x, y) > 2;
      if (d < 0.03) {
        ++floor;
        floorChanged += changed ? 1 : 0;
      }
      if (d > 0.15 + 0.04 + 0.07 && changed) ++farChanged;  // half width, a texel, a pixel
    }
  EXPECT_GT(floor, 40);
  EXPECT_EQ(floorChanged, floor);
  EXPECT_EQ(farChanged, 0);
}

// ---- Noise -------------------------------------------------------------------------------

TEST(EffectImagesGLTest, NoiseChangesTheImageOnlyWhereDeclared) {
  test::glContext();
  const auto grid = test::centredGrid(257, 257, 1.0);
  const auto pyramid = test::planePyramid(
      grid, [](double x, double y) { return 2.0 * std::sin(x / 30.0) * std::cos(y / 40.0); });
  ClipmapOptions opt;
  opt.size = 63;
  opt.lightDirection = {0.6F, 0.2F, 0.77F};
  ClipmapOptions plain = opt;
  StructuredNoise noise;
  noise.amplitude = 0.15;
  noise.wavelength = 4.0;
  noise.region = glm::dvec4(-40.0, -25.0, 5.0, 30.0);
  opt.effects.noise = noise;
  ClipmapTerrain bare(pyramid, plain), noisy(pyramid, opt);
  const Camera cam = test::downCamera({0.0, 0.0, 0.0}, 110.0, 200, 200, 50.0);
  bare.setFocus(cam.target);
  noisy.setFocus(cam.target);
  const test::Shot a = test::renderShot(bare, cam);
  const test::Shot b = test::renderShot(noisy, cam);
  test::savePng("effects_noise", b.color);
  const double pixel = 2.0 * 110.0 * std::tan(25.0 * M_PI / 180.0) / cam.height;
  int in = 0, inChanged = 0, outChanged = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const auto g = test::groundAt(b, cam, x, y);
      ASSERT_TRUE(g);
      const bool changed = test::pixelDiff(a.color, b.color, x, y) > 0;
      const bool inside =
          g->x > -40.0 + pixel && g->x < 5.0 - pixel && g->y > -25.0 + pixel && g->y < 30.0 - pixel;
      const bool outside =
          g->x < -40.0 - pixel || g->x > 5.0 + pixel || g->y < -25.0 - pixel || g->y > 30.0 + pixel;
      if (inside) {
        ++in;
        inChanged += changed ? 1 : 0;
      }
      if (outside && changed) ++outChanged;
    }
  EXPECT_EQ(outChanged, 0);
  EXPECT_GT(in, 5000);
  EXPECT_GT(inChanged, in * 9 / 10);  // value noise is rarely exactly flat

  // Tied to the grid, not to the view: moving the focus leaves the noise where it was.
  ClipmapTerrain moved(pyramid, opt);
  moved.setFocus({17.3, -9.1, 0.0});
  const test::Shot c = test::renderShot(moved, cam);
  int differ = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      differ += test::pixelDiff(b.color, c.color, x, y) > 8 ? 1 : 0;
  EXPECT_LT(differ, cam.width * cam.height / 100);
}

}  // namespace
}  // namespace regolith::clod
