#include "Viewer.hpp"

#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/Image.hpp>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

namespace regolith::tools::viewer {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr glm::vec4 kSpace{0.02F, 0.02F, 0.04F, 1.0F};

/// The declared effects of `declared` without those in `off`.
clod::Effects enabled(const clod::Effects& declared, const std::set<std::string>& off) {
  clod::Effects e = declared;
  if (off.contains("albedo")) e.albedo.reset();
  if (off.contains("tracks")) e.tracks.reset();
  if (off.contains("noise")) e.noise.reset();
  if (off.contains("heightColours")) e.heightColours.reset();
  if (off.contains("latLon")) e.latLon.reset();
  if (off.contains("overlay")) e.overlay.reset();
  return e;
}

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

glm::dvec3 rotateAbout(const glm::dvec3& v, const glm::dvec3& axis, double degrees) {
  return glm::angleAxis(degrees * kDeg, glm::normalize(axis)) * v;
}

}  // namespace

std::string Pick::text() const {
  char buf[256];
  if (!hit) {
    std::snprintf(buf, sizeof buf, "pick %d %d: nothing (sky)", x, y);
  } else if (lonLat) {
    std::snprintf(buf, sizeof buf,
                  "pick %d %d: lon %.6f lat %.6f height %.3f m dataset %s (%.6g m from the camera)",
                  x, y, a, b, height, dataset.c_str(), distance);
  } else {
    std::snprintf(buf, sizeof buf,
                  "pick %d %d: x %.3f y %.3f height %.3f m dataset %s (%.6g m from the camera)", x,
                  y, a, b, height, dataset.c_str(), distance);
  }
  return buf;
}

Viewer::Viewer(ViewScene scene, int width, int height, std::ostream& log, render::Loading loading)
    : scene_(std::move(scene)), log_(log), loading_(loading) {
  if (scene_.objects.empty() || scene_.openings.empty() || !scene_.graph)
    throw InvalidArgument("view: the scene has no object to look at");
  off_.resize(scene_.terrains.size());
  for (std::size_t t = 0; t < scene_.terrains.size(); ++t) {
    for (const std::string& e : scene_.terrains[t].options.effects.declared()) {
      off_[t].insert(e);  // declared, shown on request (keys 1..9)
      toggles_.emplace_back(t, e);
    }
  }
  rebuild();
  viewports_.resize(2);
  for (std::size_t k = 0; k < 2; ++k)
    open(k, scene_.openings[std::min(k, scene_.openings.size() - 1)]);
  if (scene_.openings.size() < 2 && !scene_.cameras.empty()) viewports_[1].state.sceneCamera = 0;
  split_ = scene_.openings.size() >= 2;
  lightBehind(0);
  draw(width, height);
}

Viewer::~Viewer() = default;

void Viewer::rebuild() {
  renderer_ = std::make_unique<render::SceneRenderer>();
  for (std::size_t t = 0; t < scene_.terrains.size(); ++t) {
    const ViewTerrain& terrain = scene_.terrains[t];
    clod::ClipmapOptions o = terrain.options;
    o.effects = enabled(terrain.options.effects, off_[t]);
    renderer_->addTerrain(terrain.drawable, terrain.pyramid, o);
  }
  for (const ViewTerrain& terrain : scene_.terrains)
    for (const int dem : terrain.cutOuts) renderer_->addCutOut(terrain.drawable, dem);
  for (const ViewMesh& m : scene_.meshes) renderer_->addMesh(m.drawable, m.vertices, m.albedo);
  for (std::size_t t = 0; t < scene_.terrains.size(); ++t) {
    const ViewTerrain& terrain = scene_.terrains[t];
    if (!terrain.farField) continue;
    farfield::PgmOptions po;
    // 160² grid points: the global view's mesh pass dominates the frame on llvmpipe
    // (docs/far-field.md); PGM's error stays under a pixel at this size.
    po.gridWidth = po.gridHeight = 160;
    // The far field follows the height-colour toggle with its own ramp (docs/viewer.md).
    po.heightColours = terrain.options.effects.heightColours && !off_[t].contains("heightColours");
    po.high = terrain.options.albedo;
    po.ambient = terrain.options.ambient;
    // Drawn per viewport slot (render(): the viewport's index): PGM's primary sphere comes
    // from the previous frame's read-back of the same view (PrimaryReadback::Lagged), which
    // another viewport's view would spoil.
    renderer_->addFarField(terrain.drawable, terrain.farField, po);
  }
}

