#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/FocusController.hpp>
#include <regolith/clod/MeshRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Placement.hpp>

#include "TerrainFixtures.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <span>
#include <utility>
#include <vector>

namespace regolith::clod {
namespace {

const glm::vec4 kMagenta{1.0F, 0.0F, 1.0F, 1.0F};

struct Shot {
  gl::RgbaImage color;
  gl::DepthImage depth;
};

Shot render(const Camera& cam, const std::function<void()>& draw) {
  gl::RenderTarget target(cam.width, cam.height);
  target.clear(kMagenta);
  draw();
  return {target.readColor(), target.readDepth()};
}

Shot renderClipmap(ClipmapTerrain& terrain, const Camera& cam) {
  return render(cam, [&] { terrain.draw(cam); });
}

bool magenta(const gl::RgbaImage& img, int x, int y) { return img.is(x, y, 255, 0, 255); }

/// Pixels where `reference` drew terrain and so did every pixel within `r` of them, and
/// whose reference surface point lies at least `margin` metres inside the DEM's square
/// extent of half-width `halfWidth` (at the DEM's own edge, coarse levels legitimately end
/// up to a coarse cell short of the full-resolution mesh).
std::vector<bool> interior(const gl::DepthImage& reference, int r, const Camera& cam = {},
                           double halfWidth = 0.0, double margin = 0.0) {
  const int w = reference.width, h = reference.height;
  std::vector<bool> in(static_cast<std::size_t>(w * h), false);
  for (int y = r; y < h - r; ++y)
    for (int x = r; x < w - r; ++x) {
      bool all = true;
      for (int dy = -r; dy <= r && all; ++dy)
        for (int dx = -r; dx <= r && all; ++dx) all = reference.at(x + dx, y + dy) > 0.0F;
      if (all && halfWidth > 0.0) {
        const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
        const double dist = cam.viewDistance(reference.at(x, y)) / glm::dot(d, cam.forward());
        const glm::dvec3 p = cam.position + dist * d;
        all = std::max(std::abs(p.x), std::abs(p.y)) < halfWidth - margin;
      }
      in[static_cast<std::size_t>(y * w + x)] = all;
    }
  return in;
}

int countMagentaInside(const gl::RgbaImage& img, const std::vector<bool>& inside) {
  int count = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (inside[static_cast<std::size_t>(y * img.width + x)] && magenta(img, x, y)) ++count;
  return count;
}

Camera obliqueCamera() {
  Camera cam;
  cam.position = {-150.0, -420.0, -1400.0 + 220.0};
  cam.target = {0.0, 0.0, -1400.0};
  cam.fovYDegrees = 50.0;
  cam.width = 480;
  cam.height = 320;
  cam.near = 1.0;
  return cam;
}

TEST(ClipmapTerrainGLTest, UploadsOnlyTheRowsAndColumnsThatEnterTheWindow) {
  test::glContext();
  const auto grid = test::centredGrid(1025, 1025, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  ClipmapOptions opt;
  opt.size = 63;
  opt.levels = 4;
  ClipmapTerrain terrain(pyramid, opt);
  const std::size_t n = 63;
  EXPECT_EQ(terrain.setFocus({0.0, 0.0, 0.0}), 4 * n * n);  // first fill: everything
  EXPECT_EQ(terrain.setFocus({0.2, -0.3, 0.0}), 0U);        // same centre samples: nothing

  // Moves in x, in y, diagonal and back: each level uploads |dr|·n + |dc|·(n − |dr|).
  const glm::dvec3 path[] = {
      {3.0, 0.0, 0.0}, {3.0, -5.0, 0.0}, {-4.0, 6.0, 0.0}, {-40.0, 30.0, 0.0}, {10.0, 10.0, 0.0}};
  for (const auto& p : path) {
    std::vector<std::pair<long long, long long>> before;
    for (std::size_t k = 0; k < 4; ++k) before.push_back(terrain.windowOrigin(k));
    std::size_t expected = 0;
    const std::size_t got = terrain.setFocus(p);
    for (std::size_t k = 0; k < 4; ++k) {
      const auto after = terrain.windowOrigin(k);
      const auto dr = static_cast<std::size_t>(std::llabs(after.first - before[k].first));
      const auto dc = static_cast<std::size_t>(std::llabs(after.second - before[k].second));
      expected += dr * n + dc * (n - dr);
    }
    EXPECT_EQ(got, expected) << "focus " << p.x << ", " << p.y;
    EXPECT_GT(got, 0U);
    EXPECT_LT(got, 4 * n * n / 2);
  }
  // Level 0 moved with the focus: its window is centred on the nearest sample.
  const auto o = terrain.windowOrigin(0);
  EXPECT_EQ(o.second, 512 + 10 - 31);
  EXPECT_EQ(o.first, 512 - 10 - 31);

  // What the toroidal updates left resident renders exactly like a fresh fill there.
  Camera cam = obliqueCamera();
  cam.target = {10.0, 10.0, -1400.0};
  cam.position = cam.target + glm::dvec3(-40.0, -90.0, 60.0);
  const Shot moved = renderClipmap(terrain, cam);
  ClipmapTerrain fresh(pyramid, opt);
  fresh.setFocus({10.0, 10.0, 0.0});
  const Shot direct = renderClipmap(fresh, cam);
  EXPECT_EQ(moved.depth.depth, direct.depth.depth);
  EXPECT_EQ(moved.color.rgba, direct.color.rgba);
  test::savePng("clipmap_after_moves", moved.color);
}

TEST(ClipmapTerrainGLTest, FlatDemDepthMatchesTheAnalyticPlane) {
  test::glContext();
  const double h0 = -1400.0;
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto pyramid = test::planePyramid(grid, [&](double, double) { return h0; });
  ClipmapTerrain terrain(pyramid, ClipmapOptions{});
  Camera cam = obliqueCamera();
  terrain.setFocus(cam.target);
  const Shot shot = renderClipmap(terrain, cam);
  test::savePng("clipmap_flat", shot.color);
  const glm::dvec3 f = cam.forward();
  int hits = 0, covered = 0;
  double worst = 0.0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
      const double t = (h0 - cam.position.z) / d.z;
      const glm::dvec3 hit = cam.position + t * d;
      const bool onDem = t > 0 && std::abs(hit.x) < 1000.0 && std::abs(hit.y) < 1000.0;
      const float depth = shot.depth.at(x, y);
      if (!onDem) continue;
      ++hits;
      if (depth <= 0.0F) continue;
      ++covered;
      const double expected = glm::dot(hit - cam.position, f);
      const double rel = std::abs(cam.viewDistance(depth) - expected) / expected;
      worst = std::max(worst, rel);
    }
  EXPECT_GT(hits, cam.width * cam.height / 3);
  EXPECT_EQ(covered, hits);  // every pixel over the DEM is drawn
  EXPECT_LT(worst, 2e-5) << "largest relative depth error";
}

TEST(ClipmapTerrainGLTest, NoGapsBetweenLevelsStaticAndWhileTheFocusMoves) {
  test::glContext();
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  ClipmapOptions opt;
  opt.size = 63;  // small levels: many level borders inside the picture
  ClipmapTerrain terrain(pyramid, opt);
  MeshRenderer reference(grid, *pyramid->level(0).source);
  int worst = 0;
  for (int step = 0; step < 12; ++step) {
    Camera cam = obliqueCamera();
    cam.target = {-60.0 + 11.3 * step, -30.0 + 7.1 * step, -1400.0};
    cam.position = cam.target + glm::dvec3(-120.0, -200.0, 200.0 - 8.0 * step);
    terrain.setFocus(cam.target);
    const Shot shot = renderClipmap(terrain, cam);
    const Shot ref = render(cam, [&] { reference.draw(cam); });
    const auto inside = interior(ref.depth, 2, cam, 1024.5, 80.0);
    // The mask must hold most of the picture, or "no holes inside it" says nothing.
    ASSERT_GT(std::count(inside.begin(), inside.end(), true), cam.width * cam.height / 4)
        << "step " << step << ": the reference mesh covers too little of the picture";
    const int holes = countMagentaInside(shot.color, inside);
    worst = std::max(worst, holes);
    EXPECT_EQ(holes, 0) << "step " << step;
    if (holes > 0) {
      gl::RgbaImage marked = shot.color;
      for (int y = 0; y < marked.height; ++y)
        for (int x = 0; x < marked.width; ++x)
          if (inside[static_cast<std::size_t>(y * marked.width + x)] && magenta(marked, x, y)) {
            auto* px = marked.rgba.data() + 4 * (y * marked.width + x);
            px[0] = 0;
            px[1] = 255;
            px[2] = 0;
          }
      test::savePng("clipmap_hills_holes" + std::to_string(step), marked);
    }
    if (step == 0 || step == 11) {
      test::savePng("clipmap_hills_step" + std::to_string(step), shot.color);
      test::savePng("mesh_hills_step" + std::to_string(step), ref.color);
    }
  }
}

}  // namespace
}  // namespace regolith::clod

