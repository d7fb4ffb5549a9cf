#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/farfield/RayCastGlobe.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>

#include "GlobeShaders.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace regolith::farfield {
namespace {

void checkBody(const GlobeBody& body) {
  constexpr std::string_view op = "farfield::RayCastGlobe::draw()";
  auto bad = [&](std::string_view field, double v, std::string_view expected) {
    const std::string value = core::number(v) + " m";
    throw InvalidArgument(
        core::format({.operation = op, .field = field, .value = value, .expected = expected}));
  };
  if (!(std::isfinite(body.a) && body.a > 0.0))
    bad("body equatorial radius a", body.a, "> 0, finite");
  if (!(std::isfinite(body.b) && body.b > 0.0)) bad("body polar radius b", body.b, "> 0, finite");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(body.centre[i])) bad("body centre coordinate", body.centre[i], "finite");
}

void checkPoints(int n) {
  if (n < 3 || n > 4096)
    throw InvalidArgument(core::format({.operation = "farfield::RayCastGlobe()",
                                        .field = "polygonPoints",
                                        .value = core::number(n),
                                        .expected = "3 to 4096"}));
}

/// The box's 12 triangles, counter-clockwise seen from outside, corners ±half.
std::vector<glm::dvec3> boxTriangles(const glm::dvec3& half) {
  std::vector<glm::dvec3> out;
  out.reserve(36);
  for (int axis = 0; axis < 3; ++axis) {
    for (const double s : {1.0, -1.0}) {
      glm::dvec3 n(0.0), u(0.0), v(0.0);
      n[axis] = s;
      u[(axis + 1) % 3] = 1.0;  // u × v = +axis; swapped for the −axis face
      v[(axis + 2) % 3] = 1.0;
      if (s < 0.0) std::swap(u, v);
      const std::array<glm::dvec3, 4> q{n - u - v, n + u - v, n + u + v, n - u + v};
      for (const int i : {0, 1, 2, 0, 2, 3}) out.push_back(q[static_cast<std::size_t>(i)] * half);
    }
  }
  return out;
}

}  // namespace

GlobeProxyGeometry globeProxy(const clod::Camera& camera, const GlobeBody& body, GlobeProxy proxy,
                              int polygonPoints) {
  checkBody(body);
  const glm::dmat3& r = body.orientation;
  const glm::dvec3 rel = body.centre - camera.position;  // centre from the eye, scene axes
  const glm::dvec3 inv{1.0 / body.a, 1.0 / body.a, 1.0 / body.b};
  GlobeProxyGeometry g;
  g.eyeScaled = -(glm::transpose(r) * rel) * inv;
  const double e = glm::length(g.eyeScaled);
  g.c = (e - 1.0) * (e + 1.0);
  if (!(g.c > 0.0)) return g;  // inside or on the ellipsoid
  const double distance = glm::length(rel);
  if (proxy == GlobeProxy::Box) {
    const double margin = 1e-6 * (distance + body.a);
    g.vertices = boxTriangles({body.a + margin, body.a + margin, body.b + margin});
    for (glm::dvec3& v : g.vertices) v = r * v + rel;
    return g;
  }
  checkPoints(polygonPoints);
  // In the scaled space (eye at e, unit sphere at 0): the silhouette circle's centre seen
  // from the eye is −e·(1 − 1/|e|²) = −e·c/|e|², its radius √c/|e|.
  const glm::dvec3 eh = g.eyeScaled / e;
  const glm::dvec3 centreFromEye = -g.eyeScaled * (g.c / (e * e));
  const double radius = std::sqrt(g.c) / e;
  // Viewport-aligned: the first vertex towards the camera's up, projected onto the circle's
  // plane (or its right, when the up is along the line of sight).
  const glm::dmat3 cam = camera.rotation();
  const glm::dvec3 camUp{cam[0][1], cam[1][1], cam[2][1]};
  const glm::dvec3 camRight{cam[0][0], cam[1][0], cam[2][0]};
  auto toScaled = [&](const glm::dvec3& w) { return (glm::transpose(r) * w) * inv; };
  glm::dvec3 u = toScaled(camUp);
  u -= glm::dot(u, eh) * eh;
  if (glm::length(u) < 1e-9 * glm::length(toScaled(camUp))) {
    u = toScaled(camRight);
    u -= glm::dot(u, eh) * eh;
  }
  u = glm::normalize(u);
  const glm::dvec3 v = glm::cross(eh, u);
  // Edges tangent to the circle: vertices at radius / cos(π/N), plus a margin of 1e-6 of the
  // eye's distance (scaled) so that float rounding cannot cut the tangent points.
  const double n = polygonPoints;
  const double reach = radius / std::cos(std::numbers::pi / n) + 1e-6 * (e + 1.0);
  const glm::dvec3 scale{body.a, body.a, body.b};
  g.vertices.reserve(static_cast<std::size_t>(polygonPoints));
  for (int i = 0; i < polygonPoints; ++i) {
    const double theta = 2.0 * std::numbers::pi * i / n;
    const glm::dvec3 p = centreFromEye + reach * (std::cos(theta) * u + std::sin(theta) * v);
    g.vertices.push_back(r * (p * scale));
  }
  return g;
}

