// ClipmapTerrain's declared effects: validation, per-focus updates and per-frame uniforms.
// Kept apart from ClipmapTerrain.cpp so the bare pipeline reads as before.

#include <regolith/clod/ClipmapTerrain.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/rover/TrackLayer.hpp>

#include "ClipmapEffectState.hpp"
#include "ClipmapLevel.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace regolith::clod {

std::vector<std::string> Effects::declared() const { return clod::declaredEffectNames(*this); }

glm::vec3 heightColour(const HeightColours& c, double h) noexcept {
  const double t = std::clamp((h - static_cast<double>(c.minHeight)) /
                                  static_cast<double>(c.maxHeight - c.minHeight),
                              0.0, 1.0) *
                   4.0;
  const int k = std::min(static_cast<int>(std::floor(t)), 3);
  const auto f = static_cast<float>(t - k);
  const auto uk = static_cast<std::size_t>(k);
  return kHeightRamp[uk] * (1.0F - f) + kHeightRamp[uk + 1] * f;
}

namespace {

const topo::Body* bodyOf(const HeightPyramid& p) {
  if (p.kind() == SurfaceKind::Planet && p.body()) return &*p.body();
  if (p.placement()) return &p.placement()->body();
  return nullptr;
}

topo::LatitudeType latitudeTypeOf(const HeightPyramid& p) {
  if (p.placement()) return p.placement()->latitudeType();
  return p.latitudeType();
}

}  // namespace

void ClipmapTerrain::initEffects() {
  const Effects& e = options_.effects;
  if (e.declared().empty()) return;
  if (e.latLon && bodyOf(*pyramid_) == nullptr)
    throw InvalidArgument(
        "ClipmapTerrain(): effects.latLon: a plane DEM without placement has no latitude "
        "or longitude; place it on a body (HeightPyramid with a topo::Placement)");
  if (e.latLon && !(e.latLon->spacingDegrees >= 0.0 && e.latLon->minPixelSpacing > 0.0))
    throw InvalidArgument("ClipmapTerrain(): effects.latLon: spacing " +
                          std::to_string(e.latLon->spacingDegrees) + "°, min pixel spacing " +
                          std::to_string(e.latLon->minPixelSpacing) + ", expected ≥ 0 and > 0");
  if (e.tracks && pyramid_->kind() == SurfaceKind::Planet)
    throw InvalidArgument(
        "ClipmapTerrain(): effects.tracks: a planet's grid is longitude/latitude; tracks "
        "need a metric grid (a plane DEM or a DEM placed on the planet)");
  if (e.tracks && (options_.trackWindow < 256 || options_.trackWindow > 8192))
    throw InvalidArgument("ClipmapTerrain(): trackWindow " + std::to_string(options_.trackWindow) +
                          ", expected 256..8192");
  if (e.noise && (e.noise->octaves < 1 || e.noise->octaves > 8 || !(e.noise->wavelength > 0.0)))
    throw InvalidArgument("ClipmapTerrain(): effects.noise: " + std::to_string(e.noise->octaves) +
                          " octaves, wavelength " + std::to_string(e.noise->wavelength) +
                          ", expected 1..8 and > 0");
  if (e.heightColours && !(e.heightColours->maxHeight > e.heightColours->minHeight))
    throw InvalidArgument("ClipmapTerrain(): effects.heightColours: range [" +
                          std::to_string(e.heightColours->minHeight) + ", " +
                          std::to_string(e.heightColours->maxHeight) + "] m, expected min < max");
  effects_ = std::make_unique<EffectState>();
  effects_->needs = EffectNeeds::of(e, pyramid_->kind() == SurfaceKind::Planet);
  if (e.albedo) {
    effects_->albedo =
        std::make_unique<TextureClipmap>(*e.albedo, "effects.albedo", options_.executor);
  }
  if (e.overlay) {
    effects_->overlay =
        std::make_unique<TextureClipmap>(*e.overlay, "effects.overlay", options_.executor);
  }
  if (e.tracks) {
    const int n = options_.trackWindow;
    GLuint id = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &id);
    effects_->tracks = gl::Texture(id);
    glTextureStorage2D(id, 1, GL_R32F, n, n);
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
    glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
    effects_->trackWindow = n;
    gl::checkGl("ClipmapTerrain(): track texture");
  }
}

