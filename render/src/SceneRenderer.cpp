#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/farfield/FarField.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/GlObjects.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/gl/RenderTarget.hpp>
#include <regolith/render/CutOutGeometry.hpp>
#include <regolith/render/SceneRenderer.hpp>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <future>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace regolith::render {

// The near field this layer draws (clod), named here without its namespace.
using clod::Camera;
using clod::ClipmapCutOut;
using clod::ClipmapFrame;
using clod::ClipmapOptions;
using clod::ClipmapTerrain;
using clod::HeightPyramid;
using clod::SurfaceKind;

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

// Towards the light in an item's frame (unit, double: the far field's sun).
glm::dvec3 sunIn(const scenegraph::Pose& itemInFocus, const glm::dvec3& lightInFocus) {
  return glm::normalize(glm::conjugate(itemInFocus.rotation) * lightInFocus);
}
glm::vec3 lightIn(const scenegraph::Pose& itemInFocus, const glm::dvec3& lightInFocus) {
  return glm::vec3(sunIn(itemInFocus, lightInFocus));
}

// A terrain's focus: the camera's position (or the view's clipmap centre), clamped onto a
// plane DEM's grid so the clipmap windows stay on the data whatever the camera does.
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
  BorderSkirt border;      // its heights (the vertices are on the GPU)
};

struct SceneRenderer::Terrain {
  std::shared_ptr<const HeightPyramid> pyramid;
  // One clipmap per view slot, each with its own windows and textures: views drawn in turn
  // (split viewports) would otherwise move one clipmap's windows back and forth every frame
  // and reload them. [0] is made by addTerrain(); a slot's other clipmaps on its first
  // prepare().
  std::vector<std::unique_ptr<ClipmapTerrain>> clipmaps;
  ClipmapOptions options;
  std::vector<int> cutBy;  // planets: the DEMs that win over them
  // DEMs that cut a planet: the finest level's cell mask and border skirt.
  std::unique_ptr<gl::Texture> mask;
  std::unique_ptr<Skirt> skirt;
  std::size_t maskLevel = 0;  // the pyramid level the mask and skirts come from
  // Planets that DEMs cut: their samples under the DEMs' origins (planetCellUnder(), every
  // level drawn), which the skirts' depth needs. Read on the executor (the clipmap's, else a
  // pool of one thread made for it) when a DEM is first seen at a place, never in draw().
  std::map<PlanetCell, float> underDems;
  std::vector<std::future<std::vector<std::pair<PlanetCell, float>>>> probes;
  std::shared_ptr<core::Executor> probeExecutor;

  // Planets: starts reading the samples under a DEM at `origin` (planet frame) that no probe
  // read yet, one per clipmap level, on the executor.
  void startProbe(const glm::dvec3& origin) {
    std::vector<PlanetCell> missing;
    for (std::size_t k = 0; k < clipmaps.front()->levelCount(); ++k) {
      const PlanetCell c = planetCellUnder(*pyramid, k, origin);
      if (underDems.count(c) == 0) missing.push_back(c);
    }
    if (missing.empty()) return;
    if (!probeExecutor)
      probeExecutor = options.executor ? options.executor : std::make_shared<core::ThreadPool>(1);
    probes.push_back(
        core::submitTask(*probeExecutor, [pyramid = pyramid, cells = std::move(missing)] {
          std::vector<std::pair<PlanetCell, float>> out;
          out.reserve(cells.size());
          for (const PlanetCell& c : cells)
            out.emplace_back(c, pyramid->level(c.level).source->sample(c.row, c.col));
          return out;
        }));
  }
  // Keeps the samples of the probes that are done (`wait`: of all, waiting for them).
  void collectProbes(bool wait) {
    // Taken out first: if a read failed (its error is rethrown here), the next frame asks
    // again for what is still missing.
    auto started = std::move(probes);
    probes.clear();
    for (auto& probe : started) {
      if (!wait && probe.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
        probes.push_back(std::move(probe));
        continue;
      }
      for (const auto& [cell, h] : probe.get()) underDems.emplace(cell, h);
    }
  }
  // The clipmap of view slot `slot`, made now if the slot has none.
  ClipmapTerrain& clipmapOf(std::size_t slot) {
    if (clipmaps.size() <= slot) clipmaps.resize(slot + 1);
    if (!clipmaps[slot]) clipmaps[slot] = std::make_unique<ClipmapTerrain>(pyramid, options);
    return *clipmaps[slot];
  }
  // The clipmap of view slot `slot`, or null if no prepare() made it.
  [[nodiscard]] ClipmapTerrain* preparedClipmap(std::size_t slot) const {
    return slot < clipmaps.size() ? clipmaps[slot].get() : nullptr;
  }
};

