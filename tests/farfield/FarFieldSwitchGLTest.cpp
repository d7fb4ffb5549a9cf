// The far field's two economies for a body that covers few pixels (docs/far-field.md, "The
// mesh pass"): a thinned PGM grid (PgmOptions::minCellPixels) draws exactly what PGM draws
// with the smaller grid, and the early switch to the impostor (impostorReliefPixels) changes
// the image by no more than the relief spans on the screen: coverage differs only where a
// ray passes between the body's lowest and highest sphere, and where both draw, the two
// surfaces are within the relief's pixels of each other.

#include <regolith/clod/Camera.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/topo/Body.hpp>

#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace regolith::farfield {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

double relief(double lat, double lon, double) {
  return 7000.0 * std::sin(3.0 * lat * kDeg) * std::cos(5.0 * lon * kDeg) +
         2000.0 * std::sin(23.0 * lon * kDeg + 0.3) * std::cos(19.0 * lat * kDeg);
}

std::shared_ptr<const HeightLayers> marsLayers() {
  static const auto layers = [] {
    LayerOptions lo;
    lo.equirectWidth = 1024;
    lo.capSize = 256;
    return std::make_shared<const HeightLayers>(
        HeightLayers::build(topo::Body::marsEllipsoid(), relief, lo));
  }();
  return layers;
}

clod::Camera camera(const glm::dvec3& position, const glm::dvec3& target, int size, double fovY) {
  clod::Camera cam;
  cam.position = position;
  cam.target = target;
  cam.up = {0.0, 0.0, 1.0};
  cam.fovYDegrees = fovY;
  cam.width = cam.height = size;
  cam.near = 1.0;
  return cam;
}

struct Images {
  gl::RgbaImage colour;
  gl::DepthImage depth;
  PgmFrame frame;
};

Images drawPgm(const clod::Camera& cam, int grid, double minCellPixels) {
  PgmOptions o;
  o.gridWidth = o.gridHeight = grid;
  o.minCellPixels = minCellPixels;
  o.readback = PrimaryReadback::Fixed;  // the same r_p in every render compared
  PgmRenderer pgm(*marsLayers(), o);
  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  Images out;
  out.frame = pgm.draw(target, cam, glm::normalize(glm::dvec3(1.0, 0.4, 0.5)));
  out.colour = target.readColor();
  out.depth = target.readDepth();
  return out;
}

std::size_t differing(const Images& a, const Images& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.colour.rgba.size(); ++i) n += a.colour.rgba[i] != b.colour.rgba[i];
  for (std::size_t i = 0; i < a.depth.depth.size(); ++i) n += a.depth.depth[i] != b.depth.depth[i];
  return n;
}

TEST(PgmRendererGL, AThinnedGridDrawsExactlyAsTheSmallerGrid) {
  test::glContext();
  const double a = topo::Body::marsEllipsoid().equatorialRadius();
  // The whole planet, small on a 256² screen: a 255² grid's cells are under a pixel (from
  // 6 a; from 4 a the even-error spread's widest cells, in the middle, span 1.1 px).
  const clod::Camera global = camera({6.0 * a, 0.0, 0.45 * a}, {0.0, 0.0, 0.0}, 256, 45.0);
  const Images thin = drawPgm(global, 255, 4.0);
  std::printf("global: cells %.2f px at 255², grid drawn %d × %d\n", thin.frame.cellPixels,
              thin.frame.gridWidth, thin.frame.gridHeight);
  ASSERT_TRUE(thin.frame.drawn);
  EXPECT_GT(thin.frame.cellPixels, 0.2);
  EXPECT_LT(thin.frame.cellPixels, 1.0);
  EXPECT_LT(thin.frame.gridWidth, 255);
  EXPECT_EQ(thin.frame.gridWidth, thin.frame.gridHeight);
  // Each halving at most doubles the cells: they end between 4 and 8 px.
  const int stride = 254 / (thin.frame.gridWidth - 1);
  EXPECT_GE(thin.frame.cellPixels * stride, 4.0);
  EXPECT_LT(thin.frame.cellPixels * stride / 2.0, 4.0);
  // The same pixels as a renderer built with the smaller grid.
  const Images small = drawPgm(global, thin.frame.gridWidth, 0.0);
  EXPECT_EQ(small.frame.gridWidth, thin.frame.gridWidth);
  EXPECT_EQ(differing(thin, small), 0U);
  test::savePng("pgm_thin_global", thin.colour);

  // Close to the ground at the horizon, cells near the eye span many pixels: no thinning,
  // and the same image as without the option.
  const topo::Body mars = topo::Body::marsEllipsoid();
  const clod::Camera low = camera(mars.toBodyFixed({10.0, 20.0, 20000.0}),
                                  mars.toBodyFixed({10.0, 25.0, 0.0}), 256, 50.0);
  const Images lowThin = drawPgm(low, 128, 4.0);
  const Images lowFull = drawPgm(low, 128, 0.0);
  std::printf("low: cells up to %.1f px, grid drawn %d\n", lowThin.frame.cellPixels,
              lowThin.frame.gridWidth);
  EXPECT_EQ(lowThin.frame.gridWidth, 128);
  EXPECT_EQ(differing(lowThin, lowFull), 0U);
}

