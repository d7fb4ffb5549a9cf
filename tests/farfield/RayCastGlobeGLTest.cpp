// The ray-cast globe (docs/ray-cast-globe.md) against a CPU oracle in long double: per pixel
// centre, the ray of clod::Camera::ray() meets the ellipsoid by the textbook quadratic
// (A t² + B t + C = 0, t = (−B − √(B² − 4AC)) / 2A in long double: a formulation the shader
// does not use). The oracle gives coverage, depth (near / view distance), the geodetic normal
// and latitude/longitude, so colours are checked too: flat albedo times Lambert, or the
// texture's level-0 bilinear value.

#include <regolith/core/Error.hpp>
#include <regolith/farfield/RayCastGlobe.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace regolith::farfield {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kMarsA = 3396190.0, kMarsB = 3376200.0;
constexpr double kWgs84A = 6378137.0, kWgs84B = 6356752.314245179;
const glm::vec4 kClear{0.0F, 0.0F, 0.0F, 1.0F};

glm::dmat3 rotationXZ(double xDeg, double zDeg) {
  const double cx = std::cos(xDeg * kDeg), sx = std::sin(xDeg * kDeg);
  const double cz = std::cos(zDeg * kDeg), sz = std::sin(zDeg * kDeg);
  const glm::dmat3 rx(1.0, 0.0, 0.0, 0.0, cx, sx, 0.0, -sx, cx);  // columns
  const glm::dmat3 rz(cz, sz, 0.0, -sz, cz, 0.0, 0.0, 0.0, 1.0);
  return rz * rx;
}

struct OraclePixel {
  bool hit = false;
  double depth = 0.0;      // near / view distance
  glm::dvec3 normal{0.0};  // geodetic normal, body axes
  double latDeg = 0.0, lonDeg = 0.0;
};

/// The textbook quadratic in long double at image position (x, y) (pixel centres at +0.5).
OraclePixel oracleAt(const clod::Camera& cam, const GlobeBody& body, double x, double y) {
  using L = long double;
  const glm::dvec3 r = cam.ray(x, y);
  const glm::dmat3 rt = glm::transpose(body.orientation);
  const glm::dvec3 o = rt * (cam.position - body.centre);
  const glm::dvec3 dir = rt * r;
  const L inv[3] = {1.0L / body.a, 1.0L / body.a, 1.0L / body.b};
  L A = 0, B = 0, C = -1;
  for (int i = 0; i < 3; ++i) {
    const L os = o[i] * inv[i], ds = dir[i] * inv[i];
    A += ds * ds;
    B += 2 * os * ds;
    C += os * os;
  }
  const L disc = B * B - 4 * A * C;
  OraclePixel p;
  if (disc < 0) return p;
  const L t = (-B - std::sqrt(disc)) / (2 * A);
  if (t <= 0) return p;
  const double view = static_cast<double>(t) * glm::dot(r, cam.forward());
  if (view < cam.near) return p;  // clipped by the near plane
  p.hit = true;
  p.depth = cam.near / view;
  L q[3];
  for (int i = 0; i < 3; ++i) q[i] = o[i] + t * dir[i];
  p.normal = glm::normalize(glm::dvec3(static_cast<double>(q[0] * inv[0] * inv[0]),
                                       static_cast<double>(q[1] * inv[1] * inv[1]),
                                       static_cast<double>(q[2] * inv[2] * inv[2])));
  p.latDeg = std::asin(std::clamp(p.normal.z, -1.0, 1.0)) / kDeg;
  p.lonDeg = static_cast<double>(std::atan2(q[1], q[0])) / kDeg;
  return p;
}

struct Oracle {
  int w = 0, h = 0;
  std::vector<OraclePixel> px;
  [[nodiscard]] const OraclePixel& at(int x, int y) const {
    return px[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
              static_cast<std::size_t>(x)];
  }
  /// True if a pixel of the 3×3 block about (x, y) differs in coverage from (x, y).
  [[nodiscard]] bool silhouette(int x, int y) const {
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int u = std::clamp(x + dx, 0, w - 1), v = std::clamp(y + dy, 0, h - 1);
        if (at(u, v).hit != at(x, y).hit) return true;
      }
    return false;
  }
};

