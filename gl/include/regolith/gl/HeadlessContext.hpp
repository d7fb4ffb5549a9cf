#pragma once
/// \file
/// A headless OpenGL 4.5 core context through EGL on Mesa's surfaceless platform.

#include <string>

namespace regolith::gl {

/// Owns an EGL display and an OpenGL 4.5 core context with no surface (EGL_MESA_platform_
/// surfaceless); everything renders into framebuffer objects (RenderTarget). On a machine
/// with no GPU Mesa's llvmpipe serves it. The constructor makes the context current on the
/// calling thread; the destructor releases and destroys it.
///
/// Throws GlError naming the EGL call and its error code if the platform, the API or a 4.5
/// core context is unavailable. Move-only in spirit: neither copyable nor movable (GL
/// objects hold references to the context that is current). One owner, one thread.
class HeadlessContext {
 public:
  HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;
  ~HeadlessContext();

  /// Makes this context current on the calling thread (throws GlError on failure).
  void makeCurrent() const;
  /// Releases the context from the calling thread.
  void release() const noexcept;
  /// "major.minor" of the context, e.g. "4.5".
  [[nodiscard]] std::string version() const;

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
};

}  // namespace regolith::gl
