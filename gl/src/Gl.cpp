#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>

#include <string>

namespace regolith::gl {

namespace {

const char* errorName(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
    case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
    default: return "unknown GL error";
  }
}

std::string glString(GLenum name) {
  const auto* s = glGetString(name);
  return s == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(s));
}

}  // namespace

void checkGl(std::string_view operation) {
  GLenum first = glGetError();
  if (first == GL_NO_ERROR) return;
  std::string msg = std::string(operation) + ": " + errorName(first);
  for (int i = 0; i < 16; ++i) {  // drain (bounded: a lost context repeats forever)
    const GLenum e = glGetError();
    if (e == GL_NO_ERROR) break;
    msg += std::string(", ") + errorName(e);
  }
  throw GlError(msg);
}

std::string glVersion() { return glString(GL_VERSION); }
std::string glRenderer() { return glString(GL_RENDERER); }

}  // namespace regolith::gl
