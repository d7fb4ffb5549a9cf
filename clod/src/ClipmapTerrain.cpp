#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Assert.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>

#include "ClipmapEffectState.hpp"
#include "ClipmapLevel.hpp"
#include "CutOutShader.hpp"
#include "EffectShaders.hpp"
#include "Shaders.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <mutex>
#include <numbers>
#include <optional>
#include <string>
#include <thread>

namespace regolith::clod {

namespace {

// What a camera can see, for whole-level culling (ClipmapOptions::cullLevels): its frustum's
// near and four side planes (infinite far plane), and on a planet the sphere that hides what
// lies behind the horizon.
class LevelCull {
 public:
  LevelCull(const Camera& camera, double occluderRadius) : eye_(camera.position) {
    const glm::dmat3 rot = camera.rotation();  // rows: right, up, -forward
    const glm::dvec3 right(rot[0][0], rot[1][0], rot[2][0]);
    const glm::dvec3 up(rot[0][1], rot[1][1], rot[2][1]);
    forward_ = -glm::dvec3(rot[0][2], rot[1][2], rot[2][2]);
    near_ = camera.near;
    const double ty = std::tan(0.5 * camera.fovYDegrees * std::numbers::pi / 180.0);
    const double tx = ty * static_cast<double>(camera.width) / static_cast<double>(camera.height);
    // A direction f + x·right + y·up is in view for |x| ≤ tx, |y| ≤ ty: inward normals.
    sides_ = {glm::normalize(right + tx * forward_), glm::normalize(-right + tx * forward_),
              glm::normalize(up + ty * forward_), glm::normalize(-up + ty * forward_)};
    const double d = glm::length(eye_);
    if (occluderRadius > 0.0 && d > occluderRadius) {
      horizon_ = true;
      toEye_ = eye_ / d;
      horizonPlane_ = occluderRadius * occluderRadius / d;
      coneHalfAngle_ = std::asin(occluderRadius / d);
    }
  }

  // True if nothing within `radius` of `centre` can be seen.
  [[nodiscard]] bool hidden(const glm::dvec3& centre, double radius) const {
    const glm::dvec3 v = centre - eye_;
    if (glm::dot(v, forward_) - near_ < -radius) return true;
    for (const glm::dvec3& n : sides_)
      if (glm::dot(v, n) < -radius) return true;
    if (!horizon_) return false;
    // Wholly beyond the plane of the horizon circle and wholly inside the cone of rays that
    // meet the occluder: every ray to it enters the occluder first (the occluder's near cap
    // lies in front of that plane).
    if (glm::dot(centre, toEye_) + radius >= horizonPlane_) return false;
    const double dist = glm::length(v);
    if (dist <= radius) return false;
    const double toCentre = std::acos(std::clamp(glm::dot(v, -toEye_) / dist, -1.0, 1.0));
    return toCentre + std::asin(radius / dist) <= coneHalfAngle_;
  }