glm::dvec3 Viewer::upAt(std::size_t object, const glm::dvec3& p) const {
  const auto& surface = scene_.objects[object].surface;
  return surface ? surface->up(p) : glm::dvec3(0.0, 0.0, 1.0);
}

void Viewer::orbitBasis(std::size_t object, const glm::dvec3& at, glm::dvec3& e, glm::dvec3& n,
                        glm::dvec3& u) const {
  const auto& surface = scene_.objects[object].surface;
  u = upAt(object, at);
  // North: the body's axis in a body-fixed frame, +y in a grid frame or an object's frame.
  const bool bodyFixed =
      surface && (surface->kind() == clod::SurfaceKind::Planet || surface->placement());
  glm::dvec3 ref = bodyFixed ? glm::dvec3(0.0, 0.0, 1.0) : glm::dvec3(0.0, 1.0, 0.0);
  glm::dvec3 h = ref - u * glm::dot(ref, u);
  if (glm::length(h) < 1e-9) {
    ref = glm::dvec3(1.0, 0.0, 0.0);
    h = ref - u * glm::dot(ref, u);
  }
  n = glm::normalize(h);
  e = glm::cross(n, u);
}

void Viewer::setOrbit(ViewportState& s, double headingDeg, double elevationDeg, double distance) {
  glm::dvec3 e, n, u;
  orbitBasis(s.object, s.target, e, n, u);
  const double hd = headingDeg * kDeg, el = std::clamp(elevationDeg, 1.0, 89.5) * kDeg;
  const glm::dvec3 look = std::sin(hd) * e + std::cos(hd) * n;
  s.eye = s.target + distance * (-std::cos(el) * look + std::sin(el) * u);
  s.up = u;
}

void Viewer::orbitAngles(const ViewportState& s, double& headingDeg, double& elevationDeg) const {
  glm::dvec3 e, n, u;
  orbitBasis(s.object, s.target, e, n, u);
  const glm::dvec3 v = s.eye - s.target;
  const double d = glm::length(v);
  elevationDeg = std::asin(std::clamp(glm::dot(v, u) / d, -1.0, 1.0)) / kDeg;
  const glm::dvec3 look = -(v - u * glm::dot(v, u));
  headingDeg =
      glm::length(look) < 1e-12 * d ? 0.0 : std::atan2(glm::dot(look, e), glm::dot(look, n)) / kDeg;
}

void Viewer::open(std::size_t viewport, const OpeningView& view) {
  ViewportState& s = viewports_[viewport].state;
  s = ViewportState{};
  s.object = view.object;
  s.target = view.target;
  setOrbit(s, view.headingDeg, view.elevationDeg, view.distance);
}

scenegraph::NodeId Viewer::cameraNode(std::size_t viewport) {
  const std::size_t object = viewports_[viewport].state.object;
  const auto key = std::make_pair(viewport, object);
  const auto it = cameraNodes_.find(key);
  if (it != cameraNodes_.end()) return it->second;
  const std::string name = "viewer" + std::to_string(viewport) + "@" + scene_.objects[object].name;
  const scenegraph::NodeId node =
      scene_.graph->add(scene_.objects[object].node, name, scenegraph::Pose::identity(),
                        scenegraph::NodeKind::Camera);
  cameraNodes_.emplace(key, node);
  return node;
}

scenegraph::NodeId Viewer::shownCamera(std::size_t viewport) {
  const ViewportState& s = viewports_[viewport].state;
  if (s.sceneCamera >= 0) return scene_.cameras[static_cast<std::size_t>(s.sceneCamera)].node;
  const scenegraph::NodeId node = cameraNode(viewport);
  scene_.graph->setLocal(node, scenegraph::Pose::lookAt(s.eye, s.target, s.up));
  return node;
}

