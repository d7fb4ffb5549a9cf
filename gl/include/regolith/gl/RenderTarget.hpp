#pragma once
/// \file
/// An offscreen framebuffer with colour and depth, and its read-back.

#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Image.hpp>

#include <glm/vec4.hpp>

namespace regolith::gl {

/// A framebuffer object with an RGBA8 colour texture and a 32-bit float depth texture,
/// set up for Camera's reversed-Z projection (glClipControl zero-to-one, depth test
/// GL_GREATER, depth cleared to 0). Headless renders and screenshots go through it.
/// Move-only; belongs to its context's thread.
class RenderTarget {
 public:
  /// Throws InvalidArgument unless 1 ≤ width, height ≤ 16384; GlError if incomplete.
  RenderTarget(int width, int height);

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] Id framebuffer() const noexcept { return fbo_.id(); }
  /// The RGBA8 colour texture (for passes that read the frame, such as screen-space
  /// composition; not while it is the bound draw target).
  [[nodiscard]] Id colorTexture() const noexcept { return color_.id(); }
  /// The DEPTH_COMPONENT32F depth texture (reversed Z: near / view distance, 0 = nothing).
  [[nodiscard]] Id depthTexture() const noexcept { return depth_.id(); }

  /// Binds the framebuffer, sets the viewport and the reversed-Z depth state.
  void bind() const noexcept;
  /// Binds, then clears colour to `rgba` (components in [0, 1]) and depth to 0 (far).
  void clear(const glm::vec4& rgba) const noexcept;
  /// Reads the colour attachment (row 0 at the top).
  [[nodiscard]] RgbaImage readColor() const;
  /// Reads the depth attachment (row 0 at the top; 0 where nothing was drawn).
  [[nodiscard]] DepthImage readDepth() const;

 private:
  int width_, height_;
  Texture color_;
  Texture depth_;
  Framebuffer fbo_;
};

/// Sets the reversed-Z depth state on the bound framebuffer (clip control zero-to-one,
/// GL_GREATER, depth writes on). Window renders call it too.
void useReversedZ() noexcept;

}  // namespace regolith::gl
