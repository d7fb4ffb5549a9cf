// PgmRenderer on the shared headless EGL context: its images against analytic ray–sphere
// and ray–ellipsoid intersection per pixel in double, from orbit down to a millimetre above
// the ground, and the hard cases of issue 19.

#include <regolith/clod/Camera.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "farfield/RayMarchOracle.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

namespace regolith::farfield {
namespace {

constexpr double kMars = 3396190.0;

/// First hit of a ray with the ellipsoid (a, a, b) scaled out by h (a sphere when a = b).
std::optional<double> hitEllipsoid(const glm::dvec3& o, const glm::dvec3& d, double a, double b) {
  const glm::dvec3 s(1.0 / a, 1.0 / a, 1.0 / b);
  const glm::dvec3 os = o * s, ds = d * s;
  const double A = glm::dot(ds, ds), B = glm::dot(os, ds), C = glm::dot(os, os) - 1.0;
  const double disc = B * B - A * C;
  if (disc < 0.0) return std::nullopt;
  // Stable roots: C / q and q / A with q = −B − sign(B)·√disc.
  const double q = -B - std::copysign(std::sqrt(disc), B);
  double t0 = C / q, t1 = q / A;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 > 0.0) return t0;
  if (t1 > 0.0) return t1;
  return std::nullopt;
}

struct Comparison {
  int bodyPixels = 0;      ///< pixels where the oracle sees the body
  int coverageMisses = 0;  ///< pixels where exactly one of the two sees it, away from the limb
  int nonFinite = 0;       ///< NaN or inf in the colour/depth read back
  /// Max height error of the drawn surface (the depth's point, |p| − the shell's radius
  /// along p), relative to the point's distance from the eye: the angle the error
  /// subtends, well-conditioned even for grazing rays where depth itself is not. Pixels next
  /// to the oracle's limb are left out.
  double maxHeightError = 0;
  /// That angle in pixels (× the focal length): the screen-space error.
  double screenError = 0;
};

/// Renders a smooth body (constant height `h0` on the ellipsoid a, b) and compares per pixel
/// with the ray–ellipsoid intersection of the shell (a + h0, b + h0): coverage must agree
/// except within one pixel of the oracle's limb.
Comparison renderAndCompare(const std::string& name, const clod::Camera& cam, double a, double b,
                            double h0, PgmOptions options = {}) {
  test::glContext();
  const topo::Body body =
      a == b ? topo::Body::sphere("test", a) : topo::Body::ellipsoid("test", a, b);
  LayerOptions lo;
  lo.equirectWidth = 256;
  lo.capSize = 64;
  const HeightLayers layers = HeightLayers::build(
      body, [h0](double, double, double) { return h0; }, lo);
  options.readback = PrimaryReadback::Fixed;
  PgmRenderer pgm(layers, options);
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  const PgmFrame frame = pgm.draw(target, cam, glm::normalize(cam.position));
  EXPECT_TRUE(frame.drawn) << name;
  const gl::DepthImage depth = target.readDepth();
  test::savePng("pgm_" + name, target.readColor());

  Comparison c;
  std::vector<int> seen(static_cast<std::size_t>(cam.width * cam.height), 0);
  const glm::dvec3 fwd = cam.forward();
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const glm::dvec3 r = cam.ray(x + 0.5, y + 0.5);
      const auto t = hitEllipsoid(cam.position, r, a + h0, b + h0);
      seen[static_cast<std::size_t>(y * cam.width + x)] = t ? 1 : 0;
      if (!std::isfinite(depth.at(x, y))) ++c.nonFinite;
    }
  }
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const int s = seen[static_cast<std::size_t>(y * cam.width + x)];
      c.bodyPixels += s;
      const float z = depth.at(x, y);
      const bool drawn = z > 0.0F;
      // Within one pixel of the oracle's limb?
      bool nearLimb = false;
      for (int dy = -1; dy <= 1 && !nearLimb; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, cam.width - 1),
                    yy = std::clamp(y + dy, 0, cam.height - 1);
          if (seen[static_cast<std::size_t>(yy * cam.width + xx)] != s) nearLimb = true;
        }
      }
      if (drawn != (s == 1)) {
        if (!nearLimb) ++c.coverageMisses;
        continue;
      }
      if (!drawn || nearLimb) continue;
      const glm::dvec3 r = cam.ray(x + 0.5, y + 0.5);
      const double along = cam.viewDistance(z) / glm::dot(r, fwd);
      const glm::dvec3 p = cam.position + along * r;
      // The shell's radius along p: where the ray from the centre through p meets it.
      const glm::dvec3 u = glm::normalize(p);
      const double shell = *hitEllipsoid(glm::dvec3(0.0), u, a + h0, b + h0);
      c.maxHeightError = std::max(c.maxHeightError, std::abs(glm::length(p) - shell) / along);
    }
  }
  c.screenError = c.maxHeightError * cam.focalPixels();
  std::printf(
      "[ %s ] body pixels %d, coverage misses %d, max height error %.3g of the distance "
      "(%.3g px)\n",
      name.c_str(), c.bodyPixels, c.coverageMisses, c.maxHeightError, c.screenError);
  return c;
}

