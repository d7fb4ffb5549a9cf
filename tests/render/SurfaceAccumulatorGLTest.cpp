// Colour composition by surface-map accumulation (docs/colour-composition.md), checked per
// pixel against the rule computed on the CPU in double: each albedo dataset encodes its id
// in a constant value, so the accumulated (Σ w·v, Σ w) of a pixel is fixed by the weights
// the rule gives each dataset there. The oracle unprojects the depth buffer itself, takes
// coverage from compose::Dataset::coverageQuality() and Kooima's α from the finite
// differences of each dataset's texture coordinates between neighbouring pixels, in the
// same 2×2 quads the GPU's fine derivatives use.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/Catalogue.hpp>
#include <regolith/compose/Dataset.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SurfaceAccumulator.hpp>

#include "compose/ComposeFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

namespace regolith::render {
namespace {

using compose::testing::demPyramid;
using compose::testing::named;
using compose::testing::planetPyramid;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The scene: a gently undulating region of the Mars ellipsoid (so the geodetic latitude's
// ellipsoid terms and foreshortening both matter), seen from 150 m at 40° below the horizon.
constexpr double kLat0 = 18.4, kLon0 = 77.5;
const topo::Body& mars() {
  static const topo::Body body = topo::Body::marsEllipsoid();
  return body;
}
double terrainHeight(double lat, double lon) {
  return -2500.0 + 2.0 * std::sin(3000.0 * lat * kDeg) * std::cos(2500.0 * lon * kDeg);
}

/// Heights of the colour datasets' bounds: the terrain's range (their samples are colours).
compose::DatasetOptions colour(const char* name, double feather, compose::Role role,
                               std::shared_ptr<const topo::SampleSource> mask = nullptr) {
  compose::DatasetOptions o = named(name, feather);
  o.role = role;
  o.heightRange = std::array<double, 2>{-2510.0, -2490.0};
  o.mask = std::move(mask);
  return o;
}

struct Scene {
  clod::Camera camera;
  std::unique_ptr<clod::ClipmapTerrain> terrain;
  std::unique_ptr<gl::RenderTarget> target;
};

/// A source of one value everywhere (a planet-sized pyramid without its memory).
class ConstantSource final : public topo::SampleSource {
 public:
  ConstantSource(std::size_t rows, std::size_t cols, float v) : rows_(rows), cols_(cols), v_(v) {}
  [[nodiscard]] std::size_t rows() const noexcept override { return rows_; }
  [[nodiscard]] std::size_t cols() const noexcept override { return cols_; }
  [[nodiscard]] float sample(std::size_t, std::size_t) const override { return v_; }

 private:
  std::size_t rows_, cols_;
  float v_;
};

Scene makeScene(int width, int height) {
  Scene s;
  const double d = 1e-5;  // 0.59 m
  const topo::TopoGrid grid(1025, 1025, kLon0 - 512 * d, kLat0 + 512 * d, d, d);
  auto samples = topo::InMemorySamples::fromFunction(1025, 1025, [&](std::size_t r, std::size_t c) {
    return static_cast<float>(terrainHeight(kLat0 + (512.0 - static_cast<double>(r)) * d,
                                            kLon0 + (static_cast<double>(c) - 512.0) * d));
  });
  auto pyramid = std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      grid, samples, clod::SurfaceKind::Planet, mars(), topo::LatitudeType::Planetodetic));
  clod::ClipmapOptions options;
  const glm::dmat3 enu = mars().enuFrame(kLat0, kLon0);
  options.lightDirection = glm::vec3(glm::normalize(0.3 * enu[0] + 0.3 * enu[1] + 0.9 * enu[2]));
  s.terrain = std::make_unique<clod::ClipmapTerrain>(pyramid, options);
  s.camera.target = mars().toBodyFixed({kLat0, kLon0, terrainHeight(kLat0, kLon0)});
  s.camera.position = s.camera.target + 120.0 * enu[2] - 100.0 * enu[1] + 20.0 * enu[0];
  s.camera.up = enu[2];
  s.camera.fovYDegrees = 60.0;
  s.camera.width = width;
  s.camera.height = height;
  s.camera.near = 0.5;
  s.terrain->setFocus(s.camera.target);
  s.terrain->finishLoading();
  s.target = std::make_unique<gl::RenderTarget>(width, height);
  s.target->clear({0.05F, 0.05F, 0.1F, 1.0F});
  s.terrain->draw(s.camera);
  return s;
}

/// A dataset's level-0 fractional texel coordinates at a planetodetic point (double), as
/// compose::Dataset locates points: planets by longitude and their latitude type, placed
/// grids through their placement at the middle of their height range.
glm::dvec2 texel(const compose::Dataset& ds, double lat, double lon, double lonNear) {
  const topo::TopoGrid& g = ds.level(0).grid;
  if (ds.isPlanet()) {
    // Longitudes in one turn around the view (a global grid's texel columns then run on
    // across ±180° as the GPU's do), else the turn the grid lies in.
    const double centre = std::isnan(lonNear) ? 0.5 * (g.west() + g.east()) : lonNear;
    return g.fractionalIndex(centre + topo::wrapLongitude180(lon - centre),
                             ds.body().fromPlanetodetic(lat, ds.latitudeType()));
  }
  const double hmid = 0.5 * (ds.heightRange()[0] + ds.heightRange()[1]);
  const glm::dvec3 xyh =
      ds.placement()->fromGeodeticNear({lat, lon, hmid}, 0.5 * (g.west() + g.east()));
  return g.fractionalIndex(xyh.x, xyh.y);
}

/// The rule on the CPU: per pixel, per role, (Σ w·v, Σ w) with w = coverage × α.
struct Expected {
  std::vector<glm::dvec4> sums;      // like readAccumulation()
  std::vector<bool> checkable;       // the pixel's quad is all terrain
  std::vector<glm::dvec3> position;  // body-fixed
  // Per dataset and pixel: coverage, α (for the seam bound).
  std::vector<std::vector<double>> coverage, alpha;
};

Expected cpuRule(const Scene& s, const compose::Snapshot& snap, double logN, double value(int),
                 double lonNear = kNaN) {
  const clod::Camera& cam = s.camera;
  const gl::DepthImage depth = s.target->readDepth();
  const int w = cam.width, h = cam.height;
  const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  Expected e;
  e.sums.assign(n, glm::dvec4(0.0));
  e.checkable.assign(n, false);
  e.position.assign(n, glm::dvec3(kNaN));
  std::vector<topo::Geodetic> geo(n);
  const glm::dvec3 f = cam.forward();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float z = depth.at(x, y);
      if (z <= 0.0F) continue;
      const glm::dvec3 ray = cam.ray(x + 0.5, y + 0.5);
      const glm::dvec3 p = cam.position + (cam.viewDistance(z) / glm::dot(ray, f)) * ray;
      const auto i = static_cast<std::size_t>(y * w + x);
      e.position[i] = p;
      geo[i] = mars().toGeodetic(p);
    }
  }
  // GL's quads: pixel (x, yGl) with yGl = h − 1 − y pairs with x ^ 1 and yGl ^ 1.
  auto idx = [&](int x, int yGl) { return static_cast<std::size_t>((h - 1 - yGl) * w + x); };
  for (int yGl = 0; yGl + 1 < h; yGl += 2) {
    for (int x = 0; x + 1 < w; x += 2) {
      const bool all = !std::isnan(e.position[idx(x, yGl)].x) &&
                       !std::isnan(e.position[idx(x + 1, yGl)].x) &&
                       !std::isnan(e.position[idx(x, yGl + 1)].x) &&
                       !std::isnan(e.position[idx(x + 1, yGl + 1)].x);
      for (int k = 0; k < 4; ++k) e.checkable[idx(x + (k & 1), yGl + (k >> 1))] = all;
    }
  }
  const auto entries = snap.entries();
  e.coverage.assign(entries.size(), std::vector<double>(n, 0.0));
  e.alpha.assign(entries.size(), std::vector<double>(n, 0.0));
  for (std::size_t di = 0; di < entries.size(); ++di) {
    const compose::Dataset& ds = *entries[di].dataset;
    if (ds.options().role == compose::Role::Height) continue;
    std::vector<glm::dvec2> t(n, glm::dvec2(kNaN));
    for (std::size_t i = 0; i < n; ++i)
      if (e.checkable[i]) t[i] = texel(ds, geo[i].latDeg, geo[i].lonDeg, lonNear);
    for (int yGl = 0; yGl + 1 < h; yGl += 2) {
      for (int x = 0; x + 1 < w; x += 2) {
        if (!e.checkable[idx(x, yGl)]) continue;
        for (int k = 0; k < 4; ++k) {
          const int px = x + (k & 1), py = yGl + (k >> 1);
          // Fine derivatives: along x within the pixel's row of the quad, along y within
          // its column.
          const glm::dvec2 dx = t[idx(x + 1, py)] - t[idx(x, py)];
          const glm::dvec2 dy = t[idx(px, yGl + 1)] - t[idx(px, yGl)];
          const double k2 = (dx.x * dx.x + dy.x * dy.x) / (dx.y * dx.y + dy.y * dy.y);
          const double a =
              std::clamp(1.0 - std::abs(0.5 * std::log(k2)) / logN, compose::kMinQuality, 1.0);
          const std::size_t i = idx(px, py);
          const double c = ds.coverageQuality(geo[i].latDeg, geo[i].lonDeg)[0];
          e.coverage[di][i] = c;
          e.alpha[di][i] = a;
          const double wgt = c * a;
          const double v = value(static_cast<int>(di));
          if (ds.options().role == compose::Role::Albedo) {
            e.sums[i] += glm::dvec4(wgt * v, wgt, 0.0, 0.0);
          } else {
            e.sums[i] += glm::dvec4(0.0, 0.0, wgt * v, wgt);
          }
        }
      }
    }
  }
  return e;
}

