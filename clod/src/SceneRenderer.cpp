#include <regolith/clod/SceneRenderer.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/RenderTarget.hpp>

#include "CutOutShader.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

namespace regolith::clod {

namespace {

// Meshes and DEM border skirts: positions relative to the item's anchor (float, small),
// uAnchorRel = anchor − camera in the item frame (double on the CPU, then float). A skirt
// vertex with aBottom = 1 sits at height uFloor (grid frame h; the anchor has h = 0),
// uSkirtIn metres inward (−normal) of its top; the floor's vertices (normal 0) too.
constexpr const char* kMeshVertex = R"(#version 450 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in float aBottom;
layout(location = 3) in vec3 aFlange;
uniform mat4 uViewProj;
uniform vec3 uAnchorRel;
uniform float uFloor;
uniform float uSkirtIn;
uniform vec2 uFlange;  // > 0: bottom vertices go outward uFlange.x and up uFlange.y instead
uniform vec3 uLitNormal;  // skirts: lit as the ground they stand for (zero: use aNormal)
out vec3 vNormal;
void main() {
  vec3 p = aBottom > 0.5 ? vec3(aPos.xy - aNormal.xy * uSkirtIn, uFloor) : aPos;
  if (uFlange.x > 0.0 && aBottom > 0.5)  // the floor (normal 0) collapses to a point
    p = dot(aNormal, aNormal) > 0.0 ? vec3(aPos.xy + aFlange.xy * uFlange.x, aPos.z + uFlange.y)
                                    : vec3(0.0);
  vNormal = dot(uLitNormal, uLitNormal) > 0.0 ? uLitNormal : aNormal;
  gl_Position = uViewProj * vec4(p + uAnchorRel, 1.0);
}
)";

constexpr const char* kMeshFragment = R"(#version 450 core
in vec3 vNormal;
uniform vec3 uLight;
uniform vec3 uAlbedo;
uniform float uAmbient;
out vec4 color;
void main() {
  float d = max(dot(normalize(vNormal), uLight), 0.0);
  color = vec4(uAlbedo * (uAmbient + (1.0 - uAmbient) * d), 1.0);
}
)";

struct SkirtVertex {
  glm::vec3 position;
  glm::vec3 normal;
  float bottom;
  glm::vec3 flange{0.0F};  // pit flanges: outward direction, mitred at corners (sum of normals)
};

void setupVao(const gl::VertexArray& vao, const gl::Buffer& buffer, GLsizei stride) {
  glVertexArrayVertexBuffer(vao.id(), 0, buffer.id(), 0, stride);
  glEnableVertexArrayAttrib(vao.id(), 0);
  glVertexArrayAttribFormat(vao.id(), 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao.id(), 0, 0);
  glEnableVertexArrayAttrib(vao.id(), 1);
  glVertexArrayAttribFormat(vao.id(), 1, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float));
  glVertexArrayAttribBinding(vao.id(), 1, 0);
  glEnableVertexArrayAttrib(vao.id(), 2);
  glVertexArrayAttribFormat(vao.id(), 2, 1, GL_FLOAT, GL_FALSE, 6 * sizeof(float));
  glVertexArrayAttribBinding(vao.id(), 2, 0);
  glEnableVertexArrayAttrib(vao.id(), 3);
  glVertexArrayAttribFormat(vao.id(), 3, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float));
  glVertexArrayAttribBinding(vao.id(), 3, 0);
}

glm::vec3 lightIn(const scenegraph::Pose& itemInFocus, const glm::dvec3& lightInFocus) {
  return glm::vec3(glm::normalize(glm::conjugate(itemInFocus.rotation) * lightInFocus));
}

// A terrain's focus: the camera's position, clamped onto a plane DEM's grid so the clipmap
// windows stay on the data whatever the camera does.
glm::dvec3 focusFor(const HeightPyramid& p, const glm::dvec3& camera) {
  if (p.kind() != SurfaceKind::Plane || p.placement()) return camera;
  const auto& g = p.level(0).grid;
  return {std::clamp(camera.x, g.west(), g.east()), std::clamp(camera.y, g.south(), g.north()),
          camera.z};
}

}  // namespace