clod::Camera looking(const glm::dvec3& from, const glm::dvec3& at, const glm::dvec3& up,
                     double fov = 45.0) {
  clod::Camera cam;
  cam.position = from;
  cam.target = at;
  cam.up = up;
  cam.fovYDegrees = fov;
  cam.width = 320;
  cam.height = 240;
  cam.near = 0.5;
  return cam;
}

TEST(PgmRendererGL, GlobalViewMatchesTheSphere) {
  const clod::Camera cam = looking({3.0 * kMars, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0});
  const Comparison c = renderAndCompare("global", cam, kMars, kMars, 0.0);
  EXPECT_GT(c.bodyPixels, 10000);
  EXPECT_EQ(c.coverageMisses, 0);
  EXPECT_EQ(c.nonFinite, 0);
  EXPECT_LT(c.screenError, 0.25);
}

// The even-error spread (PgmOptions::evenError) against the paper's even grid, on a 64²
// grid: a smooth body's only error is its chords, longest on the ground at the limb and,
// from low down, towards the horizon.
TEST(PgmRendererGL, EvenErrorSpreadLowersTheLargestErrorOfTheGrid) {
  const topo::Body mars = topo::Body::sphere("test", kMars);
  struct Case {
    const char* name;
    clod::Camera cam;
  };
  const Case cases[] = {
      {"global", looking({3.0 * kMars, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0})},
      {"low", looking(mars.toBodyFixed({0.0, 0.0, 400e3}), mars.toBodyFixed({0.0, 15.0, 0.0}),
                      {0.0, 0.0, 1.0}, 60.0)},
  };
  for (const Case& c : cases) {
    PgmOptions even;
    even.gridWidth = even.gridHeight = 64;
    even.evenError = false;
    PgmOptions spread = even;
    spread.evenError = true;
    const Comparison a =
        renderAndCompare(std::string("even_") + c.name, c.cam, kMars, kMars, 0.0, even);
    const Comparison b =
        renderAndCompare(std::string("spread_") + c.name, c.cam, kMars, kMars, 0.0, spread);
    EXPECT_GT(b.bodyPixels, 10000) << c.name;
    EXPECT_EQ(b.coverageMisses, 0) << c.name;
    EXPECT_EQ(b.nonFinite, 0) << c.name;
    EXPECT_LT(5.0 * b.screenError, a.screenError) << c.name;  // 17× and 50× here
  }
}