Oracle oracle(const clod::Camera& cam, const GlobeBody& body) {
  Oracle o{cam.width, cam.height, {}};
  o.px.reserve(static_cast<std::size_t>(cam.width) * static_cast<std::size_t>(cam.height));
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) o.px.push_back(oracleAt(cam, body, x + 0.5, y + 0.5));
  return o;
}

struct Render {
  gl::RgbaImage colour;
  gl::DepthImage depth;
  GlobeFrame frame;
};

Render render(RayCastGlobe& globe, const clod::Camera& cam, const GlobeBody& body,
              const glm::dvec3& sun) {
  (void)test::glContext();
  const gl::RenderTarget target(cam.width, cam.height);
  target.clear(kClear);
  Render r;
  r.frame = globe.draw(cam, body, sun);
  r.colour = target.readColor();
  r.depth = target.readDepth();
  return r;
}

/// Expected colour without a texture: colour × (ambient + (1 − ambient)·max(n·sun, 0)).
glm::dvec3 flatShade(const OraclePixel& p, const GlobeBody& body, const glm::dvec3& sunScene,
                     double ambient) {
  const glm::dvec3 sun = glm::normalize(glm::transpose(body.orientation) * sunScene);
  const double diffuse = std::max(glm::dot(p.normal, sun), 0.0);
  return glm::dvec3(body.colour) * (ambient + (1.0 - ambient) * diffuse) * 255.0;
}

struct Comparison {
  long covered = 0;             // oracle hits
  long silhouetteMismatch = 0;  // coverage differs, at the silhouette
  long interiorMismatch = 0;    // coverage differs away from it
  long nonFinite = 0;
  long depthChecked = 0, depthFailures = 0;
  double maxDepthRel = 0.0;      // over the checked pixels
  double maxDepthExcess = 0.0;   // max(error − tolerance) / depth
  long sensitive = 0;            // pixels whose tolerance exceeds 1e-5 (grazing rays)
  double maxShiftPx = 0.0;       // max ray shift that explains an error beyond 2e-6
  double maxDepthRelFirm = 0.0;  // max error where the tolerance is below 1e-5
  long colourChecked = 0, colourFailures = 0;
  int maxColourDiff = 0;
};

/// The GPU render against the oracle. Depth tolerance per pixel: 2e-6 relative, plus how
/// much the oracle's depth moves if the ray moves by 2e-4 px in x and in y (the float ray's
/// own rounding is 1e-4 px or less; a grazing ray's depth is that sensitive by nature).
Comparison compare(const Render& r, const Oracle& o, const clod::Camera& cam, const GlobeBody& body,
                   const std::function<bool(int, int, glm::dvec3&)>& colourAt,
                   int colourTolerance) {
  Comparison c;
  for (int y = 0; y < o.h; ++y) {
    for (int x = 0; x < o.w; ++x) {
      const float d = r.depth.at(x, y);
      if (!std::isfinite(d)) ++c.nonFinite;
      const bool gpu = d > 0.0F;
      const OraclePixel& p = o.at(x, y);
      c.covered += p.hit ? 1 : 0;
      const bool edge = o.silhouette(x, y);
      if (gpu != p.hit) {
        if (edge)
          ++c.silhouetteMismatch;
        else
          ++c.interiorMismatch;
        continue;
      }
      if (!p.hit || edge) continue;
      ++c.depthChecked;
      const double err = std::abs(static_cast<double>(d) - p.depth) / p.depth;
      constexpr double delta = 2e-4;
      const double sx = std::abs(oracleAt(cam, body, x + 0.5 + delta, y + 0.5).depth - p.depth);
      const double sy = std::abs(oracleAt(cam, body, x + 0.5, y + 0.5 + delta).depth - p.depth);
      const double tol = 2e-6 + (sx + sy) / p.depth;
      // The ray shift (px) that would explain the error beyond 2e-6.
      if (sx + sy > 0.0)
        c.maxShiftPx = std::max(c.maxShiftPx, (err - 2e-6) * p.depth / (sx + sy) * delta);
      c.maxDepthRel = std::max(c.maxDepthRel, err);
      if (tol > 1e-5)
        ++c.sensitive;
      else
        c.maxDepthRelFirm = std::max(c.maxDepthRelFirm, err);
      c.maxDepthExcess = std::max(c.maxDepthExcess, err - tol);
      if (err > tol) ++c.depthFailures;
      glm::dvec3 want;
      if (colourAt && colourAt(x, y, want)) {
        ++c.colourChecked;
        const std::uint8_t* got = r.colour.pixel(x, y);
        int diff = 0;
        for (int i = 0; i < 3; ++i)
          diff = std::max(diff, static_cast<int>(std::lround(std::abs(got[i] - want[i]))));
        c.maxColourDiff = std::max(c.maxColourDiff, diff);
        if (diff > colourTolerance) ++c.colourFailures;
      }
    }
  }
  return c;
}