render::SceneView Viewer::viewOf(std::size_t viewport) const {
  const Viewport& v = viewports_[viewport];
  render::SceneView view;
  if (v.state.sceneCamera >= 0) {
    const ViewCamera& c = scene_.cameras[static_cast<std::size_t>(v.state.sceneCamera)];
    view.fovYDegrees = c.fovYDegrees;
    view.near = c.near;
  } else {
    view.fovYDegrees = 45.0;
    view.near = std::max(0.05, 1e-3 * glm::length(v.state.eye - v.state.target));
  }
  view.width = v.width;
  view.height = v.height;
  view.lightInFocus = lightIn(scene_.objects[v.state.object].node);
  return view;
}

glm::dvec3 Viewer::lightIn(scenegraph::NodeId node) const {
  return glm::normalize(scene_.graph->relative(node, lightNode_).applyVector(light_));
}

void Viewer::lightBehind(std::size_t viewport) {
  // The sun behind the camera, 45° off its axis, up and to the left: the side of relief
  // facing the viewer is lit, and the slopes show.
  const ViewportState& s = viewports_[viewport].state;
  const glm::dvec3 f = glm::normalize(s.target - s.eye);
  const glm::dvec3 r = glm::normalize(glm::cross(f, s.up));
  const glm::dvec3 up = glm::cross(r, f);
  const double off = 45.0 * kDeg;
  light_ = glm::normalize(-std::cos(off) * f + std::sin(off) * glm::normalize(0.8 * up - 0.6 * r));
  lightNode_ = scene_.objects[s.object].node;
}

std::size_t Viewer::viewportAt(double x) const {
  if (!split_) return 0;
  return x >= viewports_[1].x ? 1 : 0;
}

void Viewer::moveTarget(ViewportState& s, const glm::dvec3& delta) {
  double hd = 0.0, el = 0.0;
  orbitAngles(s, hd, el);
  const double d = glm::length(s.eye - s.target);
  const auto& surface = scene_.objects[s.object].surface;
  glm::dvec3 t = s.target + delta;
  if (surface && surface->kind() == clod::SurfaceKind::Planet && !surface->placement()) {
    // Along the ground: keep the look-at point's height above the body.
    const double h = surface->body()->toGeodetic(s.target).height;
    topo::Geodetic g = surface->body()->toGeodetic(t);
    g.height = h;
    t = surface->body()->toBodyFixed(g);
  }
  s.target = t;
  setOrbit(s, hd, el, d);
}

void Viewer::switchFocus(std::size_t viewport, std::size_t object) {
  ViewportState& s = viewports_[viewport].state;
  if (object == s.object) return;
  const scenegraph::NodeId from = scene_.objects[s.object].node, to = scene_.objects[object].node;
  // Two world points that stay put: the old focus's origin and the new one's. Projected
  // with the camera before (in the old focus frame) and after (in the new one), each must
  // land on the same pixel.
  const render::SceneView view = viewOf(viewport);
  const auto project = [&](const ViewportState& st, const glm::dvec3& p) {
    clod::Camera c;
    c.position = st.eye;
    c.target = st.target;
    c.up = st.up;
    c.fovYDegrees = view.fovYDegrees;
    c.width = view.width;
    c.height = view.height;
    c.near = view.near;
    return c.project(p);
  };
  const glm::dvec3 oldBefore = project(s, glm::dvec3(0.0));
  const glm::dvec3 newBefore = project(s, scene_.graph->relative(from, to).translation);
  const scenegraph::Pose toFromOld = scene_.graph->relative(to, from);
  s.eye = toFromOld.apply(s.eye);
  s.target = toFromOld.apply(s.target);
  s.up = toFromOld.applyVector(s.up);
  const std::string oldName = scene_.objects[s.object].name;
  s.object = object;
  const glm::dvec3 oldAfter = project(s, toFromOld.translation);
  const glm::dvec3 newAfter = project(s, glm::dvec3(0.0));
  const std::string& newName = scene_.objects[object].name;
  char buf[480];
  std::snprintf(buf, sizeof buf,
                "focus %s -> %s (viewport %zu): the %s origin projects to (%.4f, %.4f) px "
                "before, (%.4f, %.4f) px after; the %s origin to (%.4f, %.4f) px before, "
                "(%.4f, %.4f) px after",
                oldName.c_str(), newName.c_str(), viewport + 1, oldName.c_str(), oldBefore.x,
                oldBefore.y, oldAfter.x, oldAfter.y, newName.c_str(), newBefore.x, newBefore.y,
                newAfter.x, newAfter.y);
  log_ << buf << '\n';
}