// Whatever blend state the context's last renderer left: here a dual-source factor, which
// Mesa holds against any draw into two colour buffers (both of PGM's passes), blending on or
// off. Without the renderer's own reset the draw failed with GL_INVALID_OPERATION.
TEST(PgmRendererGL, DrawsWhateverBlendFactorsTheContextWasLeftWith) {
  test::glContext();
  // The defaults again when the test ends, passed or thrown, for the tests after it.
  struct DefaultFactorsAtExit {
    DefaultFactorsAtExit() = default;
    DefaultFactorsAtExit(const DefaultFactorsAtExit&) = delete;
    DefaultFactorsAtExit& operator=(const DefaultFactorsAtExit&) = delete;
    ~DefaultFactorsAtExit() { glBlendFunc(GL_ONE, GL_ZERO); }
  } restore;
  glBlendFunc(GL_ONE, GL_SRC1_COLOR);
  const clod::Camera cam = looking({3.0 * kMars, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0});
  const Comparison c = renderAndCompare("after_dual_source_blend", cam, kMars, kMars, 0.0);
  EXPECT_GT(c.bodyPixels, 10000);
  EXPECT_EQ(c.coverageMisses, 0);
}

TEST(PgmRendererGL, EllipsoidFromAboveThePoleAndAcrossTheSeam) {
  const double b = 3376200.0;
  // Over the north pole, and over the ±180° meridian, with relief 0 but an ellipsoid.
  const Comparison pole = renderAndCompare(
      "pole", looking({0.0, 0.0, 2.0 * kMars}, {0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}), kMars, b, 1000.0);
  EXPECT_EQ(pole.coverageMisses, 0);
  EXPECT_EQ(pole.nonFinite, 0);
  EXPECT_LT(pole.screenError, 0.25);
  const Comparison seam = renderAndCompare(
      "seam", looking({-1.4 * kMars, 1.0, 0.3 * kMars}, {-kMars, 0.0, 0.0}, {0.0, 0.0, 1.0}), kMars,
      b, 1000.0);
  EXPECT_EQ(seam.coverageMisses, 0);
  EXPECT_EQ(seam.nonFinite, 0);
  EXPECT_LT(seam.screenError, 0.25);
}

TEST(PgmRendererGL, NadirViewOmegaZero) {
  const clod::Camera cam = looking({kMars + 4.0e5, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0});
  const Comparison c = renderAndCompare("nadir", cam, kMars, kMars, 0.0);
  EXPECT_EQ(c.bodyPixels, cam.width * cam.height);
  EXPECT_EQ(c.coverageMisses, 0);
  EXPECT_EQ(c.nonFinite, 0);
  EXPECT_LT(c.screenError, 0.25);
}

TEST(PgmRendererGL, GrazingViewsAtTheHorizonFromTwoMetresAndOneMillimetre) {
  for (const double altitude : {2.0, 1e-3}) {
    const glm::dvec3 eye(kMars + altitude, 0.0, 0.0);
    clod::Camera cam = looking(eye, eye + glm::dvec3(0.0, 1000.0, 0.0), {1.0, 0.0, 0.0}, 60.0);
    cam.near = altitude / 20.0;  // so the near plane cuts no ground the oracle sees
    const Comparison c =
        renderAndCompare("grazing_" + std::to_string(altitude), cam, kMars, kMars, 0.0);
    EXPECT_GT(c.bodyPixels, cam.width * cam.height / 4) << altitude;
    EXPECT_EQ(c.coverageMisses, 0) << altitude;
    EXPECT_EQ(c.nonFinite, 0) << altitude;
    EXPECT_LT(c.screenError, 0.25) << altitude;
  }
}

TEST(PgmRendererGL, LookingAwayDrawsNothingAndStaysFinite) {
  const clod::Camera cam =
      looking({2.0 * kMars, 0.0, 0.0}, {4.0 * kMars, 0.0, 0.0}, {0.0, 0.0, 1.0});
  const Comparison c = renderAndCompare("away", cam, kMars, kMars, 0.0);
  EXPECT_EQ(c.bodyPixels, 0);
  EXPECT_EQ(c.coverageMisses, 0);
  EXPECT_EQ(c.nonFinite, 0);
}

}  // namespace
}  // namespace regolith::farfield

