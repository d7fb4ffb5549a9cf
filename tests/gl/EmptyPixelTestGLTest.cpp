// gl::EmptyPixelTest: whether a render target still has a pixel with no depth. Checked at
// every corner and the centre of odd-sized targets (the full-screen triangle must reach
// each edge), against a depth of the smallest normal float (drawn, however far), and for
// the state it leaves and the pixels it must not change.

#include <regolith/gl/EmptyPixels.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include "GlContext.hpp"

#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <utility>

namespace regolith::gl {
namespace {

// Every pixel of `target` drawn at `depth` (a clear of colour and depth), then pixel (x, y)
// (GL's bottom-left origin) cleared back to depth 0 unless x < 0.
void fill(const RenderTarget& target, float depth, int x, int y) {
  target.clear({0.2F, 0.4F, 0.6F, 1.0F});
  glClearNamedFramebufferfv(target.framebuffer(), GL_DEPTH, 0, &depth);
  if (x < 0) return;
  const float empty = 0.0F;
  glEnable(GL_SCISSOR_TEST);
  glScissor(x, y, 1, 1);
  glClearNamedFramebufferfv(target.framebuffer(), GL_DEPTH, 0, &empty);
  glDisable(GL_SCISSOR_TEST);
}

TEST(EmptyPixelTestGL, FindsOneEmptyPixelAnywhereAndNoneWhereAllAreDrawn) {
  test::glContext();
  const EmptyPixelTest test;
  for (const auto& [w, h] : {std::pair{97, 61}, std::pair{1, 1}, std::pair{640, 3}}) {
    const RenderTarget target(w, h);
    target.clear({0.0F, 0.0F, 0.0F, 1.0F});
    EXPECT_TRUE(test.anyEmpty(target)) << w << " x " << h << " cleared";
    fill(target, 0.5F, -1, -1);
    EXPECT_FALSE(test.anyEmpty(target)) << w << " x " << h << " drawn at depth 0.5";
    fill(target, std::numeric_limits<float>::min(), -1, -1);
    EXPECT_FALSE(test.anyEmpty(target)) << w << " x " << h << " drawn at the smallest normal depth";
    const std::array<std::pair<int, int>, 5> pixels{
        {{0, 0}, {w - 1, 0}, {0, h - 1}, {w - 1, h - 1}, {w / 2, h / 2}}};
    for (const auto& [x, y] : pixels) {
      fill(target, 0.5F, x, y);
      EXPECT_TRUE(test.anyEmpty(target)) << w << " x " << h << ", pixel " << x << ", " << y;
    }
  }
}

TEST(EmptyPixelTestGL, ChangesNoPixelAndLeavesTheReversedZState) {
  test::glContext();
  const EmptyPixelTest test;
  const RenderTarget target(33, 17);
  fill(target, 0.25F, 3, 4);
  const RgbaImage colour = target.readColor();
  const DepthImage depth = target.readDepth();
  ASSERT_TRUE(test.anyEmpty(target));
  const RgbaImage colourAfter = target.readColor();
  const DepthImage depthAfter = target.readDepth();
  EXPECT_EQ(colourAfter.rgba, colour.rgba);
  EXPECT_EQ(depthAfter.depth, depth.depth);

  GLint func = 0;
  glGetIntegerv(GL_DEPTH_FUNC, &func);
  EXPECT_EQ(func, GL_GREATER);
  GLboolean depthWrites = GL_FALSE;
  glGetBooleanv(GL_DEPTH_WRITEMASK, &depthWrites);
  EXPECT_EQ(depthWrites, GL_TRUE);
  std::array<GLboolean, 4> colourWrites{};
  glGetBooleanv(GL_COLOR_WRITEMASK, colourWrites.data());
  EXPECT_EQ(colourWrites, (std::array<GLboolean, 4>{GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE}));
  EXPECT_TRUE(glIsEnabled(GL_DEPTH_TEST));
}

}  // namespace
}  // namespace regolith::gl