gl::Texture makeEquirectangularTexture(const gl::RgbaImage& image, bool mipmaps) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() !=
          4 * static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height))
    throw InvalidArgument(
        core::format({.operation = "farfield::makeEquirectangularTexture()",
                      .field = "image size",
                      .value = core::number(image.width) + " x " + core::number(image.height),
                      .expected = "at least 1 x 1 with 4 bytes a pixel"}));
  gl::Texture t;
  int levels = 1;
  if (mipmaps)
    while ((std::max(image.width, image.height) >> levels) > 0) ++levels;
  glTextureStorage2D(t.id(), levels, GL_RGBA8, image.width, image.height);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t.id(), 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE,
                      image.rgba.data());
  if (mipmaps) glGenerateTextureMipmap(t.id());
  glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, mipmaps ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR);
  glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(t.id(), GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTextureParameteri(t.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl::checkGl("farfield::makeEquirectangularTexture()");
  return t;
}

RayCastGlobe::RayCastGlobe(const GlobeOptions& options)
    : options_(options),
      program_("ray-cast globe", {globe_shaders::kVertex, "",
                                  std::string(globe_shaders::kVersion) + globe_shaders::kFragment}),
      countingProgram_("ray-cast globe (counting rays)",
                       {globe_shaders::kVertex, "",
                        std::string(globe_shaders::kVersion) + "#define COUNT_RAYS\n" +
                            globe_shaders::kFragment}) {
  checkPoints(options.polygonPoints);
  glVertexArrayAttribFormat(vao_.id(), 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao_.id(), 0, 0);
  glEnableVertexArrayAttrib(vao_.id(), 0);
  glNamedBufferStorage(counters_.id(), 2 * sizeof(GLuint), nullptr,
                       GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT);
  gl::checkGl("farfield::RayCastGlobe()");
}

void RayCastGlobe::setProxy(GlobeProxy proxy, int polygonPoints) {
  checkPoints(polygonPoints);
  options_.proxy = proxy;
  options_.polygonPoints = polygonPoints;
}

GlobeFrame RayCastGlobe::draw(const clod::Camera& camera, const GlobeBody& body,
                              const glm::dvec3& sunDirection, GLuint keepDepth) {
  constexpr std::string_view op = "farfield::RayCastGlobe::draw()";
  if (!(std::isfinite(sunDirection.x) && std::isfinite(sunDirection.y) &&
        std::isfinite(sunDirection.z) && glm::length(sunDirection) > 0.0))
    throw InvalidArgument(core::format(
        {.operation = op, .field = "sun direction", .expected = "finite and non-zero"}));
  const GlobeProxyGeometry geometry =
      globeProxy(camera, body, options_.proxy, options_.polygonPoints);
  GlobeFrame frame;
  if (geometry.vertices.empty()) return frame;
  frame.drawn = true;
  frame.proxyVertices = static_cast<int>(geometry.vertices.size());

  std::vector<glm::vec3> v;
  v.reserve(geometry.vertices.size());
  for (const glm::dvec3& p : geometry.vertices) v.emplace_back(p);
  const auto bytes = static_cast<GLsizeiptr>(v.size() * sizeof(glm::vec3));
  if (bytes > capacity_) {
    vertices_ = gl::Buffer();
    glNamedBufferStorage(vertices_.id(), bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
    capacity_ = bytes;
    glVertexArrayVertexBuffer(vao_.id(), 0, vertices_.id(), 0, sizeof(glm::vec3));
  }
  glNamedBufferSubData(vertices_.id(), 0, bytes, v.data());

  const glm::dmat3 rt = glm::transpose(body.orientation);
  const glm::dvec3 flatten{1.0, 1.0, body.a / body.b};
  glm::dmat3 eyeToScaled = rt * glm::transpose(camera.rotation());
  for (int c = 0; c < 3; ++c) eyeToScaled[c] *= flatten;  // diag(1, 1, a/b) · …
  const gl::Program& p = options_.countRays ? countingProgram_ : program_;
  p.use();
  p.set("uViewProj", camera.viewProjection());
  // The reference ray: through the centre's pixel if the centre is ahead and projects within
  // 8 viewports of the middle (gl_FragCoord − uRefPx then keeps 1e-3 px), else the middle.
  const glm::dvec3 rel = body.centre - camera.position;
  const double viewDistance = -(camera.rotation() * rel).z;
  const glm::dvec3 centrePx = camera.project(body.centre);
  const glm::dvec2 half{0.5 * camera.width, 0.5 * camera.height};
  const glm::dvec2 offset = glm::dvec2(centrePx.x, camera.height - centrePx.y) - half;
  const double reach = 8.0 * std::max(camera.width, camera.height);
  if (viewDistance > 0.0 && std::abs(offset.x) < reach && std::abs(offset.y) < reach) {
    const double k = body.a / viewDistance;
    p.set("uRefPx", glm::vec2(half + offset));
    p.set("uRefDir", glm::vec3(-k * geometry.eyeScaled));
    p.set("uK", static_cast<float>(k));
  } else {
    p.set("uRefPx", glm::vec2(half));
    p.set("uRefDir", glm::vec3(eyeToScaled * glm::dvec3(0.0, 0.0, -1.0)));
    p.set("uK", 0.0F);
  }
  p.set("uFocal", static_cast<float>(camera.focalPixels()));
  p.set("uEyeToScaled", glm::mat3(eyeToScaled));
  p.set("uCentre", glm::vec3(-geometry.eyeScaled));
  p.set("uC", static_cast<float>(geometry.c));
  p.set("uSqrtC", geometry.c < 0.5 ? static_cast<float>(std::sqrt(geometry.c)) : 0.0F);
  p.set("uNearOverA", static_cast<float>(camera.near / body.a));
  p.set("uAOverB", static_cast<float>(body.a / body.b));
  p.set("uSun", glm::vec3(glm::normalize(rt * sunDirection)));
  p.set("uColour", body.colour);
  p.set("uAmbient", options_.ambient);
  p.set("uTextured", body.albedoTexture != 0 ? 1 : 0);
  glBindTextureUnit(0, body.albedoTexture);
  p.set("uKeepDrawn", keepDepth != 0 ? 1 : 0);
  glBindTextureUnit(1, keepDepth);
  if (options_.countRays) {
    const std::array<GLuint, 2> zero{0, 0};
    glNamedBufferSubData(counters_.id(), 0, sizeof(zero), zero.data());
    glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, 0, counters_.id());
  }

  const GLboolean culling = glIsEnabled(GL_CULL_FACE);
  GLint cullMode = GL_BACK;
  glGetIntegerv(GL_CULL_FACE_MODE, &cullMode);
  glBindVertexArray(vao_.id());
  if (options_.proxy == GlobeProxy::Box) {
    glEnable(GL_CULL_FACE);  // the back faces: they stay behind the ellipsoid
    glCullFace(GL_FRONT);
    glDrawArrays(GL_TRIANGLES, 0, frame.proxyVertices);
  } else {
    glDisable(GL_CULL_FACE);
    glDrawArrays(GL_TRIANGLE_FAN, 0, frame.proxyVertices);
  }
  glBindVertexArray(0);
  glCullFace(static_cast<GLenum>(cullMode));
  if (culling == GL_TRUE)
    glEnable(GL_CULL_FACE);
  else
    glDisable(GL_CULL_FACE);
  glBindTextureUnit(0, 0);
  glBindTextureUnit(1, 0);

  if (options_.countRays) {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_ATOMIC_COUNTER_BARRIER_BIT);
    std::array<GLuint, 2> counts{0, 0};
    glGetNamedBufferSubData(counters_.id(), 0, sizeof(counts), counts.data());
    glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, 0, 0);
    frame.raysCast = counts[0];
    frame.raysHit = counts[1];
  }
  gl::checkGl(op);
  return frame;
}

}  // namespace regolith::farfield