/// A constant-valued source (the dataset's id code) with NaN where `keep` is false.
std::shared_ptr<const topo::SampleSource> constant(std::size_t rows, std::size_t cols, float v) {
  return std::make_shared<topo::InMemorySamples>(rows, cols, std::vector<float>(rows * cols, v));
}

topo::GridPyramid withSource(topo::GridPyramid p, std::shared_ptr<const topo::SampleSource> s) {
  p.levels[0].source = std::move(s);
  return p;
}

/// Values encode the dataset: entry i has value kValues[i].
constexpr std::array<double, 6> kValues{0.2, 0.5, 0.8, 0.65, 0.35, 0.9};
double valueOf(int i) { return kValues.at(static_cast<std::size_t>(i)); }

TEST(SurfaceAccumulatorGLTest, EachPixelBlendsTheDatasetsByCoverageTimesScreenSpaceQuality) {
  test::glContext();
  Scene s = makeScene(320, 240);
  const topo::Body& body = mars();
  const double r = body.equatorialRadius();
  const double mLon = r * std::cos(kLat0 * kDeg) * kDeg;  // metres per degree east, roughly
  compose::Catalogue cat(body);
  // 0: a regional latitude/longitude grid (planetodetic), 0.2, over the west of the view
  //    (its east edge 15 m east of the target), feathered over 30 m.
  {
    const double step = 2e-5;
    const std::size_t cols = 600, rows = 1200;
    const double east = kLon0 + 15.0 / mLon;
    auto p = planetPyramid(body, kLat0 + 600 * step, east - (cols - 0.5) * step, step, rows, cols,
                           [](double, double) { return 0.0; });
    p.latitudeType = topo::LatitudeType::Planetodetic;
    cat.add(compose::Dataset::planet(withSource(p, constant(rows, cols, 0.2F)),
                                     colour("latlon", 30.0, compose::Role::Albedo)));
  }
  // 1: a 1 m tangent-plane grid turned by 30°, 0.5, 25 m feather, 20 m north-east.
  const glm::dmat3 enu = body.enuFrame(kLat0, kLon0);
  const glm::dvec3 target = s.camera.target;
  auto geodeticAt = [&](double east, double north) {
    const topo::Geodetic g = body.toGeodetic(target + east * enu[0] + north * enu[1]);
    return topo::Geodetic{g.latDeg, g.lonDeg, 0.0};
  };
  cat.add(compose::Dataset::dem(
      withSource(demPyramid(1.0, 121, 121, [](double, double) { return 0.0; }),
                 constant(121, 121, 0.5F)),
      topo::Placement(topo::LocalTangentPlane(body, geodeticAt(20.0, 20.0), 30.0)),
      colour("plane", 25.0, compose::Role::Albedo)));
  // 2: a north polar stereographic map 0.5 m, 0.8, 20 m feather, 30 m south of the target
  //    (7900 km from its pole: its scale is 1.5 there, and anisotropy none).
  {
    const auto ps = topo::PolarStereographic::withTrueScaleLatitude(
        body, topo::PolarStereographic::Pole::North, 90.0, 0.0);
    const topo::Placement pl(body, ps);
    const topo::Geodetic c = geodeticAt(0.0, -30.0);
    const glm::dvec3 xy = pl.fromGeodetic(c);
    cat.add(compose::Dataset::dem(
        withSource(demPyramid(
                       0.5, 161, 161, [](double, double) { return 0.0; }, xy.x, xy.y),
                   constant(161, 161, 0.8F)),
        pl, colour("polar", 20.0, compose::Role::Albedo)));
  }
  // 3: an equirectangular map read planetocentric, 0.6 m, 0.65, 15 m feather, 40 m east.
  {
    const topo::Equirectangular eq(r, 0.0, 0.0);
    const topo::Placement pl(body, eq, topo::LatitudeType::Planetocentric);
    const glm::dvec3 xy = pl.fromGeodetic(geodeticAt(40.0, 10.0));
    cat.add(compose::Dataset::dem(
        withSource(demPyramid(
                       0.6, 121, 101, [](double, double) { return 0.0; }, xy.x, xy.y),
                   constant(121, 101, 0.65F)),
        pl, colour("equirect", 15.0, compose::Role::Albedo)));
  }
  // 4: an overlay on a tangent plane, 0.35, 10 m feather, over the target.
  cat.add(compose::Dataset::dem(
      withSource(demPyramid(0.8, 61, 81, [](double, double) { return 0.0; }),
                 constant(61, 81, 0.35F)),
      topo::Placement(topo::LocalTangentPlane(body, geodeticAt(-10.0, 5.0), -15.0)),
      colour("overlay", 10.0, compose::Role::Overlay)));
  // 5: a height dataset: not a colour, never drawn by the accumulator.
  cat.add(compose::Dataset::planet(planetPyramid(body, kLat0 + 0.01, kLon0 - 0.01, 1e-3, 21, 21,
                                                 [](double, double) { return -2500.0; }),
                                   named("heights")));
  const auto snap = cat.snapshot();

  SurfaceAccumulator acc;
  const AccumulationFrame frame = acc.accumulate(*s.target, s.camera, *snap);
  EXPECT_EQ(frame.visible, 5U);
  EXPECT_EQ(frame.drawn, 5U);
  for (const DatasetWindow& w : acc.windows()) EXPECT_EQ(w.level, 0U) << w.id;
  const std::vector<glm::vec4> gpu = acc.readAccumulation();
  const std::vector<glm::vec2> cover = acc.readCoverage();
  const gl::RgbaImage before = s.target->readColor();
  acc.normalise(*s.target);
  const gl::RgbaImage after = s.target->readColor();
  test::savePng("accumulation_terrain", before);
  test::savePng("accumulation_composed", after);

  const Expected e = cpuRule(s, *snap, std::log(compose::kQualityN), valueOf);
  // Tolerance. The GPU forms each point from a float depth and float offsets from its
  // reference point (≤ 300 m here: ~3e-5 m of rounding), so coverage (slope ≤ 1.5 / 10 m)
  // agrees to ~1e-5. α comes from differences of texel coordinates between neighbouring
  // pixels (0.1 .. 2 texels here) whose float rounding (~3e-5 texels after the geodetic
  // and projection differences) changes log k by ≤ 3e-4, α by ≤ 1.5e-4 (÷ log 8): 2e-3 on
  // sums of up to 4 weights leaves a factor of 3.
  constexpr double kTol = 2e-3;
  int checked = 0, overlapping = 0, overlaid = 0, printed = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < gpu.size(); ++i) {
    if (!e.checkable[i]) {
      continue;
    }
    const glm::dvec4 g(gpu[i]);
    const glm::dvec4 err = glm::abs(g - e.sums[i]);
    const double m = std::max({err.x, err.y, err.z, err.w});
    worst = std::max(worst, m);
    if (m > kTol && ++printed <= 5) {
      std::printf("pixel %zu: gpu (%.5f %.5f %.5f %.5f) cpu (%.5f %.5f %.5f %.5f)\n", i, g.x, g.y,
                  g.z, g.w, e.sums[i].x, e.sums[i].y, e.sums[i].z, e.sums[i].w);
    }
    ++checked;
    int n = 0;
    for (std::size_t d = 0; d < 4; ++d) n += e.coverage[d][i] > 0.0 ? 1 : 0;
    overlapping += n >= 2 ? 1 : 0;
    overlaid += e.coverage[4][i] > 0.0 ? 1 : 0;
    // The coverage products: Π (1 − c) per role.
    double pa = 1.0;
    for (std::size_t d = 0; d < 4; ++d) pa *= 1.0 - e.coverage[d][i];
    EXPECT_NEAR(cover[i].x, pa, 1e-3) << i;
    EXPECT_NEAR(cover[i].y, 1.0 - e.coverage[4][i], 1e-3) << i;
  }
  std::printf(
      "checked %d pixels (%d with two or more albedo datasets, %d under the overlay): "
      "worst |error| %.2e\n",
      checked, overlapping, overlaid, worst);
  EXPECT_GE(checked, 40000);
  EXPECT_GE(overlapping, 3000);
  EXPECT_GE(overlaid, 1000);
  EXPECT_LE(worst, kTol);

  // The normalised colour: terrain × (1 + (albedo − 1) × albedo coverage), then the overlay
  // ramp over it, to the 8-bit rounding of the two reads (±1 level, and the blend's).
  int compared = 0;
  for (std::size_t i = 0; i < gpu.size(); i += 7) {
    if (!e.checkable[i] || e.sums[i].w > 0.0) continue;
    const double shown = 1.0 - static_cast<double>(cover[i].x);
    const glm::dvec4 g(gpu[i]);
    const double albedo = g.y > 0.0 ? g.x / g.y : 1.0;
    const double factor = 1.0 + (albedo - 1.0) * shown;
    for (int ch = 0; ch < 3; ++ch) {
      const double want = before.rgba[4 * i + static_cast<std::size_t>(ch)] * factor;
      EXPECT_NEAR(after.rgba[4 * i + static_cast<std::size_t>(ch)], want, 1.5) << i;
    }
    ++compared;
  }
  EXPECT_GE(compared, 3000);
}

