#pragma once
// The viewer's heads-up display: lines of text drawn with a 3×5-pixel bitmap font into a
// CPU image, uploaded and blitted over the frame's top-left corner (one upload and one blit
// a frame, no blending: the text sits on a dark box).
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <string>
#include <vector>

namespace regolith::tools::viewer {

/// Draws `lines` (upper-cased; characters without a glyph print as '?') into an RGBA image,
/// `scale` screen pixels per font pixel, light text on a dark box.
[[nodiscard]] gl::RgbaImage renderText(const std::vector<std::string>& lines, int scale = 2);

/// The HUD overlay. Needs a current GL context; belongs to its thread.
class Hud {
 public:
  /// Draws `lines` over `target`'s top-left corner (clipped to the target).
  void draw(const std::vector<std::string>& lines, const gl::RenderTarget& target);

 private:
  gl::Texture texture_{0};
  gl::Framebuffer framebuffer_{0};
  int width_ = 0, height_ = 0;
};

}  // namespace regolith::tools::viewer