namespace regolith::clod {
namespace {

struct DepthStats {
  int compared = 0;
  double p99 = 0.0, max = 0.0;
};

/// Relative view-distance differences between two renders, over pixels both drew where the
/// reference has no depth discontinuity (its 4 neighbours within 2 % of it).
/// `within` (optional) selects pixels by the reference's surface point.
DepthStats compareDepth(const Camera& cam, const gl::DepthImage& a, const gl::DepthImage& ref,
                        const std::function<bool(const glm::dvec3&)>& within = {}) {
  std::vector<double> diffs;
  for (int y = 1; y + 1 < ref.height; ++y)
    for (int x = 1; x + 1 < ref.width; ++x) {
      const float r = ref.at(x, y), c = a.at(x, y);
      if (r <= 0.0F || c <= 0.0F) continue;
      if (!ref.smoothAt(x, y, cam.near, 0.02)) continue;
      const double dr = cam.viewDistance(r);
      if (within) {
        const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
        if (!within(cam.position + dr / glm::dot(d, cam.forward()) * d)) continue;
      }
      diffs.push_back(std::abs(cam.viewDistance(c) - dr) / dr);
    }
  DepthStats s;
  s.compared = static_cast<int>(diffs.size());
  if (diffs.empty()) return s;
  std::sort(diffs.begin(), diffs.end());
  s.p99 = diffs[diffs.size() * 99 / 100];
  s.max = diffs.back();
  return s;
}

TEST(ClipmapTerrainGLTest, MatchesTheFullResolutionMeshNearTheFocus) {
  test::glContext();
  const auto grid = test::centredGrid(1025, 1025, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  MeshRenderer reference(grid, *pyramid->level(0).source);
  ClipmapTerrain terrain(pyramid, ClipmapOptions{});
  Camera cam = obliqueCamera();
  cam.target = {20.0, 10.0, -1400.0};
  cam.position = cam.target + glm::dvec3(-30.0, -50.0, 45.0);
  terrain.setFocus(cam.target);
  const Shot clip = renderClipmap(terrain, cam);
  const Shot ref = render(cam, [&] { reference.draw(cam); });
  test::savePng("clipmap_near", clip.color);
  test::savePng("mesh_near", ref.color);
  // Inside level 0 (255 samples of 1 m around the focus, less the cells level 1 overlaps) the
  // clipmap draws the same triangles as the full mesh: depths agree to float rounding.
  const auto o = terrain.windowOrigin(0);
  const glm::dvec2 c0 =
      grid.sampleCentre(static_cast<double>(o.first + 127), static_cast<double>(o.second + 127));
  const DepthStats fine = compareDepth(cam, clip.depth, ref.depth, [&](const glm::dvec3& p) {
    return std::max(std::abs(p.x - c0.x), std::abs(p.y - c0.y)) < 120.0;
  });
  const DepthStats all = compareDepth(cam, clip.depth, ref.depth);
  std::printf("level 0: %d pixels, max %.3g; all: %d pixels, p99 %.3g, max %.3g\n", fine.compared,
              fine.max, all.compared, all.p99, all.max);
  EXPECT_GT(fine.compared, cam.width * cam.height / 2);
  EXPECT_LT(fine.max, 1e-5);
  // Beyond it, level 1 (2 m means of the 1 m samples) stands in: bounded by the terrain's
  // roughness at 2 m (the 10 m ripple of test::hills), stated as a relative depth bound.
  EXPECT_LT(all.p99, 5e-3);
  EXPECT_LT(all.max, 2e-2);
}

}  // namespace
}  // namespace regolith::clod

namespace regolith::clod {
namespace {

TEST(ClipmapTerrainGLTest, CraterRimSeenFromAboveIsWhereTheFormulaPutsIt) {
  test::glContext();
  const test::Crater crater;
  const auto grid = test::centredGrid(1025, 1025, 1.0);
  const auto pyramid = test::planePyramid(grid, crater);
  // Level 0 (511 samples of 1 m) holds the whole rim: the crest is drawn from the samples
  // themselves, not from 2 × 2 means, which would pull the max of this lopsided crest
  // (steep inside, gentle outside) outward by metres.
  ClipmapOptions opt;
  opt.size = 511;
  ClipmapTerrain terrain(pyramid, opt);
  Camera cam;
  cam.target = {0.0, 0.0, crater.base};
  cam.position = {0.0, 0.0, crater.base + 900.0};
  cam.up = {0.0, 1.0, 0.0};
  cam.fovYDegrees = 40.0;
  cam.width = cam.height = 400;
  cam.near = 10.0;
  terrain.setFocus(cam.target);
  const Shot shot = renderClipmap(terrain, cam);
  test::savePng("clipmap_crater_top", shot.color);
  // The surface point under a pixel, from its depth.
  const auto surfaceAt = [&](int x, int y) {
    const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
    return cam.position + cam.viewDistance(shot.depth.at(x, y)) / glm::dot(d, cam.forward()) * d;
  };
  for (int a = 0; a < 16; ++a) {
    const double phi = a * 2.0 * M_PI / 16.0;
    // Walk outward through the pixels along this azimuth: the highest point is the crest;
    // where the inner wall crosses 5 m below the crest locates the rim (the crest itself is
    // flat to 1 cm over 3 m outward, so its position is ill-conditioned).
    const double level = crater.base + crater.rimHeight - 5.0;
    const double expectedCross = crater.radius * std::sqrt(1.0 - 5.0 / crater.depth);
    double crest = -1e9, cross = 0.0, prevR = 0.0, prevZ = 0.0;
    for (double r = 150.0; r < 250.0; r += 0.25) {
      const glm::dvec3 px = cam.project({r * std::cos(phi), r * std::sin(phi), level});
      const glm::dvec3 p = surfaceAt(static_cast<int>(px.x), static_cast<int>(px.y));
      const double pr = std::hypot(p.x, p.y);
      crest = std::max(crest, p.z);
      if (cross == 0.0 && r > 150.0 && prevZ < level && p.z >= level)
        cross = prevR + (level - prevZ) / (p.z - prevZ) * (pr - prevR);
      prevR = pr;
      prevZ = p.z;
    }
    // One pixel is 0.81 m at the rim.
    EXPECT_NEAR(cross, expectedCross, 0.5) << "azimuth " << a;
    EXPECT_NEAR(crest, crater.base + crater.rimHeight, 0.05) << "azimuth " << a;
  }
  // The floor's centre: the bowl's lowest point.
  EXPECT_NEAR(surfaceAt(200, 200).z, crater.base + crater.rimHeight - crater.depth, 0.05);
}

TEST(ClipmapTerrainGLTest, CraterSilhouetteOnTheSkylineIsWhereTheFormulaPutsIt) {
  test::glContext();
  const test::Crater crater;
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto pyramid = test::planePyramid(grid, crater);
  ClipmapTerrain terrain(pyramid, ClipmapOptions{});
  // Eye 5 m above the plain, 600 m south of the centre, looking north horizontally: the
  // near rim is the skyline over the crater.
  Camera cam;
  cam.position = {0.0, -600.0, crater.base + 5.0};
  cam.target = {0.0, 0.0, crater.base + 5.0};
  cam.fovYDegrees = 10.0;
  cam.width = 480;
  cam.height = 240;
  cam.near = 1.0;
  terrain.setFocus({0.0, 0.0, crater.base});
  const Shot shot = renderClipmap(terrain, cam);
  test::savePng("clipmap_crater_skyline", shot.color);
  const double f = cam.focalPixels();
  for (int x = 40; x < cam.width; x += 40) {
    // Analytic skyline in this column: the highest elevation angle of the surface along the
    // column's vertical plane, marched at 0.1 m.
    const double sx = (x + 0.5 - 0.5 * cam.width) / f;  // x / forward distance
    double best = -1e9;
    for (double d = 50.0; d < 1500.0; d += 0.1) {
      const double h = crater(sx * d, cam.position.y + d) - cam.position.z;
      best = std::max(best, h / d);
    }
    const double expectedRow = 0.5 * cam.height - f * best;  // top edge of the terrain
    int row = 0;
    while (row < cam.height && shot.depth.at(x, row) == 0.0F) ++row;
    EXPECT_NEAR(row, expectedRow, 1.0) << "column " << x;
  }
}

TEST(ClipmapTerrainGLTest, NodataCutsAHole) {
  test::glContext();
  const auto grid = test::centredGrid(1025, 1025, 1.0);
  auto samples = topo::InMemorySamples::fromFunction(
      grid.rows(), grid.cols(), [&](std::size_t r, std::size_t c) {
        const auto p = grid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
        return std::hypot(p.x - 40.0, p.y) < 30.0 ? std::numeric_limits<float>::quiet_NaN()
                                                  : static_cast<float>(test::hills(p.x, p.y));
      });
  const auto pyramid = std::make_shared<const HeightPyramid>(
      HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane));
  ClipmapTerrain terrain(pyramid, ClipmapOptions{});
  Camera cam;
  cam.target = {0.0, 0.0, -1400.0};
  cam.position = {0.0, -1.0, -1400.0 + 400.0};
  cam.width = cam.height = 300;
  cam.near = 1.0;
  terrain.setFocus(cam.target);
  const Shot shot = renderClipmap(terrain, cam);
  test::savePng("clipmap_nodata_hole", shot.color);
  int inHole = 0, holeMagenta = 0, outside = 0, outsideMagenta = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      // Where the pixel's ray meets the plain's mean height.
      const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
      const glm::dvec3 p = cam.position + (-1400.0 - cam.position.z) / d.z * d;
      const double r = std::hypot(p.x - 40.0, p.y);
      if (r < 24.0) {
        ++inHole;
        holeMagenta += magenta(shot.color, x, y) ? 1 : 0;
      } else if (r > 40.0) {
        ++outside;
        outsideMagenta += magenta(shot.color, x, y) ? 1 : 0;
      }
    }
  EXPECT_GT(inHole, 500);
  EXPECT_EQ(holeMagenta, inHole);  // nothing drawn over nodata, no skirt inside the hole
  EXPECT_EQ(outsideMagenta, 0);
  EXPECT_GT(outside, 50000);
}

TEST(ClipmapTerrainGLTest, InnerLevelsSwitchOffFarAwayAndVerticesDoNotGrowWithTheDem) {
  test::glContext();
  ClipmapOptions opt;
  opt.size = 127;
  opt.levels = 6;
  Camera cam;
  cam.target = {0.0, 0.0, 0.0};
  cam.width = 640;
  cam.height = 360;
  std::vector<std::size_t> vertices;
  for (std::size_t side : {513U, 2049U, 4097U}) {
    const auto grid = test::centredGrid(side, side, 1.0);
    const auto pyramid = test::planePyramid(
        grid, [](double x, double y) { return 5.0 * std::sin(x / 30.0) * std::cos(y / 40.0); });
    ClipmapTerrain terrain(pyramid, opt);
    terrain.setFocus(cam.target);
    cam.position = {0.0, -40.0, 60.0};
    gl::RenderTarget target(cam.width, cam.height);
    target.clear(kMagenta);
    const ClipmapFrame near = terrain.draw(cam);
    EXPECT_EQ(near.firstLevel, 0U);
    EXPECT_EQ(near.levelsDrawn, 6U);
    vertices.push_back(near.vertices);
    // From far above, the finest levels' cells are below half a pixel: they switch off and
    // the innermost drawn level draws its centre.
    cam.position = {0.0, -400.0, 6000.0};
    const ClipmapFrame far = terrain.draw(cam);
    EXPECT_GE(far.firstLevel, 2U);
    EXPECT_EQ(far.firstLevel + far.levelsDrawn, 6U);
    EXPECT_LT(far.vertices, near.vertices);
    const gl::RgbaImage img = target.readColor();
    EXPECT_FALSE(magenta(img, cam.width / 2, cam.height / 2));  // the centre is drawn
  }
  EXPECT_EQ(vertices[0], vertices[1]);
  EXPECT_EQ(vertices[1], vertices[2]);
}

}  // namespace
}  // namespace regolith::clod

