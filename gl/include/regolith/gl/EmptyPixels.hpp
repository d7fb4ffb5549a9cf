#pragma once
/// \file
/// Whether a render target has a pixel nothing was drawn on.

#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Program.hpp>

namespace regolith::gl {

class RenderTarget;

/// Asks the GPU whether a RenderTarget still has an empty pixel: one whose depth is the
/// clear value of the reversed-Z convention (0, "nothing drawn"). One full-screen pass that
/// tests depth only (no shading, no colour or depth writes), counted by an occlusion query.
///
/// For a pass that only fills in around what is drawn (the far field after the near-field
/// clipmaps, FarField::draw with keepDrawn): where nothing is empty, it has nothing to do.
/// Not copyable; belongs to its context's thread.
class EmptyPixelTest {
 public:
  EmptyPixelTest();
  EmptyPixelTest(const EmptyPixelTest&) = delete;
  EmptyPixelTest& operator=(const EmptyPixelTest&) = delete;
  ~EmptyPixelTest();

  /// True if any pixel of `target` has depth 0. Binds `target` and waits for the GPU to
  /// finish drawing into it (the query's result). Leaves the reversed-Z depth state
  /// (useReversedZ()) and colour writes on; blending, face culling and the scissor test off.
  [[nodiscard]] bool anyEmpty(const RenderTarget& target) const;

 private:
  Program program_;
  VertexArray vao_;
  Id query_ = 0;
};

}  // namespace regolith::gl
