// PgmRenderer on the shared headless EGL context: its images against analytic ray–sphere
// and ray–ellipsoid intersection per pixel in double, from orbit down to a millimetre above
// the ground, and the hard cases of issue 19.

#include <regolith/clod/Camera.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
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