namespace regolith::clod {
namespace {

// A level's samples, forwarded, with the prefetch hints it is given recorded.
class HintedSource final : public topo::SampleSource {
 public:
  explicit HintedSource(std::shared_ptr<const topo::SampleSource> inner)
      : inner_(std::move(inner)) {}
  std::size_t rows() const noexcept override { return inner_->rows(); }
  std::size_t cols() const noexcept override { return inner_->cols(); }
  float sample(std::size_t r, std::size_t c) const override { return inner_->sample(r, c); }
  void readWindow(std::size_t r0, std::size_t c0, std::size_t nr, std::size_t nc,
                  std::span<float> out) const override {
    {
      const std::lock_guard lock(mutex_);
      ++reads_;
      const bool loaded = std::any_of(loads_.begin(), loads_.end(), [&](const auto& load) {
        return std::any_of(load.begin(), load.end(), [&](const Window& w) {
          return r0 >= w.row0 && r0 + nr <= w.row0 + w.rows && c0 >= w.col0 &&
                 c0 + nc <= w.col0 + w.cols;
        });
      });
      if (!loaded) ++readsNotLoaded_;
    }
    inner_->readWindow(r0, c0, nr, nc, out);
  }
  const float* contiguous() const noexcept override { return inner_->contiguous(); }
  void prefetch(std::span<const Window> windows) const noexcept override {
    const std::lock_guard lock(mutex_);
    hints_.emplace_back(windows.begin(), windows.end());
  }
  void load(std::span<const Window> windows) const noexcept override {
    const std::lock_guard lock(mutex_);
    loads_.emplace_back(windows.begin(), windows.end());
  }
  std::vector<std::vector<Window>> hints() const {
    const std::lock_guard lock(mutex_);
    return hints_;
  }
  std::vector<std::vector<Window>> loads() const {
    const std::lock_guard lock(mutex_);
    return loads_;
  }
  /// Window reads, and those not inside a window load() was given before them.
  std::pair<std::size_t, std::size_t> reads() const {
    const std::lock_guard lock(mutex_);
    return {reads_, readsNotLoaded_};
  }

