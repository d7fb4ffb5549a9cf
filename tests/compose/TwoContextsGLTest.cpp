// White's N04: several views of one catalogue at once. Two headless GL contexts on two
// threads draw two views of one composed catalogue whose stores page through one patch
// cache; each image must equal the same view drawn alone.
//
// Its own file and contexts: it never touches the shared test context (tests/gl/GlContext.hpp),
// because destroying a context terminates the EGL display it was made on.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/compose/ComposedPyramid.hpp>
#include <regolith/compose/FromStore.hpp>
#include <regolith/gl/HeadlessContext.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <support/StoreScratch.hpp>

#include <cmath>
#include <fstream>
#include <memory>
#include <thread>

namespace regolith::compose {
namespace {

/// A Moon store: a 1° global grid and a 50 m tangent-plane DEM at (10°N, 20°E), and a
/// catalogue file composing them.
std::filesystem::path catalogueFile() {
  const topo::Body moon = topo::Body::moon();
  const auto path = test::scratchFile("compose_gl", "two.h5");
  store::GridSource planet;
  planet.info.name = "global";
  planet.info.kind = store::GridKind::Planet;
  planet.info.rows = 180;
  planet.info.cols = 360;
  planet.info.x0 = -179.5;
  planet.info.y0 = 89.5;
  planet.info.bodyName = "Moon";
  planet.info.equatorialRadius = planet.info.polarRadius = moon.equatorialRadius();
  planet.samples = topo::InMemorySamples::fromFunction(180, 360, [](std::size_t r, std::size_t c) {
    return static_cast<float>(800.0 * std::sin(0.2 * static_cast<double>(r)) *
                              std::cos(0.15 * static_cast<double>(c)));
  });
  store::GridSource dem;
  dem.info.name = "site";
  dem.info.rows = dem.info.cols = 401;
  dem.info.x0 = -10000.0;
  dem.info.y0 = 10000.0;
  dem.info.spacingX = dem.info.spacingY = 50.0;
  dem.info.bodyName = "Moon";
  dem.info.equatorialRadius = dem.info.polarRadius = moon.equatorialRadius();
  dem.info.placement.kind = store::PlacementInfo::Kind::LocalTangentPlane;
  dem.info.placement.originLatDeg = 10.0;
  dem.info.placement.originLonDeg = 20.0;
  dem.samples = topo::InMemorySamples::fromFunction(401, 401, [](std::size_t r, std::size_t c) {
    const double x = static_cast<double>(c) - 200.0, y = static_cast<double>(r) - 200.0;
    return static_cast<float>(-300.0 + 400.0 * std::exp(-(x * x + y * y) / 4000.0));
  });
  const store::GridSource grids[] = {planet, dem};
  store::WriteOptions w;
  w.patchRows = w.patchCols = 64;
  store::writeStore(path, grids, w);
  const auto file = path.parent_path() / "two.json";
  std::ofstream(file) << R"({"datasets": [{"store": "two.h5", "grid": "global"},
                                          {"store": "two.h5", "grid": "site", "feather_m": 3000}]})";
  return file;
}

/// One view of the composed surface around the DEM, drawn on the calling thread's context.
gl::RgbaImage view(const std::shared_ptr<const ComposedSurface>& surface, double headingDeg) {
  const topo::Body& body = surface->body();
  const DrawingFrame frame = drawingFrame(surface, 10.0, 200.0);
  auto pyramid = std::make_shared<const clod::HeightPyramid>(frame.pyramid);
  clod::ClipmapOptions o;
  o.size = 127;
  const glm::dmat3 enu = body.enuFrame(10.0, 20.0);
  o.lightDirection = glm::vec3(glm::normalize(enu[2] + 0.5 * enu[0]));
  clod::ClipmapTerrain terrain(pyramid, o);
  clod::Camera cam;
  cam.target = body.toBodyFixed({10.0, 20.0, 0.0});
  const double h = headingDeg * 3.141592653589793 / 180.0;
  const glm::dvec3 back = -(std::sin(h) * enu[0] + std::cos(h) * enu[1]);
  cam.position = cam.target + 30e3 * back + 20e3 * enu[2];
  cam.up = enu[2];
  cam.width = 160;
  cam.height = 120;
  cam.near = 10.0;
  terrain.setFocus(cam.target);
  terrain.finishLoading();
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  terrain.draw(cam);
  return target.readColor();
}

TEST(TwoContextsGLTest, TwoThreadsDrawTwoViewsOfOneCatalogueThroughOneCache) {
  const CatalogueFile cf = readCatalogueFile(catalogueFile());
  const auto surface = std::make_shared<const ComposedSurface>(cf.catalogue->snapshot(), cf.rules);
  gl::RgbaImage a, b;
  std::exception_ptr errorA, errorB;
  std::thread ta([&] {
    try {
      const gl::HeadlessContext context;
      a = view(surface, 0.0);
    } catch (...) {
      errorA = std::current_exception();
    }
  });
  std::thread tb([&] {
    try {
      const gl::HeadlessContext context;
      b = view(surface, 120.0);
    } catch (...) {
      errorB = std::current_exception();
    }
  });
  ta.join();
  tb.join();
  if (errorA) std::rethrow_exception(errorA);
  if (errorB) std::rethrow_exception(errorB);
  const store::CacheStats shared = cf.pagers.front()->cache().stats();
  EXPECT_GT(shared.hits, 0U);

  // The same views, one after the other on this thread: the same pixels.
  gl::RgbaImage a1, b1;
  {
    const gl::HeadlessContext context;
    a1 = view(surface, 0.0);
    b1 = view(surface, 120.0);
  }
  ASSERT_EQ(a.rgba.size(), a1.rgba.size());
  EXPECT_TRUE(a.rgba == a1.rgba);
  EXPECT_TRUE(b.rgba == b1.rgba);
  EXPECT_FALSE(a.rgba == b.rgba);  // two different views
  // Both show terrain over most of the image.
  int lit = 0;
  for (std::size_t i = 0; i < a.rgba.size(); i += 4) lit += a.rgba[i] > 10 ? 1 : 0;
  EXPECT_GT(lit, 160 * 120 / 3);
}

}  // namespace
}  // namespace regolith::compose
