#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/HeadlessContext.hpp>

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <string>

namespace regolith::gl {

namespace {

std::string eglErrorText(const char* call) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04X", static_cast<unsigned>(eglGetError()));
  return std::string("HeadlessContext(): ") + call + " failed (EGL error " + code + ")";
}

}  // namespace

HeadlessContext::HeadlessContext() {
  // EGL 1.5 core entry point; Mesa's surfaceless platform needs no window system or device.
  EGLDisplay dpy =
      eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (dpy == EGL_NO_DISPLAY)
    throw GlError(eglErrorText("eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA)"));
  EGLint major = 0, minor = 0;
  if (eglInitialize(dpy, &major, &minor) == EGL_FALSE) throw GlError(eglErrorText("eglInitialize"));
  display_ = dpy;
  try {
    if (eglBindAPI(EGL_OPENGL_API) == EGL_FALSE) throw GlError(eglErrorText("eglBindAPI"));
    // The surfaceless platform offers pbuffer configs only (EGL's default asks for windows).
    // Nothing renders to the config's surface: all drawing goes to framebuffer objects.
    const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                    EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint count = 0;
    if (eglChooseConfig(dpy, configAttribs, &config, 1, &count) == EGL_FALSE || count < 1)
      throw GlError(eglErrorText("eglChooseConfig(EGL_PBUFFER_BIT, EGL_OPENGL_BIT)"));
    const EGLint ctxAttribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 4,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, ctxAttribs);
    if (ctx == EGL_NO_CONTEXT) throw GlError(eglErrorText("eglCreateContext(OpenGL 4.5 core)"));
    context_ = ctx;
    makeCurrent();
  } catch (...) {
    if (context_ != nullptr) eglDestroyContext(dpy, context_);
    eglTerminate(dpy);
    throw;
  }
}

HeadlessContext::~HeadlessContext() {
  release();
  eglDestroyContext(display_, context_);
  eglTerminate(display_);
}

void HeadlessContext::makeCurrent() const {
  if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) == EGL_FALSE)
    throw GlError(eglErrorText("eglMakeCurrent(surfaceless)"));
}

void HeadlessContext::release() const noexcept {
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

std::string HeadlessContext::version() const {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  return std::to_string(major) + "." + std::to_string(minor);
}

}  // namespace regolith::gl