void appendBox(std::vector<MeshVertex>& out, const glm::vec3& lo, const glm::vec3& hi) {
  const auto quad = [&](glm::vec3 n, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    for (const glm::vec3& p : {a, b, c, a, c, d}) out.push_back({p, n});
  };
  const glm::vec3 l = lo, h = hi;
  quad({1, 0, 0}, {h.x, l.y, l.z}, {h.x, h.y, l.z}, {h.x, h.y, h.z}, {h.x, l.y, h.z});
  quad({-1, 0, 0}, {l.x, h.y, l.z}, {l.x, l.y, l.z}, {l.x, l.y, h.z}, {l.x, h.y, h.z});
  quad({0, 1, 0}, {h.x, h.y, l.z}, {l.x, h.y, l.z}, {l.x, h.y, h.z}, {h.x, h.y, h.z});
  quad({0, -1, 0}, {l.x, l.y, l.z}, {h.x, l.y, l.z}, {h.x, l.y, h.z}, {l.x, l.y, h.z});
  quad({0, 0, 1}, {l.x, l.y, h.z}, {h.x, l.y, h.z}, {h.x, h.y, h.z}, {l.x, h.y, h.z});
  quad({0, 0, -1}, {l.x, h.y, l.z}, {h.x, h.y, l.z}, {h.x, l.y, l.z}, {l.x, l.y, l.z});
}

std::vector<MeshVertex> roverMesh(const RoverShape& shape) {
  std::vector<MeshVertex> v;
  const float front = shape.axleOffsets[0], rear = shape.axleOffsets[2];
  const float halfTrack = 0.5F * shape.trackWidth, halfWheel = 0.5F * shape.wheelWidth;
  const float r = shape.wheelRadius;
  // Body between the wheels, a little above them; mast and head near the front.
  const float bodyHalfWidth = std::max(0.2F, halfTrack - halfWheel - 0.05F);
  appendBox(v, {rear - 0.1F, -bodyHalfWidth, 2.0F * r + 0.1F},
            {front + 0.1F, bodyHalfWidth, 2.0F * r + 0.5F});
  const float mastX = rear + 0.75F * (front - rear);
  appendBox(v, {mastX - 0.08F, -0.08F, 2.0F * r + 0.5F}, {mastX + 0.08F, 0.08F, 2.0F});
  appendBox(v, {mastX - 0.15F, -0.25F, 2.0F}, {mastX + 0.15F, 0.25F, 2.2F});  // head
  for (const float x : shape.axleOffsets)
    for (const float y : {-halfTrack, halfTrack})
      appendBox(v, {x - r, y - halfWheel, 0.0F}, {x + r, y + halfWheel, 2.0F * r});  // wheels
  return v;
}

Camera cameraInItem(const scenegraph::Pose& pose, const SceneView& view) {
  Camera cam;
  cam.position = pose.translation;
  const glm::dvec3 forward = pose.applyVector({0.0, 0.0, -1.0});
  // The target only gives the direction; keep it near so it has full precision.
  cam.target = cam.position + forward;
  cam.up = pose.applyVector({0.0, 1.0, 0.0});
  cam.fovYDegrees = view.fovYDegrees;
  cam.width = view.width;
  cam.height = view.height;
  cam.near = view.near;
  return cam;
}

struct SceneRenderer::Skirt {
  gl::Buffer buffer;
  gl::VertexArray vao;
  GLsizei count = 0;
  glm::dvec3 anchor{0.0};  // grid frame
};

struct SceneRenderer::Terrain {
  std::shared_ptr<const HeightPyramid> pyramid;
  std::unique_ptr<ClipmapTerrain> clipmap;
  ClipmapOptions options;
  std::vector<int> cutBy;  // planets: the DEMs that win over them
  // DEMs that cut a planet: the finest level's cell mask and border skirt.
  std::unique_ptr<gl::Texture> mask;
  std::unique_ptr<Skirt> skirt;
  float edgeLow = 0.0F, edgeHigh = 0.0F;  // border heights (grid frame h)
  float lowest = 0.0F;                    // lowest sample
  std::size_t maskLevel = 0;              // the pyramid level the mask and skirts come from
};

struct SceneRenderer::Mesh {
  gl::Buffer buffer;
  gl::VertexArray vao;
  GLsizei count = 0;
  glm::vec3 albedo{0.7F};
};

SceneRenderer::SceneRenderer()
    : meshProgram_("scene mesh", gl::ShaderSources{kMeshVertex, "", kMeshFragment}) {}

SceneRenderer::~SceneRenderer() = default;