TEST(PgmRendererGL, MinCellPixelsAndImpostorReliefPixelsAreChecked) {
  test::glContext();
  PgmOptions o;
  o.minCellPixels = -1.0;
  try {
    PgmRenderer pgm(*marsLayers(), o);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "farfield::PgmRenderer(): minCellPixels is -1, expected in [0, 1e+06]");
  }
  o.minCellPixels = 0.0;
  o.impostorReliefPixels = std::nan("");
  EXPECT_THROW(PgmRenderer(*marsLayers(), o), InvalidArgument);
}

/// Distance along the pixel's ray to what the depth image holds there (NaN if nothing).
double alongRay(const clod::Camera& cam, const gl::DepthImage& depth, int x, int y) {
  const float z = depth.at(x, y);
  if (!(z > 0.0F)) return std::nan("");
  return cam.viewDistance(z) / glm::dot(cam.ray(x + 0.5, y + 0.5), cam.forward());
}

TEST(FarFieldGL, TheEarlyImpostorIsWithinTheReliefInPixels) {
  test::glContext();
  const topo::Body mars = topo::Body::marsEllipsoid();
  const double a = mars.equatorialRadius();
  const glm::dvec3 sun = glm::normalize(glm::dvec3(1.0, 0.4, 0.5));
  // 4 R away (PGM still has its secondary sphere) on a 400² screen.
  const clod::Camera cam = camera({4.0 * a, 0.5 * a, 1.0 * a}, {0.0, 0.0, 0.0}, 400, 35.0);
  PgmOptions po;
  po.gridWidth = po.gridHeight = 256;
  po.readback = PrimaryReadback::Fixed;
  FarField pgmOnly(marsLayers(), po);
  po.impostorReliefPixels = 1.0;
  FarField early(marsLayers(), po);

  gl::RenderTarget target(cam.width, cam.height);
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  const FarFieldFrame fp = pgmOnly.draw(target, cam, sun, true);
  const gl::DepthImage pgmDepth = target.readDepth();
  test::savePng("farfield_switch_pgm", target.readColor());
  target.clear({0.0F, 0.0F, 0.0F, 1.0F});
  const FarFieldFrame fi = early.draw(target, cam, sun, true);
  const gl::DepthImage impDepth = target.readDepth();
  test::savePng("farfield_switch_impostor", target.readColor());

  const double reliefPx = fi.reliefPixels;
  std::printf("relief %.3f px\n", reliefPx);
  EXPECT_EQ(fp.mode, FarFieldMode::Pgm);
  ASSERT_EQ(fi.mode, FarFieldMode::Impostor);
  EXPECT_GT(reliefPx, 0.3);  // the two really differ by some relief
  EXPECT_LE(reliefPx, 1.0);
  EXPECT_DOUBLE_EQ(fp.reliefPixels, reliefPx);

  // Coverage: a pixel drawn by only one of them has its ray pass between the body's lowest
  // and highest sphere (with the pixel's own half-diagonal of slack).
  const double minR = mars.polarRadius() + marsLayers()->minHeight();
  const double maxR = a + marsLayers()->maxHeight();
  int both = 0, onlyOne = 0, outsideBand = 0;
  double worst = 0.0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const double tp = alongRay(cam, pgmDepth, x, y), ti = alongRay(cam, impDepth, x, y);
      const glm::dvec3 r = cam.ray(x + 0.5, y + 0.5);
      if (std::isnan(tp) != std::isnan(ti)) {
        ++onlyOne;
        const double closest = glm::length(cam.position - glm::dot(cam.position, r) * r);
        const double slack = 0.71 * glm::length(cam.position) / cam.focalPixels();
        if (closest < minR - slack || closest > maxR + slack) ++outsideBand;
        continue;
      }
      if (std::isnan(tp)) continue;
      ++both;
      // The two surfaces' separation seen from the eye: along the ray, foreshortened by the
      // incidence, over the distance, times the focal length.
      const glm::dvec3 p = cam.position + tp * r;
      const double incidence = std::abs(glm::dot(glm::normalize(p), r));
      worst = std::max(worst, std::abs(tp - ti) * incidence / tp * cam.focalPixels());
    }
  }
  std::printf("both %d px, one only %d px (outside the relief band %d), worst %.3f px\n", both,
              onlyOne, outsideBand, worst);
  EXPECT_GT(both, 20000);
  EXPECT_EQ(outsideBand, 0);
  EXPECT_LE(worst, reliefPx + 0.01);
}

