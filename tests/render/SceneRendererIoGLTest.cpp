// render::SceneRenderer reads no terrain inside draw(): prepare() moves the clipmaps and reads
// their windows on the executors (waiting for them, or in the background for a frame loop),
// and starts the reads of the planet's samples under a DEM (the skirt's depth); the DEM's
// mask and skirt are read when the cut-out is added. Counted by a SampleSource that wraps
// the real in-memory samples and notes which thread read them; a gate holds the reads back
// to show that a background prepare() does not wait for them.
#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/SceneRenderer.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>
#include <regolith/scenegraph/SitePose.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace regolith::render {
namespace {

using clod::ClipmapOptions;
using clod::HeightPyramid;
using clod::LatLonLines;
using clod::SurfaceKind;

// Reads of the sources a test wraps: sample() and readWindow() calls, on the thread that
// drew (the render thread) and on any other thread.
// While the gate is closed, reads wait for it (at most 20 s, then they go on and count as
// late: a prepare() that waited for them would show as late reads, not as a hung test).
struct Reads {
  std::thread::id renderThread = std::this_thread::get_id();
  std::atomic<std::size_t> samplesHere{0}, windowsHere{0}, elsewhere{0}, late{0};
  [[nodiscard]] std::size_t here() const { return samplesHere + windowsHere; }
  [[nodiscard]] std::size_t all() const { return here() + elsewhere; }
  void reset() { samplesHere = windowsHere = elsewhere = 0; }