// A planet's far field: one farfield::FarField per view slot, made on the slot's first draw.
struct SceneRenderer::FarFields {
  std::shared_ptr<const farfield::HeightLayers> layers;
  farfield::PgmOptions options;
  std::vector<std::unique_ptr<farfield::FarField>> bySlot;
};

struct SceneRenderer::Mesh {
  gl::Buffer buffer;
  gl::VertexArray vao;
  GLsizei count = 0;
  glm::vec3 albedo{0.7F};
};

SceneRenderer::SceneRenderer()
    : meshProgram_(std::make_unique<gl::Program>(
          "scene mesh", gl::ShaderSources{kMeshVertex, "", kMeshFragment})) {}

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
  t->clipmaps.push_back(std::make_unique<ClipmapTerrain>(std::move(pyramid), options));
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
  if (p->second->cutBy.size() >= clod::kMaxClipmapCutOuts)
    throw InvalidArgument("SceneRenderer::addCutOut(): planet " + std::to_string(planet) +
                          " already has " + std::to_string(clod::kMaxClipmapCutOuts) + " DEMs");
  p->second->cutBy.push_back(dem);
  if (!p->second->options.cutOuts) {
    // The planet's program gains the cut-out test (only planets that DEMs cut carry it): its
    // clipmaps are made again, slot 0 now and the others on their next prepare().
    p->second->options.cutOuts = true;
    p->second->clipmaps.clear();
    p->second->clipmapOf(0);
  }
  if (t.mask) return;  // already cuts another planet

  // The finest level's samples, its cell mask and the skirt (CutOutGeometry.hpp), read and
  // built here, once: draw() reads nothing. The finest pyramid level at most
  // kMaxCutOutMaskSide a side (a paged DEM may be far larger than memory; its level 0 is then
  // represented by a coarser one, and the inward skirt widens to that level's cell).
  const std::size_t m = cutOutMaskLevel(*t.pyramid);
  t.maskLevel = m;
  const auto& level = t.pyramid->level(m);
  const topo::TopoGrid& g = level.grid;
  if (std::max(g.rows(), g.cols()) > kMaxCutOutMaskSide)
    throw InvalidArgument("SceneRenderer::addCutOut(): DEM " + std::to_string(dem) +
                          " has no pyramid level of at most " + std::to_string(kMaxCutOutMaskSide) +
                          " samples a side for its cell mask");
  const std::size_t rows = g.rows(), cols = g.cols();
  if (rows < 2 || cols < 2)
    throw InvalidArgument("SceneRenderer::addCutOut(): DEM " + std::to_string(dem) +
                          " has fewer than 2×2 samples");
  std::vector<float> h(rows * cols);
  level.source->readWindow(0, 0, rows, cols, h);
  const CellMask cells = cellMask(g, h);
  t.mask = std::make_unique<gl::Texture>();
  glTextureStorage2D(t.mask->id(), 1, GL_R8, static_cast<GLsizei>(cells.cols),
                     static_cast<GLsizei>(cells.rows));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t.mask->id(), 0, 0, 0, static_cast<GLsizei>(cells.cols),
                      static_cast<GLsizei>(cells.rows), GL_RED, GL_UNSIGNED_BYTE,
                      cells.cells.data());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);

  BorderSkirt border = borderSkirt(g, h, cells);
  auto skirt = std::make_unique<Skirt>();
  skirt->anchor = border.anchor;
  static_assert(sizeof(SkirtVertex) == 10 * sizeof(float), "setupVao() reads 10 floats a vertex");
  glNamedBufferStorage(skirt->buffer.id(),
                       static_cast<GLsizeiptr>(border.vertices.size() * sizeof(SkirtVertex)),
                       border.vertices.data(), 0);
  setupVao(skirt->vao, skirt->buffer, sizeof(SkirtVertex));
  skirt->count = static_cast<GLsizei>(border.vertices.size());
  border.vertices = {};  // on the GPU now; the heights are what draw() needs
  skirt->border = std::move(border);
  t.skirt = std::move(skirt);
  gl::checkGl("SceneRenderer::addCutOut()");
}

