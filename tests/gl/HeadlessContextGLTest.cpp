#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include "GlContext.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace regolith::gl {
namespace {

TEST(HeadlessContextGLTest, GivesOpenGL45Core) {
  auto& ctx = test::glContext();
  EXPECT_EQ(ctx.version(), "4.5") << glVersion() << " on " << glRenderer();
  GLint mask = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &mask);
  EXPECT_NE(mask & GL_CONTEXT_CORE_PROFILE_BIT, 0);
}

TEST(HeadlessContextGLTest, ClearsAndReadsBackColourAndDepth) {
  test::glContext();
  RenderTarget target(64, 32);
  target.clear({1.0F, 0.0F, 1.0F, 1.0F});
  // A scissored clear marks the top-left quadrant (GL's origin is bottom-left): read-back
  // must put it at the top of the image.
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 16, 32, 16);
  glClearColor(0.0F, 1.0F, 0.0F, 1.0F);
  glClear(GL_COLOR_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  const RgbaImage img = target.readColor();
  ASSERT_EQ(img.width, 64);
  ASSERT_EQ(img.height, 32);
  EXPECT_TRUE(img.is(0, 0, 0, 255, 0));
  EXPECT_TRUE(img.is(31, 15, 0, 255, 0));
  EXPECT_TRUE(img.is(32, 0, 255, 0, 255));
  EXPECT_TRUE(img.is(0, 16, 255, 0, 255));
  EXPECT_TRUE(img.is(63, 31, 255, 0, 255));
  EXPECT_EQ(img.pixel(63, 31)[3], 255);
  const DepthImage depth = target.readDepth();
  EXPECT_EQ(depth.at(5, 5), 0.0F);  // reversed Z: cleared to far
  test::savePng("context_clear", img);
}

TEST(HeadlessContextGLTest, ShaderErrorsCarryTheInfoLog) {
  test::glContext();
  try {
    Program p("broken",
              ShaderSources{"#version 450 core\nvoid main() { gl_Position = oops; }\n", "", ""});
    FAIL() << "compiled a broken shader";
  } catch (const GlError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'broken'"), std::string::npos) << what;
    EXPECT_NE(what.find("vertex shader does not compile"), std::string::npos) << what;
    EXPECT_NE(what.find("oops"), std::string::npos) << what;  // from Mesa's log
  }
}

TEST(HeadlessContextGLTest, PngRoundTripAndErrors) {
  test::glContext();
  RgbaImage img{3, 2, {}};
  for (int i = 0; i < 6; ++i)
    img.rgba.insert(img.rgba.end(), {static_cast<std::uint8_t>(40 * i), 7, 200, 255});
  const auto path =
      (std::filesystem::temp_directory_path() / "regolith_png_roundtrip.png").string();
  writePng(path, img);
  const RgbaImage back = readPng(path);
  EXPECT_EQ(back.width, 3);
  EXPECT_EQ(back.height, 2);
  EXPECT_EQ(back.rgba, img.rgba);
  std::remove(path.c_str());
  EXPECT_THROW((void)readPng(path), regolith::Error);
  EXPECT_THROW(writePng("/nonexistent-dir/x.png", img), regolith::Error);
  RgbaImage bad{4, 4, {1, 2, 3}};
  EXPECT_THROW(writePng(path, bad), InvalidArgument);
}

}  // namespace
}  // namespace regolith::gl