/// A strip along an inclined ground track (Kooima §4.2): a tangent-plane grid whose data
/// fill a band with wavy edges, NaN elsewhere, and a mask feathered from that nodata border
/// (compose::featherMask), over a base albedo map. Along screen rows, which cross the
/// strip's borders, the composed value changes between neighbouring pixels by at most what
/// the feather allows; the same strip without its mask shows the seam (the check can fail).
struct StripResult {
  double worstExcess = -1.0;  // largest |ΔV| − allowed between neighbouring pixels
  double largestStep = 0.0;   // largest |ΔV|
  int pairs = 0, crossing = 0;
  double worstRule = 0.0;
};

StripResult stripScene(bool feathered, const char* png) {
  Scene s = makeScene(320, 240);
  const topo::Body& body = mars();
  const glm::dmat3 enu = body.enuFrame(kLat0, kLon0);
  compose::Catalogue cat(body);
  // Base: a lat/lon grid over the whole view, 0.2, no feather needed (it covers all).
  const double step = 2e-5;
  auto base = planetPyramid(body, kLat0 + 0.006, kLon0 - 0.006, step, 601, 601,
                            [](double, double) { return 0.0; });
  base.latitudeType = topo::LatitudeType::Planetodetic;
  cat.add(compose::Dataset::planet(withSource(base, constant(601, 601, 0.2F)),
                                   colour("base", 0.0, compose::Role::Albedo)));
  // The strip: 0.5 m samples, 481 × 481, a band ~50 m wide along a direction 25° from the
  // plane's x axis, its edges waving by ±6 m; value 1.0 inside.
  const double sp = 0.5;
  const std::size_t n = 481;
  const topo::TopoGrid grid(n, n, -120.0, 120.0, sp, sp);
  const double a = 25.0 * kDeg;
  auto values = topo::InMemorySamples::fromFunction(n, n, [&](std::size_t r, std::size_t c) {
    const double x = -120.0 + sp * static_cast<double>(c), y = 120.0 - sp * static_cast<double>(r);
    const double along = x * std::cos(a) + y * std::sin(a);
    const double across = -x * std::sin(a) + y * std::cos(a);
    const double halfWidth = 25.0 + 6.0 * std::sin(along / 9.0);
    return std::abs(across) <= halfWidth ? 1.0F : std::numeric_limits<float>::quiet_NaN();
  });
  std::shared_ptr<const topo::SampleSource> mask;
  if (feathered) mask = compose::featherMask(grid, *values, 24.0, true);  // 12 m
  topo::GridPyramid strip;
  strip.levels.push_back({grid, values});
  const topo::Geodetic origin = body.toGeodetic(s.camera.target + 10.0 * enu[1]);
  cat.add(compose::Dataset::dem(
      strip,
      topo::Placement(topo::LocalTangentPlane(body, {origin.latDeg, origin.lonDeg, 0.0}, 0.0)),
      colour("strip", 0.0, compose::Role::Albedo, mask)));
  const auto snap = cat.snapshot();
  SurfaceAccumulator acc;
  acc.accumulate(*s.target, s.camera, *snap);
  const std::vector<glm::vec4> gpu = acc.readAccumulation();
  acc.normalise(*s.target);
  test::savePng(png, s.target->readColor());

  const std::array<double, 2> v{0.2, 1.0};
  const Expected e =
      cpuRule(s, *snap, std::log(compose::kQualityN), [](int i) { return i == 0 ? 0.2 : 1.0; });
  StripResult out;
  const int w = s.camera.width;
  const double featherMetres = 24.0 * sp;
  for (int y = 0; y < s.camera.height; ++y) {
    for (int x = 0; x + 1 < w; ++x) {
      const auto i = static_cast<std::size_t>(y * w + x), j = i + 1;
      if (!e.checkable[i] || !e.checkable[j] || gpu[i].y <= 0.0F || gpu[j].y <= 0.0F) continue;
      if (feathered) {
        const glm::dvec4 g(gpu[i]);
        out.worstRule =
            std::max({out.worstRule, std::abs(g.x - e.sums[i].x), std::abs(g.y - e.sums[i].y)});
      }
      const double vi = static_cast<double>(gpu[i].x / gpu[i].y);
      const double vj = static_cast<double>(gpu[j].x / gpu[j].y);
      const double change = std::abs(vj - vi);
      // What the feather allows: the strip's coverage c = smoothstep(d / W) of the distance
      // d to its nodata border rises by at most 1.5 δ / W between points δ apart on the
      // ground (√2 for the bilinear mask between diagonal samples); its share
      // s = c αs / (c αs + αb) by at most that times max αs αb / (c αs + αb)², and V by
      // |1.0 − 0.2| times that. Plus 2e-3 for α's own change between the pixels and float.
      double ratio = 0.0;
      for (std::size_t k : {i, j}) {
        const double as = e.alpha[1][k], ab = e.alpha[0][k], c = e.coverage[1][k];
        ratio = std::max(ratio, as * ab / ((c * as + ab) * (c * as + ab)));
      }
      const double delta = glm::length(e.position[j] - e.position[i]);
      const double allowed =
          (v[1] - v[0]) * ratio * 1.5 * std::sqrt(2.0) * delta / featherMetres + 2e-3;
      out.worstExcess = std::max(out.worstExcess, change - allowed);
      out.largestStep = std::max(out.largestStep, change);
      ++out.pairs;
      const bool ci = e.coverage[1][i] > 0.0 && e.coverage[1][i] < 1.0;
      out.crossing += ci ? 1 : 0;
    }
  }
  return out;
}

