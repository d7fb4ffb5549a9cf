#pragma once
/// \file
/// OpenGL 4.5 core declarations and GL error checks.
///
/// Regolith calls GL through libglvnd's libOpenGL, which exports every core entry point up
/// to 4.6, so this header declares them from the Khronos core profile header and no loader
/// runs. A context must be current on the calling thread (HeadlessContext, WindowContext).

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>

#include <string>
#include <string_view>

namespace regolith::gl {

/// Throws GlError naming `operation` and the GL error code if glGetError() reports one
/// (all pending errors are drained).
void checkGl(std::string_view operation);

/// The GL_VERSION, GL_RENDERER strings of the current context.
[[nodiscard]] std::string glVersion();
[[nodiscard]] std::string glRenderer();

}  // namespace regolith::gl
