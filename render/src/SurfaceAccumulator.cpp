#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>
#include <regolith/gl/Program.hpp>
#include <regolith/render/SurfaceAccumulator.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "Shaders.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>

namespace regolith::render {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Frames a dataset may stay cached without being drawn.
constexpr std::uint64_t kKeepFrames = 8;

enum class Kind : int { LatLon = 0, Polar = 1, TangentPlane = 2 };

/// First positive hit of a ray (origin o, unit direction d) with the ellipsoid of radii
/// (a + h, a + h, b + h); -1 if none.
double hitShell(const glm::dvec3& o, const glm::dvec3& d, double a, double b) {
  const glm::dvec3 s(1.0 / a, 1.0 / a, 1.0 / b);
  const glm::dvec3 os = o * s, ds = d * s;
  const double A = glm::dot(ds, ds), B = glm::dot(os, ds), C = glm::dot(os, os) - 1.0;
  const double disc = B * B - A * C;
  if (disc < 0.0) return -1.0;
  const double sq = std::sqrt(disc);
  const double t0 = (-B - sq) / A, t1 = (-B + sq) / A;
  if (t0 > 0.0) return t0;
  return t1 > 0.0 ? t1 : -1.0;
}

/// Reads rows [r0, r0 + nr) and columns [c0, c0 + nc) of a source; columns wrap modulo
/// cols() when `wrap` (a grid that covers a whole turn of longitude).
void readWrapped(const topo::SampleSource& src, std::int64_t r0, std::int64_t c0, int nr, int nc,
                 bool wrap, std::vector<float>& out) {
  const auto cols = static_cast<std::int64_t>(src.cols());
  out.assign(static_cast<std::size_t>(nr) * static_cast<std::size_t>(nc), 0.0F);
  std::vector<float> piece;
  std::int64_t c = c0;
  while (c < c0 + nc) {
    const std::int64_t sc = wrap ? ((c % cols) + cols) % cols : c;
    const std::int64_t n = std::min(c0 + nc - c, cols - sc);
    piece.resize(static_cast<std::size_t>(nr) * static_cast<std::size_t>(n));
    src.readWindow(static_cast<std::size_t>(r0), static_cast<std::size_t>(sc),
                   static_cast<std::size_t>(nr), static_cast<std::size_t>(n), piece);
    for (int r = 0; r < nr; ++r) {
      std::copy_n(piece.data() + static_cast<std::size_t>(r) * static_cast<std::size_t>(n), n,
                  out.data() + static_cast<std::size_t>(r) * static_cast<std::size_t>(nc) +
                      static_cast<std::size_t>(c - c0));
    }
    c += n;
  }
}

glm::vec3 f3(const glm::dvec3& v) { return glm::vec3(v); }

}  // namespace

/// A dataset's window texture (values, validity and mask) at one level.
struct SurfaceAccumulator::Cached {
  compose::DatasetId id = 0;
  std::shared_ptr<const compose::Dataset> dataset;
  std::size_t level = 0;
  std::int64_t r0 = 0, c0 = 0;
  int rows = 0, cols = 0;
  gl::Texture texels{0};
  std::uint64_t lastFrame = 0;
};

/// One dataset's pass: the window it reads and its uniforms (computed in double).
struct SurfaceAccumulator::Pass {
  const Cached* window = nullptr;
  const compose::Dataset* dataset = nullptr;
  glm::dvec3 reference{0.0};  // R, body-fixed, on the reference surface
  double latR = 0.0, lonR = 0.0;
  glm::dvec2 gridR{0.0};  // R's grid coordinates (LTP: at the mid height)
  glm::ivec4 scissor{0};  // x, y (GL, bottom-left), width, height
};

SurfaceAccumulator::SurfaceAccumulator(AccumulatorOptions options)
    : options_(options),
      geodetic_("surface geodetic pass",
                gl::ShaderSources{gl::kFullScreenTriangle,
                                  {},
                                  std::string(shaders::kVersion) + shaders::kHelpers +
                                      shaders::kGeodeticFragment}),
      accumulate_("surface accumulation",
                  gl::ShaderSources{gl::kFullScreenTriangle,
                                    {},
                                    std::string(shaders::kVersion) + shaders::kHelpers +
                                        shaders::kAccumulateFragment}),
      normalise_("surface normalisation",
                 gl::ShaderSources{gl::kFullScreenTriangle, {}, shaders::kNormaliseFragment}) {
  constexpr const char* op = "render::SurfaceAccumulator()";
  auto bad = [&](const char* field, const std::string& value, const char* expected) {
    throw InvalidArgument(
        core::format({.operation = op, .field = field, .value = value, .expected = expected}));
  };
  if (options_.maxWindow < 64 || options_.maxWindow > 8192)
    bad("maxWindow", std::to_string(options_.maxWindow) + " texels", "64..8192");
  if (!(options_.qualityN > 1.0) || !std::isfinite(options_.qualityN))
    bad("qualityN", core::number(options_.qualityN), "finite, > 1");
  if (options_.lattice < 3 || options_.lattice > 257)
    bad("lattice", std::to_string(options_.lattice) + " rays per side", "3..257");
  if (!(options_.overlayMax > options_.overlayMin))
    bad("overlay range",
        core::number(options_.overlayMin) + " .. " + core::number(options_.overlayMax),
        "min < max");
}