TEST(SurfaceAccumulatorGLTest, AFeatheredStripWithANonRectangularBorderShowsNoSeam) {
  test::glContext();
  const StripResult r = stripScene(true, "accumulation_strip");
  std::printf(
      "feathered strip: %d neighbour pairs, %d in the feather, largest step %.4f, worst "
      "excess over the feather's bound %.2e, worst |rule error| %.2e\n",
      r.pairs, r.crossing, r.largestStep, r.worstExcess, r.worstRule);
  EXPECT_GE(r.pairs, 40000);
  EXPECT_GE(r.crossing, 2000);
  EXPECT_LE(r.worstExcess, 0.0);
  EXPECT_LE(r.worstRule, 2e-3);
  // Control: without the mask the strip's border is a step between two pixels: from the
  // base's 0.2 to the even blend (0.2 αb + 1.0 αs) / (αb + αs) ≈ 0.6.
  const StripResult hard = stripScene(false, "accumulation_strip_unfeathered");
  std::printf("unfeathered strip: largest step %.4f\n", hard.largestStep);
  EXPECT_GT(hard.largestStep, 0.3);
  EXPECT_GT(hard.worstExcess, 0.25);
}

TEST(SurfaceAccumulatorGLTest, AGlobalMapSeenFromOrbitReadsACoarserLevelAcrossTheAntimeridian) {
  test::glContext();
  const topo::Body& body = mars();
  // Terrain: a global grid of 0.5° at height 0; camera 3000 km above 10° N, 179.5° E.
  const double tStep = 0.5;
  const topo::TopoGrid tGrid(360, 720, -180.0 + 0.5 * tStep, 90.0 - 0.5 * tStep, tStep, tStep);
  auto pyramid = std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      tGrid, std::make_shared<ConstantSource>(360, 720, 0.0F), clod::SurfaceKind::Planet, body,
      topo::LatitudeType::Planetodetic));
  clod::ClipmapTerrain terrain(pyramid, clod::ClipmapOptions{});
  clod::Camera cam;
  const double latC = 10.0, lonC = 179.5;
  cam.target = body.toBodyFixed({latC, lonC, 0.0});
  const glm::dmat3 enu = body.enuFrame(latC, lonC);
  cam.position = cam.target + 3.0e6 * enu[2] - 1.0e6 * enu[1];
  cam.up = enu[2];
  cam.fovYDegrees = 40.0;
  cam.width = 256;
  cam.height = 192;
  cam.near = 1000.0;
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  Scene s;
  s.camera = cam;
  s.target = std::make_unique<gl::RenderTarget>(cam.width, cam.height);
  s.target->clear({0.0F, 0.0F, 0.0F, 1.0F});
  terrain.draw(cam);
  // Albedo: a global grid of 45° / 4096 (650 m) with 12 levels (each an exact global grid,
  // so Dataset keeps them all), value 0.4 everywhere.
  topo::GridPyramid p;
  for (int l = 0; l < 12; ++l) {
    const double st = 45.0 * std::ldexp(1.0, l - 12);
    const auto rows = static_cast<std::size_t>(std::lround(180.0 / st));
    const auto cols = static_cast<std::size_t>(std::lround(360.0 / st));
    p.levels.push_back({topo::TopoGrid(rows, cols, -180.0 + 0.5 * st, 90.0 - 0.5 * st, st, st),
                        std::make_shared<ConstantSource>(rows, cols, 0.4F)});
  }
  p.planetBody = body;
  p.latitudeType = topo::LatitudeType::Planetodetic;
  compose::DatasetOptions o = named("global");
  o.role = compose::Role::Albedo;
  o.heightRange = std::array<double, 2>{-10.0, 10.0};
  compose::Catalogue cat(body);
  cat.add(compose::Dataset::planet(p, o));
  const auto snap = cat.snapshot();
  AccumulatorOptions ao;
  ao.maxWindow = 256;
  SurfaceAccumulator acc(ao);
  const AccumulationFrame frame = acc.accumulate(*s.target, cam, *snap);
  ASSERT_EQ(frame.drawn, 1U);
  const DatasetWindow& w = acc.windows().at(0);
  const topo::TopoGrid& wg = snap->entries()[0].dataset->level(w.level).grid;
  std::printf("level %zu (%.2f deg), window %d x %d from column %lld of %zu\n", w.level,
              wg.spacingX(), w.cols, w.rows, static_cast<long long>(w.col0), wg.cols());
  // The footprint (~12 km) alone would pick level 4 (0.18°, 10 km); the visible ~110° of
  // longitude in a 256-texel window need 0.7° (level 6).
  EXPECT_GE(w.level, 6U);
  EXPECT_LE(w.cols, 256);
  EXPECT_LE(w.rows, 256);
  // The window runs across the antimeridian: its columns leave the grid's [0, cols).
  EXPECT_GT(static_cast<std::size_t>(w.col0) + static_cast<std::size_t>(w.cols), wg.cols());
  const std::vector<glm::vec4> gpu = acc.readAccumulation();
  acc.normalise(*s.target);
  test::savePng("accumulation_global", s.target->readColor());
  const Expected e = cpuRule(
      s, *snap, std::log(compose::kQualityN), [](int) { return 0.4; }, lonC);
  // Positions 3000 km away: float keeps ~0.3 m of them, ~1e-4 of a 6 km pixel; α as above.
  int checked = 0, east = 0, west = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < gpu.size(); ++i) {
    if (!e.checkable[i]) continue;
    const glm::dvec4 g(gpu[i]);
    worst = std::max({worst, std::abs(g.x - e.sums[i].x), std::abs(g.y - e.sums[i].y)});
    ++checked;
    const double lon = mars().toGeodetic(e.position[i]).lonDeg;
    (lon > 0.0 ? east : west)++;
  }
  std::printf("checked %d pixels (%d east of 180°, %d west): worst |error| %.2e\n", checked, east,
              west, worst);
  EXPECT_GE(checked, 10000);
  EXPECT_GE(east, 2000);
  EXPECT_GE(west, 2000);
  EXPECT_LE(worst, 2e-3);
}