 private:
  std::shared_ptr<const topo::SampleSource> inner_;
  mutable std::mutex mutex_;
  mutable std::vector<std::vector<Window>> hints_, loads_;
  mutable std::size_t reads_ = 0, readsNotLoaded_ = 0;
};

/// The 2049² hills pyramid, each level's source wrapped in a HintedSource (in `sources`).
std::shared_ptr<const HeightPyramid> hintedHills(
    std::vector<std::shared_ptr<const HintedSource>>& sources) {
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto plain = test::planePyramid(grid, test::hills);
  std::vector<HeightPyramid::Level> levels;
  for (std::size_t k = 0; k < plain->levelCount(); ++k) {
    sources.push_back(std::make_shared<const HintedSource>(plain->level(k).source));
    levels.push_back({plain->level(k).grid, sources.back()});
  }
  return std::make_shared<const HeightPyramid>(levels, SurfaceKind::Plane);
}

TEST(ClipmapTerrainGLTest, TheLoaderHasEachLevelsWindowLoadedByItsSourceBeforeReadingIt) {
  test::glContext();
  std::vector<std::shared_ptr<const HintedSource>> sources;
  const auto pyramid = hintedHills(sources);
  ClipmapOptions opt;
  opt.size = 127;
  ClipmapTerrain terrain(pyramid, opt);
  terrain.requestFocus({0.0, 0.0, 0.0});
  terrain.finishLoading();
  // Levels 0 and 1 hold their window whole: one load of the 127² window, as one window
  // (the rows' runs joined).
  for (std::size_t k = 0; k < 2; ++k) {
    const auto loads = sources[k]->loads();
    ASSERT_EQ(loads.size(), 1U) << "level " << k;
    ASSERT_EQ(loads[0].size(), 1U) << "level " << k;
    EXPECT_EQ(loads[0][0].rows, 127U) << "level " << k;
    EXPECT_EQ(loads[0][0].cols, 127U) << "level " << k;
  }
  // Then a move: the strip that enters is loaded, then read.
  terrain.requestFocus({40.0, 0.0, 0.0});
  terrain.finishLoading();
  const auto moved = sources[0]->loads();
  ASSERT_EQ(moved.size(), 2U);
  std::size_t area = 0;
  for (const auto& w : moved[1]) area += w.rows * w.cols;
  EXPECT_GT(area, 0U);
  EXPECT_LT(area, 127U * 127U) << "only the columns that enter the window";
  // Every window read at every level lies inside a window loaded before it (the levels
  // beyond the clipmap's are neither loaded nor read).
  std::size_t levelsRead = 0;
  for (std::size_t k = 0; k < sources.size(); ++k) {
    const auto [reads, notLoaded] = sources[k]->reads();
    EXPECT_EQ(reads > 0, !sources[k]->loads().empty()) << "level " << k;
    EXPECT_EQ(notLoaded, 0U) << "level " << k;
    levelsRead += reads > 0 ? 1 : 0;
  }
  EXPECT_EQ(levelsRead, terrain.levelCount());
}

TEST(ClipmapTerrainGLTest, TheLoaderHintsTheRingAroundEachLevelsWindowToItsSource) {
  test::glContext();
  std::vector<std::shared_ptr<const HintedSource>> sources;
  const auto pyramid = hintedHills(sources);
  ClipmapOptions opt;
  opt.size = 127;
  opt.prefetchMargin = 32;
  ClipmapTerrain terrain(pyramid, opt);
  terrain.requestFocus({0.0, 0.0, 0.0});
  terrain.finishLoading();
  // Levels 0 and 1 (2049² and 1025² samples) hold their window and its ring whole: one hint
  // each, four windows that tile the (127 + 2·32)² square around the 127² window.
  for (std::size_t k = 0; k < 2; ++k) {
    const auto hints = sources[k]->hints();
    ASSERT_EQ(hints.size(), 1U) << "level " << k;
    ASSERT_EQ(hints[0].size(), 4U) << "level " << k;
    std::size_t r0 = SIZE_MAX, c0 = SIZE_MAX, r1 = 0, c1 = 0, area = 0;
    for (const topo::SampleSource::Window& w : hints[0]) {
      r0 = std::min(r0, w.row0);
      c0 = std::min(c0, w.col0);
      r1 = std::max(r1, w.row0 + w.rows);
      c1 = std::max(c1, w.col0 + w.cols);
      area += w.rows * w.cols;
    }
    EXPECT_EQ(r1 - r0, 127U + 64U) << "level " << k;
    EXPECT_EQ(c1 - c0, 127U + 64U) << "level " << k;
    EXPECT_EQ(area, 191U * 191U - 127U * 127U) << "level " << k;
  }
  // Every hint lies inside its level's grid.
  for (std::size_t k = 0; k < sources.size(); ++k) {
    for (const auto& hint : sources[k]->hints()) {
      for (const topo::SampleSource::Window& w : hint) {
        EXPECT_GT(w.rows * w.cols, 0U);
        EXPECT_LE(w.row0 + w.rows, pyramid->level(k).grid.rows());
        EXPECT_LE(w.col0 + w.cols, pyramid->level(k).grid.cols());
      }
    }
  }
  // Without a margin there is no hint.
  ClipmapOptions none = opt;
  none.prefetchMargin = 0;
  const std::size_t before = sources[0]->hints().size();
  ClipmapTerrain quiet(pyramid, none);
  quiet.requestFocus({0.0, 0.0, 0.0});
  quiet.finishLoading();
  EXPECT_EQ(sources[0]->hints().size(), before);
}

TEST(ClipmapTerrainGLTest, BackgroundLoadingIsCoarseFirstAndNeverShowsAGap) {
  test::glContext();
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  ClipmapOptions opt;
  opt.size = 127;
  ClipmapTerrain terrain(pyramid, opt);
  const std::size_t levels = terrain.levelCount();

  // Start: nothing resident; the first frames draw what has arrived, coarsest first.
  terrain.requestFocus({0.0, 0.0, 0.0});
  std::vector<std::size_t> arrival;  // resident level count after each update
  while (terrain.loading()) {
    terrain.update(true);
    const auto resident = terrain.residentLevels();
    // Resident levels always form a coarse suffix [k, levels).
    std::size_t k = levels;
    while (k > 0 && resident[k - 1]) --k;
    for (std::size_t j = 0; j < k; ++j) EXPECT_FALSE(resident[j]) << "level " << j;
    arrival.push_back(levels - k);
  }
  EXPECT_EQ(arrival.back(), levels);
  EXPECT_TRUE(std::is_sorted(arrival.begin(), arrival.end()));

  // A fast, jumpy pan: the focus leaps up to ~500 m per frame (more than level 0's and
  // level 1's windows), and frames call update() without waiting.
  // Whatever has arrived, nothing is left unpainted: this camera looks down steeply enough
  // that every pixel meets the terrain well inside the DEM (checked below).
  std::size_t coarserFrames = 0;
  for (int frame = 0; frame < 30; ++frame) {
    Camera cam = obliqueCamera();
    cam.target = {350.0 * std::sin(frame * 1.3), 250.0 * std::cos(frame * 0.9), -1400.0};
    cam.position = cam.target + glm::dvec3(-90.0, -150.0, 200.0);
    terrain.requestFocus(cam.target);
    terrain.update(false);
    const auto [first, count] = terrain.activeLevels(cam);
    if (first > 0) ++coarserFrames;
    EXPECT_GT(count, 0U);
    const Shot shot = renderClipmap(terrain, cam);
    int holes = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
        const glm::dvec3 p = cam.position + (-1400.0 - cam.position.z) / d.z * d;
        ASSERT_LT(std::max(std::abs(p.x), std::abs(p.y)), 900.0);
        holes += magenta(shot.color, x, y) ? 1 : 0;
      }
    EXPECT_EQ(holes, 0) << "frame " << frame;
  }
  std::printf("fast pan: %zu of 30 frames drew from a coarser level while loading\n",
              coarserFrames);