namespace regolith::farfield {
namespace {

constexpr double kMoon = 1737400.0;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

/// A Gaussian mountain `peak` metres high with σ = `sigma` metres, centred at (lat0, lon0), on
/// a flat Moon.
HeightLayers::HeightFunction mountain(double lat0, double lon0, double peak, double sigma) {
  const topo::Body moon = topo::Body::moon();
  const glm::dvec3 c = glm::normalize(moon.toBodyFixed({lat0, lon0, 0.0}));
  return [c, peak, sigma](double lat, double lon, double) {
    const glm::dvec3 p(std::cos(lat * kDegree) * std::cos(lon * kDegree),
                       std::cos(lat * kDegree) * std::sin(lon * kDegree), std::sin(lat * kDegree));
    const double arc = std::acos(std::clamp(glm::dot(p, c), -1.0, 1.0)) * kMoon;
    return peak * std::exp(-0.5 * (arc / sigma) * (arc / sigma));
  };
}

HeightLayers moonLayers(const HeightLayers::HeightFunction& f) {
  LayerOptions lo;
  lo.equirectWidth = 2048;
  lo.capSize = 256;
  return HeightLayers::build(topo::Body::moon(), f, lo);
}

TEST(PgmRendererGL, AMountainBehindTheHorizonRisesIntoView) {
  test::glContext();
  // A 10 km mountain 200 km east of a camera 1 km up: its foot is 140 km beyond the
  // horizon (59 km), its top 4 km above the curve.
  const double lonM = 200e3 / kMoon / kDegree;
  const HeightLayers layers = moonLayers(mountain(0.0, lonM, 10000.0, 40000.0));
  const topo::Body moon = topo::Body::moon();
  clod::Camera cam;
  cam.position = moon.toBodyFixed({0.0, 0.0, 1000.0});
  cam.target = moon.toBodyFixed({0.0, lonM, 2000.0});
  cam.up = {1.0, 0.0, 0.0};
  cam.fovYDegrees = 8.0;
  cam.width = 320;
  cam.height = 240;
  cam.near = 1.0;
  PgmOptions options;
  options.readback = PrimaryReadback::Stall;
  options.gridWidth = options.gridHeight = 1024;
  PgmRenderer pgm(layers, options);
  gl::RenderTarget target(cam.width, cam.height);
  for (int frame = 0; frame < 2; ++frame) {  // the second frame uses the measured r_p
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    const PgmFrame f = pgm.draw(target, cam, glm::normalize(glm::dvec3(0.3, -1.0, 0.2)));
    ASSERT_TRUE(f.drawn);
    ASSERT_TRUE(f.spheres.secondaryExists());
  }
  test::savePng("pgm_mountain_behind_horizon", target.readColor());
  const gl::DepthImage depth = target.readDepth();
  // The silhouette's top in the peak's column: the camera, the centre and the equator are
  // in one plane with the camera's up, so every equator point projects onto that column; the
  // highest of them in the image (the layers' own heights, sampled every 100 m) is the top.
  const glm::dvec3 pp = cam.project(moon.toBodyFixed({0.0, lonM, 10000.0}));
  ASSERT_GT(pp.z, 0.0);
  const int col = static_cast<int>(pp.x);
  double expectTop = 1e9;
  for (double x = 1000.0; x < 400e3; x += 100.0) {
    const double lon = x / kMoon / kDegree;
    const glm::dvec3 q = cam.project(moon.toBodyFixed({0.0, lon, layers.heightAt(0.0, lon)}));
    if (q.z > 0.0) expectTop = std::min(expectTop, q.y);
  }
  int top = -1;
  for (int y = 0; y < cam.height && top < 0; ++y) {
    if (depth.at(col, y) > 0.0F) top = y;
  }
  // The bare sphere's horizon row in that column: the first ray from the top that hits it.
  int horizon = -1;
  for (int y = 0; y < cam.height && horizon < 0; ++y) {
    if (hitEllipsoid(cam.position, cam.ray(col + 0.5, y + 0.5), kMoon, kMoon)) horizon = y;
  }
  std::printf("expected top row %.2f, top drawn row %d, bare horizon row %d\n", expectTop, top,
              horizon);
  ASSERT_GE(top, 0);
  EXPECT_LT(top, horizon - 10);                     // the mountain stands well above the horizon
  EXPECT_LE(std::abs(top + 0.5 - expectTop), 1.5);  // its top where the oracle has it

  // The whole image against brute-force ray marching of the same surface in double:
  // silhouettes (the mountain against the sky, the horizon) within one pixel.
  test::OracleSurface surface{
      moon, [&layers](double lat, double lon) { return layers.heightAt(lat, lon); },
      layers.minHeight(), layers.maxHeight()};
  const test::OracleImage oracle = test::rayMarch(cam, surface, 200.0);
  const test::SilhouetteReport report = test::compareSilhouettes(oracle, depth);
  std::printf("oracle: %s\n", report.describe().c_str());
  test::savePng("pgm_mountain_oracle", test::depthPicture(oracle));
  EXPECT_EQ(report.misplacedPixels(), 0U) << report.describe();
}

// Culling the clockwise triangles (PgmOptions::cullFolds) removes only triangles that the
// surface in front hides: every view draws the same colour and depth, bit for bit, with and
// without it. A view where a culled triangle showed would differ here.
TEST(PgmRendererGL, CullingTheFoldedTrianglesChangesNoPixel) {
  test::glContext();
  const double lonM = 200e3 / kMoon / kDegree;
  const HeightLayers layers = moonLayers(mountain(0.0, lonM, 10000.0, 40000.0));
  const topo::Body moon = topo::Body::moon();
  struct View {
    const char* name = "";
    clod::Camera cam;
  };
  clod::Camera behind;
  behind.position = moon.toBodyFixed({0.0, 0.0, 1000.0});
  behind.target = moon.toBodyFixed({0.0, lonM, 2000.0});
  behind.up = {1.0, 0.0, 0.0};
  behind.fovYDegrees = 8.0;
  behind.width = 320;
  behind.height = 240;
  behind.near = 1.0;
  const View views[] = {
      {"global", looking({3.0 * kMoon, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0})},
      {"limb", looking(moon.toBodyFixed({10.0, -20.0, 300e3}), moon.toBodyFixed({0.0, 5.0, 0.0}),
                       {0.0, 0.0, 1.0}, 60.0)},
      {"pole", looking({0.2 * kMoon, 0.0, 1.5 * kMoon}, {0.0, 0.0, kMoon}, {1.0, 0.0, 0.0}, 70.0)},
      {"mountain_behind_horizon", behind},
  };
  for (const View& v : views) {
    gl::RgbaImage colour[2];
    gl::DepthImage depth[2];
    std::size_t bodyPixels = 0;
    for (int cull = 0; cull < 2; ++cull) {
      PgmOptions options;
      options.readback = PrimaryReadback::Stall;
      options.cullFolds = cull == 1;
      PgmRenderer pgm(layers, options);
      gl::RenderTarget target(v.cam.width, v.cam.height);
      for (int frame = 0; frame < 2; ++frame) {  // the second frame uses the measured r_p
        target.clear({0.0F, 0.0F, 0.0F, 1.0F});
        ASSERT_TRUE(pgm.draw(target, v.cam, glm::normalize(glm::dvec3(0.3, -1.0, 0.2))).drawn)
            << v.name;
      }
      colour[cull] = target.readColor();
      depth[cull] = target.readDepth();
    }
    for (const float z : depth[1].depth) bodyPixels += z > 0.0F ? 1U : 0U;
    // A pixel differs if its colour or depth does. Where the fold is the silhouette and no
    // grid line runs along it, the folded triangles' sliver outside the last front-facing
    // row is the limb's outermost pixels: culling may take those (the even-error spread's
    // rows made one such pixel in the limb view), and nothing else.
    // On the silhouette: a neighbour (not the pixel itself) is empty in the image drawn
    // without culling, so a hole culling made inside the body counts as inside.
    const int w = v.cam.width, h = v.cam.height;
    const auto empty = [&](int x, int y) {
      return !(depth[0].at(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1)) > 0.0F);
    };
    std::size_t differing = 0, inside = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y * w + x);
        bool differs = depth[0].depth[i] != depth[1].depth[i];
        for (std::size_t c = 0; c < 4; ++c)
          differs = differs || colour[0].rgba[4 * i + c] != colour[1].rgba[4 * i + c];
        if (!differs) continue;
        ++differing;
        bool onSilhouette = false;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            onSilhouette = onSilhouette || ((dx != 0 || dy != 0) && empty(x + dx, y + dy));
          }
        }
        inside += onSilhouette ? 0U : 1U;
      }
    }
    std::printf("[ cull %s ] body pixels %zu, differing pixels %zu (%zu off the silhouette)\n",
                v.name, bodyPixels, differing, inside);
    test::savePng(std::string("pgm_cull_") + v.name, colour[1]);
    EXPECT_GT(bodyPixels, 1000U) << v.name;  // the view shows the body
    EXPECT_EQ(inside, 0U) << v.name;
    EXPECT_LE(differing, bodyPixels / 10000) << v.name;
  }
}

