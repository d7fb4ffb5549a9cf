// clod::SceneRenderer reads no terrain inside draw() for its cut-outs: the planet's samples
// under a DEM (the skirt's depth) are read on an executor when the DEM is first seen at its
// place, the DEM's mask and skirt when the cut-out is added. Counted by a SampleSource that
// wraps the real in-memory samples and notes which thread read them.
#include <regolith/clod/SceneRenderer.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/scenegraph/SitePose.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <memory>
#include <span>
#include <thread>
#include <utility>
#include <vector>

namespace regolith::clod {
namespace {

// Reads of the sources a test wraps: sample() and readWindow() calls, on the thread that
// drew (the render thread) and on any other thread.
struct Reads {
  std::thread::id renderThread = std::this_thread::get_id();
  std::atomic<std::size_t> samplesHere{0}, windowsHere{0}, elsewhere{0};
  [[nodiscard]] std::size_t here() const { return samplesHere + windowsHere; }
  void reset() { samplesHere = windowsHere = elsewhere = 0; }
};

class CountingSamples final : public topo::SampleSource {
 public:
  CountingSamples(std::shared_ptr<const topo::SampleSource> inner, Reads& reads)
      : inner_(std::move(inner)), reads_(reads) {}
  [[nodiscard]] std::size_t rows() const noexcept override { return inner_->rows(); }
  [[nodiscard]] std::size_t cols() const noexcept override { return inner_->cols(); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override {
    ++(std::this_thread::get_id() == reads_.renderThread ? reads_.samplesHere : reads_.elsewhere);
    return inner_->sample(row, col);
  }
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override {
    ++(std::this_thread::get_id() == reads_.renderThread ? reads_.windowsHere : reads_.elsewhere);
    inner_->readWindow(row0, col0, nrows, ncols, out);
  }

 private:
  std::shared_ptr<const topo::SampleSource> inner_;
  Reads& reads_;
};

// `p` with every level's source wrapped.
std::vector<HeightPyramid::Level> counted(const HeightPyramid& p, Reads& reads) {
  std::vector<HeightPyramid::Level> levels;
  for (std::size_t k = 0; k < p.levelCount(); ++k)
    levels.push_back(
        {p.level(k).grid, std::make_shared<CountingSamples>(p.level(k).source, reads)});
  return levels;
}

TEST(SceneRendererIoGLTest, DrawReadsNothingOnceTheWindowsAreResident) {
  test::glContext();
  Reads reads;
  const topo::Body mars = topo::Body::marsSphere();
  // A 1° planet with relief, and a 101 × 101 DEM at 4 m (a bowl) placed on it where the
  // planet's relief is near 0 (sin(0.1 row) = 0 at row 94.2: 4.7° S).
  const topo::TopoGrid pg(180, 360, -179.5, 89.5, 1.0, 1.0);
  const auto planetSamples =
      topo::InMemorySamples::fromFunction(180, 360, [](std::size_t r, std::size_t c) {
        return static_cast<float>(800.0 * std::sin(0.1 * static_cast<double>(r)) *
                                  std::cos(0.07 * static_cast<double>(c)));
      });
  const auto planetPlain = HeightPyramid::fromSamples(pg, planetSamples, SurfaceKind::Planet, mars);
  auto planet =
      std::make_shared<const HeightPyramid>(counted(planetPlain, reads), SurfaceKind::Planet, mars);
  const topo::TopoGrid dg(101, 101, -200.0, 200.0, 4.0, 4.0);
  const auto demSamples =
      topo::InMemorySamples::fromFunction(101, 101, [&](std::size_t r, std::size_t c) {
        const glm::dvec2 p = dg.sampleCentre(static_cast<double>(r), static_cast<double>(c));
        return static_cast<float>(1e-3 * (p.x * p.x + p.y * p.y) - 30.0);
      });
  const auto demPlain = HeightPyramid::fromSamples(dg, demSamples, SurfaceKind::Plane);
  auto dem = std::make_shared<const HeightPyramid>(counted(demPlain, reads), SurfaceKind::Plane);

  SceneRenderer r;
  ClipmapOptions o;
  o.size = 63;
  r.addTerrain(0, planet, o);
  o.albedo = {0.3F, 0.7F, 0.3F};  // the DEM green, the planet its default sand
  r.addTerrain(1, dem, o);
  r.addCutOut(0, 1);
  EXPECT_GE(reads.windowsHere, 1U);  // the DEM's mask and skirt: read when the cut-out is added
  reads.reset();

  scenegraph::SceneGraph g("mars");
  const auto p = g.add(g.root(), "planet", {}, scenegraph::NodeKind::Terrain, 0);
  const auto d = g.add(p, "dem", scenegraph::tangentPlanePose(mars, {-4.7, -5.5, 0.0}, 0.0),
                       scenegraph::NodeKind::Terrain, 1);
  const auto cam =
      g.add(d, "camera",
            scenegraph::Pose::lookAt({-400.0, -500.0, 250.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}),
            scenegraph::NodeKind::Camera);
  SceneView view;
  view.width = 160;
  view.height = 120;
  view.near = 1.0;
  gl::RenderTarget target(view.width, view.height);
  const auto shoot = [&](scenegraph::NodeId focus) {
    target.clear({1.0F, 0.0F, 1.0F, 1.0F});
    const SceneFrame f = r.draw(g.renderList(focus, cam), view);
    EXPECT_EQ(f.terrainsDrawn, 2U);
    return target.readColor();
  };

  // First frame: the clipmaps load their windows (ClipmapTerrain::setFocus() reads on this
  // thread), and the planet's samples under the DEM are read on another thread.
  const gl::RgbaImage first = shoot(d);
  test::savePng("scene_io_first", first);
  EXPECT_GT(reads.windowsHere, 0U);
  EXPECT_GT(reads.elsewhere, 0U);
  // The same view again, and from another focus: nothing moved, nothing is read.
  reads.reset();
  const gl::RgbaImage again = shoot(d);
  EXPECT_EQ(reads.here(), 0U);
  EXPECT_EQ(reads.elsewhere, 0U);
  EXPECT_EQ(again.rgba, first.rgba);
  (void)shoot(p);
  EXPECT_EQ(reads.here(), 0U);
  EXPECT_EQ(reads.elsewhere, 0U);
  // The picture holds the DEM and the planet around it, with no hole below the horizon
  // (the sky, left at the clear colour, is the top few rows).
  std::size_t green = 0, ground = 0, holes = 0;
  for (int y = 0; y < first.height; ++y)
    for (int x = 0; x < first.width; ++x) {
      const auto* px = first.pixel(x, y);
      green += px[1] > px[0] ? 1U : 0U;
      ground += px[0] > px[1] && px[2] < 200 ? 1U : 0U;
      holes += y >= first.height / 4 && first.is(x, y, 255, 0, 255) ? 1U : 0U;  // row 0 at the top
    }
  EXPECT_GT(green, 1000U);
  EXPECT_GT(ground, 1000U);
  EXPECT_EQ(holes, 0U);
}

}  // namespace
}  // namespace regolith::clod