void SceneRenderer::addTerrain(int drawable, std::shared_ptr<const HeightPyramid> pyramid,
                               const ClipmapOptions& options) {
  if (!pyramid) throw InvalidArgument("SceneRenderer::addTerrain(): pyramid is null");
  if (terrains_.count(drawable) != 0 || meshes_.count(drawable) != 0)
    throw InvalidArgument("SceneRenderer::addTerrain(): drawable key " + std::to_string(drawable) +
                          " is taken");
  auto t = std::make_unique<Terrain>();
  t->pyramid = pyramid;
  t->options = options;
  t->clipmap = std::make_unique<ClipmapTerrain>(std::move(pyramid), options);
  terrains_.emplace(drawable, std::move(t));
}

void SceneRenderer::addMesh(int drawable, const std::vector<MeshVertex>& vertices,
                            const glm::vec3& albedo) {
  if (terrains_.count(drawable) != 0 || meshes_.count(drawable) != 0)
    throw InvalidArgument("SceneRenderer::addMesh(): drawable key " + std::to_string(drawable) +
                          " is taken");
  if (vertices.empty() || vertices.size() % 3 != 0)
    throw InvalidArgument("SceneRenderer::addMesh(): " + std::to_string(vertices.size()) +
                          " vertices, expected a non-empty multiple of 3 (triangles)");
  auto m = std::make_unique<Mesh>();
  std::vector<SkirtVertex> verts;
  verts.reserve(vertices.size());
  for (const auto& v : vertices) verts.push_back({v.position, v.normal, 0.0F, glm::vec3(0.0F)});
  glNamedBufferStorage(m->buffer.id(), static_cast<GLsizeiptr>(verts.size() * sizeof(SkirtVertex)),
                       verts.data(), 0);
  setupVao(m->vao, m->buffer, sizeof(SkirtVertex));
  m->count = static_cast<GLsizei>(vertices.size());
  m->albedo = albedo;
  gl::checkGl("SceneRenderer::addMesh()");
  meshes_.emplace(drawable, std::move(m));
}