 private:
  glm::dvec3 eye_, forward_{0.0};
  double near_ = 0.0;
  std::array<glm::dvec3, 4> sides_{};
  bool horizon_ = false;
  glm::dvec3 toEye_{0.0};
  double horizonPlane_ = 0.0, coneHalfAngle_ = 0.0;
};

}  // namespace

gl::ShaderSources ClipmapTerrain::bareSources() {
  return gl::ShaderSources{shaders::kClipmapVertex, shaders::kDropNodataGeometry,
                           shaders::kLitFragment};
}

gl::ShaderSources ClipmapTerrain::programSourcesFor(const ClipmapOptions& options, bool planet) {
  gl::ShaderSources s = composeClipmapSources(options.effects, planet);
  // Scene graph: the cut-out test (CutOutShader.hpp) only where a DEM may win over this
  // terrain; inert until setCutOuts() names a DEM.
  if (options.cutOuts) s.fragment = shaders::withCutOuts(s.fragment);
  return s;
}

struct ClipmapTerrain::Job {
  std::size_t level = 0;
  ClipmapLevel::Plan plan;
  std::exception_ptr error;  // a failed read, rethrown by update() on the render thread
};

// The background loader: a queue served coarsest level first by one task at a time on the
// executor (so reads keep the order a single worker gave them), and the finished plans
// waiting for the render thread to upload them.
struct ClipmapTerrain::Loader {
  std::mutex mutex;
  std::condition_variable done;
  std::vector<Job> queue, finished;
  std::vector<bool> busy;  // per level: a job queued, running or finished, not yet applied
  std::optional<glm::dvec3> target;
  bool draining = false;  // a drain task is submitted or running
  std::shared_ptr<core::Executor> executor;
};

ClipmapTerrain::ClipmapTerrain(std::shared_ptr<const HeightPyramid> pyramid, ClipmapOptions options)
    : pyramid_(std::move(pyramid)),
      options_(std::move(options)),
      sources_(programSourcesFor(options_, pyramid_ && pyramid_->kind() == SurfaceKind::Planet)),
      program_("clipmap", sources_) {
  if (!pyramid_) throw InvalidArgument("ClipmapTerrain(): pyramid is null");
  const int n = options_.size;
  if (n < 15 || n > 2047 || n % 2 == 0)
    throw InvalidArgument("ClipmapTerrain(): size " + std::to_string(n) +
                          ", expected an odd number of vertices in 15..2047");
  // On a planet a level's triangles are chords: past ~3° a cell sags a kilometre or more
  // below a Mars-sized surface, and a window wider than a full meridian circle folds back over
  // itself.
  std::size_t usable = pyramid_->levelCount();
  if (pyramid_->kind() == SurfaceKind::Planet) {
    usable = 0;
    while (usable < pyramid_->levelCount()) {
      const double dy = pyramid_->level(usable).grid.spacingY();
      if (dy > 3.0 || (n - 1) * dy > 360.0) break;
      ++usable;
    }
    if (usable == 0)
      throw InvalidArgument(
          "ClipmapTerrain(): the planet's finest level has spacing " +
          std::to_string(pyramid_->level(0).grid.spacingY()) + "° and the window (size − 1) × " +
          "spacing is " +
          std::to_string(static_cast<double>(n - 1) * pyramid_->level(0).grid.spacingY()) +
          "°; expected a spacing of at most 3° and a window of at most 360° (use a smaller size)");
  }
  // A level whose half-window spans the whole grid covers it from any focus on it: coarser
  // levels would add nothing but vertices.
  std::size_t covering = usable;
  for (std::size_t k = 0; k < usable; ++k) {
    const auto& g = pyramid_->level(k).grid;
    const auto halfCells = static_cast<std::size_t>((n - 1) / 2);
    if (halfCells >= std::max(g.rows(), g.cols())) {
      covering = k + 1;
      break;
    }
  }
  const std::size_t count = options_.levels == 0 ? covering : options_.levels;
  if (count > usable)
    throw InvalidArgument("ClipmapTerrain(): " + std::to_string(count) +
                          " levels asked for, the pyramid has " + std::to_string(usable) +
                          " usable (" + std::to_string(pyramid_->levelCount()) + " in all)");
  for (std::size_t k = 0; k < count; ++k)
    levels_.push_back(std::make_unique<ClipmapLevel>(*pyramid_, k, n));
  // The finer level spans (n−1)/4 of this level's cells each side of its centre, which may
  // sit up to 0.75 cell off this level's centre; one more cell of overlap for safety.
  hole_ = static_cast<int>(std::floor((n - 1) / 4.0 - 0.75)) - 1;
  buildMesh();
  initEffects();
}

ClipmapTerrain::~ClipmapTerrain() {
  if (loader_) {
    // The drain task reads this terrain's levels: wait until it has returned. Jobs still
    // queued are dropped first, so it stops after the one it is reading.
    std::unique_lock lock(loader_->mutex);
    loader_->queue.clear();
    loader_->done.wait(lock, [&] { return !loader_->draining; });
  }
}

int ClipmapTerrain::polarFor(const glm::dvec2& g) const {
  // Planets: within 40° of a pole every level uses a polar stereographic lattice about it,
  // elsewhere latitude/longitude rows and columns. All levels switch together, so a finer
  // level's window always covers the hole of the next coarser one in the same lattice.
  if (pyramid_->kind() == SurfaceKind::Planet && std::abs(g.y) > 50.0) return g.y > 0 ? 1 : -1;
  return 0;
}

void ClipmapTerrain::requestFocus(const glm::dvec3& focus) {
  if (!loader_) {
    loader_ = std::make_unique<Loader>();
    loader_->busy.assign(levels_.size(), false);
    loader_->executor =
        options_.executor ? options_.executor : std::make_shared<core::ThreadPool>(1);
  }
  {
    const std::lock_guard lock(loader_->mutex);
    loader_->target = focus;
  }
  updateEffects(focus, true);
  schedule();
}

void ClipmapTerrain::schedule() {
  std::unique_lock lock(loader_->mutex);
  if (!loader_->target) return;
  const glm::dvec2 g = pyramid_->gridPoint(*loader_->target);
  const int polar = polarFor(g);
  bool any = false;
  for (std::size_t k = levels_.size(); k-- > 0;) {
    if (loader_->busy[k]) continue;
    ClipmapLevel::Plan plan = levels_[k]->plan(g.x, g.y, polar);
    if (plan.empty()) continue;
    loader_->busy[k] = true;
    loader_->queue.push_back(Job{k, std::move(plan), nullptr});
    any = true;
  }
  if (!any || loader_->draining) return;
  loader_->draining = true;
  lock.unlock();
  loader_->executor->submit([this] { drainQueue(); });
}

void ClipmapTerrain::drainQueue() {
  Loader& L = *loader_;
  std::unique_lock lock(L.mutex);
  while (!L.queue.empty()) {
    // Coarsest level first: it covers the most ground and the finer ones wait for it anyway.
    auto it = std::max_element(L.queue.begin(), L.queue.end(),
                               [](const Job& a, const Job& b) { return a.level < b.level; });
    Job job = std::move(*it);
    L.queue.erase(it);
    lock.unlock();
    const ClipmapLevel& level = *levels_[job.level];
    try {
      level.fetch(job.plan);
      level.prefetch(job.plan, options_.prefetchMargin);
    } catch (...) {
      job.error = std::current_exception();
    }
    lock.lock();
    L.finished.push_back(std::move(job));
    L.done.notify_all();
  }
  L.draining = false;
  L.done.notify_all();
}

std::size_t ClipmapTerrain::update(bool wait) {
  if (!loader_) return 0;
  std::vector<Job> ready;
  {
    std::unique_lock lock(loader_->mutex);
    if (wait) {
      const bool running =
          std::any_of(loader_->busy.begin(), loader_->busy.end(), [](bool b) { return b; });
      if (running) loader_->done.wait(lock, [&] { return !loader_->finished.empty(); });
    }
    ready.swap(loader_->finished);
  }
  // Coarse first, as loaded.
  std::sort(ready.begin(), ready.end(),
            [](const Job& a, const Job& b) { return a.level > b.level; });
  {
    const std::lock_guard lock(loader_->mutex);
    for (const Job& job : ready) loader_->busy[job.level] = false;
  }
  std::size_t count = 0;
  for (const Job& job : ready) {
    if (job.error) std::rethrow_exception(job.error);  // e.g. a store read that failed
    count += levels_[job.level]->apply(job.plan);
  }
  if (effects_) (void)pollEffects(wait && ready.empty());  // texture windows: counted apart
  uploaded_ += count;
  schedule();
  return count;
}

bool ClipmapTerrain::loading() const {
  if (!loader_) return false;
  if (effects_ && effectsLoading()) return true;
  const std::lock_guard lock(loader_->mutex);
  return std::any_of(loader_->busy.begin(), loader_->busy.end(), [](bool b) { return b; });
}

std::size_t ClipmapTerrain::finishLoading() {
  std::size_t count = 0;
  while (loading()) count += update(true);
  return count;
}

std::vector<bool> ClipmapTerrain::residentLevels() const {
  std::vector<bool> out;
  for (const auto& l : levels_) out.push_back(l->valid());
  return out;
}

std::size_t ClipmapTerrain::firstConsistent() const {
  // The coarsest resident level, extended inward while each finer level is resident and
  // covers the next one's hole.
  std::size_t k = levels_.size();
  while (k > 0 && levels_[k - 1]->valid() &&
         (k == levels_.size() || levels_[k - 1]->covers(*levels_[k], hole_)))
    --k;
  return k;
}

void ClipmapTerrain::setOptions(const ClipmapOptions& options) {
  if (options.size != options_.size || options.levels != options_.levels)
    throw InvalidArgument(
        "ClipmapTerrain::setOptions(): size and levels are fixed at "
        "construction");
  const auto sameTexture = [](const std::optional<DrapedTexture>& a,
                              const std::optional<DrapedTexture>& b) {
    return a.has_value() == b.has_value() &&
           (!a || (a->channels == b->channels && a->window == b->window));
  };
  if (options.effects.declared() != options_.effects.declared() ||
      options.cutOuts != options_.cutOuts || options.effects.tracks != options_.effects.tracks ||
      options.trackWindow != options_.trackWindow ||
      !sameTexture(options.effects.albedo, options_.effects.albedo) ||
      !sameTexture(options.effects.overlay, options_.effects.overlay))
    throw InvalidArgument(
        "ClipmapTerrain::setOptions(): the declared effects (and their track layer and "
        "textures) are fixed at construction; build a new terrain to change them");
  options_ = options;
}

void ClipmapTerrain::buildMesh() {
  const int n = options_.size;
  std::vector<std::int32_t> verts;
  verts.reserve(static_cast<std::size_t>(n * n + 4 * (n - 1)) * 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) verts.insert(verts.end(), {i, j, 0});
  // Perimeter loop: top row →, right column ↓, bottom row ←, left column ↑.
  std::vector<std::array<int, 2>> perimeter;
  perimeter.reserve(4 * static_cast<std::size_t>(n - 1));
  for (int i = 0; i < n - 1; ++i) perimeter.push_back({i, 0});
  for (int j = 0; j < n - 1; ++j) perimeter.push_back({n - 1, j});
  for (int i = n - 1; i > 0; --i) perimeter.push_back({i, n - 1});
  for (int j = n - 1; j > 0; --j) perimeter.push_back({0, j});
  for (const auto& p : perimeter) verts.insert(verts.end(), {p[0], p[1], 1});

  const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * n + i); };
  const int m = (n - 1) / 2;
  const auto inHole = [&](int i, int j) {
    return i >= m - hole_ && i < m + hole_ && j >= m - hole_ && j < m + hole_;
  };
  std::vector<std::uint32_t> hole, ring, skirt;
  for (int j = 0; j < n - 1; ++j)
    for (int i = 0; i < n - 1; ++i) {
      auto& out = inHole(i, j) ? hole : ring;
      // Same diagonal as the brute-force strips: (i, j+1)–(i+1, j).
      out.insert(out.end(), {at(i, j), at(i, j + 1), at(i + 1, j)});
      out.insert(out.end(), {at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
    }
  const auto base = static_cast<std::uint32_t>(n * n);
  const auto np = static_cast<std::uint32_t>(perimeter.size());
  for (std::uint32_t k = 0; k < np; ++k) {
    const std::uint32_t k1 = (k + 1) % np;
    const std::uint32_t t0 = at(perimeter[k][0], perimeter[k][1]);
    const std::uint32_t t1 = at(perimeter[k1][0], perimeter[k1][1]);
    skirt.insert(skirt.end(), {t0, t1, base + k, t1, base + k1, base + k});
  }
  holeIndices_ = hole.size();
  ringIndices_ = ring.size();
  skirtIndices_ = skirt.size();
  std::vector<std::uint32_t> all;
  all.reserve(hole.size() + ring.size() + skirt.size());
  all.insert(all.end(), hole.begin(), hole.end());
  all.insert(all.end(), ring.begin(), ring.end());
  all.insert(all.end(), skirt.begin(), skirt.end());

  glNamedBufferStorage(vertices_.id(), static_cast<GLsizeiptr>(verts.size() * sizeof(std::int32_t)),
                       verts.data(), 0);
  glNamedBufferStorage(indices_.id(), static_cast<GLsizeiptr>(all.size() * sizeof(std::uint32_t)),
                       all.data(), 0);
  glVertexArrayVertexBuffer(vao_.id(), 0, vertices_.id(), 0, 3 * sizeof(std::int32_t));
  glVertexArrayElementBuffer(vao_.id(), indices_.id());
  glEnableVertexArrayAttrib(vao_.id(), 0);
  glVertexArrayAttribIFormat(vao_.id(), 0, 3, GL_INT, 0);
  glVertexArrayAttribBinding(vao_.id(), 0, 0);
  gl::checkGl("ClipmapTerrain::buildMesh()");
}

std::size_t ClipmapTerrain::setFocus(const glm::dvec3& focus) {
  if (loader_ && loading())
    throw InvalidArgument(
        "ClipmapTerrain::setFocus(): background loading is running; call "
        "finishLoading() first or keep using requestFocus()");
  const glm::dvec2 g = pyramid_->gridPoint(focus);
  const int polar = polarFor(g);
  std::size_t count = 0;
  for (auto& level : levels_) count += level->moveTo(g.x, g.y, polar);
  uploaded_ += count;
  updateEffects(focus);
  return count;
}

std::pair<long long, long long> ClipmapTerrain::windowOrigin(std::size_t level) const {
  const auto& l = *levels_.at(level);
  return {l.row0(), l.col0()};
}

std::pair<std::size_t, std::size_t> ClipmapTerrain::activeLevels(const Camera& camera) const {
  const std::size_t count = levels_.size();
  const std::size_t consistent = firstConsistent();
  if (consistent == count) return {count, 0};  // nothing resident yet
  std::size_t first = count - 1;
  const double focal = camera.focalPixels();
  const double half = 0.5 * (options_.size - 1);
  for (std::size_t k = 0; k + 1 < count; ++k) {
    const auto& l = *levels_[k];
    if (!l.valid()) continue;
    const double cell = l.cellMetres();
    const double mid = 0.5 * static_cast<double>(l.minHeight() + l.maxHeight());
    const glm::dvec3 c = l.centre() + pyramid_->up(l.centre()) * mid;
    const double radius = half * cell * std::sqrt(2.0);
    const double d = std::max(glm::length(camera.position - c) - radius, 0.0);
    if (d == 0.0 || cell * focal / d >= options_.minCellPixels) {
      first = k;
      break;
    }
  }
  first = std::max(first, consistent);
  return {first, count - first};
}

ClipmapFrame ClipmapTerrain::draw(const Camera& camera) const {
  ClipmapFrame frame;
  const auto [first, count] = activeLevels(camera);
  frame.firstLevel = first;
  program_.use();
  program_.set("uViewProj", camera.viewProjection());
  program_.set("uN", options_.size);
  program_.set("uPlanet", pyramid_->kind() == SurfaceKind::Planet ? 1 : 0);
  program_.set("uLight", glm::normalize(options_.lightDirection));
  program_.set("uAlbedo", options_.albedo);
  program_.set("uAmbient", options_.ambient);
  if (effects_) setEffectUniforms(camera, frame);
  if (options_.cutOuts) setCutOutUniforms(camera);
  glBindVertexArray(vao_.id());
  glDisable(GL_CULL_FACE);
  // The occluder on a planet: a sphere under every height the levels hold (and the body's
  // polar radius), lowered by 0.5 % of the radius for the other terrains drawn with it.
  std::optional<LevelCull> cull;
  if (options_.cullLevels) {
    double occluder = 0.0;
    if (pyramid_->kind() == SurfaceKind::Planet) {
      double lowest = 0.0;
      for (const auto& l : levels_)
        if (l->valid()) lowest = std::min(lowest, static_cast<double>(l->minHeight()));
      const double polar = pyramid_->body()->polarRadius();
      occluder = std::max(polar + lowest - 0.005 * polar, 0.0);
    }
    cull.emplace(camera, occluder);
  }
  for (std::size_t k = first; k < first + count; ++k) {
    const auto& l = *levels_[k];
    if (!l.valid()) continue;
    // Skirts reach below the lowest sample of this level and of the next coarser one.
    float lo = l.minHeight(), hi = l.maxHeight();
    if (k + 1 < levels_.size()) {
      lo = std::min(lo, levels_[k + 1]->minHeight());
      hi = std::max(hi, levels_[k + 1]->maxHeight());
    }
    // On a planet add the sag of a chord across a coarse cell (c²/8R), so the skirt also
    // reaches below the next level's flat triangles.
    const double cell = l.cellMetres();
    double sag = 0.0;
    if (pyramid_->kind() == SurfaceKind::Planet) {
      const double c2 = 2.0 * cell;
      sag = c2 * c2 / (8.0 * pyramid_->body()->polarRadius());
    }
    const double skirt = static_cast<double>(hi - lo) + sag + 0.1 * cell;
    if (cull) {
      // The skirt hangs `skirt` metres below each sample (radially on a planet).
      const ClipmapLevel::Bound b = l.bound(skirt);
      if (cull->hidden(b.centre, b.radius)) {
        ++frame.levelsCulled;
        continue;
      }
    }
    program_.set("uOrigin", glm::ivec2(l.texelX(0), l.texelY(0)));
    program_.set("uAnchorRel", glm::vec3(l.anchor() - camera.position));
    program_.set("uAnchorFromCentre", glm::vec3(l.anchor()));
    program_.set("uUp", glm::vec3(pyramid_->up(l.anchor())));
    program_.set("uSkirtDepth", static_cast<float>(skirt));
    glm::vec4 finer(0.0F, 0.0F, -1.0F, -1.0F);  // empty
    if (k > first) finer = glm::vec4(levels_[k - 1]->footprintIn(l));
    program_.set("uFinerRect", finer);
    program_.set("uDepthPush", options_.overlapDepthPush);
    if (effects_) setLevelUniforms(k);
    glBindTextureUnit(0, l.texture());
    ++frame.textureBinds;
    const std::size_t start = k == first ? 0 : holeIndices_;
    const std::size_t n = holeIndices_ + ringIndices_ + skirtIndices_ - start;
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(n), GL_UNSIGNED_INT,
                   // GL takes offsets into the bound index buffer as pointers.
                   // NOLINTNEXTLINE(performance-no-int-to-ptr)
                   reinterpret_cast<const void*>(start * sizeof(std::uint32_t)));
    frame.vertices += n;
    ++frame.levelsDrawn;
  }
  glBindVertexArray(0);
  gl::checkGl("ClipmapTerrain::draw()");
  return frame;
}

