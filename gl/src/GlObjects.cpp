#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlObjects.hpp>

#include <type_traits>

namespace regolith::gl {
static_assert(std::is_same_v<Id, GLuint>, "gl::Id must be GLuint");
}  // namespace regolith::gl

namespace regolith::gl {

template <GlKind K>
GlObject<K>::GlObject() {
  if constexpr (K == GlKind::Buffer) glCreateBuffers(1, &id_);
  if constexpr (K == GlKind::VertexArray) glCreateVertexArrays(1, &id_);
  if constexpr (K == GlKind::Texture2D) glCreateTextures(GL_TEXTURE_2D, 1, &id_);
  if constexpr (K == GlKind::Framebuffer) glCreateFramebuffers(1, &id_);
  if constexpr (K == GlKind::Renderbuffer) glCreateRenderbuffers(1, &id_);
  checkGl("GlObject::GlObject()");
}

template <GlKind K>
void GlObject<K>::reset() noexcept {
  if (id_ == 0) return;
  if constexpr (K == GlKind::Buffer) glDeleteBuffers(1, &id_);
  if constexpr (K == GlKind::VertexArray) glDeleteVertexArrays(1, &id_);
  if constexpr (K == GlKind::Texture2D) glDeleteTextures(1, &id_);
  if constexpr (K == GlKind::Framebuffer) glDeleteFramebuffers(1, &id_);
  if constexpr (K == GlKind::Renderbuffer) glDeleteRenderbuffers(1, &id_);
  id_ = 0;
}

template class GlObject<GlKind::Buffer>;
template class GlObject<GlKind::VertexArray>;
template class GlObject<GlKind::Texture2D>;
template class GlObject<GlKind::Framebuffer>;
template class GlObject<GlKind::Renderbuffer>;

}  // namespace regolith::gl
