#include <regolith/gl/EmptyPixels.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>

namespace regolith::gl {

namespace {

// The full-screen triangle lies at window depth 0 (clip z 0 under glClipControl's zero-to-one
// depth), which the depth test GL_EQUAL passes only where the target's depth is still the
// clear value.
constexpr const char* kFragment = R"(#version 450 core
void main() {}
)";

}  // namespace

EmptyPixelTest::EmptyPixelTest()
    : program_("gl::EmptyPixelTest", {kFullScreenTriangle, {}, kFragment}) {
  glCreateQueries(GL_ANY_SAMPLES_PASSED, 1, &query_);
  checkGl("gl::EmptyPixelTest()");
}

EmptyPixelTest::~EmptyPixelTest() { glDeleteQueries(1, &query_); }

bool EmptyPixelTest::anyEmpty(const RenderTarget& target) const {
  target.bind();
  glDepthFunc(GL_EQUAL);
  glDepthMask(GL_FALSE);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_SCISSOR_TEST);
  program_.use();
  glBindVertexArray(vao_.id());
  glBeginQuery(GL_ANY_SAMPLES_PASSED, query_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glEndQuery(GL_ANY_SAMPLES_PASSED);
  glBindVertexArray(0);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  useReversedZ();
  GLuint any = 0;
  glGetQueryObjectuiv(query_, GL_QUERY_RESULT, &any);  // waits for the GPU
  checkGl("gl::EmptyPixelTest::anyEmpty()");
  return any != 0;
}

}  // namespace regolith::gl