TEST(PgmRendererGL, ACameraBelowTheMountainTopSeesItAboveTheHorizontal) {
  test::glContext();
  const double lonM = 40e3 / kMoon / kDegree;  // 40 km away, 10 km high; the eye 1 km up
  const HeightLayers layers = moonLayers(mountain(0.0, lonM, 10000.0, 15000.0));
  const topo::Body moon = topo::Body::moon();
  clod::Camera cam;
  cam.position = moon.toBodyFixed({0.0, 0.0, 1000.0});
  const glm::dmat3 enu = moon.enuFrame(0.0, 0.0);
  cam.target = cam.position + enu[0];  // level, looking east
  cam.up = enu[2];
  cam.fovYDegrees = 40.0;
  cam.width = 320;
  cam.height = 240;
  cam.near = 1.0;
  PgmOptions options;
  options.gridWidth = options.gridHeight = 1024;
  PgmRenderer pgm(layers, options);
  ASSERT_LT(glm::length(cam.position), pgm.maxRadius());  // below the maximum sphere
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  const PgmFrame f = pgm.draw(target, cam, enu[2]);
  ASSERT_TRUE(f.drawn);
  test::savePng("pgm_below_mountain_top", target.readColor());
  const gl::DepthImage depth = target.readDepth();
  const int mid = cam.width / 2;
  // Rows above the image centre look above the horizontal: the mountain fills some.
  int above = 0;
  for (int y = 0; y < cam.height / 2 - 2; ++y) above += depth.at(mid, y) > 0.0F ? 1 : 0;
  double expectTop = 1e9;  // as in the test above: the equator's highest projection
  for (double x = 100.0; x < 200e3; x += 50.0) {
    const double lon = x / kMoon / kDegree;
    const glm::dvec3 q = cam.project(moon.toBodyFixed({0.0, lon, layers.heightAt(0.0, lon)}));
    if (q.z > 0.0) expectTop = std::min(expectTop, q.y);
  }
  std::printf("drawn rows above the horizontal %d, expected top row %.2f\n", above, expectTop);
  EXPECT_GT(above, 20);
  int top = -1;
  for (int y = 0; y < cam.height && top < 0; ++y) {
    if (depth.at(mid, y) > 0.0F) top = y;
  }
  EXPECT_LE(std::abs(top + 0.5 - expectTop), 1.5);
  for (const float z : depth.depth) ASSERT_TRUE(std::isfinite(z));
  // Against brute-force ray marching of the layers' surface: silhouettes within a pixel.
  test::OracleSurface surface{
      moon, [&layers](double lat, double lon) { return layers.heightAt(lat, lon); },
      layers.minHeight(), layers.maxHeight()};
  const test::SilhouetteReport report =
      test::compareSilhouettes(test::rayMarch(cam, surface, 100.0), depth);
  std::printf("oracle: %s\n", report.describe().c_str());
  EXPECT_EQ(report.misplacedPixels(), 0U) << report.describe();
}