void ClipmapTerrain::updateEffects(const glm::dvec3& focus, bool background) {
  gridOrigin_ = pyramid_->gridPoint(focus);
  if (!effects_) return;
  updateGround(background);
  for (TextureClipmap* t : {effects_->albedo.get(), effects_->overlay.get()}) {
    if (t == nullptr) continue;
    if (background)
      t->request(gridOrigin_);
    else
      (void)t->update(gridOrigin_);
  }
}

std::size_t ClipmapTerrain::pollEffects(bool wait) {
  std::size_t count = 0;
  for (TextureClipmap* t : {effects_->albedo.get(), effects_->overlay.get()})
    if (t != nullptr) count += t->poll(wait);
  FocusGround& g = effects_->ground;
  std::future<FocusGround>& job = effects_->groundJob;
  if (job.valid() && (wait || job.wait_for(std::chrono::seconds(0)) == std::future_status::ready)) {
    auto done = std::move(job);
    g = done.get();      // rethrows a read error; the next focus asks again
    updateGround(true);  // the focus may have moved on meanwhile
  }
  return count;
}

bool ClipmapTerrain::effectsLoading() const noexcept {
  for (const TextureClipmap* t : {effects_->albedo.get(), effects_->overlay.get()})
    if (t != nullptr && t->loading()) return true;
  return effects_->groundJob.valid();
}

std::vector<std::string> ClipmapTerrain::passes() const {
  std::vector<std::string> out;
  if (effects_ && effects_->albedo) out.emplace_back("albedo-clipmap");
  if (effects_ && effects_->overlay) out.emplace_back("overlay-clipmap");
  if (effects_ && options_.effects.tracks) out.emplace_back("track-upload");
  out.emplace_back("terrain");
  return out;
}

FocusGround focusGround(const HeightPyramid& pyramid, glm::dvec2 o, bool read) {
  // The coarsest level's nearest sample; 0 m off the grid or over nodata.
  const auto& top = pyramid.level(pyramid.levelCount() - 1);
  const glm::dvec2 f = glm::round(top.grid.fractionalIndex(o.x, o.y));
  FocusGround g;
  g.known = true;
  if (!(f.x >= 0.0 && f.y >= 0.0 && f.x < static_cast<double>(top.grid.cols()) &&
        f.y < static_cast<double>(top.grid.rows())))
    return g;
  g.row = static_cast<std::int64_t>(f.y);
  g.col = static_cast<std::int64_t>(f.x);
  if (read) {
    const float s =
        top.source->sample(static_cast<std::size_t>(g.row), static_cast<std::size_t>(g.col));
    if (!std::isnan(s) && !top.grid.isNodata(s)) g.height = static_cast<double>(s);
  }
  return g;
}

namespace {

// Degrees between lat/lon lines adapted to the camera's altitude above `groundHeight` (metres)
// at grid point `o`.
double adaptedSpacing(const HeightPyramid& pyramid, const LatLonLines& ll, glm::dvec2 o,
                      double groundHeight, const Camera& camera) {
  const topo::Body& body = *bodyOf(pyramid);
  const double r = body.equatorialRadius();
  // Altitude above the ground: the camera's height above the ellipsoid less the ground's at
  // the focus (FocusGround). Not |position| − r: below the equatorial radius (a DEM placed at
  // −1.4 km) that was ≤ 0, and the lines came out a fraction of a pixel apart.
  const glm::dvec3 ground = pyramid.position(o.x, o.y, groundHeight);
  const double altitude =
      std::max(body.toGeodetic(camera.position).height - body.toGeodetic(ground).height, 1.0);
  const double degPerPixel = altitude / camera.focalPixels() / r * 180.0 / std::numbers::pi;
  const double wanted = ll.minPixelSpacing * degPerPixel;
  // 90, 60, 45, 30, 20, 15, 10, 5, 2, 1, then 1-2-5 steps down.
  std::vector<double> nice{90, 60, 45, 30, 20, 15, 10, 5, 2, 1};
  // m / 10^k, not m × 0.1^k: the spacing reads 0.002 in the legend's JSON, not
  // 0.0020000000000000005.
  for (int k = 1; k <= 7; ++k)
    for (double m : {5.0, 2.0, 1.0}) nice.push_back(m / std::pow(10.0, k));
  double best = nice.front();
  for (double s : nice)
    if (s >= wanted) best = s;
  return best;
}

}  // namespace