TEST(SurfaceAccumulatorGLTest, APolarCapMapIsExactAtItsPole) {
  test::glContext();
  const topo::Body& body = mars();
  // Terrain: the global 0.5° grid at height 0 (its clipmap continues over the pole);
  // camera 400 km above the north pole, looking down at it from a little to the side.
  const double tStep = 0.5;
  const topo::TopoGrid tGrid(360, 720, -180.0 + 0.5 * tStep, 90.0 - 0.5 * tStep, tStep, tStep);
  auto pyramid = std::make_shared<const clod::HeightPyramid>(clod::HeightPyramid::fromSamples(
      tGrid, std::make_shared<ConstantSource>(360, 720, 0.0F), clod::SurfaceKind::Planet, body,
      topo::LatitudeType::Planetodetic));
  clod::ClipmapTerrain terrain(pyramid, clod::ClipmapOptions{});
  Scene s;
  clod::Camera& cam = s.camera;
  cam.target = body.toBodyFixed({90.0, 0.0, 0.0});
  cam.position = body.toBodyFixed({88.0, 30.0, 400.0e3});
  cam.up = glm::dvec3(0.0, 0.0, 1.0);
  cam.fovYDegrees = 50.0;
  cam.width = 256;
  cam.height = 192;
  cam.near = 1000.0;
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  s.target = std::make_unique<gl::RenderTarget>(cam.width, cam.height);
  s.target->clear({0.0F, 0.0F, 0.0F, 1.0F});
  terrain.draw(cam);
  // A north polar stereographic cap, 1 km samples, 401² centred on the pole, 0.6, feathered
  // over 40 km; and a second one turned by its central meridian (90° E), 0.3, over 60 km:
  // both meet the pole, where longitude has no meaning and ρ → 0.
  compose::Catalogue cat(body);
  for (int k = 0; k < 2; ++k) {
    const auto ps = topo::PolarStereographic::withTrueScaleLatitude(
        body, topo::PolarStereographic::Pole::North, 90.0, k == 0 ? 0.0 : 90.0);
    const std::size_t n = k == 0 ? 401 : 301;
    const double sp = k == 0 ? 1000.0 : 1500.0;
    compose::DatasetOptions o = named(k == 0 ? "cap" : "turned cap", k == 0 ? 40e3 : 60e3);
    o.role = compose::Role::Albedo;
    o.heightRange = std::array<double, 2>{-10.0, 10.0};
    cat.add(
        compose::Dataset::dem(withSource(demPyramid(sp, n, n, [](double, double) { return 0.0; }),
                                         constant(n, n, k == 0 ? 0.6F : 0.3F)),
                              topo::Placement(body, ps), o));
  }
  const auto snap = cat.snapshot();
  SurfaceAccumulator acc;
  ASSERT_EQ(acc.accumulate(*s.target, cam, *snap).drawn, 2U);
  const std::vector<glm::vec4> gpu = acc.readAccumulation();
  acc.normalise(*s.target);
  // The context is left with the GL's default blend factors: with the normalising pass's
  // dual-source one (GL_SRC1_COLOR) Mesa refused the far field's next draw into two buffers.
  GLint src = 0, dst = 0;
  glGetIntegerv(GL_BLEND_SRC_RGB, &src);
  glGetIntegerv(GL_BLEND_DST_RGB, &dst);
  EXPECT_EQ(src, GL_ONE);
  EXPECT_EQ(dst, GL_ZERO);
  test::savePng("accumulation_pole", s.target->readColor());
  const Expected e =
      cpuRule(s, *snap, std::log(compose::kQualityN), [](int i) { return i == 0 ? 0.6 : 0.3; });
  // Positions ~400 km away: float keeps ~0.04 m of them, 4e-5 of a 1 km sample.
  int checked = 0, both = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < gpu.size(); ++i) {
    if (!e.checkable[i]) continue;
    const glm::dvec4 g(gpu[i]);
    worst = std::max({worst, std::abs(g.x - e.sums[i].x), std::abs(g.y - e.sums[i].y)});
    ++checked;
    both += e.coverage[0][i] > 0.0 && e.coverage[1][i] > 0.0 ? 1 : 0;
  }
  std::printf("checked %d pixels (%d under both caps): worst |error| %.2e\n", checked, both, worst);
  EXPECT_GE(checked, 20000);
  EXPECT_GE(both, 10000);
  EXPECT_LE(worst, 2e-3);
}