TEST(PgmRendererGL, SecondarySphereVanishingSwitchesToTheImpostor) {
  test::glContext();
  const HeightLayers layers = moonLayers(mountain(0.0, 0.0, 8000.0, 100000.0));
  PgmOptions options;
  options.readback = PrimaryReadback::Fixed;
  PgmRenderer pgm(layers, options);
  // Bisect the distance where r_s crosses 0 with the renderer's radii.
  double lo = 1.5 * kMoon, hi = 1000.0 * kMoon;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (referenceSpheres(mid, pgm.primaryRadius(), pgm.maxRadius(), 0.9).secondaryExists() ? lo : hi) =
        mid;
  }
  for (const double d : {lo, hi * 1.0001}) {
    clod::Camera cam;
    cam.position = {d, 0.0, 0.0};
    cam.target = {0.0, 0.0, 0.0};
    cam.up = {0.0, 0.0, 1.0};
    cam.fovYDegrees = 10.0;
    cam.width = 200;
    cam.height = 200;
    cam.near = 1.0;
    gl::RenderTarget target(cam.width, cam.height);
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    const PgmFrame f = pgm.draw(target, cam, {1.0, 0.0, 0.0});
    const gl::DepthImage depth = target.readDepth();
    int drawn = 0, inner = 0, missed = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const float z = depth.at(x, y);
        ASSERT_TRUE(std::isfinite(z));
        drawn += z > 0.0F ? 1 : 0;
        const auto hits = [&](int px, int py) {
          return hitEllipsoid(cam.position, cam.ray(px + 0.5, py + 0.5), pgm.minRadius(),
                              pgm.minRadius())
              .has_value();
        };
        if (hits(x, y)) {
          ++inner;
          // A pixel that certainly sees the body (its ray meets the lowest sphere, and so
          // do its neighbours': not at the limb) must be drawn.
          const bool interior =
              hits(x - 1, y) && hits(x + 1, y) && hits(x, y - 1) && hits(x, y + 1);
          missed += z > 0.0F || !interior ? 0 : 1;
        }
      }
    }
    std::printf("d = %.6g R: r_s = %.6g m, drawn %d, body pixels %d, missed %d\n", d / kMoon,
                f.spheres.secondary, drawn, inner, missed);
    if (d == lo) {
      ASSERT_TRUE(f.drawn);  // r_s → 0⁺ still draws, and draws the whole disc
      EXPECT_GT(f.spheres.secondary, 0.0);
      EXPECT_LT(f.spheres.secondary, 1e-3 * kMoon);
      EXPECT_GT(inner, 1000);
      EXPECT_EQ(missed, 0);
    } else {
      EXPECT_FALSE(f.drawn);  // r_s < 0: the impostor's turn
      EXPECT_LE(f.spheres.secondary, 0.0);
      EXPECT_EQ(drawn, 0);
    }
  }
}