void SceneRenderer::addFarField(int planet, std::shared_ptr<const farfield::HeightLayers> layers,
                                const farfield::PgmOptions& options) {
  const char* op = "SceneRenderer::addFarField()";
  const auto t = terrains_.find(planet);
  if (t == terrains_.end())
    throw InvalidArgument(core::format({.operation = op,
                                        .field = "planet",
                                        .value = core::number(planet),
                                        .expected = "the key of a terrain added before"}));
  if (t->second->pyramid->kind() != SurfaceKind::Planet && !t->second->pyramid->placement())
    throw InvalidArgument(core::format(
        {.operation = op,
         .field = "planet",
         .value = core::number(planet),
         .expected = "a terrain drawn body-fixed (a Planet pyramid, or one with a placement)"}));
  if (layers == nullptr)
    throw InvalidArgument(core::format({.operation = op,
                                        .field = "layers",
                                        .value = "null",
                                        .expected = "the planet's height layers"}));
  if (farFields_.count(planet) != 0)
    throw InvalidArgument(core::format({.operation = op,
                                        .field = "planet",
                                        .value = core::number(planet),
                                        .expected = "a planet without a far field yet"}));
  auto f = std::make_unique<FarFields>();
  f->layers = std::move(layers);
  f->options = options;
  farFields_.emplace(planet, std::move(f));
}

const ClipmapTerrain* SceneRenderer::terrain(int drawable) const {
  const auto it = terrains_.find(drawable);
  return it == terrains_.end() ? nullptr : it->second->clipmaps.front().get();
}

namespace {

void checkSlot(const char* op, std::size_t slot) {
  if (slot >= SceneRenderer::kMaxSlots)
    throw InvalidArgument(
        core::format({.operation = op,
                      .field = "slot",
                      .value = core::number(slot),
                      .expected = "a view slot below " + core::number(SceneRenderer::kMaxSlots)}));
}

void checkView(const char* op, const SceneView& view) {
  if (view.width < 1 || view.height < 1 || !(view.near > 0.0) ||
      !(view.fovYDegrees > 0.0 && view.fovYDegrees < 180.0))
    throw InvalidArgument(std::string(op) + ": viewport " + std::to_string(view.width) + "×" +
                          std::to_string(view.height) + ", near " + std::to_string(view.near) +
                          " m, field of view " + std::to_string(view.fovYDegrees) +
                          "°: expected a non-empty viewport, near > 0 and fov in (0, 180)");
}

// A DEM's origin in its planet's frame.
glm::dvec3 demOrigin(const scenegraph::RenderItem& planet, const scenegraph::RenderItem& dem) {
  return (planet.inFocus.inverse() * dem.inFocus).translation;
}

}  // namespace