// The public bound and the shader's arrays are one number.
static_assert(kMaxClipmapCutOuts == static_cast<std::size_t>(shaders::kMaxCutOuts));

glm::dvec3 cutOutProjection(double near, double fovYDegrees, int width, int height) {
  const double f = 1.0 / std::tan(0.5 * fovYDegrees * std::numbers::pi / 180.0);
  const double aspect = static_cast<double>(width) / height;
  return {near, aspect / f, 1.0 / f};
}

void ClipmapTerrain::setCutOuts(std::span<const ClipmapCutOut> cutOuts,
                                const glm::ivec2& viewportOrigin) {
  REGOLITH_ASSERT(
      options_.cutOuts || cutOuts.empty(),
      "ClipmapTerrain::setCutOuts(): the terrain has no cut-out test (options.cutOuts)");
  REGOLITH_ASSERT(cutOuts.size() <= static_cast<std::size_t>(shaders::kMaxCutOuts),
                  "ClipmapTerrain::setCutOuts(): more cut-outs than the shader holds");
  REGOLITH_ASSERT(std::all_of(cutOuts.begin(), cutOuts.end(),
                              [](const ClipmapCutOut& c) { return c.mask != nullptr; }),
                  "ClipmapTerrain::setCutOuts(): a cut-out without its mask");
  cutOuts_.assign(cutOuts.begin(), cutOuts.end());
  cutViewportOrigin_ = viewportOrigin;
}

