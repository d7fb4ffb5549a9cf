#pragma once
/// \file
/// Move-only owners of GL object names, created with GL 4.5 direct state access.
///
/// Each wrapper creates its object in the constructor (glCreate*) and deletes it in the
/// destructor; moves transfer the name and leave 0 behind. A context must be current on the
/// calling thread for construction and destruction. Not thread-safe (GL objects belong to
/// their context's thread).
///
/// Needs no GL header (nor does Program.hpp or RenderTarget.hpp): the renderers' public
/// headers hold GL objects without declaring GL to their users. Code that calls GL includes
/// <regolith/gl/Gl.hpp>.

#include <utility>

namespace regolith::gl {

/// A GL object name: Id, which the Khronos headers define as unsigned int (checked
/// where GL is declared, in GlObjects.cpp).
using Id = unsigned int;

/// The kinds of GL object a GlObject can own.
enum class GlKind { Buffer, VertexArray, Texture2D, Framebuffer, Renderbuffer };

/// Owns one GL object name of kind K.
template <GlKind K>
class GlObject {
 public:
  /// Creates a new object (glCreateBuffers, glCreateVertexArrays, glCreateTextures(2D), ...).
  GlObject();
  /// Takes ownership of an existing name (0 for none).
  explicit GlObject(Id adopted) noexcept : id_(adopted) {}
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;
  GlObject(GlObject&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlObject& operator=(GlObject&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  ~GlObject() { reset(); }

  /// The GL name (0 after a move).
  [[nodiscard]] Id id() const noexcept { return id_; }
  /// Deletes the object now.
  void reset() noexcept;

 private:
  Id id_ = 0;
};

using Buffer = GlObject<GlKind::Buffer>;
using VertexArray = GlObject<GlKind::VertexArray>;
using Texture = GlObject<GlKind::Texture2D>;
using Framebuffer = GlObject<GlKind::Framebuffer>;
using Renderbuffer = GlObject<GlKind::Renderbuffer>;

extern template class GlObject<GlKind::Buffer>;
extern template class GlObject<GlKind::VertexArray>;
extern template class GlObject<GlKind::Texture2D>;
extern template class GlObject<GlKind::Framebuffer>;
extern template class GlObject<GlKind::Renderbuffer>;

}  // namespace regolith::gl
