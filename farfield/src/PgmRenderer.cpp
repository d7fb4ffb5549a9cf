#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/farfield/PgmRenderer.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/Program.hpp>

#include "Checks.hpp"
#include "PgmShaders.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>

namespace regolith::farfield {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr const char* kOp = "farfield::PgmRenderer()";
/// The entries of the spread's table: the size of the grid shader's uSpread array.
constexpr int kSpreadEntries = 256;

void requireRange(const char* field, double v, double lo, double hi) {
  detail::requireRange(kOp, field, v, lo, hi);
}

/// A mipmapped R32F texture of a layer (rows from the bottom), wrapping in s if asked.
gl::Texture uploadLayer(const std::vector<float>& texels, int width, int height, bool wrapS) {
  gl::Texture tex;
  const int levels = 1 + static_cast<int>(std::floor(std::log2(std::max(width, height))));
  glTextureStorage2D(tex.id(), levels, GL_R32F, width, height);
  glTextureSubImage2D(tex.id(), 0, 0, 0, width, height, GL_RED, GL_FLOAT, texels.data());
  glGenerateTextureMipmap(tex.id());
  glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(tex.id(), GL_TEXTURE_WRAP_S, wrapS ? GL_REPEAT : GL_CLAMP_TO_EDGE);
  glTextureParameteri(tex.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return tex;
}

gl::Texture gridTexture(int width, int height) {
  gl::Texture tex;
  glTextureStorage2D(tex.id(), 1, GL_RGBA32F, width, height);
  glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return tex;
}

float decodeOrdered(std::uint32_t u) {
  const std::uint32_t bits = (u & 0x80000000U) != 0U ? (u & 0x7FFFFFFFU) : ~u;
  float f = 0.0F;
  static_assert(sizeof f == sizeof bits);
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

glm::vec3 f3(const glm::dvec3& v) { return glm::vec3(v); }

/// One triangle strip per pair of rows of a w × h grid, joined by the fixed restart index,
/// into `buffer`; returns the index count.
GLsizei uploadStrips(const gl::Buffer& buffer, int w, int h) {
  std::vector<std::uint32_t> idx;
  idx.reserve(static_cast<std::size_t>(h - 1) * (2 * static_cast<std::size_t>(w) + 1));
  for (int j = 0; j + 1 < h; ++j) {
    for (int i = 0; i < w; ++i) {
      idx.push_back(static_cast<std::uint32_t>((j + 1) * w + i));
      idx.push_back(static_cast<std::uint32_t>(j * w + i));
    }
    idx.push_back(0xFFFFFFFFU);
  }
  glNamedBufferStorage(buffer.id(), static_cast<GLsizeiptr>(idx.size() * sizeof(std::uint32_t)),
                       idx.data(), 0);
  return static_cast<GLsizei>(idx.size());
}

}  // namespace

PgmRenderer::PgmRenderer(const HeightLayers& layers, PgmOptions options)
    : options_(options),
      layerOptions_(layers.options()),
      capRadius_(layers.capRadius()),
      a_(layers.body().equatorialRadius()),
      b_(layers.body().polarRadius()),
      minHeight_(layers.minHeight()),
      maxHeight_(layers.maxHeight()),
      grid_("farfield PGM grid pass", {gl::kFullScreenTriangle, {}, shaders::kGridFragment}),
      mesh_("farfield PGM mesh pass", {shaders::kMeshVertex, {}, shaders::kMeshFragment}),
      reduce_(gl::Program::compute("farfield PGM radius reduction", shaders::kReduceCompute)) {
  requireRange("gridWidth", options.gridWidth, 8, 4096);
  requireRange("gridHeight", options.gridHeight, 8, 4096);
  requireRange("zeta", options.zeta, 0.05, 1.0);
  requireRange("primaryMargin", options.primaryMargin, 0.0, 1.0);
  requireRange("minCellPixels", options.minCellPixels, 0.0, 1.0e6);
  requireRange("impostorReliefPixels", options.impostorReliefPixels, 0.0, 1.0e6);
  minRadius_ = b_ + minHeight_;
  maxRadius_ = a_ + maxHeight_;
  primary_ = minRadius_;

  equirect_ = uploadLayer(layers.equirect(), layers.equirectWidth(), layers.equirectHeight(), true);
  north_ = uploadLayer(layers.north(), layers.capSize(), layers.capSize(), false);
  south_ = uploadLayer(layers.south(), layers.capSize(), layers.capSize(), false);

  const int w = options.gridWidth, h = options.gridHeight;
  gridPos_ = gridTexture(w, h);
  gridNrm_ = gridTexture(w, h);
  glNamedFramebufferTexture(gridFbo_.id(), GL_COLOR_ATTACHMENT0, gridPos_.id(), 0);
  glNamedFramebufferTexture(gridFbo_.id(), GL_COLOR_ATTACHMENT1, gridNrm_.id(), 0);
  const GLenum buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glNamedFramebufferDrawBuffers(gridFbo_.id(), 2, buffers);
  if (glCheckNamedFramebufferStatus(gridFbo_.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    throw gl::GlError(std::string(kOp) + ": the grid framebuffer is incomplete");
  }

  indexCount_ = uploadStrips(indices_, w, h);
  for (gl::Buffer& b : minBuffers_) {
    const std::uint32_t init = 0xFFFFFFFFU;
    glNamedBufferStorage(b.id(), sizeof init, &init, GL_DYNAMIC_STORAGE_BIT);
  }
  glCreateQueries(GL_TIME_ELAPSED, 3, timers_.data());
  gl::checkGl(kOp);
}

PgmRenderer::~PgmRenderer() {
  glDeleteQueries(3, timers_.data());
  for (void* f : fences_) {
    if (f != nullptr) glDeleteSync(static_cast<GLsync>(f));
  }
}

void PgmRenderer::restart() noexcept {
  primary_ = minRadius_;
  for (void*& f : fences_) {
    if (f != nullptr) glDeleteSync(static_cast<GLsync>(f));
    f = nullptr;
  }
  frameIndex_ = 0;
}

void PgmRenderer::setFrameUniforms(const clod::Camera& camera, const ReferenceSpheres& s,
                                   const SamplingCamera& sc, const glm::dvec3& sun) const {
  const gl::Program& g = grid_;
  const glm::dvec3 nadir = -glm::normalize(camera.position);
  glm::dvec3 anyPerp =
      glm::cross(nadir, std::abs(nadir.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0));
  anyPerp = glm::normalize(anyPerp);
  g.set("uFwd", f3(sc.forward));
  g.set("uRight", f3(sc.rightAxis));
  g.set("uUp", f3(sc.up));
  g.set("uNadir", f3(nadir));
  g.set("uAnyPerp", f3(anyPerp));
  g.set("uBounds", glm::vec4(static_cast<float>(sc.left), static_cast<float>(sc.right),
                             static_cast<float>(sc.bottom), static_cast<float>(sc.top)));
  g.set("uD", static_cast<float>(s.d));
  g.set("uRp", static_cast<float>(s.primary));
  g.set("uAlt", static_cast<float>(s.d - s.primary));
  g.set("uD2R2", static_cast<float>((s.d - s.primary) * (s.d + s.primary)));
  g.set("uBegin", static_cast<float>(s.begin));
  g.set("uTau0", static_cast<float>(s.tau0));
  g.set("uTauTop", static_cast<float>(s.tauTop));
  g.set("uTauS", static_cast<float>(s.tauS));
  g.set("uOmegaSb", static_cast<float>(s.omegaSBegin));
  g.set("uRs", static_cast<float>(s.secondary));
  g.set("uA", static_cast<float>(a_));
  g.set("uB", static_cast<float>(b_));
  g.set("uAminusRp", static_cast<float>(a_ - s.primary));
  g.set("uAB2", static_cast<float>((a_ / b_) * (a_ / b_)));
  g.set("uEquirect", 0);
  g.set("uNorth", 1);
  g.set("uSouth", 2);
  g.set("uEquirectRows", 0.5F * static_cast<float>(layerOptions_.equirectWidth));
  g.set("uCapSize", static_cast<float>(layerOptions_.capSize));
  g.set("uCapRadius", static_cast<float>(capRadius_));
  g.set("uCapLat", static_cast<float>(layerOptions_.capLatitude * kDeg));
  g.set("uCapBlend", static_cast<float>(layerOptions_.blendDegrees * kDeg));
  g.set("uLodBias", options_.lodBias);

  const gl::Program& m = mesh_;
  m.set("uPos", 0);
  m.set("uNrm", 1);
  m.set("uViewProj", camera.viewProjection());
  m.set("uSun", f3(glm::normalize(sun)));
  m.set("uLow", options_.low);
  m.set("uHigh", options_.high);
  m.set("uHeightRange", glm::vec2(static_cast<float>(minHeight_), static_cast<float>(maxHeight_)));
  m.set("uHeightColours", options_.heightColours ? 1 : 0);
  m.set("uAmbient", options_.ambient);
}

PgmFrame PgmRenderer::draw(const gl::RenderTarget& target, const clod::Camera& camera,
                           const glm::dvec3& sun, bool keepDrawn) {
  if (camera.width != target.width() || camera.height != target.height()) {
    throw InvalidArgument(
        core::format({.operation = "farfield::PgmRenderer::draw()",
                      .field = "camera size",
                      .value = core::number(camera.width) + " x " + core::number(camera.height),
                      .expected = "the target's " + core::number(target.width()) + " x " +
                                  core::number(target.height())}));
  }
  PgmFrame frame;
  frame.minVisibleRadius = std::numeric_limits<double>::quiet_NaN();
  const double d = glm::length(camera.position);
  frame.spheres = referenceSpheres(d, primary_, maxRadius_, options_.zeta);
  if (!frame.spheres.secondaryExists()) return frame;

  const glm::dmat3 rot = camera.rotation();  // rows: right, up, -forward
  const glm::dvec3 right(rot[0][0], rot[1][0], rot[2][0]);
  const glm::dvec3 up(rot[0][1], rot[1][1], rot[2][1]);
  const glm::dvec3 fwd = camera.forward();
  const double aspect = static_cast<double>(camera.width) / camera.height;
  const Frustum view = viewFrustum(fwd, right, up, camera.fovYDegrees * kDeg, aspect);
  const glm::dvec3 nadir = -camera.position / d;
  frame.sampling = samplingCamera(view, nadir, frame.spheres.tauTop);
  setFrameUniforms(camera, frame.spheres, frame.sampling, sun);
  setSpread(frame, nadir);

  // The grid drawn: the full grid, or every stride-th point (minCellPixels).
  const int stride = gridStride(camera, frame);
  const int gw = (options_.gridWidth - 1) / stride + 1, gh = (options_.gridHeight - 1) / stride + 1;
  frame.gridWidth = gw;
  frame.gridHeight = gh;
  GLuint indexBuffer = indices_.id();
  GLsizei indexCount = indexCount_;
  if (stride > 1) {
    if (thinWidth_ != gw || thinHeight_ != gh) {
      thinIndices_ = gl::Buffer();
      thinIndexCount_ = uploadStrips(thinIndices_, gw, gh);
      thinWidth_ = gw;
      thinHeight_ = gh;
    }
    indexBuffer = thinIndices_.id();
    indexCount = thinIndexCount_;
  }
  glVertexArrayElementBuffer(vao_.id(), indexBuffer);
  grid_.set("uGrid", glm::vec2(static_cast<float>(gw), static_cast<float>(gh)));
  mesh_.set("uGridWidth", gw);

  // 1. The grid pass.
  glBindFramebuffer(GL_FRAMEBUFFER, gridFbo_.id());
  glViewport(0, 0, gw, gh);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  // Both passes draw into two colour buffers, which Mesa refuses while any blend factor is
  // dual-source (GL_SRC1_COLOR), blending on or off: whatever the context's last renderer
  // left, the default factors.
  glBlendFunc(GL_ONE, GL_ZERO);
  glBindTextureUnit(0, equirect_.id());
  glBindTextureUnit(1, north_.id());
  glBindTextureUnit(2, south_.id());
  grid_.use();
  glBindVertexArray(vao_.id());
  if (options_.timePasses) glBeginQuery(GL_TIME_ELAPSED, timers_[0]);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  if (options_.timePasses) glEndQuery(GL_TIME_ELAPSED);

  // 2. The mesh pass, with the radius buffer as a second colour attachment of the target.
  if (radiusWidth_ != target.width() || radiusHeight_ != target.height()) {
    radius_ = gl::Texture();
    glTextureStorage2D(radius_.id(), 1, GL_R32F, target.width(), target.height());
    glTextureParameteri(radius_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(radius_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    drawnDepth_ = gl::Texture();
    glTextureStorage2D(drawnDepth_.id(), 1, GL_DEPTH_COMPONENT32F, target.width(), target.height());
    radiusWidth_ = target.width();
    radiusHeight_ = target.height();
  }
  if (keepDrawn) {
    glCopyImageSubData(target.depthTexture(), GL_TEXTURE_2D, 0, 0, 0, 0, drawnDepth_.id(),
                       GL_TEXTURE_2D, 0, 0, 0, 0, target.width(), target.height(), 1);
  }
  mesh_.set("uKeepDrawn", keepDrawn ? 1 : 0);
  mesh_.set("uDrawnDepth", 2);
  glBindTextureUnit(2, drawnDepth_.id());
  const GLuint fbo = target.framebuffer();
  glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT1, radius_.id(), 0);
  const GLenum both[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glNamedFramebufferDrawBuffers(fbo, 2, both);
  const float none = 3.0e38F;
  glClearNamedFramebufferfv(fbo, GL_COLOR, 1, &none);
  target.bind();
  // The grid's triangles are counter-clockwise on screen wherever the surface faces the eye;
  // where the grid folds back over itself (the ground behind the limb that the occluded-area
  // sampling reaches, drawn and then hidden) they turn clockwise, and culling them saves
  // their rasterisation (PgmOptions::cullFolds, docs/far-field.md).
  if (options_.cullFolds) {
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CCW);
    glCullFace(GL_BACK);
  } else {
    glDisable(GL_CULL_FACE);
  }
  glEnable(GL_PRIMITIVE_RESTART_FIXED_INDEX);
  glBindTextureUnit(0, gridPos_.id());
  glBindTextureUnit(1, gridNrm_.id());
  mesh_.use();
  glBindVertexArray(vao_.id());
  if (options_.timePasses) glBeginQuery(GL_TIME_ELAPSED, timers_[1]);
  glDrawElements(GL_TRIANGLE_STRIP, indexCount, GL_UNSIGNED_INT, nullptr);
  if (options_.timePasses) glEndQuery(GL_TIME_ELAPSED);
  glDisable(GL_PRIMITIVE_RESTART_FIXED_INDEX);
  glDisable(GL_CULL_FACE);
  glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT1, 0, 0);
  glNamedFramebufferDrawBuffer(fbo, GL_COLOR_ATTACHMENT0);
  frame.drawn = true;

  // 3. The minimum visible radius, for the next frame's primary sphere.
  primaryOf_[static_cast<std::size_t>(frameIndex_)] = frame.spheres.primary;
  if (options_.timePasses) glBeginQuery(GL_TIME_ELAPSED, timers_[2]);
  reduce(target, frame);
  if (options_.timePasses) {
    glEndQuery(GL_TIME_ELAPSED);
    double* out[] = {&frame.gridMs, &frame.meshMs, &frame.reduceMs};
    for (std::size_t i = 0; i < 3; ++i) {
      GLuint64 ns = 0;
      glGetQueryObjectui64v(timers_[i], GL_QUERY_RESULT, &ns);  // waits for the GPU
      *out[i] = static_cast<double>(ns) * 1e-6;
    }
  }
  gl::checkGl("farfield::PgmRenderer::draw()");
  return frame;
}

void PgmRenderer::setSpread(PgmFrame& frame, const glm::dvec3& nadir) {
  // The spread keeps the grid's coverage only where the grid holds the nadir (RaySpread).
  if (!options_.evenError || !frame.sampling.holds(nadir)) {
    grid_.set("uSpreadOn", 0);
    return;
  }
  const ReferenceSpheres& s = frame.spheres;
  const ReferenceSpheres& was = spreadSpheres_;
  if (!spread_.active() || s.d != was.d || s.primary != was.primary || s.maximum != was.maximum ||
      s.zeta != was.zeta) {
    spread_ = evenErrorSpread(s, kSpreadEntries);
    spreadSpheres_ = s;
    if (spread_.active()) {
      std::array<float, kSpreadEntries> table{};
      std::transform(spread_.table.begin(), spread_.table.end(), table.begin(),
                     [](double w) { return static_cast<float>(w); });
      glProgramUniform1fv(grid_.id(), grid_.uniform("uSpread"), kSpreadEntries, table.data());
    }
  }
  grid_.set("uSpreadOn", spread_.active() ? 1 : 0);
  if (spread_.active()) frame.spread = spread_;
}

int PgmRenderer::gridStride(const clod::Camera& camera, PgmFrame& frame) const {
  if (options_.minCellPixels <= 0.0) return 1;
  // A grid point lies on its eye ray before the height displaces it, so the angle between
  // neighbouring rays, times the focal length, is the cell's size on the screen, as long as
  // the displacement is small against the distance: only while the whole relief subtends
  // under 0.05 rad from the eye (never from below a mountain top, where heights move points
  // across the screen). The largest over a 9 × 9 sample of the grid's cells whose ray is in
  // view.
  const double d = glm::length(camera.position);
  if (d - maxRadius_ <= 20.0 * (maxRadius_ - minRadius_)) return 1;
  const SamplingCamera& sc = frame.sampling;
  const glm::dvec3 nadir = -camera.position / d;
  const auto ray = [&](double u, double v) { return frame.spread.ray(sc.ray(u, v), nadir); };
  const double du = 1.0 / (options_.gridWidth - 1), dv = 1.0 / (options_.gridHeight - 1);
  const double f = camera.focalPixels();
  double largest = 0.0;
  for (int b = 0; b <= 8; ++b) {
    for (int a = 0; a <= 8; ++a) {
      const double u = std::min(a / 8.0, 1.0 - du), v = std::min(b / 8.0, 1.0 - dv);
      const glm::dvec3 r = ray(u, v);
      const glm::dvec3 q = camera.project(camera.position + r);
      if (q.z <= 0.0 || q.x < 0.0 || q.y < 0.0 || q.x > camera.width || q.y > camera.height) {
        continue;
      }
      largest = std::max(
          {largest, glm::length(ray(u + du, v) - r) * f, glm::length(ray(u, v + dv) - r) * f});
    }
  }
  frame.cellPixels = largest;
  if (largest <= 0.0) return 1;  // no sampled cell in view: keep the grid
  int stride = 1;
  while (largest * stride < options_.minCellPixels &&
         (options_.gridWidth - 1) / (2 * stride) + 1 >= 8 &&
         (options_.gridHeight - 1) / (2 * stride) + 1 >= 8) {
    stride *= 2;
  }
  return stride;
}

void PgmRenderer::reduce(const gl::RenderTarget& target, PgmFrame& frame) {
  if (options_.readback == PrimaryReadback::Fixed) return;
  const auto slot = static_cast<std::size_t>(frameIndex_);
  const std::uint32_t init = 0xFFFFFFFFU;
  glNamedBufferSubData(minBuffers_[slot].id(), 0, sizeof init, &init);
  glBindTextureUnit(3, radius_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, minBuffers_[slot].id());
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
  reduce_.use();
  glDispatchCompute(static_cast<GLuint>((target.width() + 63) / 64),
                    static_cast<GLuint>((target.height() + 63) / 64), 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);

  const auto take = [&](std::size_t s) {
    std::uint32_t bits = 0;
    glGetNamedBufferSubData(minBuffers_[s].id(), 0, sizeof bits, &bits);
    const float offset = decodeOrdered(bits);
    if (offset < 1.0e38F) {
      const double radius = primaryOf_[s] + static_cast<double>(offset);
      frame.minVisibleRadius = radius;
      const double margin = options_.primaryMargin * (maxRadius_ - minRadius_);
      primary_ = std::clamp(radius - margin, minRadius_, maxRadius_);
    }
  };
  if (options_.readback == PrimaryReadback::Stall) {
    take(slot);
    return;
  }
  // Lagged: read the other buffer if its fence has passed, and fence this one.
  const std::size_t other = 1 - slot;
  if (fences_[other] != nullptr) {
    const auto fence = static_cast<GLsync>(fences_[other]);
    if (glClientWaitSync(fence, 0, 0) != GL_TIMEOUT_EXPIRED) take(other);
    glDeleteSync(fence);
    fences_[other] = nullptr;
  }
  if (fences_[slot] != nullptr) glDeleteSync(static_cast<GLsync>(fences_[slot]));
  fences_[slot] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  frameIndex_ = static_cast<int>(other);
}

namespace {

std::vector<glm::vec4> readGrid(GLuint texture, int width, int height) {
  std::vector<glm::vec4> out(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT,
                    static_cast<GLsizei>(out.size() * sizeof(glm::vec4)), out.data());
  return out;
}

}  // namespace

std::vector<glm::vec4> PgmRenderer::readGridPositions() const {
  return readGrid(gridPos_.id(), options_.gridWidth, options_.gridHeight);
}

std::vector<glm::vec4> PgmRenderer::readGridNormals() const {
  return readGrid(gridNrm_.id(), options_.gridWidth, options_.gridHeight);
}

}  // namespace regolith::farfield