  // Once loading finishes, the picture is the synchronous one (to float rounding: the two
  // reached their windows by different moves, so their level anchors differ).
  terrain.finishLoading();
  Camera cam = obliqueCamera();
  cam.target = {350.0 * std::sin(29 * 1.3), 250.0 * std::cos(29 * 0.9), -1400.0};
  cam.position = cam.target + glm::dvec3(-90.0, -150.0, 200.0);
  const Shot async = renderClipmap(terrain, cam);
  ClipmapTerrain sync(pyramid, opt);
  sync.setFocus(cam.target);
  const Shot direct = renderClipmap(sync, cam);
  const DepthStats diff = compareDepth(cam, async.depth, direct.depth);
  EXPECT_GT(diff.compared, cam.width * cam.height / 2);
  EXPECT_LT(diff.max, 1e-5);
  test::savePng("clipmap_async_end", async.color);
}

}  // namespace
}  // namespace regolith::clod

namespace regolith::clod {
namespace {

// Grazing views: the eye a few metres above the ground looking along it, so level borders
// are seen edge-on and any vertical step between levels would open a slit of background.
TEST(ClipmapTerrainGLTest, NoSlitsBetweenLevelsAtGrazingAngles) {
  test::glContext();
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  ClipmapOptions opt;
  opt.size = 31;  // level borders at 15, 30, 60, 120 ... m: many in view
  ClipmapTerrain terrain(pyramid, opt);
  MeshRenderer reference(grid, *pyramid->level(0).source);
  for (int step = 0; step < 6; ++step) {
    Camera cam;
    const double a = 0.9 * step;
    cam.target = {200.0 * std::cos(a), 200.0 * std::sin(a), 0.0};
    cam.target.z = test::hills(cam.target.x, cam.target.y);
    const glm::dvec3 dir{std::cos(a + 2.0), std::sin(a + 2.0), 0.0};
    cam.position = cam.target - 60.0 * dir;
    cam.position.z = test::hills(cam.position.x, cam.position.y) + 4.0;
    cam.target = cam.position + 100.0 * dir - glm::dvec3(0.0, 0.0, 6.0);
    cam.width = 480;
    cam.height = 240;
    cam.near = 0.5;
    cam.fovYDegrees = 40.0;
    terrain.setFocus(cam.position);
    const Shot shot = renderClipmap(terrain, cam);
    // The same view with the overlap depth push (what the viewer uses): no slit either.
    ClipmapOptions pushed = opt;
    pushed.overlapDepthPush = 0.02F;
    terrain.setOptions(pushed);
    const Shot shotPushed = renderClipmap(terrain, cam);
    terrain.setOptions(opt);
    const Shot ref = render(cam, [&] { reference.draw(cam); });
    // Leave out the 12 pixels under the skyline: there coarse levels legitimately trim
    // ridges (a level-of-detail error, not a crack), which the full mesh draws higher.
    auto inside = interior(ref.depth, 2, cam, 1024.5, 80.0);
    for (int x = 0; x < cam.width; ++x) {
      int sky = 0;
      for (int y = 0; y < cam.height; ++y) {
        if (ref.depth.at(x, y) == 0.0F) sky = y + 1;
        if (y < sky + 12) inside[static_cast<std::size_t>(y * cam.width + x)] = false;
      }
    }
    ASSERT_GT(std::count(inside.begin(), inside.end(), true), cam.width * cam.height / 4)
        << "step " << step << ": the reference mesh covers too little of the picture";
    const int holes = countMagentaInside(shot.color, inside);
    EXPECT_EQ(holes, 0) << "step " << step;
    EXPECT_EQ(countMagentaInside(shotPushed.color, inside), 0) << "step " << step << ", pushed";
    if (step == 5) test::savePng("clipmap_grazing5_pushed", shotPushed.color);
    if (step == 0 || step == 5 || holes > 0) {
      gl::RgbaImage marked = shot.color;
      for (int y = 0; y < marked.height; ++y)
        for (int x = 0; x < marked.width; ++x)
          if (inside[static_cast<std::size_t>(y * marked.width + x)] && magenta(marked, x, y)) {
            auto* px = marked.rgba.data() + 4 * (y * marked.width + x);
            px[0] = 0;
            px[1] = 255;
            px[2] = 0;
          }
      test::savePng("clipmap_grazing" + std::to_string(step), marked);
      test::savePng("mesh_grazing" + std::to_string(step), ref.color);
    }
  }
}

}  // namespace
}  // namespace regolith::clod

