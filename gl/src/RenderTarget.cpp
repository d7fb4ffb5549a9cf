#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace regolith::gl {

void useReversedZ() noexcept {
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  glClearDepth(0.0);
}

RenderTarget::RenderTarget(int width, int height) : width_(width), height_(height) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InvalidArgument("RenderTarget(): size " + std::to_string(width) + " x " +
                          std::to_string(height) + ", expected 1..16384 on each side");
  glTextureStorage2D(color_.id(), 1, GL_RGBA8, width, height);
  glTextureStorage2D(depth_.id(), 1, GL_DEPTH_COMPONENT32F, width, height);
  glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT0, color_.id(), 0);
  glNamedFramebufferTexture(fbo_.id(), GL_DEPTH_ATTACHMENT, depth_.id(), 0);
  const GLenum status = glCheckNamedFramebufferStatus(fbo_.id(), GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw GlError("RenderTarget(): framebuffer incomplete (status " + std::to_string(status) + ")");
  checkGl("RenderTarget()");
}

void RenderTarget::bind() const noexcept {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glViewport(0, 0, width_, height_);
  useReversedZ();
}

void RenderTarget::clear(const glm::vec4& rgba) const noexcept {
  bind();
  glClearColor(rgba.r, rgba.g, rgba.b, rgba.a);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

RgbaImage RenderTarget::readColor() const {
  const auto w = static_cast<std::size_t>(width_);
  const auto h = static_cast<std::size_t>(height_);
  std::vector<std::uint8_t> raw(w * h * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(color_.id(), 0, GL_RGBA, GL_UNSIGNED_BYTE, static_cast<GLsizei>(raw.size()),
                    raw.data());
  checkGl("RenderTarget::readColor()");
  RgbaImage out{width_, height_, std::vector<std::uint8_t>(raw.size())};
  for (std::size_t y = 0; y < h; ++y)  // GL's row 0 is the bottom
    std::copy_n(raw.data() + (h - 1 - y) * w * 4, w * 4, out.rgba.data() + y * w * 4);
  return out;
}

DepthImage RenderTarget::readDepth() const {
  const auto w = static_cast<std::size_t>(width_);
  const auto h = static_cast<std::size_t>(height_);
  std::vector<float> raw(w * h);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTextureImage(depth_.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT,
                    static_cast<GLsizei>(raw.size() * sizeof(float)), raw.data());
  checkGl("RenderTarget::readDepth()");
  DepthImage out{width_, height_, std::vector<float>(raw.size())};
  for (std::size_t y = 0; y < h; ++y)
    std::copy_n(raw.data() + (h - 1 - y) * w, w, out.depth.data() + y * w);
  return out;
}

}  // namespace regolith::gl