void print(const char* name, const Comparison& c, const GlobeFrame& f) {
  std::printf(
      "%s: covered %ld, coverage mismatches %ld at the silhouette, %ld inside; depth checked "
      "%ld, max rel err %.3g (%.3g where the tolerance is < 1e-5, %ld grazing pixels above; "
      "beyond 2e-6 as if the ray moved %.2g px), failures %ld; colour checked %ld, max diff %d, "
      "failures %ld; rays cast %llu, hit %llu\n",
      name, c.covered, c.silhouetteMismatch, c.interiorMismatch, c.depthChecked, c.maxDepthRel,
      c.maxDepthRelFirm, c.sensitive, c.maxShiftPx, c.depthFailures, c.colourChecked,
      c.maxColourDiff, c.colourFailures, static_cast<unsigned long long>(f.raysCast),
      static_cast<unsigned long long>(f.raysHit));
}

void expectMatches(const Comparison& c) {
  EXPECT_GT(c.covered, 0);
  EXPECT_EQ(c.nonFinite, 0);
  EXPECT_EQ(c.interiorMismatch, 0);
  // At most one pixel of mismatch across the silhouette: a mismatched pixel lies on it (above)
  // and mismatches are rare there.
  EXPECT_LE(c.silhouetteMismatch, std::max<long>(2, c.covered / 2000));
  EXPECT_EQ(c.depthFailures, 0) << "max excess over the tolerance " << c.maxDepthExcess;
  EXPECT_EQ(c.colourFailures, 0) << "max colour difference " << c.maxColourDiff;
}

long coveredPixels(const Render& r) {
  long n = 0;
  for (const float d : r.depth.depth) n += d > 0.0F ? 1 : 0;
  return n;
}

/// Both proxies, counting rays: the images must be identical; the polygon casts fewer rays.
void checkBothProxies(const std::string& name, const clod::Camera& cam, const GlobeBody& body,
                      const glm::dvec3& sun, int colourTolerance = 2, bool flatColour = true) {
  (void)test::glContext();
  GlobeOptions options;
  options.countRays = true;
  options.proxy = GlobeProxy::Box;
  RayCastGlobe globe(options);
  const Render box = render(globe, cam, body, sun);
  globe.setProxy(GlobeProxy::Polygon, 16);
  const Render poly = render(globe, cam, body, sun);
  test::savePng("globe_" + name + "_box", box.colour);
  test::savePng("globe_" + name + "_polygon", poly.colour);
  EXPECT_EQ(box.colour.rgba, poly.colour.rgba) << name << ": the proxies draw different colours";
  EXPECT_EQ(box.depth.depth, poly.depth.depth) << name << ": the proxies draw different depths";
  EXPECT_EQ(box.frame.raysHit, poly.frame.raysHit);
  EXPECT_EQ(static_cast<long>(poly.frame.raysHit), coveredPixels(poly));
  EXPECT_GE(poly.frame.raysCast, poly.frame.raysHit);
  const Oracle o = oracle(cam, body);
  std::function<bool(int, int, glm::dvec3&)> colourAt;
  if (flatColour)
    colourAt = [&](int x, int y, glm::dvec3& want) {
      want = flatShade(o.at(x, y), body, sun, globe.options().ambient);
      return true;
    };
  const Comparison c = compare(poly, o, cam, body, colourAt, colourTolerance);
  print(name.c_str(), c, poly.frame);
  std::printf("%s: box cast %llu rays for %llu hits\n", name.c_str(),
              static_cast<unsigned long long>(box.frame.raysCast),
              static_cast<unsigned long long>(box.frame.raysHit));
  expectMatches(c);
}