double ClipmapTerrain::latLonSpacing(const Camera& camera) const {
  const auto& ll = options_.effects.latLon;
  if (!ll) throw InvalidArgument("ClipmapTerrain::latLonSpacing(): lat/lon lines not declared");
  if (ll->spacingDegrees > 0.0) return ll->spacingDegrees;
  FocusGround g = effects_->ground;
  // Not read yet (no focus set, or its background read still running): read it here.
  if (!focusGround(*pyramid_, gridOrigin_, false).sameSample(g))
    g = focusGround(*pyramid_, gridOrigin_, true);
  return adaptedSpacing(*pyramid_, *ll, gridOrigin_, g.height, camera);
}

void ClipmapTerrain::updateGround(bool background) {
  if (!options_.effects.latLon) return;
  EffectState& st = *effects_;
  const FocusGround want = focusGround(*pyramid_, gridOrigin_, false);
  if (want.sameSample(st.ground)) return;
  if (want.row < 0) {  // off the grid: nothing to read
    st.ground = want;
    return;
  }
  if (!background) {
    if (st.groundJob.valid()) st.groundJob.wait();  // not left to overwrite this one
    st.groundJob = {};
    st.ground = focusGround(*pyramid_, gridOrigin_, true);
    return;
  }
  if (st.groundJob.valid()) return;  // pollEffects() asks again once it is in
  if (!st.groundExecutor)
    st.groundExecutor =
        options_.executor ? options_.executor : std::make_shared<core::ThreadPool>(1);
  st.groundJob = core::submitTask(*st.groundExecutor, [pyramid = pyramid_, o = gridOrigin_] {
    return focusGround(*pyramid, o, true);
  });
}

