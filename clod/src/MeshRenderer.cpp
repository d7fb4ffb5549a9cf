#include <regolith/clod/MeshRenderer.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>

#include "Shaders.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace regolith::clod {

MeshRenderer::MeshRenderer(const topo::TopoGrid& grid, const topo::SampleSource& source)
    : grid_(grid),
      program_("mesh", gl::ShaderSources{shaders::kMeshVertex, shaders::kDropNodataGeometry,
                                         shaders::kLitFragment}) {
  if (source.rows() != grid.rows() || source.cols() != grid.cols())
    throw InvalidArgument("MeshRenderer(): source is " + std::to_string(source.rows()) + " x " +
                          std::to_string(source.cols()) + ", grid is " +
                          std::to_string(grid.rows()) + " x " + std::to_string(grid.cols()));
  if (grid.rows() > 16384 || grid.cols() > 16384)
    throw InvalidArgument("MeshRenderer(): grid is " + std::to_string(grid.rows()) + " x " +
                          std::to_string(grid.cols()) + ", at most 16384 a side");
  const auto rows = grid.rows(), cols = grid.cols();
  std::vector<float> h(rows * cols);
  source.readWindow(0, 0, rows, cols, h);
  for (auto& v : h)
    if (grid.isNodata(v)) v = std::numeric_limits<float>::quiet_NaN();
  glTextureStorage2D(heights_.id(), 1, GL_R32F, static_cast<GLsizei>(cols),
                     static_cast<GLsizei>(rows));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(heights_.id(), 0, 0, 0, static_cast<GLsizei>(cols),
                      static_cast<GLsizei>(rows), GL_RED, GL_FLOAT, h.data());
  glTextureParameteri(heights_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(heights_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl::checkGl("MeshRenderer()");
}

std::size_t MeshRenderer::draw(const Camera& camera) const {
  program_.use();
  program_.set("uViewProj", camera.viewProjection());
  program_.set("uOriginRel", glm::vec3(glm::dvec3(grid_.x0(), grid_.y0(), 0.0) - camera.position));
  program_.set("uSpacing", glm::vec2(static_cast<float>(grid_.spacingX()),
                                     static_cast<float>(grid_.spacingY())));
  program_.set("uLight", glm::normalize(lightDirection));
  program_.set("uAlbedo", albedo);
  program_.set("uAmbient", ambient);
  glBindTextureUnit(0, heights_.id());
  glBindVertexArray(vao_.id());
  glDisable(GL_CULL_FACE);
  const auto perStrip = static_cast<GLsizei>(2 * grid_.cols());
  const auto strips = static_cast<GLsizei>(grid_.rows() - 1);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, perStrip, strips);
  glBindVertexArray(0);
  gl::checkGl("MeshRenderer::draw()");
  return static_cast<std::size_t>(perStrip) * static_cast<std::size_t>(strips);
}

}  // namespace regolith::clod