namespace regolith::clod {
namespace {

// The camera looks past a rover at a point 500 m beyond it. With the focus at the look-at
// point the rover stands on a coarse level; tied to the rover, the focus puts level 0 (the
// full-resolution samples) under it, and the surface there matches the full mesh.
TEST(ClipmapTerrainGLTest, FocusTiedToARoverPutsTheFinestLevelUnderIt) {
  test::glContext();
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  const auto pyramid = test::planePyramid(grid, test::hills);
  MeshRenderer reference(grid, *pyramid->level(0).source);
  const glm::dvec3 rover{-250.0, -150.0, test::hills(-250.0, -150.0)};
  Camera cam;
  cam.position = rover + glm::dvec3(-25.0, -25.0, 18.0);
  cam.target = rover + 14.0 * (rover - cam.position);  // ~600 m beyond the rover
  cam.width = cam.height = 200;
  cam.near = 0.5;
  FocusController focus;
  focus.addCamera(cam, 0.0);
  const Shot ref = render(cam, [&] { reference.draw(cam); });

  const auto centreError = [&](const glm::dvec3& f) {
    ClipmapTerrain terrain(pyramid, ClipmapOptions{});
    terrain.setFocus(f);
    const Shot shot = renderClipmap(terrain, cam);
    double worst = 0.0;
    for (int y = 95; y < 105; ++y)
      for (int x = 95; x < 105; ++x) {
        const double r = cam.viewDistance(ref.depth.at(x, y));
        worst = std::max(worst, std::abs(cam.viewDistance(shot.depth.at(x, y)) - r) / r);
      }
    return worst;
  };
  const double untied = centreError(focus.focus(0.0));
  focus.tieTo([&] { return rover; });
  const double tied = centreError(focus.focus(0.0));
  std::printf("depth error at the rover: focus on the look-at point %.2e, tied %.2e\n", untied,
              tied);
  EXPECT_LT(tied, 1e-5);
  EXPECT_GT(untied, 10.0 * tied);
}

}  // namespace
}  // namespace regolith::clod