std::size_t SceneRenderer::prepare(const scenegraph::RenderList& list, const SceneView& view,
                                   Loading loading, std::size_t slot) {
  checkView("SceneRenderer::prepare()", view);
  checkSlot("SceneRenderer::prepare()", slot);
  // Every terrain asks first, so their executors read side by side; then each uploads.
  std::vector<ClipmapTerrain*> asked;
  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = terrains_.find(item.drawable);
    if (it == terrains_.end()) continue;
    Terrain& t = *it->second;
    const glm::dvec3 centre = view.clipmapCentreInFocus
                                  ? item.inFocus.inverse().apply(*view.clipmapCentreInFocus)
                                  : cameraInItem(item.cameraInItem(), view).position;
    ClipmapTerrain& clipmap = t.clipmapOf(slot);
    clipmap.requestFocus(focusFor(*t.pyramid, centre));
    asked.push_back(&clipmap);
  }
  std::size_t count = 0;
  for (ClipmapTerrain* c : asked)
    count += loading == Loading::Wait ? c->finishLoading() : c->update(false);
  preparedTexels_ += count;

  // The skirts' depth needs each planet's sample under each DEM that cuts it: read on the
  // executor for a DEM seen at a new place (collected by draw()'s skirt pass). A DEM that
  // stays where it is reads nothing again.
  if (skirts_)
    for (auto& [key, planet] : terrains_) {
      const scenegraph::RenderItem* pi = list.findDrawable(key);
      if (pi == nullptr) continue;
      for (const int dem : planet->cutBy)
        if (const scenegraph::RenderItem* di = list.findDrawable(dem); di != nullptr)
          planet->startProbe(demOrigin(*pi, *di));
      if (loading == Loading::Wait) planet->collectProbes(true);
    }
  return count;
}