void SceneRenderer::addCutOut(int planet, int dem) {
  const auto p = terrains_.find(planet);
  const auto d = terrains_.find(dem);
  if (p == terrains_.end() || d == terrains_.end())
    throw InvalidArgument("SceneRenderer::addCutOut(): no terrain for key " +
                          std::to_string(p == terrains_.end() ? planet : dem));
  if (p->second->pyramid->kind() != SurfaceKind::Planet)
    throw InvalidArgument("SceneRenderer::addCutOut(): terrain " + std::to_string(planet) +
                          " is not a planet");
  Terrain& t = *d->second;
  if (t.pyramid->kind() != SurfaceKind::Plane || t.pyramid->placement())
    throw InvalidArgument("SceneRenderer::addCutOut(): terrain " + std::to_string(dem) +
                          " is not a plane DEM in its own frame (place it with the scene graph)");
  if (p->second->cutBy.size() >= static_cast<std::size_t>(shaders::kMaxCutOuts))
    throw InvalidArgument("SceneRenderer::addCutOut(): planet " + std::to_string(planet) +
                          " already has " + std::to_string(shaders::kMaxCutOuts) + " DEMs");
  p->second->cutBy.push_back(dem);
  if (!p->second->options.cutOuts) {
    // The planet's program gains the cut-out test (only planets that DEMs cut carry it).
    p->second->options.cutOuts = true;
    p->second->clipmap = std::make_unique<ClipmapTerrain>(p->second->pyramid, p->second->options);
  }
  if (t.mask) return;  // already cuts another planet

  // The finest level's samples, its cell mask (a cell has data if its four corners do) and
  // the skirt: one quad along every cell side between a cell with data and one without.
  // The finest pyramid level at most kMaxMaskSide a side (a paged DEM may be far larger than
  // memory; its level 0 is then represented by a coarser one, and the inward skirt widens to
  // that level's cell).
  constexpr std::size_t kMaxMaskSide = 4096;
  std::size_t m = 0;
  while (m + 1 < t.pyramid->levelCount() &&
         std::max(t.pyramid->level(m).grid.rows(), t.pyramid->level(m).grid.cols()) > kMaxMaskSide)
    ++m;
  t.maskLevel = m;
  const auto& level = t.pyramid->level(m);
  const topo::TopoGrid& g = level.grid;
  if (std::max(g.rows(), g.cols()) > kMaxMaskSide)
    throw InvalidArgument("SceneRenderer::addCutOut(): DEM " + std::to_string(dem) +
                          " has no pyramid level of at most " + std::to_string(kMaxMaskSide) +
                          " samples a side for its cell mask");
  const std::size_t rows = g.rows(), cols = g.cols();
  if (rows < 2 || cols < 2)
    throw InvalidArgument("SceneRenderer::addCutOut(): DEM " + std::to_string(dem) +
                          " has fewer than 2×2 samples");
  std::vector<float> h(rows * cols);
  level.source->readWindow(0, 0, rows, cols, h);
  for (float& v : h)
    if (g.isNodata(v)) v = std::numeric_limits<float>::quiet_NaN();
  const std::size_t cr = rows - 1, cc = cols - 1;
  std::vector<std::uint8_t> cell(cr * cc, 0);
  const auto at = [&](std::size_t r, std::size_t c) { return h[r * cols + c]; };
  for (std::size_t r = 0; r < cr; ++r)
    for (std::size_t c = 0; c < cc; ++c)
      cell[r * cc + c] = !std::isnan(at(r, c)) && !std::isnan(at(r, c + 1)) &&
                                 !std::isnan(at(r + 1, c)) && !std::isnan(at(r + 1, c + 1))
                             ? 255
                             : 0;
  t.mask = std::make_unique<gl::Texture>();
  glTextureStorage2D(t.mask->id(), 1, GL_R8, static_cast<GLsizei>(cc), static_cast<GLsizei>(cr));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t.mask->id(), 0, 0, 0, static_cast<GLsizei>(cc), static_cast<GLsizei>(cr),
                      GL_RED, GL_UNSIGNED_BYTE, cell.data());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);

  const auto has = [&](long long r, long long c) {
    return r >= 0 && c >= 0 && r < static_cast<long long>(cr) && c < static_cast<long long>(cc) &&
           cell[static_cast<std::size_t>(r) * cc + static_cast<std::size_t>(c)] != 0;
  };
  auto skirt = std::make_unique<Skirt>();
  skirt->anchor = {g.x0() + 0.5 * static_cast<double>(cc) * g.spacingX(),
                   g.y0() - 0.5 * static_cast<double>(cr) * g.spacingY(), 0.0};
  std::vector<SkirtVertex> verts;
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  const auto point = [&](std::size_t r, std::size_t c) {
    const float v = at(r, c);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    const glm::dvec2 xy = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return glm::vec3(glm::dvec3(xy.x, xy.y, static_cast<double>(v)) - skirt->anchor);
  };
  // Border sides between sample points ka and kb (row·cols + col), outward normal n; the
  // flange direction at a point sums the normals of the sides meeting there (a mitre).
  struct Side {
    std::size_t ka, kb;
    glm::vec3 n;
  };
  std::vector<Side> sides;
  std::map<std::size_t, glm::vec3> mitre;
  const auto side = [&](std::size_t ra, std::size_t ca, std::size_t rb, std::size_t cb,
                        glm::vec3 n) {
    sides.push_back({ra * cols + ca, rb * cols + cb, n});
    mitre[ra * cols + ca] += n;
    mitre[rb * cols + cb] += n;
  };
  for (long long r = 0; r < static_cast<long long>(cr); ++r)
    for (long long c = 0; c < static_cast<long long>(cc); ++c) {
      if (!has(r, c)) continue;
      const auto ur = static_cast<std::size_t>(r), uc = static_cast<std::size_t>(c);
      if (!has(r - 1, c)) side(ur, uc, ur, uc + 1, {0, 1, 0});           // north
      if (!has(r + 1, c)) side(ur + 1, uc, ur + 1, uc + 1, {0, -1, 0});  // south
      if (!has(r, c - 1)) side(ur, uc, ur + 1, uc, {-1, 0, 0});          // west
      if (!has(r, c + 1)) side(ur, uc + 1, ur + 1, uc + 1, {1, 0, 0});   // east
    }
  for (const Side& sd : sides) {
    const glm::vec3 a = point(sd.ka / cols, sd.ka % cols), b = point(sd.kb / cols, sd.kb % cols);
    const glm::vec3 fa = mitre[sd.ka], fb = mitre[sd.kb];
    for (const auto& [q, bottom, f] : {std::tuple{a, 0.0F, fa},
                                       {b, 0.0F, fb},
                                       {b, 1.0F, fb},
                                       {a, 0.0F, fa},
                                       {b, 1.0F, fb},
                                       {a, 1.0F, fa}})
      verts.push_back({q, sd.n, bottom, f});
  }
  t.edgeLow = lo;
  t.edgeHigh = hi;
  // The floor: a rectangle under every cell with data, at the skirts' bottom. Whatever small
  // crack a DEM's own clipmap levels leave (where a level's border meets the grid's edge
  // its skirt is cut), the view through it ends on the floor, not on the planet's far side.
  t.lowest = std::numeric_limits<float>::max();
  double fx0 = std::numeric_limits<double>::max(), fx1 = -fx0, fy0 = fx0, fy1 = -fx0;
  for (std::size_t r = 0; r < cr; ++r)
    for (std::size_t c = 0; c < cc; ++c) {
      if (cell[r * cc + c] == 0) continue;
      for (std::size_t k = 0; k < 4; ++k) {
        const std::size_t rr = r + k / 2, ccol = c + k % 2;
        t.lowest = std::min(t.lowest, at(rr, ccol));
        const glm::dvec2 xy = g.sampleCentre(static_cast<double>(rr), static_cast<double>(ccol));
        fx0 = std::min(fx0, xy.x), fx1 = std::max(fx1, xy.x);
        fy0 = std::min(fy0, xy.y), fy1 = std::max(fy1, xy.y);
      }
    }
  if (!verts.empty()) {
    const auto corner = [&](double x, double y) {
      return glm::vec3(glm::dvec3(x, y, 0.0) - skirt->anchor);
    };
    for (const glm::vec3& q : {corner(fx0, fy0), corner(fx1, fy0), corner(fx1, fy1),
                               corner(fx0, fy0), corner(fx1, fy1), corner(fx0, fy1)})
      verts.push_back({q, glm::vec3(0.0F), 1.0F, glm::vec3(0.0F)});
  }
  glNamedBufferStorage(skirt->buffer.id(),
                       static_cast<GLsizeiptr>(verts.size() * sizeof(SkirtVertex)), verts.data(),
                       0);
  setupVao(skirt->vao, skirt->buffer, sizeof(SkirtVertex));
  skirt->count = static_cast<GLsizei>(verts.size());
  t.skirt = std::move(skirt);
  gl::checkGl("SceneRenderer::addCutOut()");
}