TEST(PgmRendererGL, MinimumVisibleRadiusIsReadBackStalledOrAFrameLater) {
  test::glContext();
  // A crater 3 km deep (a negative mountain) under a camera 300 km up.
  const HeightLayers layers = moonLayers(mountain(0.0, 0.0, -3000.0, 30000.0));
  clod::Camera cam;
  cam.position = {kMoon + 3.0e5, 0.0, 0.0};
  cam.target = {0.0, 0.0, 0.0};
  cam.up = {0.0, 0.0, 1.0};
  cam.width = 200;
  cam.height = 150;
  cam.near = 1.0;
  gl::RenderTarget target(cam.width, cam.height);
  double stalled = 0.0;
  {
    PgmOptions options;
    options.readback = PrimaryReadback::Stall;
    options.minCellPixels = 0.0;  // the full grid's sampling of the crater floor
    PgmRenderer pgm(layers, options);
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    const PgmFrame f = pgm.draw(target, cam, {1.0, 0.0, 0.0});
    stalled = f.minVisibleRadius;
    // The crater floor is the lowest point: within the grid's sampling of its bottom.
    EXPECT_NEAR(stalled, kMoon - 3000.0, 30.0);
    // Lowered by the margin but never below the body's lowest radius (here the crater floor
    // itself, so the clamp holds it there).
    EXPECT_LE(pgm.primaryRadius(), stalled);
    EXPECT_GE(pgm.primaryRadius(), pgm.minRadius());
    // Looking at flat ground away from the crater: the minimum visible radius is the datum,
    // and the next primary is that less the margin (2 % of the relief).
    clod::Camera side = cam;
    side.position = {(kMoon + 3.0e4) * std::cos(0.3), (kMoon + 3.0e4) * std::sin(0.3), 0.0};
    side.target = {kMoon * std::cos(0.31), kMoon * std::sin(0.31), 0.0};
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    const PgmFrame g = pgm.draw(target, side, {1.0, 0.0, 0.0});
    EXPECT_NEAR(g.minVisibleRadius, kMoon, 1.0);
    EXPECT_NEAR(pgm.primaryRadius(), kMoon - 0.02 * (pgm.maxRadius() - pgm.minRadius()), 1.0);
  }
  PgmOptions options;
  options.readback = PrimaryReadback::Lagged;
  options.minCellPixels = 0.0;  // the same grid as the stalled read
  PgmRenderer pgm(layers, options);
  double lagged = std::numeric_limits<double>::quiet_NaN();
  int frames = 0;
  for (; frames < 5 && std::isnan(lagged); ++frames) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    lagged = pgm.draw(target, cam, {1.0, 0.0, 0.0}).minVisibleRadius;
    if (frames == 0) {
      EXPECT_TRUE(std::isnan(lagged));  // nothing to read in the first frame
    }
  }
  std::printf("stalled %.3f m, lagged %.3f m after %d frames\n", stalled, lagged, frames);
  EXPECT_NEAR(lagged, stalled, 1e-3);
}

}  // namespace
}  // namespace regolith::farfield