/// A camera at `distance` from the centre of `body` (scene frame = body frame rotated by its
/// orientation), looking at the centre from the direction (latDeg, lonDeg) of the body.
clod::Camera lookingAtCentre(const GlobeBody& body, double latDeg, double lonDeg, double distance,
                             double fovDeg, int w, int h) {
  const glm::dvec3 dirBody{std::cos(latDeg * kDeg) * std::cos(lonDeg * kDeg),
                           std::cos(latDeg * kDeg) * std::sin(lonDeg * kDeg),
                           std::sin(latDeg * kDeg)};
  clod::Camera cam;
  cam.position = body.centre + distance * (body.orientation * dirBody);
  cam.target = body.centre;
  cam.up = body.orientation * glm::dvec3(0.0, 0.0, 1.0);
  cam.fovYDegrees = fovDeg;
  cam.width = w;
  cam.height = h;
  cam.near = 1.0;
  return cam;
}

GlobeBody mars(const glm::dvec3& centre, const glm::dmat3& orientation) {
  GlobeBody b;
  b.centre = centre;
  b.orientation = orientation;
  b.a = kMarsA;
  b.b = kMarsB;
  b.colour = glm::vec3(0.85F, 0.55F, 0.35F);
  return b;
}

TEST(RayCastGlobeGLTest, MarsFrom1e8MetresMatchesOracleWithBothProxies) {
  // Far from the scene origin too: the centre at 2e11 m, the eye 1e8 m from it.
  const GlobeBody body = mars({2.0e11, -7.0e10, 3.0e10}, rotationXZ(25.0, 40.0));
  clod::Camera cam = lookingAtCentre(body, 20.0, 30.0, 1.0e8, 5.0, 640, 480);
  cam.target += 1.2e6 * (body.orientation * glm::dvec3(0.0, 1.0, 0.0));  // off centre
  checkBothProxies("mars_1e8", cam, body, glm::normalize(glm::dvec3(1.0, 0.4, 0.3)));
}

TEST(RayCastGlobeGLTest, Wgs84From1e11MetresThroughANarrowFieldMatchesOracle) {
  GlobeBody body;
  body.centre = {-1.4e11, 5.0e10, 2.0e9};
  body.orientation = rotationXZ(-23.44, 75.0);
  body.a = kWgs84A;
  body.b = kWgs84B;
  body.colour = glm::vec3(0.3F, 0.5F, 0.9F);
  // The eye 1e11 m from the centre, 2e-4 rad from the top of the image to the bottom: the
  // globe (1.28e-4 rad across) spans about 300 px; the focal length is 2.4e6 px.
  const clod::Camera cam = lookingAtCentre(body, 10.0, -60.0, 1.0e11, 2.0e-4 / kDeg, 480, 480);
  checkBothProxies("wgs84_1e11", cam, body, glm::normalize(glm::dvec3(-0.2, 1.0, 0.1)));
}

TEST(RayCastGlobeGLTest, MarsFrom1KilometreLookingAtTheHorizonMatchesOracle) {
  const topo::Body mb = topo::Body::marsEllipsoid();
  ASSERT_EQ(mb.equatorialRadius(), kMarsA);
  ASSERT_EQ(mb.polarRadius(), kMarsB);
  const GlobeBody body = mars({0.0, 0.0, 0.0}, glm::dmat3(1.0));
  const double lat = 35.0, lon = 120.0;
  const glm::dmat3 enu = mb.enuFrame(lat, lon);
  clod::Camera cam;
  cam.position = mb.toBodyFixed({lat, lon, 1000.0});
  // The horizon from 1 km is 0.77° below the horizontal; look 0.5° below it, north-east.
  const glm::dvec3 dir = glm::normalize(std::cos(1.27 * kDeg) * (enu[0] + enu[1]) / std::sqrt(2.0) -
                                        std::sin(1.27 * kDeg) * enu[2]);
  cam.target = cam.position + 1.0e4 * dir;
  cam.up = enu[2];
  cam.fovYDegrees = 30.0;
  cam.width = 640;
  cam.height = 360;
  cam.near = 0.5;
  checkBothProxies("mars_horizon_1km", cam, body, glm::normalize(enu[2] + 0.5 * enu[0]));
}