const ClipmapTerrain* SceneRenderer::terrain(int drawable) const {
  const auto it = terrains_.find(drawable);
  return it == terrains_.end() ? nullptr : it->second->clipmap.get();
}

SceneFrame SceneRenderer::draw(const scenegraph::RenderList& list, const SceneView& view) {
  if (view.width < 1 || view.height < 1 || !(view.near > 0.0) ||
      !(view.fovYDegrees > 0.0 && view.fovYDegrees < 180.0))
    throw InvalidArgument("SceneRenderer::draw(): viewport " + std::to_string(view.width) + "×" +
                          std::to_string(view.height) + ", near " + std::to_string(view.near) +
                          " m, field of view " + std::to_string(view.fovYDegrees) +
                          "°: expected a non-empty viewport, near > 0 and fov in (0, 180)");
  SceneFrame frame;
  glViewport(view.x, view.y, view.width, view.height);
  gl::useReversedZ();
  const double f = 1.0 / std::tan(0.5 * view.fovYDegrees * std::numbers::pi / 180.0);
  const double aspect = static_cast<double>(view.width) / view.height;

  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = terrains_.find(item.drawable);
    if (it == terrains_.end()) {
      if (meshes_.count(item.drawable) == 0) ++frame.itemsUnknown;
      continue;
    }
    Terrain& t = *it->second;
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    frame.texelsUploaded += t.clipmap->setFocus(focusFor(*t.pyramid, cam.position));
    ClipmapOptions opts = t.options;
    opts.lightDirection = lightIn(item.inFocus, view.lightInFocus);
    t.clipmap->setOptions(opts);

    // Cut-outs: for every DEM over this planet that is in the list, eye → DEM mask cell.
    const gl::Program& prog = t.clipmap->program();
    int cuts = 0;
    for (const int dem : t.cutBy) {
      const scenegraph::RenderItem* d = list.findDrawable(dem);
      if (d == nullptr) continue;
      const Terrain& dt = *terrains_.at(dem);
      const auto& g = dt.pyramid->level(dt.maskLevel).grid;
      // DEM grid frame ← planet frame, composed through the focus in double.
      const scenegraph::Pose planetToDem = d->inFocus.inverse() * item.inFocus;
      const glm::dmat3 eyeToWorld = glm::transpose(cam.rotation());
      const glm::dmat3 eyeToGrid = planetToDem.matrix() * eyeToWorld;
      const glm::dvec3 camInGrid = planetToDem.apply(cam.position);
      glm::dmat3 s(1.0);
      s[0][0] = 1.0 / g.spacingX();
      s[1][1] = -1.0 / g.spacingY();
      const glm::dvec3 cellOfCamera =
          s * camInGrid + glm::dvec3(-g.x0() / g.spacingX(), g.y0() / g.spacingY(), 0.0);
      static constexpr std::array<const char*, 4> kEyeToCell{
          "uCutEyeToCell[0]", "uCutEyeToCell[1]", "uCutEyeToCell[2]", "uCutEyeToCell[3]"};
      static constexpr std::array<const char*, 4> kCellOfCamera{
          "uCutCellOfCamera[0]", "uCutCellOfCamera[1]", "uCutCellOfCamera[2]",
          "uCutCellOfCamera[3]"};
      const auto slot = static_cast<std::size_t>(cuts);
      prog.set(kEyeToCell.at(slot), glm::mat3(s * eyeToGrid));
      prog.set(kCellOfCamera.at(slot), glm::vec3(cellOfCamera));
      glBindTextureUnit(static_cast<GLuint>(shaders::kCutOutFirstUnit + cuts), dt.mask->id());
      ++cuts;
    }
    prog.set("uCutCount", cuts);
    prog.set("uCutViewport",
             glm::vec4(static_cast<float>(view.x), static_cast<float>(view.y),
                       static_cast<float>(view.width), static_cast<float>(view.height)));
    prog.set("uCutProj", glm::vec3(glm::dvec3(view.near, aspect / f, 1.0 / f)));
    const ClipmapFrame cf = t.clipmap->draw(cam);
    frame.vertices += cf.vertices;
    ++frame.terrainsDrawn;
  }

  // DEM border skirts: below both the DEM's border and the planet under it, reaching inward
  // past the coarsest DEM level's edge (a coarse level's border sits up to half a cell inside
  // the finest level's).
  meshProgram_.use();
  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = terrains_.find(item.drawable);
    if (!skirts_ || it == terrains_.end() || !it->second->skirt) continue;
    Terrain& t = *it->second;
    double gap = 0.0, sag = 0.0, above = 0.0;
    for (const auto& [key, planet] : terrains_) {
      if (std::find(planet->cutBy.begin(), planet->cutBy.end(), item.drawable) ==
          planet->cutBy.end())
        continue;
      const scenegraph::RenderItem* pi = list.findDrawable(key);
      if (pi == nullptr) continue;
      // How far the planet's surface can be from the DEM border: the planet's relief over
      // the cell under the DEM and the sag of a chord across its coarsest cell drawn.
      const Camera pc = cameraInItem(pi->cameraInItem(), view);
      const auto [first, count] = planet->clipmap->activeLevels(pc);
      const std::size_t k = count == 0 ? planet->clipmap->levelCount() - 1 : first;
      const auto& pg = planet->pyramid->level(k).grid;
      const double r = planet->pyramid->body()->polarRadius();
      const double cell = 2.0 * pg.spacingY() * std::numbers::pi / 180.0 * r;
      sag = std::max(sag, cell * cell / (8.0 * r));
      const glm::dvec3 demOrigin = (pi->inFocus.inverse() * item.inFocus).translation;
      const glm::dvec2 ll = planet->pyramid->gridPoint(demOrigin);
      const glm::dvec2 idx = pg.fractionalIndex(ll.x, ll.y);
      const auto rr = static_cast<std::size_t>(
          std::clamp(std::floor(idx.y), 0.0, static_cast<double>(pg.rows() - 1)));
      const auto ccol = static_cast<std::size_t>(
          std::clamp(std::floor(idx.x), 0.0, static_cast<double>(pg.cols() - 1)));
      const double ph = static_cast<double>(planet->pyramid->level(k).source->sample(rr, ccol));
      const double demH = planet->pyramid->body()->toGeodetic(demOrigin).height;
      gap = std::max({gap, std::abs(demH + static_cast<double>(t.edgeLow) - ph),
                      std::abs(demH + static_cast<double>(t.edgeHigh) - ph)});
      // How far the planet's chords surely lie above the border's highest point (a DEM set
      // lower than the planet: a pit whose walls rise from the border to the planet).
      // (The chord across one cell sags at most c²/8R below its samples.)
      above = std::max(
          above, ph - 0.25 * cell * cell / (8.0 * r) - demH - static_cast<double>(t.edgeHigh));
    }
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    const auto [first, count] = t.clipmap->activeLevels(cam);
    const std::size_t coarsest = count == 0 ? t.clipmap->levelCount() - 1 : first + count - 1;
    // Inward: past the coarsest drawn level's inset, and past a coarse mask's cells.
    const double maskCell = t.pyramid->level(t.maskLevel).grid.spacingX();
    const double inward = std::max(t.pyramid->level(coarsest).grid.spacingX(),
                                   t.maskLevel > 0 ? 2.0 * maskCell : maskCell);
    // The bottom: below the lowest sample and below the planet anywhere along the border.
    const double floor =
        std::min(static_cast<double>(t.lowest), static_cast<double>(t.edgeLow) - gap - sag) -
        inward - 1.0;
    meshProgram_.set("uViewProj", cam.viewProjection());
    meshProgram_.set("uAnchorRel", glm::vec3(t.skirt->anchor - cam.position));
    meshProgram_.set("uFloor", static_cast<float>(floor - t.skirt->anchor.z));
    meshProgram_.set("uFlange", glm::vec2(0.0F));
    meshProgram_.set("uSkirtIn", static_cast<float>(inward));
    meshProgram_.set("uLitNormal", glm::vec3(0.0F, 0.0F, 1.0F));
    meshProgram_.set("uLight", lightIn(item.inFocus, view.lightInFocus));
    meshProgram_.set("uAlbedo", t.options.albedo);
    meshProgram_.set("uAmbient", t.options.ambient);
    glBindVertexArray(t.skirt->vao.id());
    // Twice: straight down (closes the wall between the border and a planet below or above
    // it, seen from outside), then down and inward (covers the band a coarser DEM level
    // leaves inside the finest level's border, seen from above).
    meshProgram_.set("uSkirtIn", 0.0F);
    glDrawArrays(GL_TRIANGLES, 0, t.skirt->count);
    meshProgram_.set("uSkirtIn", static_cast<float>(inward));
    glDrawArrays(GL_TRIANGLES, 0, t.skirt->count);
    frame.vertices += 2 * static_cast<std::size_t>(t.skirt->count);
    if (above > 0.0) {
      // A pit: a flange from the border rising outward under the planet (slope 1:4) to the
      // planet's lowest chord height there, so a view into the pit meets a wall.
      meshProgram_.set("uFlange", glm::vec2(static_cast<float>(std::max(4.0 * above, inward)),
                                            static_cast<float>(above)));
      glDrawArrays(GL_TRIANGLES, 0, t.skirt->count);
      meshProgram_.set("uFlange", glm::vec2(0.0F));
      frame.vertices += static_cast<std::size_t>(t.skirt->count);
    }
  }

  // Meshes: item → camera in double, the camera in the item frame, floats small.
  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = meshes_.find(item.drawable);
    if (it == meshes_.end()) continue;
    const Mesh& m = *it->second;
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    meshProgram_.set("uViewProj", cam.viewProjection());
    meshProgram_.set("uAnchorRel", glm::vec3(-cam.position));
    meshProgram_.set("uFloor", 0.0F);
    meshProgram_.set("uSkirtIn", 0.0F);
    meshProgram_.set("uFlange", glm::vec2(0.0F));
    meshProgram_.set("uLitNormal", glm::vec3(0.0F));
    meshProgram_.set("uLight", lightIn(item.inFocus, view.lightInFocus));
    meshProgram_.set("uAlbedo", m.albedo);
    meshProgram_.set("uAmbient", 0.25F);
    glBindVertexArray(m.vao.id());
    glDrawArrays(GL_TRIANGLES, 0, m.count);
    frame.vertices += static_cast<std::size_t>(m.count);
    ++frame.meshesDrawn;
  }
  glBindVertexArray(0);
  gl::checkGl("SceneRenderer::draw()");
  return frame;
}

}  // namespace regolith::clod