void Viewer::toggleEffect(std::size_t index) {
  if (index >= toggles_.size()) return;
  const auto& [t, name] = toggles_[index];
  const bool on = off_[t].contains(name);
  if (on)
    off_[t].erase(name);
  else
    off_[t].insert(name);
  rebuild();
  const clod::ClipmapTerrain* clipmap = renderer_->terrain(scene_.terrains[t].drawable);
  std::string passes;
  for (const std::string& p : clipmap->passes()) passes += (passes.empty() ? "" : ", ") + p;
  log_ << "effect " << scene_.terrains[t].name << " " << name << " " << (on ? "on" : "off")
       << ": pipeline rebuilt, " << clipmap->options().effects.declared().size()
       << " effects compiled in, passes " << passes << '\n';
}

void Viewer::keyPressed(int code) {
  ViewportState& s = viewports_[active_].state;
  if (code == gl::keys::kEscape) {
    quit_ = true;
  } else if (code == gl::keys::kTab) {
    switchFocus(active_, (s.object + 1) % scene_.objects.size());
  } else if (code >= '1' && code <= '9') {
    toggleEffect(static_cast<std::size_t>(code - '1'));
  } else if (code == 'F') {
    s.fly = !s.fly;
  } else if (code == 'V') {
    split_ = !split_;
    if (!split_) active_ = 0;
  } else if (code == 'C') {
    const int n = static_cast<int>(scene_.cameras.size());
    s.sceneCamera = s.sceneCamera + 1 >= n ? -1 : s.sceneCamera + 1;
  } else if (code == 'H') {
    hudOn_ = !hudOn_;
  } else if (code == 'L') {
    lightBehind(active_);
  } else if (code == 'R') {
    open(active_, scene_.openings[std::min(active_, scene_.openings.size() - 1)]);
  } else if (code == 'G') {
    // Frame the focus object.
    const ViewObject& o = scene_.objects[s.object];
    double elevation = 35.0;
    if (o.surface && o.surface->kind() == clod::SurfaceKind::Planet && !o.surface->placement()) {
      const glm::dvec2 nadir = o.surface->gridPoint(s.eye);
      s.target = o.surface->position(nadir.x, nadir.y, 0.0);
      elevation = 75.0;
    } else if (o.surface && !o.surface->placement()) {
      const auto& g = o.surface->level(0).grid;
      s.target = {0.5 * (g.west() + g.east()), 0.5 * (g.south() + g.north()), 0.0};
    } else {
      s.target = glm::dvec3(0.0);
    }
    s.fly = false;
    setOrbit(s, 20.0, elevation, 1.2 * o.size);
  } else if (code == 'P') {
    char name[32];
    std::snprintf(name, sizeof name, "viewer-%03d.png", shots_++);
    screenshot(name);
  } else {
    held_.insert(code);
    fresh_.insert(code);
  }
}

void Viewer::stepHeldKeys() {
  ViewportState& s = viewports_[active_].state;
  if (s.sceneCamera >= 0) return;
  const double d = glm::length(s.eye - s.target);
  const glm::dvec3 f = glm::normalize(s.target - s.eye);
  const glm::dvec3 r = glm::normalize(glm::cross(f, s.up));
  for (const int k : held_) {
    if (s.fly) {
      const double step = 0.02 * d;
      glm::dvec3 move(0.0);
      if (k == 'W') move = f * step;
      if (k == 'S') move = -f * step;
      if (k == 'D') move = r * step;
      if (k == 'A') move = -r * step;
      if (k == 'E') move = s.up * step;
      if (k == 'Q') move = -s.up * step;
      s.eye += move;
      s.target += move;
    } else {
      glm::dvec3 e, n, u;
      orbitBasis(s.object, s.target, e, n, u);
      glm::dvec3 fwd = f - u * glm::dot(f, u);
      fwd = glm::length(fwd) > 1e-9 ? glm::normalize(fwd) : n;
      const glm::dvec3 right = glm::cross(fwd, u);
      const double step = 0.02 * d;
      if (k == 'W') moveTarget(s, fwd * step);
      if (k == 'S') moveTarget(s, -fwd * step);
      if (k == 'D') moveTarget(s, right * step);
      if (k == 'A') moveTarget(s, -right * step);
      if (k == 'E' || k == 'Q') {
        double hd = 0.0, el = 0.0;
        orbitAngles(s, hd, el);
        setOrbit(s, hd, el, d * (k == 'E' ? 0.95 : 1.0 / 0.95));
      }
    }
  }
}