// The near field covering the whole target (a close view whose clipmap fills the screen)
// leaves the far field nothing to do: FarField draws nothing (mode Covered), changes no
// pixel, and PGM's primary sphere, measured on earlier frames, starts again from the lowest
// radius. One empty pixel where the body is brings PGM back, and it fills that pixel only.
TEST(FarFieldGL, ACoveredTargetIsLeftAsItIsAndPgmStartsAgainLow) {
  test::glContext();
  const topo::Body mars = topo::Body::marsEllipsoid();
  const double a = mars.equatorialRadius();
  const glm::dvec3 sun = glm::normalize(glm::dvec3(1.0, 0.4, 0.5));
  // 300 km up, looking down a little off the nadir: the ground fills the view.
  const glm::dvec3 eye = glm::normalize(glm::dvec3(1.0, 0.3, 0.4)) * (a + 300.0e3);
  const clod::Camera cam = camera(eye, 0.9 * eye + glm::dvec3(0.0, 0.0, 5.0e4), 64, 40.0);
  PgmOptions po;
  po.gridWidth = po.gridHeight = 64;  // the default read-back: lagged by a frame
  FarField field(marsLayers(), po);
  PgmRenderer& pgm = field.pgm();

  gl::RenderTarget target(cam.width, cam.height);
  for (int frame = 0; frame < 4; ++frame) {
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    ASSERT_EQ(field.draw(target, cam, sun, true).mode, FarFieldMode::Pgm) << frame;
    glFinish();  // the lagged read-back's fence has passed by the next frame
  }
  // The ground seen from here lies well above the body's lowest radius.
  ASSERT_GT(pgm.primaryRadius(), pgm.minRadius() + 100.0);

  // Every pixel drawn (at a depth in front of the ground, in a colour PGM never draws).
  const float drawn = 0.9F;
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  glClearNamedFramebufferfv(target.framebuffer(), GL_DEPTH, 0, &drawn);
  const gl::RgbaImage before = target.readColor();
  const FarFieldFrame covered = field.draw(target, cam, sun, true);
  EXPECT_EQ(covered.mode, FarFieldMode::Covered);
  EXPECT_FALSE(covered.pgm.drawn);
  EXPECT_EQ(target.readColor().rgba, before.rgba);
  EXPECT_EQ(pgm.primaryRadius(), pgm.minRadius());

  // One pixel at the centre left empty: PGM draws it, and only it.
  const float empty = 0.0F;
  glEnable(GL_SCISSOR_TEST);
  glScissor(cam.width / 2, cam.height / 2, 1, 1);
  glClearNamedFramebufferfv(target.framebuffer(), GL_DEPTH, 0, &empty);
  glDisable(GL_SCISSOR_TEST);
  const FarFieldFrame filled = field.draw(target, cam, sun, true);
  EXPECT_EQ(filled.mode, FarFieldMode::Pgm);
  const gl::RgbaImage after = target.readColor();
  const gl::DepthImage depth = target.readDepth();
  int changed = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const bool centre = x == cam.width / 2 && y == cam.height - 1 - cam.height / 2;
      const bool same = after.is(x, y, 255, 0, 255);
      if (!same) ++changed;
      if (centre) {
        EXPECT_FALSE(same) << "the empty pixel was not filled";
        EXPECT_GT(depth.at(x, y), 0.0F);
        EXPECT_LT(depth.at(x, y), drawn);
      }
    }
  }
  EXPECT_EQ(changed, 1);

  // Without keepDrawn there is no test: PGM draws over the target by the depth test.
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  glClearNamedFramebufferfv(target.framebuffer(), GL_DEPTH, 0, &drawn);
  EXPECT_EQ(field.draw(target, cam, sun, false).mode, FarFieldMode::Pgm);
}

}  // namespace
}  // namespace regolith::farfield