SceneFrame SceneRenderer::draw(const scenegraph::RenderList& list, const SceneView& view,
                               const gl::RenderTarget* target, std::size_t slot) {
  checkView("SceneRenderer::draw()", view);
  checkSlot("SceneRenderer::draw()", slot);
  if (target != nullptr && !farFields_.empty() &&
      (view.x != 0 || view.y != 0 || view.width != target->width() ||
       view.height != target->height()))
    throw InvalidArgument(core::format(
        {.operation = "SceneRenderer::draw()",
         .field = "view",
         .value = "viewport " + core::number(view.x) + ", " + core::number(view.y) + ", " +
                  core::number(view.width) + " x " + core::number(view.height),
         .expected = "the whole target (" + core::number(target->width()) + " x " +
                     core::number(target->height()) + ") where far fields are drawn"}));
  SceneFrame frame;
  frame.texelsUploaded = std::exchange(preparedTexels_, 0);
  glViewport(view.x, view.y, view.width, view.height);
  gl::useReversedZ();

  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = terrains_.find(item.drawable);
    if (it == terrains_.end()) {
      if (meshes_.count(item.drawable) == 0) ++frame.itemsUnknown;
      continue;
    }
    Terrain& t = *it->second;
    ClipmapTerrain* const clipmap = t.preparedClipmap(slot);
    if (clipmap == nullptr) continue;  // never prepared in this slot: nothing to draw
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    ClipmapOptions opts = t.options;
    opts.lightDirection = lightIn(item.inFocus, view.lightInFocus);
    clipmap->setOptions(opts);

    // Cut-outs: for every DEM over this planet that is in the list, eye → DEM mask cell.
    if (t.options.cutOuts) {
      std::vector<ClipmapCutOut> cuts;
      for (const int dem : t.cutBy) {
        const scenegraph::RenderItem* d = list.findDrawable(dem);
        if (d == nullptr) continue;
        const Terrain& dt = *terrains_.at(dem);
        // DEM grid frame ← planet frame, composed through the focus in double.
        const scenegraph::Pose planetToDem = d->inFocus.inverse() * item.inFocus;
        cuts.push_back(
            {dt.mask.get(), cutOutTransform(planetToDem, glm::transpose(cam.rotation()),
                                            cam.position, dt.pyramid->level(dt.maskLevel).grid)});
      }
      clipmap->setCutOuts(cuts, {view.x, view.y});
    }
    const ClipmapFrame cf = clipmap->draw(cam);
    frame.vertices += cf.vertices;
    ++frame.terrainsDrawn;
  }

  // DEM border skirts: below both the DEM's border and the planet under it, reaching inward
  // past the coarsest DEM level's edge (a coarse level's border sits up to half a cell inside
  // the finest level's). skirtDrop() (CutOutGeometry.hpp) says how deep and how far in.
  meshProgram_->use();
  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = terrains_.find(item.drawable);
    if (!skirts_ || it == terrains_.end() || !it->second->skirt) continue;
    Terrain& t = *it->second;
    const ClipmapTerrain* const demClipmap = t.preparedClipmap(slot);
    if (demClipmap == nullptr) continue;
    std::vector<PlanetUnderDem> under;
    bool known = true;  // every planet's sample under this DEM has been read
    for (auto& [key, planet] : terrains_) {
      if (std::find(planet->cutBy.begin(), planet->cutBy.end(), item.drawable) ==
          planet->cutBy.end())
        continue;
      const scenegraph::RenderItem* pi = list.findDrawable(key);
      if (pi == nullptr) continue;
      // The planet level drawn finest for this camera: its sample under the DEM's origin.
      const ClipmapTerrain* const planetClipmap = planet->preparedClipmap(slot);
      if (planetClipmap == nullptr) {  // the planet is not drawn in this slot
        known = false;
        break;
      }
      const Camera pc = cameraInItem(pi->cameraInItem(), view);
      const auto [first, count] = planetClipmap->activeLevels(pc);
      const std::size_t k = count == 0 ? planetClipmap->levelCount() - 1 : first;
      const glm::dvec3 origin = demOrigin(*pi, item);
      const PlanetCell cell = planetCellUnder(*planet->pyramid, k, origin);
      if (planet->underDems.count(cell) == 0) planet->collectProbes(false);
      if (planet->underDems.count(cell) == 0) {
        // Not read yet (prepare() in the background, or not called for this list): asked
        // for now, and this DEM's skirt waits for a later frame rather than this frame for a
        // read.
        planet->startProbe(origin);
        known = false;
        break;
      }
      PlanetUnderDem u;
      u.planetHeight = static_cast<double>(planet->underDems.at(cell));
      u.demHeight = planet->pyramid->body()->toGeodetic(origin).height;
      u.spacingDegrees = planet->pyramid->level(k).grid.spacingY();
      u.radius = planet->pyramid->body()->polarRadius();
      under.push_back(u);
    }
    if (!known) continue;
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    const auto [first, count] = demClipmap->activeLevels(cam);
    const std::size_t coarsest = count == 0 ? demClipmap->levelCount() - 1 : first + count - 1;
    const SkirtDrop drop =
        skirtDrop(t.skirt->border, under, t.pyramid->level(coarsest).grid.spacingX(),
                  t.pyramid->level(t.maskLevel).grid.spacingX(), t.maskLevel > 0);
    meshProgram_->set("uViewProj", cam.viewProjection());
    meshProgram_->set("uAnchorRel", glm::vec3(t.skirt->anchor - cam.position));
    meshProgram_->set("uFloor", static_cast<float>(drop.floor - t.skirt->anchor.z));
    meshProgram_->set("uFlange", glm::vec2(0.0F));
    meshProgram_->set("uSkirtIn", static_cast<float>(drop.inward));
    meshProgram_->set("uLitNormal", glm::vec3(0.0F, 0.0F, 1.0F));
    meshProgram_->set("uLight", lightIn(item.inFocus, view.lightInFocus));
    meshProgram_->set("uAlbedo", t.options.albedo);
    meshProgram_->set("uAmbient", t.options.ambient);
    glBindVertexArray(t.skirt->vao.id());
    // Twice: straight down (closes the wall between the border and a planet below or above
    // it, seen from outside), then down and inward (covers the band a coarser DEM level
    // leaves inside the finest level's border, seen from above).
    meshProgram_->set("uSkirtIn", 0.0F);
    glDrawArrays(GL_TRIANGLES, 0, t.skirt->count);
    meshProgram_->set("uSkirtIn", static_cast<float>(drop.inward));
    glDrawArrays(GL_TRIANGLES, 0, t.skirt->count);
    frame.vertices += 2 * static_cast<std::size_t>(t.skirt->count);
    if (drop.flange.y > 0.0) {
      // A pit: a flange from the border rising outward under the planet.
      meshProgram_->set("uFlange", glm::vec2(drop.flange));
      glDrawArrays(GL_TRIANGLES, 0, t.skirt->count);
      meshProgram_->set("uFlange", glm::vec2(0.0F));
      frame.vertices += static_cast<std::size_t>(t.skirt->count);
    }
  }

  // Meshes: item → camera in double, the camera in the item frame, floats small.
  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = meshes_.find(item.drawable);
    if (it == meshes_.end()) continue;
    const Mesh& m = *it->second;
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    meshProgram_->set("uViewProj", cam.viewProjection());
    meshProgram_->set("uAnchorRel", glm::vec3(-cam.position));
    meshProgram_->set("uFloor", 0.0F);
    meshProgram_->set("uSkirtIn", 0.0F);
    meshProgram_->set("uFlange", glm::vec2(0.0F));
    meshProgram_->set("uLitNormal", glm::vec3(0.0F));
    meshProgram_->set("uLight", lightIn(item.inFocus, view.lightInFocus));
    meshProgram_->set("uAlbedo", m.albedo);
    meshProgram_->set("uAmbient", 0.25F);
    glBindVertexArray(m.vao.id());
    glDrawArrays(GL_TRIANGLES, 0, m.count);
    frame.vertices += static_cast<std::size_t>(m.count);
    ++frame.meshesDrawn;
  }
  glBindVertexArray(0);
  gl::checkGl("SceneRenderer::draw()");
  if (target != nullptr) drawFarFields(list, view, *target, slot, frame);
  return frame;
}