void Viewer::drag(double dx, double dy, int button) {
  ViewportState& s = viewports_[active_].state;
  if (s.sceneCamera >= 0) return;
  if (s.fly) {
    // Look around: yaw about the up vector, pitch about the camera's right.
    const glm::dvec3 f = s.target - s.eye;
    const glm::dvec3 r = glm::cross(glm::normalize(f), s.up);
    glm::dvec3 g = rotateAbout(f, s.up, -0.2 * dx);
    const glm::dvec3 pitched = rotateAbout(g, r, -0.2 * dy);
    if (std::abs(glm::dot(glm::normalize(pitched), glm::normalize(s.up))) < 0.99) g = pitched;
    s.target = s.eye + g;
    return;
  }
  double hd = 0.0, el = 0.0;
  orbitAngles(s, hd, el);
  const double d = glm::length(s.eye - s.target);
  if (button == 0) {
    setOrbit(s, hd + 0.3 * dx, el + 0.3 * dy, d);
  } else {
    // Pan: the look-at point follows the cursor on the ground.
    const render::SceneView view = viewOf(active_);
    const double metresPerPixel =
        2.0 * d * std::tan(0.5 * view.fovYDegrees * kDeg) / std::max(view.height, 1);
    glm::dvec3 e, n, u;
    orbitBasis(s.object, s.target, e, n, u);
    const glm::dvec3 f = glm::normalize(s.target - s.eye);
    glm::dvec3 fwd = f - u * glm::dot(f, u);
    fwd = glm::length(fwd) > 1e-9 ? glm::normalize(fwd) : n;
    const glm::dvec3 right = glm::cross(fwd, u);
    moveTarget(s, (-dx * right + dy * fwd) * metresPerPixel);
  }
}

void Viewer::handle(const gl::WindowEvent& event) {
  using Type = gl::WindowEvent::Type;
  switch (event.type) {
    case Type::Key:
      if (event.press) {
        keyPressed(event.code);
      } else if (fresh_.contains(event.code)) {
        released_.insert(event.code);  // pressed and released before a frame: one step
      } else {
        held_.erase(event.code);
      }
      break;
    case Type::MouseButton:
      if (event.press) {
        active_ = viewportAt(cursorX_);
        button_ = event.code;
        pressX_ = cursorX_;
        pressY_ = cursorY_;
        dragged_ = false;
      } else if (event.code == button_) {
        if (button_ == 0 && !dragged_) (void)pick(cursorX_, cursorY_);
        button_ = -1;
      }
      break;
    case Type::CursorMove: {
      const double dx = event.x - cursorX_, dy = event.y - cursorY_;
      cursorX_ = event.x;
      cursorY_ = event.y;
      if (button_ >= 0) {
        if (std::hypot(cursorX_ - pressX_, cursorY_ - pressY_) >= 3.0) dragged_ = true;
        if (dragged_) drag(dx, dy, button_);
      } else {
        active_ = viewportAt(cursorX_);
      }
      break;
    }
    case Type::Scroll: {
      ViewportState& s = viewports_[active_].state;
      if (s.sceneCamera >= 0) break;
      const double factor = std::pow(0.85, event.y);
      if (s.fly)  // the look-at point nearer: slower steps
        s.target = s.eye + (s.target - s.eye) * factor;
      else
        s.eye = s.target + (s.eye - s.target) * factor;
      break;
    }
  }
}