SurfaceAccumulator::~SurfaceAccumulator() = default;

void SurfaceAccumulator::requireSupported(const compose::Dataset& dataset, const char* operation) {
  if (dataset.isPlanet()) return;
  const topo::Placement& p = *dataset.placement();
  const auto kind = p.kind();
  if (kind == topo::Placement::Kind::LocalTangentPlane ||
      kind == topo::Placement::Kind::PolarStereographic ||
      kind == topo::Placement::Kind::Equirectangular)
    return;
  const char* name =
      kind == topo::Placement::Kind::TransverseMercator ? "transverse Mercator" : "PROJ-projected";
  throw InvalidArgument(
      core::format({.operation = operation,
                    .field = "dataset '" + dataset.name() + "' (" +
                             compose::roleName(dataset.options().role) + ") placement",
                    .value = name,
                    .expected = "a planet latitude/longitude grid, a local tangent plane, a polar "
                                "stereographic or an equirectangular map"}));
}

void SurfaceAccumulator::resize(int width, int height) {
  if (width == width_ && height == height_) return;
  sums_ = gl::Texture();
  cover_ = gl::Texture();
  glTextureStorage2D(sums_.id(), 1, GL_RGBA32F, width, height);
  glTextureStorage2D(cover_.id(), 1, GL_RG32F, width, height);
  for (GLuint t : {sums_.id(), cover_.id()}) {
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  geo_ = gl::Texture();
  glTextureStorage2D(geo_.id(), 1, GL_RGBA32F, width, height);
  glTextureParameteri(geo_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(geo_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  geoFbo_ = gl::Framebuffer();
  glNamedFramebufferTexture(geoFbo_.id(), GL_COLOR_ATTACHMENT0, geo_.id(), 0);
  if (glCheckNamedFramebufferStatus(geoFbo_.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw gl::GlError("render::SurfaceAccumulator: geodetic framebuffer incomplete");
  fbo_ = gl::Framebuffer();
  glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT0, sums_.id(), 0);
  glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT1, cover_.id(), 0);
  const std::array<GLenum, 2> bufs{GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glNamedFramebufferDrawBuffers(fbo_.id(), 2, bufs.data());
  const GLenum status = glCheckNamedFramebufferStatus(fbo_.id(), GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw gl::GlError("render::SurfaceAccumulator: accumulation framebuffer incomplete (status " +
                      std::to_string(status) + ")");
  width_ = width;
  height_ = height;
  gl::checkGl("render::SurfaceAccumulator::resize()");
}

namespace {

/// Grid coordinates (level 0's units) of a body-fixed point, or nullopt where the
/// placement has no image. Planet longitudes are taken in the turn nearest `lonNear`.
std::optional<glm::dvec2> gridOf(const compose::Dataset& ds, const glm::dvec3& p, double lonNear) {
  const topo::Geodetic g = ds.body().toGeodetic(p);
  if (ds.isPlanet()) {
    const double lon = lonNear + topo::wrapLongitude180(g.lonDeg - lonNear);
    return glm::dvec2(lon, ds.body().fromPlanetodetic(g.latDeg, ds.latitudeType()));
  }
  const topo::TopoGrid& grid = ds.level(0).grid;
  const double hmid = 0.5 * (ds.heightRange()[0] + ds.heightRange()[1]);
  try {
    const glm::dvec3 xyh = ds.placement()->fromGeodeticNear({g.latDeg, g.lonDeg, hmid},
                                                            0.5 * (grid.west() + grid.east()));
    if (!std::isfinite(xyh.x) || !std::isfinite(xyh.y)) return std::nullopt;
    return glm::dvec2(xyh.x, xyh.y);
  } catch (const DomainError&) {
    return std::nullopt;
  }
}

}  // namespace

SurfaceAccumulator::Cached* SurfaceAccumulator::window(const compose::CatalogueEntry& e,
                                                       const clod::Camera& camera,
                                                       std::array<double, 2> heights,
                                                       AccumulationFrame& frame) {
  const compose::Dataset& ds = *e.dataset;
  const compose::DatasetId id = e.id;
  const topo::Body& body = ds.body();
  const topo::TopoGrid& g0 = ds.level(0).grid;
  const bool planet = ds.isPlanet();
  bool wrap = false;
  if (planet) {
    const topo::TopoPlanet p(g0, body, ds.latitudeType(), ds.level(0).source);
    wrap = p.isGlobalInLongitude();
  }
  // Lattice of rays: where each meets the shells of the lowest, middle and highest height
  // gives the part of the grid the view can see and the finest pixel footprint.
  const double lo = heights[0], hi = heights[1];
  const double a = body.equatorialRadius(), b = body.polarRadius();
  const int n = options_.lattice;
  const double lonNear = planet ? 0.5 * (g0.west() + g0.east()) : 0.0;
  glm::dvec2 gmin(std::numeric_limits<double>::infinity()), gmax(-gmin);
  double footprint = std::numeric_limits<double>::infinity();
  std::vector<glm::dvec2> mids(static_cast<std::size_t>(n) * static_cast<std::size_t>(n),
                               glm::dvec2(kNaN));
  auto at = [n](int i, int j) {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i);
  };
  double lonRef = lonNear;
  bool haveRef = false;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double px = camera.width * static_cast<double>(i) / (n - 1);
      const double py = camera.height * static_cast<double>(j) / (n - 1);
      const glm::dvec3 ray = camera.ray(px, py);
      for (int k = 0; k < 3; ++k) {
        const double h = k == 0 ? lo : k == 1 ? 0.5 * (lo + hi) : hi;
        const double t = hitShell(camera.position, ray, a + h, b + h);
        if (t < 0.0) continue;
        const glm::dvec3 p = camera.position + t * ray;
        const auto gp = gridOf(ds, p, lonRef);
        if (!gp) continue;
        if (planet && !haveRef) {
          lonRef = gp->x;  // later longitudes unwrap around the first one
          haveRef = true;
        }
        gmin = glm::min(gmin, *gp);
        gmax = glm::max(gmax, *gp);
        if (k == 1) {
          mids[at(i, j)] = *gp;
          footprint = std::min(footprint, t / camera.focalPixels());
        }
      }
    }
  }
  if (!(gmin.x <= gmax.x)) return nullptr;
  // Margin: the largest grid step between neighbouring lattice rays.
  glm::dvec2 margin(0.0);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const glm::dvec2 m = mids[at(i, j)];
      if (std::isnan(m.x)) continue;
      if (i + 1 < n) {
        const glm::dvec2 r = mids[at(i + 1, j)];
        if (!std::isnan(r.x)) margin = glm::max(margin, glm::abs(r - m));
      }
      if (j + 1 < n) {
        const glm::dvec2 d = mids[at(i, j + 1)];
        if (!std::isnan(d.x)) margin = glm::max(margin, glm::abs(d - m));
      }
    }
  }
  gmin -= margin;
  gmax += margin;
  // Level: the one that serves the finest footprint, coarser while the window is too big.
  std::size_t level = std::isfinite(footprint) ? ds.levelFor(footprint) : ds.levelCount() - 1;
  level = std::min(level, ds.levelCount() - 1);
  std::int64_t r0 = 0, c0 = 0, r1 = 0, c1 = 0;
  const std::int64_t maxW = options_.maxWindow;
  for (;; ++level) {
    const topo::TopoGrid& gridL = ds.level(level).grid;
    const auto rows = static_cast<std::int64_t>(gridL.rows()),
               cols = static_cast<std::int64_t>(gridL.cols());
    c0 = static_cast<std::int64_t>(std::floor((gmin.x - gridL.x0()) / gridL.spacingX())) - 2;
    c1 = static_cast<std::int64_t>(std::ceil((gmax.x - gridL.x0()) / gridL.spacingX())) + 2;
    r0 = static_cast<std::int64_t>(std::floor((gridL.y0() - gmax.y) / gridL.spacingY())) - 2;
    r1 = static_cast<std::int64_t>(std::ceil((gridL.y0() - gmin.y) / gridL.spacingY())) + 2;
    r0 = std::max<std::int64_t>(r0, 0);
    r1 = std::min<std::int64_t>(r1, rows - 1);
    if (wrap) {
      if (c1 - c0 + 1 > cols) c1 = c0 + cols - 1;
    } else {
      c0 = std::max<std::int64_t>(c0, 0);
      c1 = std::min<std::int64_t>(c1, cols - 1);
    }
    if (r1 < r0 || c1 < c0) return nullptr;
    if ((r1 - r0 + 1 <= maxW && c1 - c0 + 1 <= maxW) || level + 1 >= ds.levelCount()) break;
  }
  if (r1 - r0 + 1 > maxW) {  // even the coarsest level is too big: its centre
    const std::int64_t c = (r0 + r1) / 2;
    r0 = c - maxW / 2;
    r1 = r0 + maxW - 1;
  }
  if (c1 - c0 + 1 > maxW) {
    const std::int64_t c = (c0 + c1) / 2;
    c0 = c - maxW / 2;
    c1 = c0 + maxW - 1;
  }
  // Reuse the cached window if it holds this one.
  for (auto& c : cache_) {
    if (c->id != id || c->dataset.get() != &ds) continue;
    if (c->level == level && c->r0 <= r0 && c->c0 <= c0 && c->r0 + c->rows - 1 >= r1 &&
        c->c0 + c->cols - 1 >= c1) {
      c->lastFrame = frame_;
      return c.get();
    }
  }
  // A new window, padded by a quarter of its size so that small moves reuse it.
  const topo::TopoGrid& gridL = ds.level(level).grid;
  const auto rows = static_cast<std::int64_t>(gridL.rows()),
             cols = static_cast<std::int64_t>(gridL.cols());
  const std::int64_t padR = std::max<std::int64_t>(8, (r1 - r0 + 1) / 4);
  const std::int64_t padC = std::max<std::int64_t>(8, (c1 - c0 + 1) / 4);
  r0 = std::max<std::int64_t>(0, r0 - padR);
  r1 = std::min<std::int64_t>(rows - 1, r1 + padR);
  if (r1 - r0 + 1 > maxW) {
    const std::int64_t extra = r1 - r0 + 1 - maxW;
    r0 += extra / 2;
    r1 = r0 + maxW - 1;
  }
  c0 -= padC;
  c1 += padC;
  if (!wrap) {
    c0 = std::max<std::int64_t>(0, c0);
    c1 = std::min<std::int64_t>(cols - 1, c1);
  } else if (c1 - c0 + 1 > cols) {
    const std::int64_t extra = c1 - c0 + 1 - cols;
    c0 += extra / 2;
    c1 = c0 + cols - 1;
  }
  if (c1 - c0 + 1 > maxW) {
    const std::int64_t extra = c1 - c0 + 1 - maxW;
    c0 += extra / 2;
    c1 = c0 + maxW - 1;
  }
  auto entry = std::make_unique<Cached>();
  entry->id = id;
  entry->dataset = e.dataset;
  entry->level = level;
  entry->r0 = r0;
  entry->c0 = c0;
  entry->rows = static_cast<int>(r1 - r0 + 1);
  entry->cols = static_cast<int>(c1 - c0 + 1);
  entry->lastFrame = frame_;
  // One RGB32F texel per sample: (value or 0, 1 if the value is valid else 0, mask), so that
  // the hardware's bilinear filter gives (Σ t·v, Σ t) over the valid taps (the value is
  // their ratio, NaN taps left out) and the mask read bilinearly as Dataset reads it.
  const auto count = static_cast<std::size_t>(entry->rows) * static_cast<std::size_t>(entry->cols);
  std::vector<float> buf, maskBuf(count, 1.0F), texels(3 * count);
  readWrapped(*ds.level(level).source, r0, c0, entry->rows, entry->cols, wrap, buf);
  if (const auto& mask = ds.options().mask) {
    if (level == 0) {
      readWrapped(*mask, r0, c0, entry->rows, entry->cols, wrap, maskBuf);
      for (float& m : maskBuf) m = std::isnan(m) ? 0.0F : std::clamp(m, 0.0F, 1.0F);
    } else {
      // The mask at this level's sample centres, read as Dataset reads it (level 0,
      // bilinear).
      const auto cols0 = static_cast<double>(g0.cols());
      for (int r = 0; r < entry->rows; ++r) {
        for (int c = 0; c < entry->cols; ++c) {
          const glm::dvec2 xy =
              gridL.sampleCentre(static_cast<double>(r0 + r), static_cast<double>(c0 + c));
          glm::dvec2 uv = g0.fractionalIndex(xy.x, xy.y);
          if (wrap) uv.x = uv.x - cols0 * std::floor(uv.x / cols0);
          maskBuf[static_cast<std::size_t>(r) * static_cast<std::size_t>(entry->cols) +
                  static_cast<std::size_t>(c)] =
              static_cast<float>(compose::maskValue(*mask, uv.x, uv.y));
        }
      }
    }
  }
  for (std::size_t i = 0; i < count; ++i) {
    const bool valid = !gridL.isNodata(buf[i]) && std::isfinite(buf[i]);
    texels[3 * i] = valid ? buf[i] : 0.0F;
    texels[3 * i + 1] = valid ? 1.0F : 0.0F;
    texels[3 * i + 2] = maskBuf[i];
  }
  entry->texels = gl::Texture();
  glTextureStorage2D(entry->texels.id(), 1, GL_RGB32F, entry->cols, entry->rows);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(entry->texels.id(), 0, 0, 0, entry->cols, entry->rows, GL_RGB, GL_FLOAT,
                      texels.data());
  glTextureParameteri(entry->texels.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(entry->texels.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(entry->texels.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(entry->texels.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  frame.texelsUploaded += count;
  gl::checkGl("render::SurfaceAccumulator: window upload");
  // Replace an older window of the same dataset.
  std::erase_if(cache_, [&](const std::unique_ptr<Cached>& c) { return c->id == id; });
  cache_.push_back(std::move(entry));
  return cache_.back().get();
}

AccumulationFrame SurfaceAccumulator::accumulate(const gl::RenderTarget& target,
                                                 const clod::Camera& camera,
                                                 const compose::Snapshot& snapshot) {
  constexpr const char* op = "render::SurfaceAccumulator::accumulate()";
  if (camera.width != target.width() || camera.height != target.height()) {
    throw InvalidArgument(
        core::format({.operation = op,
                      .field = "camera size",
                      .value = std::to_string(camera.width) + " x " + std::to_string(camera.height),
                      .expected = "the target's, " + std::to_string(target.width()) + " x " +
                                  std::to_string(target.height())}));
  }
  ++frame_;
  AccumulationFrame frame;
  windows_.clear();

  // The view frustum in body-fixed metres: four sides, the near plane and a far plane
  // beyond which every point of the body lies behind its horizon.
  const glm::dmat3 rot = camera.rotation();
  const glm::dvec3 right(rot[0][0], rot[1][0], rot[2][0]);
  const glm::dvec3 up(rot[0][1], rot[1][1], rot[2][1]);
  const glm::dvec3 fwd(-rot[0][2], -rot[1][2], -rot[2][2]);
  const double ty = std::tan(0.5 * camera.fovYDegrees * kDeg);
  const double tx = ty * camera.width / camera.height;
  const topo::Body& body = snapshot.body();
  const double rMin =
      std::max(0.5 * body.polarRadius(), body.polarRadius() + snapshot.lowestHeight());
  const double rMax = body.equatorialRadius() + std::max(0.0, snapshot.highestHeight());
  const double cam = glm::length(camera.position);
  const double far = std::sqrt(std::max(0.0, cam * cam - rMin * rMin)) +
                     std::sqrt(std::max(0.0, rMax * rMax - rMin * rMin)) + 1.0;
  std::array<glm::dvec4, 6> planes{};
  auto plane = [&](const glm::dvec3& nrm, double offset) {
    return glm::dvec4(nrm, -glm::dot(nrm, camera.position) + offset);
  };
  planes[0] = plane(tx * fwd - right, 0.0);
  planes[1] = plane(tx * fwd + right, 0.0);
  planes[2] = plane(ty * fwd - up, 0.0);
  planes[3] = plane(ty * fwd + up, 0.0);
  planes[4] = plane(fwd, -camera.near);
  planes[5] = plane(-fwd, far);
  std::vector<std::uint32_t> visible;
  snapshot.visible(planes, visible);
  std::vector<const compose::CatalogueEntry*> colour;
  for (std::uint32_t i : visible) {
    const compose::CatalogueEntry& e = snapshot.entries()[i];
    if (e.dataset->options().role == compose::Role::Height) continue;
    requireSupported(*e.dataset, op);  // before any GL work
    colour.push_back(&e);
  }
  frame.visible = colour.size();

  // Windows and reference points (CPU, double).
  std::vector<Pass> passes;
  for (const compose::CatalogueEntry* e : colour) {
    const compose::Dataset& ds = *e->dataset;
    const Cached* found = window(*e, camera,
                                 {std::min(ds.heightRange()[0], snapshot.lowestHeight()),
                                  std::max(ds.heightRange()[1], snapshot.highestHeight())},
                                 frame);
    if (found == nullptr) continue;
    const Cached& w = *found;
    Pass p;
    p.window = &w;
    p.dataset = &ds;
    // R: the window's centre on the reference surface.
    const topo::TopoGrid& gridL = ds.level(w.level).grid;
    const glm::dvec2 centre = gridL.sampleCentre(static_cast<double>(w.r0) + 0.5 * (w.rows - 1),
                                                 static_cast<double>(w.c0) + 0.5 * (w.cols - 1));
    const double hmid = 0.5 * (ds.heightRange()[0] + ds.heightRange()[1]);
    double lat = 0.0, lon = 0.0;
    if (ds.isPlanet()) {
      lat = body.toPlanetodetic(std::clamp(centre.y, -90.0, 90.0), ds.latitudeType());
      lon = centre.x;
    } else {
      try {
        const topo::Geodetic g = ds.placement()->toGeodetic(centre.x, centre.y, hmid);
        lat = g.latDeg;
        lon = g.lonDeg;
      } catch (const DomainError&) {
        const topo::Geodetic g = body.toGeodetic(camera.target);
        lat = g.latDeg;
        lon = g.lonDeg;
      }
    }
    p.latR = lat;
    p.lonR = lon;
    p.reference = body.toBodyFixed({lat, lon, 0.0});
    if (ds.isPlanet()) {
      p.gridR = {lon, body.fromPlanetodetic(lat, ds.latitudeType())};
    } else {
      const topo::TopoGrid& g0 = ds.level(0).grid;
      const bool ltp = ds.placement()->kind() == topo::Placement::Kind::LocalTangentPlane;
      const glm::dvec3 xyh = ds.placement()->fromGeodeticNear({lat, lon, ltp ? hmid : 0.0},
                                                              0.5 * (g0.west() + g0.east()));
      p.gridR = {xyh.x, xyh.y};
    }
    // Scissor: the screen rectangle of the dataset's bounds (all of it if a corner is
    // behind the camera).
    p.scissor = {0, 0, camera.width, camera.height};
    const auto& bb = ds.bounds();
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    bool behind = false;
    for (int k = 0; k < 8; ++k) {
      const glm::dvec3 c((k & 1) ? bb[1].x : bb[0].x, (k & 2) ? bb[1].y : bb[0].y,
                         (k & 4) ? bb[1].z : bb[0].z);
      const glm::dvec3 s = camera.project(c);
      if (!(s.z > 0.0)) {
        behind = true;
        break;
      }
      x0 = std::min(x0, s.x);
      x1 = std::max(x1, s.x);
      y0 = std::min(y0, s.y);
      y1 = std::max(y1, s.y);
    }
    if (!behind) {
      const auto ix0 =
          static_cast<int>(std::clamp(std::floor(x0) - 1.0, 0.0, double(camera.width)));
      const auto ix1 = static_cast<int>(std::clamp(std::ceil(x1) + 1.0, 0.0, double(camera.width)));
      const auto iy0 =
          static_cast<int>(std::clamp(std::floor(y0) - 1.0, 0.0, double(camera.height)));
      const auto iy1 =
          static_cast<int>(std::clamp(std::ceil(y1) + 1.0, 0.0, double(camera.height)));
      // Whole 2×2 quads, so that screen derivatives see the same neighbours.
      const int qx0 = ix0 & ~1, qy0 = (camera.height - iy1) & ~1;
      p.scissor = {qx0, qy0, ((ix1 - qx0 + 1) & ~1), ((camera.height - iy0 - qy0 + 1) & ~1)};
      if (p.scissor.z <= 0 || p.scissor.w <= 0) continue;
    }
    windows_.push_back({e->id, w.level, w.r0, w.c0, w.rows, w.cols});
    passes.push_back(p);
  }
  // Drop windows of datasets not drawn for a while.
  std::erase_if(cache_, [&](const std::unique_ptr<Cached>& c) {
    return c->lastFrame + kKeepFrames < frame_;
  });

  resize(target.width(), target.height());
  const std::array<float, 4> zero{0.0F, 0.0F, 0.0F, 0.0F}, one{1.0F, 1.0F, 1.0F, 1.0F};
  glClearNamedFramebufferfv(fbo_.id(), GL_COLOR, 0, zero.data());
  glClearNamedFramebufferfv(fbo_.id(), GL_COLOR, 1, one.data());
  glClearNamedFramebufferfv(geoFbo_.id(), GL_COLOR, 0, zero.data());
  if (passes.empty()) {
    target.bind();
    return frame;
  }
  glViewport(0, 0, width_, height_);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glBindVertexArray(vao_.id());
  glBindTextureUnit(2, target.depthTexture());
  const glm::mat3 eyeToWorld(glm::transpose(rot));
  const auto viewport =
      glm::vec2(static_cast<float>(camera.width), static_cast<float>(camera.height));

  // The geodetic pass, once per frame over the union of the passes' rectangles: latitude,
  // longitude and height relative to R0, the point of the reference surface under the
  // screen's centre (or under the camera if that ray misses the body).
  glm::ivec4 all = passes.front().scissor;
  for (const Pass& p : passes) {
    const glm::ivec2 lo = glm::min(glm::ivec2(all.x, all.y), glm::ivec2(p.scissor.x, p.scissor.y));
    const glm::ivec2 hi =
        glm::max(glm::ivec2(all.x + all.z, all.y + all.w),
                 glm::ivec2(p.scissor.x + p.scissor.z, p.scissor.y + p.scissor.w));
    all = {lo.x, lo.y, hi.x - lo.x, hi.y - lo.y};
  }
  topo::Geodetic frameRef = body.toGeodetic(camera.position);
  {
    const double hMid = 0.5 * (snapshot.lowestHeight() + snapshot.highestHeight());
    const glm::dvec3 ray = camera.ray(0.5 * camera.width, 0.5 * camera.height);
    const double t =
        hitShell(camera.position, ray, body.equatorialRadius() + hMid, body.polarRadius() + hMid);
    if (t > 0.0) frameRef = body.toGeodetic(camera.position + t * ray);
  }
  const glm::dvec3 r0 = body.toBodyFixed({frameRef.latDeg, frameRef.lonDeg, 0.0});
  {
    const double s0 = std::sin(frameRef.latDeg * kDeg), c0 = std::cos(frameRef.latDeg * kDeg);
    const double n0 = body.primeVerticalRadius(frameRef.latDeg);
    glBindFramebuffer(GL_FRAMEBUFFER, geoFbo_.id());
    glDisable(GL_BLEND);
    glEnable(GL_SCISSOR_TEST);
    glScissor(all.x, all.y, all.z, all.w);
    const gl::Program& gp = geodetic_;
    gp.use();
    gp.set("uEyeToWorld", eyeToWorld);
    gp.set("uViewport", viewport);
    gp.set("uFocal", static_cast<float>(camera.focalPixels()));
    gp.set("uNear", static_cast<float>(camera.near));
    gp.set("uRRel", f3(r0 - camera.position));
    gp.set("uWorldToEnu",
           glm::mat3(glm::transpose(body.enuFrame(frameRef.latDeg, frameRef.lonDeg))));
    gp.set("uRef", glm::vec4(glm::dvec4(s0, c0, n0 * c0, n0)));
    gp.set("uA", static_cast<float>(body.equatorialRadius()));
    gp.set("uE2", static_cast<float>(body.eccentricitySquared()));
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }

  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glEnablei(GL_BLEND, 0);
  glBlendEquationi(0, GL_FUNC_ADD);
  glBlendFunci(0, GL_ONE, GL_ONE);
  glEnablei(GL_BLEND, 1);
  glBlendEquationi(1, GL_FUNC_ADD);
  glBlendFunci(1, GL_ZERO, GL_ONE_MINUS_SRC_COLOR);
  glBindTextureUnit(1, geo_.id());

  const gl::Program& pr = accumulate_;
  pr.use();
  pr.set("uEyeToWorld", eyeToWorld);
  pr.set("uViewport", viewport);
  pr.set("uFocal", static_cast<float>(camera.focalPixels()));
  pr.set("uNear", static_cast<float>(camera.near));
  pr.set("uA", static_cast<float>(body.equatorialRadius()));
  pr.set("uE2", static_cast<float>(body.eccentricitySquared()));
  pr.set("uLogN", static_cast<float>(std::log(options_.qualityN)));
  pr.set("uMinQuality", static_cast<float>(compose::kMinQuality));
  for (const Pass& p : passes) {
    const compose::Dataset& ds = *p.dataset;
    const Cached& w = *p.window;
    const topo::TopoGrid& g0 = ds.level(0).grid;
    const topo::TopoGrid& gridL = ds.level(w.level).grid;
    const double sR = std::sin(p.latR * kDeg), cR = std::cos(p.latR * kDeg);
    const glm::dmat3 enu = body.enuFrame(p.latR, p.lonR);
    pr.set("uRRel", f3(p.reference - camera.position));
    pr.set("uWorldToEnu", glm::mat3(glm::transpose(enu)));
    pr.set("uRef", glm::vec4(glm::dvec4(sR, cR, 0.0, 0.0)));
    pr.set("uRefDelta",
           glm::vec2(glm::dvec2((p.latR - frameRef.latDeg) * kDeg,
                                topo::wrapLongitude180(p.lonR - frameRef.lonDeg) * kDeg)));
    Kind kind = Kind::LatLon;
    glm::dvec2 lin(1.0 / kDeg, 1.0 / kDeg);
    int centric = ds.latitudeType() == topo::LatitudeType::Planetocentric ? 1 : 0;
    if (!ds.isPlanet()) {
      const topo::Placement& pl = *ds.placement();
      centric = pl.latitudeType() == topo::LatitudeType::Planetocentric ? 1 : 0;
      if (const auto* eq = pl.equirectangular()) {
        lin = {eq->radius() * std::cos(eq->latTrueScaleDeg() * kDeg), eq->radius()};
      } else if (const auto* ps = pl.polarStereographic()) {
        kind = Kind::Polar;
        const double sg = ps->pole() == topo::PolarStereographic::Pole::North ? 1.0 : -1.0;
        const double e = std::sqrt(ps->eccentricitySquared());
        const double phiN = sg * p.latR * kDeg;
        const double sN = std::sin(phiN);
        const double tA = phiN >= 0.0 ? std::cos(phiN) / (1.0 + sN) : (1.0 - sN) / std::cos(phiN);
        const double eR = e == 0.0 ? 1.0 : std::pow((1.0 - e * sN) / (1.0 + e * sN), 0.5 * e);
        const glm::dvec2 onEquator = ps->forward({0.0, ps->lonCentreDeg()});
        const double rhoFactor =
            std::hypot(onEquator.x - ps->falseEasting(), onEquator.y - ps->falseNorthing());
        const double k = rhoFactor / eR;
        pr.set("uPolar", glm::vec4(glm::dvec4(sg, tA, k * tA, k)));
        const double dl = (p.lonR - ps->lonCentreDeg()) * kDeg;
        pr.set("uPolarDl", glm::vec2(glm::dvec2(std::sin(dl), std::cos(dl))));
        pr.set("uEcc", static_cast<float>(e));
      } else if (const auto* ltp = pl.localTangentPlane()) {
        kind = Kind::TangentPlane;
        const glm::dmat3 toEnu = glm::transpose(enu);
        pr.set("uPlaneX", f3(toEnu * ltp->xAxis()));
        pr.set("uPlaneY", f3(toEnu * ltp->yAxis()));
        pr.set("uHmid", static_cast<float>(0.5 * (ds.heightRange()[0] + ds.heightRange()[1])));
      }
    }
    pr.set("uKind", static_cast<int>(kind));
    pr.set("uCentric", centric);
    pr.set("uLinScale", glm::vec2(lin));
    const glm::dvec2 texR = gridL.fractionalIndex(p.gridR.x, p.gridR.y) -
                            glm::dvec2(static_cast<double>(w.c0), static_cast<double>(w.r0));
    pr.set("uTexR", glm::vec2(texR));
    pr.set("uSpacingL", glm::vec2(glm::dvec2(gridL.spacingX(), gridL.spacingY())));
    pr.set("uSpacing0", glm::vec2(glm::dvec2(g0.spacingX(), g0.spacingY())));
    pr.set("uWindow", glm::ivec2(w.cols, w.rows));
    pr.set("uEdge", glm::vec4(glm::dvec4(p.gridR.x - g0.west(), g0.east() - p.gridR.x,
                                         p.gridR.y - g0.south(), g0.north() - p.gridR.y)));
    glm::vec4 on(1.0F);
    if (ds.isPlanet()) {
      const topo::TopoPlanet tp(g0, body, ds.latitudeType(), ds.level(0).source);
      if (tp.isGlobalInLongitude()) on.x = on.y = 0.0F;
      if (tp.hasSouthCap()) on.z = 0.0F;
      if (tp.hasNorthCap()) on.w = 0.0F;
    }
    pr.set("uEdgeOn", on);
    pr.set("uPlanet", ds.isPlanet() ? 1 : 0);
    pr.set("uFeather", static_cast<float>(ds.options().featherMetres));
    pr.set("uRole", ds.options().role == compose::Role::Albedo ? 0 : 1);
    glBindTextureUnit(0, w.texels.id());
    glScissor(p.scissor.x, p.scissor.y, p.scissor.z, p.scissor.w);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    ++frame.drawn;
  }
  glDisable(GL_SCISSOR_TEST);
  glDisablei(GL_BLEND, 0);
  glDisablei(GL_BLEND, 1);
  glBlendFunc(GL_ONE, GL_ZERO);  // the defaults, for every buffer
  glBindVertexArray(0);
  target.bind();
  gl::checkGl(op);
  return frame;
}

void SurfaceAccumulator::normalise(const gl::RenderTarget& target) const {
  constexpr const char* op = "render::SurfaceAccumulator::normalise()";
  if (width_ != target.width() || height_ != target.height()) {
    throw InvalidArgument(core::format(
        {.operation = op,
         .field = "target size",
         .value = std::to_string(target.width()) + " x " + std::to_string(target.height()),
         .expected = "the size of the last accumulate(), " + std::to_string(width_) + " x " +
                     std::to_string(height_)}));
  }
  target.bind();
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_SRC1_COLOR);
  normalise_.use();
  normalise_.set("uGain", options_.albedoGain);
  normalise_.set("uOverlayOpacity", options_.overlayOpacity);
  normalise_.set("uOverlayRange", glm::vec2(options_.overlayMin, options_.overlayMax));
  glBindTextureUnit(0, sums_.id());
  glBindTextureUnit(1, cover_.id());
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glDisable(GL_BLEND);
  // The GL's default factors again: Mesa refuses any later draw into more than one colour
  // buffer (the far field's passes) while a blend factor is dual-source (GL_SRC1_COLOR),
  // blending on or off (GL_INVALID_OPERATION at the draw).
  glBlendFunc(GL_ONE, GL_ZERO);
  target.bind();
  gl::checkGl(op);
}

std::vector<glm::vec4> SurfaceAccumulator::readAccumulation() const {
  const auto w = static_cast<std::size_t>(width_), h = static_cast<std::size_t>(height_);
  std::vector<glm::vec4> raw(w * h), out(w * h);
  if (raw.empty()) return out;
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTextureImage(sums_.id(), 0, GL_RGBA, GL_FLOAT,
                    static_cast<GLsizei>(raw.size() * sizeof(glm::vec4)), raw.data());
  gl::checkGl("render::SurfaceAccumulator::readAccumulation()");
  for (std::size_t y = 0; y < h; ++y)
    std::copy_n(raw.data() + (h - 1 - y) * w, w, out.data() + y * w);
  return out;
}

std::vector<glm::vec2> SurfaceAccumulator::readCoverage() const {
  const auto w = static_cast<std::size_t>(width_), h = static_cast<std::size_t>(height_);
  std::vector<glm::vec2> raw(w * h), out(w * h);
  if (raw.empty()) return out;
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTextureImage(cover_.id(), 0, GL_RG, GL_FLOAT,
                    static_cast<GLsizei>(raw.size() * sizeof(glm::vec2)), raw.data());
  gl::checkGl("render::SurfaceAccumulator::readCoverage()");
  for (std::size_t y = 0; y < h; ++y)
    std::copy_n(raw.data() + (h - 1 - y) * w, w, out.data() + y * w);
  return out;
}

}  // namespace regolith::render
