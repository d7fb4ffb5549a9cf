#pragma once
/// \file
/// The error type of the GL layer.

#include <regolith/core/Error.hpp>

namespace regolith::gl {

/// A GL or EGL call failed: no display, no 4.5 core context, a shader that does not
/// compile (the message carries the info log), an incomplete framebuffer.
class GlError : public regolith::Error {
 public:
  using regolith::Error::Error;
};

}  // namespace regolith::gl