void Viewer::draw(int width, int height) {
  stepHeldKeys();
  // Keys pressed and released within one batch of events still move one step.
  for (const int k : released_) held_.erase(k);
  released_.clear();
  fresh_.clear();
  width = std::max(width, 2);
  height = std::max(height, 1);
  if (!image_ || image_->width() != width || image_->height() != height)
    image_ = std::make_unique<gl::RenderTarget>(width, height);
  viewports_[0].x = 0;
  viewports_[0].width = split_ ? width / 2 : width;
  viewports_[1].x = width / 2;
  viewports_[1].width = width - width / 2;
  image_->clear(kSpace);
  vertices_ = 0;
  for (std::size_t k = 0; k < (split_ ? 2U : 1U); ++k) {
    Viewport& v = viewports_[k];
    v.height = height;
    if (!v.target || v.target->width() != v.width || v.target->height() != v.height)
      v.target = std::make_unique<gl::RenderTarget>(v.width, v.height);
    const scenegraph::NodeId camera = shownCamera(k);
    const scenegraph::NodeId focus = scene_.objects[v.state.object].node;
    const render::SceneView view = viewOf(k);
    v.target->clear(kSpace);
    const scenegraph::RenderList list = scene_.graph->renderList(focus, camera);
    // Each viewport in its own slot: its own clipmaps, which the other's camera never moves.
    renderer_->prepare(list, view, loading_, k);
    // The far fields too (their PGM grids counted in the vertices), in this viewport's slot.
    const render::SceneFrame frame = renderer_->draw(list, view, v.target.get(), k);
    vertices_ += frame.vertices;
    glBlitNamedFramebuffer(v.target->framebuffer(), image_->framebuffer(), 0, 0, v.width, v.height,
                           v.x, 0, v.x + v.width, v.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  if (split_) {  // a divider
    glEnable(GL_SCISSOR_TEST);
    image_->bind();
    glScissor(viewports_[1].x - 1, 0, 2, height);
    glClearColor(0.5F, 0.5F, 0.55F, 1.0F);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);
  }
  if (scene_.cache) {
    const std::uint64_t loads = scene_.cache->stats().loads;
    loadsFrame_ = loads - loads_;
    loads_ = loads;
  }
  updateHud();
  if (hudOn_) hud_.draw(hudLines_, *image_);
}

void Viewer::updateHud() {
  char buf[256];
  hudLines_.clear();
  std::snprintf(buf, sizeof buf, "FRAME %.1f MS  VERTICES %zu  PATCHES LOADED +%llu", frameMs_,
                vertices_, static_cast<unsigned long long>(loadsFrame_));
  std::string first = buf;
  if (scene_.cache) {
    const store::CacheStats st = scene_.cache->stats();
    std::snprintf(buf, sizeof buf, "  CACHE %.1f/%.0f MB (%zu PATCHES)",
                  static_cast<double>(st.residentBytes) / 1048576.0,
                  static_cast<double>(st.capacityBytes) / 1048576.0, st.residentPatches);
    first += buf;
  }
  hudLines_.push_back(first);
  for (std::size_t k = 0; k < (split_ ? 2U : 1U); ++k) {
    const ViewportState& s = viewports_[k].state;
    const std::string camera = s.sceneCamera >= 0
                                   ? scene_.cameras[static_cast<std::size_t>(s.sceneCamera)].name
                                   : (s.fly ? "FREE, FLY" : "FREE, ORBIT");
    std::snprintf(buf, sizeof buf, "VIEW %zu%s: FOCUS %s  CAMERA %s  %.4g KM FROM TARGET", k + 1,
                  k == active_ ? "*" : "", scene_.objects[s.object].name.c_str(), camera.c_str(),
                  glm::length(s.eye - s.target) / 1000.0);
    hudLines_.push_back(buf);
  }
  std::string effects = "EFFECTS";
  for (std::size_t i = 0; i < toggles_.size() && i < 9; ++i) {
    const auto& [t, name] = toggles_[i];
    if (i > 0 && i % 3 == 0) {
      hudLines_.push_back(effects);
      effects = "       ";
    }
    effects += "  " + std::to_string(i + 1) + " " + scene_.terrains[t].name + " " + name +
               (off_[t].contains(name) ? " OFF" : " ON");
  }
  hudLines_.push_back(toggles_.empty() ? "EFFECTS NONE DECLARED" : effects);
  hudLines_.push_back(pickLine_);
  hudLines_.push_back(
      "DRAG ORBIT/LOOK  RIGHT DRAG PAN  WHEEL ZOOM  WASDQE MOVE  F FLY  TAB FOCUS  1-9 EFFECTS");
  hudLines_.push_back(
      "V SPLIT  C CAMERA  G FRAME  L SUN BEHIND  R RESET  CLICK PICK  P SCREENSHOT  H HUD  ESC");
  for (std::string& l : hudLines_) l = upper(l);
}

Pick Viewer::pick(double x, double y) {
  Pick p;
  p.x = static_cast<int>(std::floor(x));
  p.y = static_cast<int>(std::floor(y));
  const std::size_t k = viewportAt(x);
  Viewport& v = viewports_[k];
  const int px = p.x - v.x, py = p.y;
  if (v.target && px >= 0 && py >= 0 && px < v.width && py < v.height) {
    float depth = 0.0F;
    glGetTextureSubImage(v.target->depthTexture(), 0, px, v.height - 1 - py, 0, 1, 1, 1,
                         GL_DEPTH_COMPONENT, GL_FLOAT, sizeof depth, &depth);
    if (depth > 0.0F) {
      const scenegraph::NodeId camera = shownCamera(k);
      const scenegraph::NodeId focus = scene_.objects[v.state.object].node;
      const render::SceneView view = viewOf(k);
      const clod::Camera cam = render::cameraInItem(scene_.graph->relative(focus, camera), view);
      // The pixel's centre, at the depth it holds, in double.
      const glm::dvec3 ray = cam.ray(px + 0.5, py + 0.5);
      const double along = cam.viewDistance(static_cast<double>(depth));
      const glm::dvec3 point = cam.position + ray * (along / glm::dot(ray, cam.forward()));
      p.hit = true;
      p.distance = glm::length(point - cam.position);
      // The dataset: the terrain of highest priority whose grid holds the point.
      const ViewTerrain* best = nullptr;
      glm::dvec3 inBest(0.0);
      for (const ViewTerrain& t : scene_.terrains) {
        const glm::dvec3 q = scene_.graph->relative(t.node, focus).apply(point);
        const glm::dvec2 g = t.pyramid->gridPoint(q);
        const bool holds = t.pyramid->kind() == clod::SurfaceKind::Planet ||
                           t.pyramid->level(0).grid.contains(g.x, g.y);
        if (holds && (best == nullptr || t.pickPriority > best->pickPriority)) {
          best = &t;
          inBest = q;
        }
      }
      p.dataset = best ? best->name : "?";
      if (scene_.bodyGrid) {
        const glm::dvec3 q = scene_.graph->relative(scene_.bodyNode, focus).apply(point);
        const glm::dvec2 g = scene_.bodyGrid->gridPoint(q);
        p.lonLat = true;
        p.a = g.x;
        p.b = g.y;
        p.height = scene_.bodyGrid->body()->toGeodetic(q).height;
        // The pixel's ray in the body frame, for an outside check (a ray/terrain
        // intersection in double: tests/tools/test_viewer.py).
        const scenegraph::Pose toBody = scene_.graph->relative(scene_.bodyNode, focus);
        const glm::dvec3 eye = toBody.apply(cam.position), dir = toBody.applyVector(ray);
        char line[256];
        std::snprintf(line, sizeof line,
                      "pick ray in the body frame: eye %.17g %.17g %.17g dir %.17g %.17g %.17g",
                      eye.x, eye.y, eye.z, dir.x, dir.y, dir.z);
        log_ << line << '\n';
      } else if (best) {
        const glm::dvec2 g = best->pyramid->gridPoint(inBest);
        p.a = g.x;
        p.b = g.y;
        p.height = best->pyramid->placement() ? best->pyramid->placement()->fromBodyFixed(inBest).z
                                              : inBest.z;
      }
    }
  }
  log_ << p.text() << std::endl;
  char buf[160];
  if (!p.hit) {
    std::snprintf(buf, sizeof buf, "PICK %d %d: NOTHING", p.x, p.y);
  } else {
    std::snprintf(buf, sizeof buf, "PICK %s %.5f %s %.5f  HEIGHT %.1f M  %s",
                  p.lonLat ? "LON" : "X", p.a, p.lonLat ? "LAT" : "Y", p.b, p.height,
                  p.dataset.c_str());
  }
  pickLine_ = buf;
  return p;
}

void Viewer::screenshot(const std::string& path) {
  gl::writePng(path, image_->readColor());
  log_ << "screenshot " << path << " (" << image_->width() << "x" << image_->height() << ")"
       << std::endl;
}

}  // namespace regolith::tools::viewer