void SceneRenderer::drawFarFields(const scenegraph::RenderList& list, const SceneView& view,
                                  const gl::RenderTarget& target, std::size_t slot,
                                  SceneFrame& frame) {
  // Beyond the clipmaps: each planet's far field in its body-fixed frame (the item's), where
  // nothing is drawn yet.
  for (const scenegraph::RenderItem& item : list.items) {
    const auto it = farFields_.find(item.drawable);
    if (it == farFields_.end()) continue;
    FarFields& f = *it->second;
    if (f.bySlot.size() <= slot) f.bySlot.resize(slot + 1);
    std::unique_ptr<farfield::FarField>& field = f.bySlot[slot];
    if (field == nullptr) field = std::make_unique<farfield::FarField>(f.layers, f.options);
    const Camera cam = cameraInItem(item.cameraInItem(), view);
    const farfield::FarFieldFrame ff =
        field->draw(target, cam, sunIn(item.inFocus, view.lightInFocus), true);
    if (ff.mode == farfield::FarFieldMode::Pgm) {
      ++frame.farFieldsPgm;
      // The grid drawn: the options' size, or smaller where PgmOptions::minCellPixels thins it.
      frame.vertices +=
          static_cast<std::size_t>(ff.pgm.gridWidth) * static_cast<std::size_t>(ff.pgm.gridHeight);
    } else if (ff.mode == farfield::FarFieldMode::Impostor) {
      ++frame.farFieldsImpostor;
    } else if (ff.mode == farfield::FarFieldMode::Covered) {
      ++frame.farFieldsCovered;
    }
  }
}

}  // namespace regolith::render