TEST(SurfaceAccumulatorGLTest, RefusesAPlacementItCannotMap) {
  test::glContext();
  const topo::Body& body = mars();
  compose::Catalogue cat(body);
  const topo::TransverseMercator tm(body, kLon0);
  const topo::Placement pl(body, tm);
  const glm::dvec3 xy = pl.fromGeodetic({kLat0, kLon0, 0.0});
  cat.add(compose::Dataset::dem(
      withSource(demPyramid(
                     1.0, 101, 101, [](double, double) { return 0.0; }, xy.x, xy.y),
                 constant(101, 101, 0.5F)),
      pl, colour("utm-like", 0.0, compose::Role::Albedo)));
  Scene s = makeScene(64, 48);
  SurfaceAccumulator acc;
  try {
    (void)acc.accumulate(*s.target, s.camera, *cat.snapshot());
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "render::SurfaceAccumulator::accumulate(): dataset 'utm-like' (albedo) "
                 "placement is transverse Mercator, expected a planet latitude/longitude grid, "
                 "a local tangent plane, a polar stereographic or an equirectangular map");
  }
  clod::Camera wrong = s.camera;
  wrong.width = 65;
  EXPECT_THROW((void)acc.accumulate(*s.target, wrong, *cat.snapshot()), InvalidArgument);
}

}  // namespace
}  // namespace regolith::render