namespace regolith::farfield {
namespace {

TEST(PgmRendererGL, BadOptionsAndCameraAreNamed) {
  test::glContext();
  LayerOptions lo;
  lo.equirectWidth = 64;
  lo.capSize = 16;
  const HeightLayers layers = HeightLayers::build(
      topo::Body::moon(), [](double, double, double) { return 0.0; }, lo);
  PgmOptions o;
  o.gridWidth = 4;
  try {
    PgmRenderer pgm(layers, o);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "farfield::PgmRenderer(): gridWidth is 4, expected in [8, 4096]");
  }
  o.gridWidth = 16;
  o.zeta = 0.0;
  EXPECT_THROW(PgmRenderer(layers, o), InvalidArgument);
  o.zeta = 0.9;
  PgmRenderer pgm(layers, o);
  gl::RenderTarget target(32, 32);
  clod::Camera cam;
  cam.position = {3.0 * kMoon, 0.0, 0.0};
  cam.target = {0.0, 0.0, 0.0};
  cam.width = 40;
  cam.height = 32;
  try {
    (void)pgm.draw(target, cam, {1.0, 0.0, 0.0});
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(
        e.what(),
        "farfield::PgmRenderer::draw(): camera size is 40 x 32, expected the target's 32 x 32");
  }
  EXPECT_THROW(FarField(nullptr), InvalidArgument);
}

}  // namespace
}  // namespace regolith::farfield