TEST(RayCastGlobeGLTest, Wgs84NadirFrom1KilometreHasNoCancellation) {
  // Straight down from 1 km: b and √disc are both ≈ 1 in the scaled space, their difference
  // 1.6e-4; the shader's c / (b + √disc) keeps the depth to float precision.
  const topo::Body eb = topo::Body::earthWgs84();
  GlobeBody body;
  body.a = eb.equatorialRadius();
  body.b = eb.polarRadius();
  clod::Camera cam;
  cam.position = eb.toBodyFixed({-33.0, 151.0, 1000.0});
  cam.target = eb.toBodyFixed({-33.0, 151.0, 0.0});
  cam.up = eb.enuFrame(-33.0, 151.0)[1];
  cam.fovYDegrees = 90.0;
  cam.width = 320;
  cam.height = 240;
  cam.near = 0.5;
  checkBothProxies("wgs84_nadir_1km", cam, body, glm::normalize(glm::dvec3(1.0, 1.0, 0.0)));
}

TEST(RayCastGlobeGLTest, MarsFrom1MillimetreLookingAtTheHorizonMatchesOracle) {
  // 1 mm above the ground: |e| − 1 = 3e-10, below float's resolution of the eye vector; the
  // quadratic's constant c = |e|² − 1 comes from double. A 90° field and a near plane of
  // 2 mm: the steepest rays meet the ground nearer than the near plane and are clipped.
  const topo::Body mb = topo::Body::marsEllipsoid();
  const GlobeBody body = mars({0.0, 0.0, 0.0}, glm::dmat3(1.0));
  const double lat = -62.0, lon = -100.0;
  const glm::dmat3 enu = mb.enuFrame(lat, lon);
  clod::Camera cam;
  cam.position = mb.toBodyFixed({lat, lon, 1.0e-3});
  cam.target = cam.position + glm::normalize(enu[1] - 0.2 * enu[0] - 0.01 * enu[2]);
  cam.up = enu[2];
  cam.fovYDegrees = 90.0;
  cam.width = 480;
  cam.height = 360;
  cam.near = 2.0e-3;
  checkBothProxies("mars_horizon_1mm", cam, body, glm::normalize(enu[2] + enu[0]));
}

/// A smooth, periodic test map: R peaks at ±180°, G follows latitude, B wiggles in longitude.
/// Constant at each pole.
glm::dvec3 mapColour(double latDeg, double lonDeg) {
  const double c = std::cos(latDeg * kDeg);
  return {128.0 + 100.0 * c * std::cos((lonDeg - 180.0) * kDeg),
          128.0 + 100.0 * std::sin(latDeg * kDeg),
          128.0 + 60.0 * c * std::sin(2.0 * lonDeg * kDeg)};
}

gl::RgbaImage testMap(int w, int h) {
  gl::RgbaImage img{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w * h * 4))};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::dvec3 c = mapColour(90.0 - (y + 0.5) * 180.0 / h, -180.0 + (x + 0.5) * 360.0 / w);
      auto* p = img.rgba.data() + 4 * static_cast<std::size_t>(y * w + x);
      for (int i = 0; i < 3; ++i) p[i] = static_cast<std::uint8_t>(std::lround(c[i]));
      p[3] = 255;
    }
  return img;
}

/// Level-0 bilinear lookup of `img` at (lat, lon): repeat in longitude, clamp in latitude.
glm::dvec3 bilinear(const gl::RgbaImage& img, double latDeg, double lonDeg) {
  const double u = (lonDeg + 180.0) / 360.0 * img.width - 0.5;
  const double v = (90.0 - latDeg) / 180.0 * img.height - 0.5;
  const double x0 = std::floor(u), y0 = std::floor(v);
  const double fx = u - x0, fy = v - y0;
  glm::dvec3 out(0.0);
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      int x = static_cast<int>(x0) + i, y = static_cast<int>(y0) + j;
      x = ((x % img.width) + img.width) % img.width;
      y = std::clamp(y, 0, img.height - 1);
      const double wgt = (i ? fx : 1.0 - fx) * (j ? fy : 1.0 - fy);
      const std::uint8_t* p = img.pixel(x, y);
      out += wgt * glm::dvec3(p[0], p[1], p[2]);
    }
  return out;
}