namespace regolith::clod {
namespace {

// A DEM placed on Mars by a local tangent plane: positions are body-fixed (3.4e6 m), the
// camera too, and a flat DEM at h = 0 draws exactly the tangent plane.
TEST(ClipmapTerrainGLTest, PlacedDemIsDrawnOnItsPlanetInBodyFixedCoordinates) {
  test::glContext();
  const topo::LocalTangentPlane plane(topo::Body::marsEllipsoid(), {-2.05, -5.5, -1400.0}, 30.0);
  const topo::Placement placement(plane);
  const auto grid = test::centredGrid(2049, 2049, 1.0);
  auto samples = std::make_shared<topo::InMemorySamples>(
      grid.rows(), grid.cols(), std::vector<float>(grid.rows() * grid.cols(), 0.0F));
  const auto pyramid =
      std::make_shared<const HeightPyramid>(HeightPyramid::fromSamples(grid, samples, placement));
  ClipmapTerrain terrain(pyramid, ClipmapOptions{});
  Camera cam = obliqueCamera();
  cam.position = placement.toBodyFixed(-150.0, -420.0, 220.0);
  cam.target = placement.toBodyFixed(0.0, 0.0, 0.0);
  cam.up = plane.zAxis();
  ASSERT_GT(glm::length(cam.position), 3.3e6);
  terrain.setFocus(cam.target);
  const Shot shot = renderClipmap(terrain, cam);
  test::savePng("clipmap_placed_on_mars", shot.color);
  const glm::dvec3 o = plane.originBodyFixed(), nrm = plane.zAxis();
  int hits = 0, covered = 0;
  double worst = 0.0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const glm::dvec3 d = cam.ray(x + 0.5, y + 0.5);
      const double t = glm::dot(o - cam.position, nrm) / glm::dot(d, nrm);
      const glm::dvec3 g = plane.fromBodyFixed(cam.position + t * d);
      if (!(t > 0 && std::abs(g.x) < 1000.0 && std::abs(g.y) < 1000.0)) continue;
      ++hits;
      if (shot.depth.at(x, y) <= 0.0F) continue;
      ++covered;
      const double expected = t * glm::dot(d, cam.forward());
      worst =
          std::max(worst, std::abs(cam.viewDistance(shot.depth.at(x, y)) - expected) / expected);
    }
  EXPECT_GT(hits, cam.width * cam.height / 3);
  EXPECT_EQ(covered, hits);
  EXPECT_LT(worst, 2e-5);
  EXPECT_NEAR(glm::length(pyramid->up(cam.target) - nrm), 0.0, 1e-9);
}

}  // namespace
}  // namespace regolith::clod