  void close() {
    const std::lock_guard lock(mutex);
    open = false;
  }
  void openGate() {
    {
      const std::lock_guard lock(mutex);
      open = true;
    }
    opened.notify_all();
  }
  void pass() {
    std::unique_lock lock(mutex);
    if (!opened.wait_for(lock, std::chrono::seconds(20), [&] { return open; })) ++late;
  }
  std::mutex mutex;
  std::condition_variable opened;
  bool open = true;
};

class CountingSamples final : public topo::SampleSource {
 public:
  CountingSamples(std::shared_ptr<const topo::SampleSource> inner, Reads& reads)
      : inner_(std::move(inner)), reads_(reads) {}
  [[nodiscard]] std::size_t rows() const noexcept override { return inner_->rows(); }
  [[nodiscard]] std::size_t cols() const noexcept override { return inner_->cols(); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override {
    reads_.pass();
    ++(std::this_thread::get_id() == reads_.renderThread ? reads_.samplesHere : reads_.elsewhere);
    return inner_->sample(row, col);
  }
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override {
    reads_.pass();
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

// A 1° planet with relief, and a 101 × 101 DEM at 4 m (a bowl) placed on it where the
// planet's relief is near 0 (sin(0.1 row) = 0 at row 94.2: 4.7° S), both read through
// CountingSamples; a camera above the DEM.
struct World {
  explicit World(Reads& reads) {
    const topo::TopoGrid pg(180, 360, -179.5, 89.5, 1.0, 1.0);
    const auto planetSamples =
        topo::InMemorySamples::fromFunction(180, 360, [](std::size_t r, std::size_t c) {
          return static_cast<float>(800.0 * std::sin(0.1 * static_cast<double>(r)) *
                                    std::cos(0.07 * static_cast<double>(c)));
        });
    const auto planetPlain =
        HeightPyramid::fromSamples(pg, planetSamples, SurfaceKind::Planet, mars);
    planet = std::make_shared<const HeightPyramid>(counted(planetPlain, reads), SurfaceKind::Planet,
                                                   mars);
    const topo::TopoGrid dg(101, 101, -200.0, 200.0, 4.0, 4.0);
    const auto demSamples =
        topo::InMemorySamples::fromFunction(101, 101, [&](std::size_t r, std::size_t c) {
          const glm::dvec2 p = dg.sampleCentre(static_cast<double>(r), static_cast<double>(c));
          return static_cast<float>(1e-3 * (p.x * p.x + p.y * p.y) - 30.0);
        });
    const auto demPlain = HeightPyramid::fromSamples(dg, demSamples, SurfaceKind::Plane);
    dem = std::make_shared<const HeightPyramid>(counted(demPlain, reads), SurfaceKind::Plane);
    planetNode = g.add(g.root(), "planet", {}, scenegraph::NodeKind::Terrain, 0);
    demNode = g.add(planetNode, "dem", scenegraph::tangentPlanePose(mars, {-4.7, -5.5, 0.0}, 0.0),
                    scenegraph::NodeKind::Terrain, 1);
    cam = g.add(demNode, "camera", lookFrom({-400.0, -500.0, 250.0}), scenegraph::NodeKind::Camera);
    view.width = 160;
    view.height = 120;
    view.near = 1.0;
  }
  static scenegraph::Pose lookFrom(const glm::dvec3& eye) {
    return scenegraph::Pose::lookAt(eye, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0});
  }
  // The planet (key 0, with lat/lon lines adapted to the view if `latLon`) cut by the DEM
  // (key 1, green).
  [[nodiscard]] std::unique_ptr<SceneRenderer> renderer(bool latLon = false) const {
    auto r = std::make_unique<SceneRenderer>();
    ClipmapOptions o;
    o.size = 63;
    if (latLon) o.effects.latLon = LatLonLines{};
    r->addTerrain(0, planet, o);
    o.effects = {};
    o.albedo = {0.3F, 0.7F, 0.3F};  // the DEM green, the planet its default sand
    r->addTerrain(1, dem, o);
    r->addCutOut(0, 1);
    return r;
  }

  const topo::Body mars = topo::Body::marsSphere();
  std::shared_ptr<const HeightPyramid> planet, dem;
  scenegraph::SceneGraph g{"mars"};
  scenegraph::NodeId planetNode{}, demNode{}, cam{};
  SceneView view;
};

// The reads of one prepare() and of the draw() after it.
struct Shot {
  gl::RgbaImage image;
  std::size_t prepareHere = 0, prepareElsewhere = 0, texels = 0;
  std::size_t drawHere = 0;   // reads on the render thread while draw() ran
  std::size_t drawReads = 0;  // on any thread (a background loader may be reading meanwhile)
};

Shot shoot(SceneRenderer& r, World& w, Reads& reads, gl::RenderTarget& target,
           scenegraph::NodeId focus, Loading loading = Loading::Wait) {
  Shot s;
  const scenegraph::RenderList list = w.g.renderList(focus, w.cam);
  reads.reset();
  s.texels = r.prepare(list, w.view, loading);
  s.prepareHere = reads.here();
  s.prepareElsewhere = reads.elsewhere;
  reads.reset();
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  const SceneFrame f = r.draw(list, w.view);
  EXPECT_EQ(f.terrainsDrawn, 2U);
  EXPECT_EQ(f.texelsUploaded, s.texels);
  s.image = target.readColor();
  s.drawHere = reads.here();
  s.drawReads = reads.all();
  return s;
}

TEST(SceneRendererIoGLTest, DrawReadsNothingAndPrepareReadsOnTheExecutors) {
  test::glContext();
  Reads reads;
  World w(reads);
  const auto r = w.renderer();
  EXPECT_GE(reads.windowsHere, 1U);  // the DEM's mask and skirt: read when the cut-out is added
  gl::RenderTarget target(w.view.width, w.view.height);

  // First frame: prepare() loads the clipmaps' windows and the planet's samples under the
  // DEM, all on other threads, and waits for them; draw() reads nothing.
  const Shot first = shoot(*r, w, reads, target, w.demNode);
  test::savePng("scene_io_first", first.image);
  EXPECT_EQ(first.prepareHere, 0U);
  EXPECT_GT(first.prepareElsewhere, 0U);
  EXPECT_GT(first.texels, 0U);
  EXPECT_EQ(first.drawReads, 0U);
  // The same view again, and from another focus: nothing moved, nothing is read.
  const Shot again = shoot(*r, w, reads, target, w.demNode);
  EXPECT_EQ(again.prepareHere + again.prepareElsewhere + again.drawReads, 0U);
  EXPECT_EQ(again.texels, 0U);
  EXPECT_EQ(again.image.rgba, first.image.rgba);
  const Shot other = shoot(*r, w, reads, target, w.planetNode);
  EXPECT_EQ(other.prepareHere + other.prepareElsewhere + other.drawReads, 0U);
  // The picture holds the DEM and the planet around it, with no hole below the horizon
  // (the sky, left at the clear colour, is the top few rows).
  std::size_t green = 0, ground = 0, holes = 0;
  const gl::RgbaImage& im = first.image;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const auto* px = im.pixel(x, y);
      green += px[1] > px[0] ? 1U : 0U;
      ground += px[0] > px[1] && px[2] < 200 ? 1U : 0U;
      holes += y >= im.height / 4 && im.is(x, y, 255, 0, 255) ? 1U : 0U;  // row 0 at the top
    }
  EXPECT_GT(green, 1000U);
  EXPECT_GT(ground, 1000U);
  EXPECT_EQ(holes, 0U);
}

// The camera flies over the DEM and away over the planet (lat/lon lines adapted to its
// altitude, which reads the ground under the focus): every frame's windows move and are read
// by prepare(), on other threads; no draw() reads a sample on any thread.
TEST(SceneRendererIoGLTest, DrawReadsNoSourceWhileTheCameraMoves) {
  test::glContext();
  Reads reads;
  World w(reads);
  const auto r = w.renderer(true);
  gl::RenderTarget target(w.view.width, w.view.height);
  std::size_t read = 0;
  for (int i = 0; i < 6; ++i) {
    const double k = std::pow(4.0, i);  // 1 km to 1000 km from the DEM
    w.g.setLocal(w.cam, World::lookFrom({-400.0 * k, -500.0 * k, 250.0 * k}));
    const Shot s = shoot(*r, w, reads, target, i % 2 == 0 ? w.demNode : w.planetNode);
    EXPECT_EQ(s.prepareHere, 0U) << "frame " << i;
    EXPECT_EQ(s.drawReads, 0U) << "frame " << i;
    read += s.prepareElsewhere;
    if (i == 0 || i == 5) test::savePng("scene_io_moving_" + std::to_string(i), s.image);
  }
  EXPECT_GT(read, 0U);
  EXPECT_EQ(reads.late, 0U);
}

// Loading::Background (the viewer's frame loop): with every read held back, prepare() returns
// and draw() draws what is resident (nothing yet: the clear colour). Once the reads go on,
// the frames fill in, and the last one is the frame a waiting prepare() gives.
TEST(SceneRendererIoGLTest, BackgroundPrepareDoesNotWaitAndEndsAtTheWaitingFrame) {
  test::glContext();
  Reads reads;
  World w(reads);
  gl::RenderTarget target(w.view.width, w.view.height);
  const Shot waited = shoot(*w.renderer(true), w, reads, target, w.demNode);

  const auto r = w.renderer(true);
  reads.close();
  const Shot held = shoot(*r, w, reads, target, w.demNode, Loading::Background);
  EXPECT_EQ(held.texels, 0U);
  EXPECT_EQ(held.prepareHere, 0U);
  EXPECT_EQ(held.drawReads, 0U);
  std::size_t cleared = 0;
  for (int y = 0; y < held.image.height; ++y)
    for (int x = 0; x < held.image.width; ++x)
      cleared += held.image.is(x, y, 255, 0, 255) ? 1U : 0U;
  EXPECT_EQ(cleared, static_cast<std::size_t>(held.image.width * held.image.height));
  EXPECT_TRUE(r->terrain(0)->loading());
  reads.openGate();

  // Frames until both clipmaps have caught up (a frame loop does not wait; this one sleeps a
  // little between frames), then until the DEM's skirt, which waits for the planet's sample
  // under the DEM (read on the planet's own executor), is drawn: the waiting frame.
  std::size_t texels = 0, frames = 0;
  Shot last;
  bool settled = false;
  while (!settled && frames < 2000) {
    settled = !r->terrain(0)->loading() && !r->terrain(1)->loading();
    last = shoot(*r, w, reads, target, w.demNode, Loading::Background);
    EXPECT_EQ(last.prepareHere, 0U);
    EXPECT_EQ(last.drawHere, 0U);  // the loader may read on its thread meanwhile
    texels += last.texels;
    ++frames;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(settled);
  for (int i = 0; i < 400 && (i == 0 || last.image.rgba != waited.image.rgba); ++i) {
    last = shoot(*r, w, reads, target, w.demNode, Loading::Background);
    EXPECT_EQ(last.texels, 0U);  // nothing left to upload
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  test::savePng("scene_io_background", last.image);
  EXPECT_EQ(texels, waited.texels);
  EXPECT_EQ(last.image.rgba, waited.image.rgba);
  EXPECT_EQ(reads.late, 0U);
}

// Views drawn in turn (the viewer's split viewports) each take a view slot with clipmaps of
// their own: preparing slot 1 for a camera 1000 km away moves none of slot 0's windows, so
// slot 0's view prepared again reads and uploads nothing and draws the same image. A slot
// never prepared draws no terrain; a slot out of range is refused by name.
TEST(SceneRendererIoGLTest, EachViewSlotKeepsItsOwnClipmaps) {
  test::glContext();
  Reads reads;
  World w(reads);
  const auto r = w.renderer();
  gl::RenderTarget target(w.view.width, w.view.height);
  const scenegraph::Pose nearPose = World::lookFrom({-400.0, -500.0, 250.0});
  const scenegraph::Pose farPose = World::lookFrom({-400.0e3, -500.0e3, 250.0e3});
  const auto frame = [&](const scenegraph::Pose& pose, std::size_t slot, std::size_t& texels,
                         std::size_t& readsMade) {
    w.g.setLocal(w.cam, pose);
    const scenegraph::RenderList list = w.g.renderList(w.demNode, w.cam);
    reads.reset();
    texels = r->prepare(list, w.view, Loading::Wait, slot);
    readsMade = reads.all();
    target.clear({1.0F, 0.0F, 1.0F, 1.0F});
    const SceneFrame f = r->draw(list, w.view, nullptr, slot);
    EXPECT_EQ(f.terrainsDrawn, 2U) << "slot " << slot;
    return target.readColor();
  };
  std::size_t texels = 0, readsMade = 0;
  const gl::RgbaImage nearImage = frame(nearPose, 0, texels, readsMade);
  EXPECT_GT(texels, 0U);
  const gl::RgbaImage farImage = frame(farPose, 1, texels, readsMade);
  EXPECT_GT(texels, 0U);  // slot 1's own windows, filled for its own camera
  EXPECT_GT(readsMade, 0U);
  EXPECT_NE(farImage.rgba, nearImage.rgba);
  const gl::RgbaImage nearAgain = frame(nearPose, 0, texels, readsMade);
  EXPECT_EQ(texels, 0U);
  EXPECT_EQ(readsMade, 0U);
  EXPECT_EQ(nearAgain.rgba, nearImage.rgba);
  const gl::RgbaImage farAgain = frame(farPose, 1, texels, readsMade);
  EXPECT_EQ(texels, 0U);
  EXPECT_EQ(farAgain.rgba, farImage.rgba);

  // Slot 2 was never prepared: nothing of it is drawn.
  const scenegraph::RenderList list = w.g.renderList(w.demNode, w.cam);
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  EXPECT_EQ(r->draw(list, w.view, nullptr, 2).terrainsDrawn, 0U);
  const gl::RgbaImage untouched = target.readColor();
  std::size_t cleared = 0;
  for (int y = 0; y < untouched.height; ++y)
    for (int x = 0; x < untouched.width; ++x) cleared += untouched.is(x, y, 255, 0, 255) ? 1U : 0U;
  EXPECT_EQ(cleared, static_cast<std::size_t>(untouched.width * untouched.height));

  const auto refused = [&](auto&& call) {
    try {
      call();
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string expected = "slot is " + std::to_string(SceneRenderer::kMaxSlots) +
                               ", expected a view slot below " +
                               std::to_string(SceneRenderer::kMaxSlots);
  EXPECT_NE(refused([&] {
              (void)r->prepare(list, w.view, Loading::Wait, SceneRenderer::kMaxSlots);
            }).find("SceneRenderer::prepare(): " + expected),
            std::string::npos);
  EXPECT_NE(refused([&] {
              (void)r->draw(list, w.view, nullptr, SceneRenderer::kMaxSlots);
            }).find("SceneRenderer::draw(): " + expected),
            std::string::npos);
}

}  // namespace
}  // namespace regolith::render