TEST(RayCastGlobeGLTest, TexturedPolesAndSeamHaveNoLineOrDot) {
  (void)test::glContext();
  const gl::RgbaImage map = testMap(256, 128);
  const gl::Texture tex = makeEquirectangularTexture(map, true);  // mipmapped: the seam's trap
  GlobeBody body = mars({1.0e9, 2.0e9, -3.0e9}, rotationXZ(10.0, -20.0));
  body.albedoTexture = tex.id();
  body.colour = glm::vec3(1.0F);
  GlobeOptions options;
  options.ambient = 1.0F;  // albedo only: the texture's own values
  for (const auto& [name, lat] : {std::pair{"seam", 5.0}, {"pole_seam", 62.0}}) {
    SCOPED_TRACE(name);
    clod::Camera cam = lookingAtCentre(body, lat, 179.3, 3.0 * kMarsA, 40.0, 640, 480);
    // Rolled by 17°: the seam then crosses the 2 × 2 quads of the derivatives (seen straight,
    // it would run along a quad boundary, where no quad straddles it).
    cam.up = body.orientation * glm::dvec3(0.0, std::sin(17.0 * kDeg), std::cos(17.0 * kDeg));
    RayCastGlobe globe(options);
    const Render r = render(globe, cam, body, glm::dvec3(1.0, 0.0, 0.0));
    test::savePng(std::string("globe_texture_") + name, r.colour);
    const Oracle o = oracle(cam, body);
    // Colour against the level-0 bilinear lookup where the texture is magnified (the surface
    // faces the eye within 60°, so no mip level above 0 applies).
    const glm::dvec3 toEye =
        glm::transpose(body.orientation) * glm::normalize(cam.position - body.centre);
    auto colourAt = [&](int x, int y, glm::dvec3& want) {
      const OraclePixel& p = o.at(x, y);
      if (glm::dot(p.normal, toEye) < 0.5) return false;
      want = bilinear(map, p.latDeg, p.lonDeg);
      return true;
    };
    const Comparison c = compare(r, o, cam, body, colourAt, 3);
    print(name, c, r.frame);
    expectMatches(c);
    EXPECT_GT(c.colourChecked, 50000);
    // Across the seam: the pixels nearest to 179.99° E and 179.99° W on the same row.
    int checkedRows = 0;
    for (int y = 0; y < o.h; y += 8) {
      int east = -1, west = -1;
      double bestE = 1.0, bestW = 1.0;
      for (int x = 0; x < o.w; ++x) {
        const OraclePixel& p = o.at(x, y);
        if (!p.hit || o.silhouette(x, y) || std::abs(p.latDeg) > 85.0) continue;
        if (std::abs(p.lonDeg - 179.99) < bestE) bestE = std::abs(p.lonDeg - 179.99), east = x;
        if (std::abs(p.lonDeg + 179.99) < bestW) bestW = std::abs(p.lonDeg + 179.99), west = x;
      }
      if (east < 0 || west < 0 || bestE > 0.5 || bestW > 0.5) continue;
      ++checkedRows;
      for (int i = 0; i < 3; ++i)
        EXPECT_LE(std::abs(r.colour.pixel(east, y)[i] - r.colour.pixel(west, y)[i]), 4)
            << "row " << y << " columns " << east << ", " << west;
    }
    EXPECT_GT(checkedRows, 10);
  }
}