// The cut-out test's uniforms (CutOutShader.hpp): per DEM the eye → cell map and its mask on
// texture units kCutOutFirstUnit + i, the count, the viewport and the projection.
void ClipmapTerrain::setCutOutUniforms(const Camera& camera) const {
  static constexpr std::array<const char*, 4> kEyeToCell{"uCutEyeToCell[0]", "uCutEyeToCell[1]",
                                                         "uCutEyeToCell[2]", "uCutEyeToCell[3]"};
  static constexpr std::array<const char*, 4> kCellOfCamera{
      "uCutCellOfCamera[0]", "uCutCellOfCamera[1]", "uCutCellOfCamera[2]", "uCutCellOfCamera[3]"};
  static_assert(kEyeToCell.size() == static_cast<std::size_t>(shaders::kMaxCutOuts));
  for (std::size_t i = 0; i < cutOuts_.size(); ++i) {
    const ClipmapCutOut& c = cutOuts_[i];
    program_.set(kEyeToCell.at(i), glm::mat3(c.transform.eyeToCell));
    program_.set(kCellOfCamera.at(i), glm::vec3(c.transform.cellOfCamera));
    glBindTextureUnit(static_cast<GLuint>(shaders::kCutOutFirstUnit) + static_cast<GLuint>(i),
                      c.mask->id());
  }
  program_.set("uCutCount", static_cast<int>(cutOuts_.size()));
  program_.set(
      "uCutViewport",
      glm::vec4(static_cast<float>(cutViewportOrigin_.x), static_cast<float>(cutViewportOrigin_.y),
                static_cast<float>(camera.width), static_cast<float>(camera.height)));
  program_.set("uCutProj", glm::vec3(cutOutProjection(camera.near, camera.fovYDegrees, camera.width,
                                                      camera.height)));
}

}  // namespace regolith::clod