void ClipmapTerrain::setEffectUniforms(const Camera& camera, ClipmapFrame& frame) const {
  const Effects& e = options_.effects;
  EffectState& st = *effects_;
  const glm::dvec2 o = gridOrigin_;
  if (st.needs.axes) {
    // Scene vectors per grid unit at the origin, divided by their squared length, so a
    // height slope (metres per grid unit) times the vector is the normal's tilt.
    const double eps = 1e-3 * pyramid_->level(0).grid.spacingX();
    const auto axis = [&](glm::dvec2 d) {
      const glm::dvec3 v = (pyramid_->position(o.x + d.x, o.y + d.y, 0.0) -
                            pyramid_->position(o.x - d.x, o.y - d.y, 0.0)) /
                           (2.0 * eps);
      return glm::vec3(v / glm::dot(v, v));
    };
    program_.set("uAxisX", axis({eps, 0.0}));
    program_.set("uAxisY", axis({0.0, eps}));
  }
  const auto drape = [&](const TextureClipmap& t, const char* name, GLuint unit) {
    const std::string n(name);
    program_.set(("u" + n + "Levels").c_str(), t.levels());
    program_.set(("u" + n + "Spacing0").c_str(), static_cast<float>(t.spacing0()));
    const auto rects = t.windowRects(o);
    glProgramUniform4fv(program_.id(), program_.uniform(("u" + n + "Win").c_str()),
                        static_cast<GLsizei>(rects.size()), glm::value_ptr(rects.front()));
    glBindTextureUnit(unit, t.texture());
    ++frame.textureBinds;
  };
  if (st.albedo) drape(*st.albedo, "Albedo", 2);
  if (st.overlay) {
    drape(*st.overlay, "Overlay", 3);
    program_.set("uOverlayOpacity", e.overlay->opacity);
  }
  if (e.noise) {
    const auto& nz = *e.noise;
    program_.set("uNoiseAmp", static_cast<float>(nz.amplitude));
    program_.set("uNoiseWave", static_cast<float>(nz.wavelength));
    program_.set("uNoiseOctaves", nz.octaves);
    program_.set("uNoiseAlbedo", nz.albedoVariation);
    // The lattice is periodic (256 cells), so only (origin / wavelength) mod 256 matters.
    const auto wrap = [&](double v) {
      return static_cast<float>(std::fmod(v / nz.wavelength, 256.0) + (v < 0 ? 256.0 : 0.0));
    };
    program_.set("uNoiseOffset", glm::vec2(wrap(o.x), wrap(o.y)));
    glm::vec4 region(-1e30F, -1e30F, 1e30F, 1e30F);
    if (nz.region)
      region =
          glm::vec4(static_cast<float>(nz.region->x - o.x), static_cast<float>(nz.region->y - o.y),
                    static_cast<float>(nz.region->z - o.x), static_cast<float>(nz.region->w - o.y));
    program_.set("uNoiseRegion", region);
  }
  if (e.tracks) {
    const rover::TrackLayer& layer = *e.tracks;
    const int n = st.trackWindow;
    const double texel = layer.texelMetres();
    const auto cx = static_cast<std::int64_t>(std::floor(o.x / texel)) - n / 2;
    const auto cy = static_cast<std::int64_t>(std::floor(o.y / texel)) - n / 2;
    const std::uint64_t version = layer.version();
    std::vector<float> buf;
    if (!st.trackLoaded || std::llabs(cx - st.trackTx0) > n / 4 ||
        std::llabs(cy - st.trackTy0) > n / 4) {
      st.trackTx0 = cx;
      st.trackTy0 = cy;
      buf.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
      layer.read(cx, cy, n, n, buf);
      glTextureSubImage2D(st.tracks.id(), 0, 0, 0, n, n, GL_RED, GL_FLOAT, buf.data());
      st.trackLoaded = true;
    } else if (version != st.trackVersion) {
      const auto r = layer.dirtySince(st.trackVersion);
      const std::int64_t x0 = std::max(r[0], st.trackTx0), y0 = std::max(r[1], st.trackTy0);
      const std::int64_t x1 = std::min(r[2], st.trackTx0 + n), y1 = std::min(r[3], st.trackTy0 + n);
      if (x1 > x0 && y1 > y0) {
        const auto w = static_cast<int>(x1 - x0), h = static_cast<int>(y1 - y0);
        buf.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
        layer.read(x0, y0, w, h, buf);
        glTextureSubImage2D(st.tracks.id(), 0, static_cast<GLint>(x0 - st.trackTx0),
                            static_cast<GLint>(y0 - st.trackTy0), w, h, GL_RED, GL_FLOAT,
                            buf.data());
      }
    }
    st.trackVersion = version;
    program_.set("uTrackOrigin",
                 glm::vec2(static_cast<float>(static_cast<double>(st.trackTx0) * texel - o.x),
                           static_cast<float>(static_cast<double>(st.trackTy0) * texel - o.y)));
    program_.set("uTrackExtent", static_cast<float>(n * texel));
    program_.set("uTrackTexel", static_cast<float>(texel));
    program_.set("uTrackDarken", options_.trackDarkening);
    glBindTextureUnit(1, st.tracks.id());
    ++frame.textureBinds;
  }
  if (e.heightColours) {
    program_.set("uHeightRange", glm::vec2(e.heightColours->minHeight, e.heightColours->maxHeight));
    program_.set("uHeightShaded", e.heightColours->shaded ? 1 : 0);
  }
  if (e.latLon) {
    const topo::Body& body = *bodyOf(*pyramid_);
    const double ratio = body.equatorialRadius() / body.polarRadius();
    // The ground read when the focus was set (never read here).
    const double spacing = e.latLon->spacingDegrees > 0.0
                               ? e.latLon->spacingDegrees
                               : adaptedSpacing(*pyramid_, *e.latLon, o, st.ground.height, camera);
    program_.set("uLatLonSpacing", static_cast<float>(spacing));
    program_.set("uLatLonColour", e.latLon->colour);
    program_.set("uLatLonWidth", e.latLon->widthPixels);
    program_.set("uLatAxisRatio2",
                 static_cast<float>(latitudeTypeOf(*pyramid_) == topo::LatitudeType::Planetodetic
                                        ? ratio * ratio
                                        : 1.0));
  }
  gl::checkGl("ClipmapTerrain::draw(): effects");
}

void ClipmapTerrain::setLevelUniforms(std::size_t k) const {
  if (!effects_->needs.grid) return;
  const ClipmapLevel& l = *levels_[k];
  const auto& g = pyramid_->level(k).grid;
  const glm::dvec2 p0 =
      g.sampleCentre(static_cast<double>(l.row0()), static_cast<double>(l.col0()));
  program_.set("uGrid0", glm::vec2(glm::dvec2(p0.x - gridOrigin_.x, p0.y - gridOrigin_.y)));
  program_.set("uGridStep", glm::vec2(glm::dvec2(g.spacingX(), g.spacingY())));
  program_.set("uGridFromBody", l.polar() != 0 ? 1 : 0);
  program_.set("uGridOrigin", glm::vec2(gridOrigin_));
  double ratio2 = 1.0;
  if (pyramid_->kind() == SurfaceKind::Planet &&
      pyramid_->latitudeType() == topo::LatitudeType::Planetodetic) {
    const double q = pyramid_->body()->equatorialRadius() / pyramid_->body()->polarRadius();
    ratio2 = q * q;
  }
  program_.set("uGridLatRatio2", static_cast<float>(ratio2));
}

}  // namespace regolith::clod