TEST(RayCastGlobeGLTest, RasterisedTrianglesDepthTestAgainstTheGlobe) {
  (void)test::glContext();
  const GlobeBody body = mars({3.0e10, 1.0e10, 0.0}, rotationXZ(0.0, 15.0));
  const clod::Camera cam = lookingAtCentre(body, -10.0, 45.0, 2.0e7, 25.0, 480, 360);
  const Oracle o = oracle(cam, body);
  const OraclePixel& mid = o.at(240, 180);
  ASSERT_TRUE(mid.hit);
  const double surface = cam.near / mid.depth;  // view distance of the globe at the middle
  // A big square perpendicular to the view axis: 1e-4 in front of or behind the nearest
  // surface point, so it cuts the globe in a ring.
  const gl::Program flat("test triangle", {R"(#version 450 core
layout(location = 0) in vec3 aPos;
uniform mat4 uViewProj;
void main() { gl_Position = uViewProj * vec4(aPos, 1.0); }
)",
                                           "",
                                           R"(#version 450 core
out vec4 oColour;
void main() { oColour = vec4(0.0, 1.0, 0.0, 1.0); }
)"});
  const glm::dmat3 rot = cam.rotation();
  const glm::dvec3 right{rot[0][0], rot[1][0], rot[2][0]}, up{rot[0][1], rot[1][1], rot[2][1]};
  for (const double factor : {0.9999, 1.0001, 1.01}) {
    for (const bool globeFirst : {true, false}) {
      SCOPED_TRACE(factor);
      SCOPED_TRACE(globeFirst);
      const double dist = factor * surface;
      std::vector<glm::vec3> quad;
      for (const auto& [sx, sy] :
           {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}})
        quad.emplace_back(dist * cam.forward() + 0.3 * dist * (sx * right + sy * up));
      gl::Buffer vbo;
      glNamedBufferStorage(vbo.id(), static_cast<GLsizeiptr>(quad.size() * sizeof(glm::vec3)),
                           quad.data(), 0);
      gl::VertexArray vao;
      glVertexArrayVertexBuffer(vao.id(), 0, vbo.id(), 0, sizeof(glm::vec3));
      glVertexArrayAttribFormat(vao.id(), 0, 3, GL_FLOAT, GL_FALSE, 0);
      glVertexArrayAttribBinding(vao.id(), 0, 0);
      glEnableVertexArrayAttrib(vao.id(), 0);
      const gl::RenderTarget target(cam.width, cam.height);
      target.clear(kClear);
      RayCastGlobe globe;
      auto triangle = [&] {
        flat.use();
        flat.set("uViewProj", cam.viewProjection());
        glBindVertexArray(vao.id());
        glDrawArrays(GL_TRIANGLES, 0, 6);
        glBindVertexArray(0);
      };
      if (globeFirst) {
        (void)globe.draw(cam, body, cam.position - body.centre);
        triangle();
      } else {
        triangle();
        (void)globe.draw(cam, body, cam.position - body.centre);
      }
      const gl::RgbaImage img = target.readColor();
      test::savePng("globe_triangle_" + std::to_string(factor) +
                        (globeFirst ? "_globe_first" : "_quad_first"),
                    img);
      // Expected: the quad covers the whole image (its half-width 0.3·dist is beyond the
      // 12.5° half field); the globe wins where its depth is greater than the quad's.
      const double quadDepth = cam.near / dist;
      long wrong = 0, globeSeen = 0, quadSeen = 0;
      for (int y = 0; y < o.h; ++y)
        for (int x = 0; x < o.w; ++x) {
          const OraclePixel& p = o.at(x, y);
          if (o.silhouette(x, y)) continue;
          if (p.hit && std::abs(p.depth - quadDepth) < 2e-6 * quadDepth) continue;  // the ring
          const bool globeWins = p.hit && p.depth > quadDepth;
          const bool green = img.is(x, y, 0, 255, 0);
          globeSeen += globeWins ? 1 : 0;
          quadSeen += globeWins ? 0 : 1;
          if (green == globeWins) ++wrong;
        }
      std::printf("factor %.4f, globe first %d: globe %ld px, quad %ld px, wrong %ld\n", factor,
                  globeFirst ? 1 : 0, globeSeen, quadSeen, wrong);
      EXPECT_EQ(wrong, 0);
      EXPECT_GT(quadSeen, 1000);
      if (factor > 1.0) {
        EXPECT_GT(globeSeen, 50);  // 1.0001: a cap of 2 km depth, ~5 px radius
      }
    }
  }
}

/// Closest approach to the centre, in the scaled space, of the eye ray through `towards`
/// (relative to the eye, scene axes).
double closestApproach(const GlobeBody& body, const GlobeProxyGeometry& g,
                       const glm::dvec3& towards) {
  const glm::dvec3 inv{1.0 / body.a, 1.0 / body.a, 1.0 / body.b};
  const glm::dvec3 d = glm::normalize((glm::transpose(body.orientation) * towards) * inv);
  return glm::length(g.eyeScaled - glm::dot(g.eyeScaled, d) * d);
}

TEST(RayCastGlobeGLTest, PolygonEdgesTouchTheSilhouetteAndTheBoxBoundsIt) {
  // CPU only: the polygon's edge midpoints lie on rays tangent to the ellipsoid (closest
  // approach 1 in the scaled space, plus the documented 1e-6 margin), its vertices on rays
  // that miss; every box vertex lies outside the ellipsoid.
  const GlobeBody body = mars({4.0e10, -2.0e10, 1.0e9}, rotationXZ(30.0, -50.0));
  for (const double distance : {3.0e6 + 1.0e3 + kMarsA, 1.0e7, 1.0e8, 1.0e11}) {
    const clod::Camera cam = lookingAtCentre(body, 33.0, 71.0, distance, 30.0, 640, 480);
    for (const int n : {3, 4, 16, 64}) {
      const GlobeProxyGeometry g = globeProxy(cam, body, GlobeProxy::Polygon, n);
      ASSERT_EQ(g.vertices.size(), static_cast<std::size_t>(n));
      const double e = glm::length(g.eyeScaled);
      for (int i = 0; i < n; ++i) {
        const glm::dvec3& a = g.vertices[static_cast<std::size_t>(i)];
        const glm::dvec3& b = g.vertices[static_cast<std::size_t>((i + 1) % n)];
        const double mid = closestApproach(body, g, 0.5 * (a + b));
        EXPECT_GE(mid, 1.0) << distance << " m, N " << n << ", edge " << i;
        EXPECT_LE(mid - 1.0, 1.1e-6 * (e + 1.0)) << distance << " m, N " << n << ", edge " << i;
        EXPECT_GT(closestApproach(body, g, a), 1.0);
      }
    }
    const GlobeProxyGeometry box = globeProxy(cam, body, GlobeProxy::Box, 0);
    ASSERT_EQ(box.vertices.size(), 36U);
    const double m = 1e-6 * (distance + body.a);
    for (const glm::dvec3& v : box.vertices) {
      const glm::dvec3 q = glm::transpose(body.orientation) * (v + cam.position - body.centre);
      EXPECT_NEAR(std::abs(q.x), body.a + m, 1e-9 * distance);
      EXPECT_NEAR(std::abs(q.y), body.a + m, 1e-9 * distance);
      EXPECT_NEAR(std::abs(q.z), body.b + m, 1e-9 * distance);
    }
  }
}

TEST(RayCastGlobeGLTest, InsideTheEllipsoidDrawsNothing) {
  (void)test::glContext();
  const GlobeBody body = mars({0.0, 0.0, 0.0}, glm::dmat3(1.0));
  clod::Camera cam;
  cam.position = {kMarsA - 10.0, 0.0, 0.0};
  cam.target = {0.0, 0.0, 0.0};
  RayCastGlobe globe;
  const gl::RenderTarget target(cam.width, cam.height);
  target.clear(kClear);
  EXPECT_FALSE(globe.draw(cam, body, glm::dvec3(1.0, 0.0, 0.0)).drawn);
}

TEST(RayCastGlobeGLTest, BadInputIsNamed) {
  (void)test::glContext();
  GlobeOptions options;
  options.polygonPoints = 2;
  try {
    const RayCastGlobe g(options);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "farfield::RayCastGlobe(): polygonPoints is 2, expected 3 to 4096");
  }
  RayCastGlobe globe;
  GlobeBody body;
  body.a = -1.0;
  try {
    (void)globe.draw(clod::Camera{}, body, glm::dvec3(1.0, 0.0, 0.0));
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "farfield::RayCastGlobe::draw(): body equatorial radius a is -1 m, expected > 0, "
                 "finite");
  }
}

}  // namespace
}  // namespace regolith::farfield
