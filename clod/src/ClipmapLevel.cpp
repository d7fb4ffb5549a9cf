#include "ClipmapLevel.hpp"

#include <regolith/gl/Gl.hpp>
#include <regolith/gl/GlError.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace regolith::clod {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::int64_t floorMod(std::int64_t a, std::int64_t n) {
  const std::int64_t m = a % n;
  return m < 0 ? m + n : m;
}

}  // namespace

ClipmapLevel::ClipmapLevel(const HeightPyramid& pyramid, std::size_t level, int n)
    : pyramid_(pyramid), level_(level), n_(n) {
  const auto& g = grid();
  if (pyramid.kind() == SurfaceKind::Planet) {
    const double span = static_cast<double>(g.cols()) * g.spacingX();
    wrapLon_ = std::abs(span - 360.0) <= 1e-9 * 360.0;
    const bool north = std::abs(g.north() - 90.0) <= 1e-9 * 90.0;
    const bool south = std::abs(g.south() + 90.0) <= 1e-9 * 90.0;
    crossPoles_ = wrapLon_ && north && south && g.cols() % 2 == 0;
  }
  glTextureStorage2D(texture_.id(), 1, GL_RGBA32F, n, n);
  glTextureParameteri(texture_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(texture_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  heights_.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), kNaN);
  gl::checkGl("ClipmapLevel()");
}

const topo::TopoGrid& ClipmapLevel::grid() const noexcept { return pyramid_.level(level_).grid; }

int ClipmapLevel::texelX(std::int64_t i) const noexcept {
  return static_cast<int>(floorMod(col0_ + i, n_));
}
int ClipmapLevel::texelY(std::int64_t j) const noexcept {
  return static_cast<int>(floorMod(row0_ + j, n_));
}

bool ClipmapLevel::realIndex(std::int64_t vr, std::int64_t vc, std::size_t& r,
                             std::size_t& c) const {
  const auto rows = static_cast<std::int64_t>(grid().rows());
  const auto cols = static_cast<std::int64_t>(grid().cols());
  if (crossPoles_) {
    // Period 2·rows in virtual rows; the second half is the far side of a pole, half a
    // turn of longitude away.
    std::int64_t m = floorMod(vr, 2 * rows);
    if (m >= rows) {
      m = 2 * rows - 1 - m;
      vc += cols / 2;
    }
    vr = m;
  }
  if (vr < 0 || vr >= rows) return false;
  if (wrapLon_) vc = floorMod(vc, cols);
  if (vc < 0 || vc >= cols) return false;
  r = static_cast<std::size_t>(vr);
  c = static_cast<std::size_t>(vc);
  return true;
}

glm::dvec2 ClipmapLevel::lattice(double vr, double vc) const {
  return lattice(vr, vc, polar_, polarStep_);
}

glm::dvec2 ClipmapLevel::lattice(double vr, double vc, int polar, double step) const {
  if (polar == 0) return grid().sampleCentre(vr, vc);
  // Spherical stereographic map of radius a about the pole: only the lattice, positions
  // still come from the body through pyramid_.position().
  const double a = pyramid_.body()->equatorialRadius();
  const double x = vc * step, y = -vr * step;
  const double rho = std::hypot(x, y);
  const double colat = 2.0 * std::atan(rho / (2.0 * a)) * 180.0 / M_PI;
  if (polar > 0) return {std::atan2(x, -y) * 180.0 / M_PI, 90.0 - colat};
  return {std::atan2(x, y) * 180.0 / M_PI, -90.0 + colat};
}

glm::dvec3 ClipmapLevel::centre() const {
  const std::int64_t half = (n_ - 1) / 2;
  const glm::dvec2 p =
      lattice(static_cast<double>(row0_ + half), static_cast<double>(col0_ + half));
  return pyramid_.position(p.x, p.y, 0.0);
}

ClipmapLevel::Bound ClipmapLevel::bound(double below) const {
  const double lo = static_cast<double>(minH_) - below, hi = static_cast<double>(maxH_);
  const double half = 0.5 * static_cast<double>(n_ - 1);
  const auto r0 = static_cast<double>(row0_), c0 = static_cast<double>(col0_);
  const double last = static_cast<double>(n_ - 1);
  Bound b;
  if (pyramid_.kind() == SurfaceKind::Planet) {
    const topo::Body& body = *pyramid_.body();
    const double a = body.equatorialRadius(), polarR = body.polarRadius();
    // The window's angular radius about its centre sample: every vertex's direction lies
    // within theta of the centre's. On a lat/lon lattice a meridian step then a parallel
    // step reach any sample, so theta <= half the latitude span + half the longitude span
    // (rows past a pole and columns past the seam are the same points continued), plus
    // twice the largest geodetic-geocentric latitude difference (about the flattening).
    double theta = 0.0;
    const double flattening = (a - polarR) / a;
    if (polar_ == 0) {
      theta = half * (spacingX() + spacingY()) * std::numbers::pi / 180.0;
    } else {
      // A stereographic square: the largest angle to its border, sampled finely, plus two
      // lattice steps' angle.
      const glm::dvec3 c = glm::normalize(centre());
      const auto dir = [&](double vr, double vc) {
        const glm::dvec2 g = lattice(vr, vc);
        return glm::normalize(pyramid_.position(g.x, g.y, 0.0));
      };
      constexpr int kEdge = 32;
      for (int e = 0; e <= kEdge; ++e) {
        const double t = last * e / kEdge;
        for (const glm::dvec3& d :
             {dir(r0, c0 + t), dir(r0 + last, c0 + t), dir(r0 + t, c0), dir(r0 + t, c0 + last)})
          theta = std::max(theta, std::acos(std::clamp(glm::dot(c, d), -1.0, 1.0)));
      }
      theta += 2.0 * polarStep_ / polarR;
    }
    theta = std::min(theta + 2.0 * flattening + 1e-9, std::numbers::pi);
    // |P − c| ≤ ||P| − |c|| + 2|c|·sin(θ/2) for P within θ of c's direction.
    // A vertex at height h lies between polarR + min(h, 0) and a + max(h, 0) from the centre.
    b.centre = centre();
    const double rc = glm::length(b.centre);
    const double nearest = polarR + std::min(lo, 0.0), farthest = a + std::max(hi, 0.0);
    b.radius = std::max(farthest - rc, rc - nearest) + 2.0 * rc * std::sin(0.5 * theta);
    b.radius = b.radius * (1.0 + 1e-9) + 1e-3;
    return b;
  }
  // A plane's window is the rectangle of its lattice; a placed one is sampled on a 9 × 9
  // lattice over it at both heights, with the largest step between neighbours as margin for
  // what bends between them.
  // On the stack: draw() asks every level for its bound every frame.
  constexpr std::size_t kSteps = 8;
  std::array<glm::dvec3, 2 * (kSteps + 1) * (kSteps + 1)> pts{};
  std::size_t count = 0;
  double step = 0.0;
  for (std::size_t i = 0; i <= kSteps; ++i) {
    for (std::size_t j = 0; j <= kSteps; ++j) {
      const glm::dvec2 g = lattice(r0 + last * static_cast<double>(i) / kSteps,
                                   c0 + last * static_cast<double>(j) / kSteps);
      for (const double h : {lo, hi}) pts[count++] = pyramid_.position(g.x, g.y, h);
      if (j > 0) step = std::max(step, glm::length(pts[count - 1] - pts[count - 3]));
      if (i > 0) {
        const std::size_t above = count - 1 - 2 * (kSteps + 1);
        step = std::max(step, glm::length(pts[count - 1] - pts[above]));
      }
    }
  }
  glm::dvec3 lower(std::numeric_limits<double>::infinity()), upper(-lower);
  for (const glm::dvec3& p : pts) {
    lower = glm::min(lower, p);
    upper = glm::max(upper, p);
  }
  b.centre = 0.5 * (lower + upper);
  for (const glm::dvec3& p : pts) b.radius = std::max(b.radius, glm::length(p - b.centre));
  if (pyramid_.placement()) b.radius += step;
  b.radius = b.radius * (1.0 + 1e-9) + 1e-3;
  return b;
}

double ClipmapLevel::cellMetres() const {
  const std::int64_t half = (n_ - 1) / 2;
  const double r = static_cast<double>(row0_ + half);
  const double c = static_cast<double>(col0_ + half);
  const auto at = [&](double rr, double cc) {
    const glm::dvec2 p = lattice(rr, cc);
    return pyramid_.position(p.x, p.y, 0.0);
  };
  const glm::dvec3 o = at(r, c);
  return std::max(glm::length(at(r, c + 1) - o), glm::length(at(r + 1, c) - o));
}

float ClipmapLevel::sampleAt(std::int64_t vr, std::int64_t vc) const {
  std::size_t r = 0, c = 0;
  if (!realIndex(vr, vc, r, c)) return kNaN;
  const float v = pyramid_.level(level_).source->sample(r, c);
  return grid().isNodata(v) ? kNaN : v;
}

float ClipmapLevel::interpolate(const glm::dvec2& g) const {
  const glm::dvec2 f = grid().fractionalIndex(g.x, g.y);
  const double fr = std::floor(f.y), fc = std::floor(f.x);
  const double tr = f.y - fr, tc = f.x - fc;
  const auto r = static_cast<std::int64_t>(fr), c = static_cast<std::int64_t>(fc);
  const double v00 = static_cast<double>(sampleAt(r, c));
  const double v01 = static_cast<double>(sampleAt(r, c + 1));
  const double v10 = static_cast<double>(sampleAt(r + 1, c));
  const double v11 = static_cast<double>(sampleAt(r + 1, c + 1));
  const double top = v00 + (v01 - v00) * tc, bottom = v10 + (v11 - v10) * tc;
  return static_cast<float>(top + (bottom - top) * tr);  // NaN if any is NaN
}

ClipmapLevel::Plan ClipmapLevel::plan(double gx, double gy, int polar) const {
  const auto& g = grid();
  const std::int64_t half = (n_ - 1) / 2;
  Plan p;
  p.polar = crossPoles_ ? polar : 0;
  p.polarStep =
      p.polar == 0 ? 0.0 : pyramid_.body()->equatorialRadius() * g.spacingY() * M_PI / 180.0;
  glm::dvec2 f = g.fractionalIndex(gx, gy);
  if (p.polar != 0) {
    const double a = pyramid_.body()->equatorialRadius();
    const double colat = (p.polar > 0 ? 90.0 - gy : 90.0 + gy) * M_PI / 180.0;
    const double rho = 2.0 * a * std::tan(0.5 * colat);
    const double lon = gx * M_PI / 180.0;
    const double x = rho * std::sin(lon), y = (p.polar > 0 ? -rho : rho) * std::cos(lon);
    f = {x / p.polarStep, -y / p.polarStep};
  }
  p.col0 = static_cast<std::int64_t>(std::llround(f.x)) - half;
  p.row0 = static_cast<std::int64_t>(std::llround(f.y)) - half;
  const std::int64_t n = n_;
  const std::int64_t dr = p.row0 - row0_, dc = p.col0 - col0_;
  const bool farFromAnchor =
      std::llabs(p.row0 + half - anchorRow_) > n || std::llabs(p.col0 + half - anchorCol_) > n;
  p.full =
      !valid_ || p.polar != polar_ || std::llabs(dr) >= n || std::llabs(dc) >= n || farFromAnchor;
  if (p.full) {
    p.anchorRow = p.row0 + half;
    p.anchorCol = p.col0 + half;
    p.regions.push_back({p.row0, p.row0 + n, p.col0, p.col0 + n, {}});
    return p;
  }
  p.anchorRow = anchorRow_;
  p.anchorCol = anchorCol_;
  p.anchor = anchor_;
  // New rows over the full width of the new window; new columns only over the rows that
  // were resident before.
  std::int64_t keepR0 = p.row0, keepR1 = p.row0 + n;
  if (dr > 0) {
    p.regions.push_back({row0_ + n, p.row0 + n, p.col0, p.col0 + n, {}});
    keepR1 = row0_ + n;
  } else if (dr < 0) {
    p.regions.push_back({p.row0, row0_, p.col0, p.col0 + n, {}});
    keepR0 = row0_;
  }
  if (dc > 0) {
    p.regions.push_back({keepR0, keepR1, p.col0 + n - dc, p.col0 + n, {}});
  } else if (dc < 0) {
    p.regions.push_back({keepR0, keepR1, p.col0, p.col0 - dc, {}});
  }
  return p;
}

bool ClipmapLevel::Plan::empty() const noexcept { return !full && regions.empty(); }

std::size_t ClipmapLevel::Plan::texels() const noexcept {
  std::size_t t = 0;
  for (const auto& r : regions)
    t += static_cast<std::size_t>(r.r1 - r.r0) * static_cast<std::size_t>(r.c1 - r.c0);
  return t;
}

void ClipmapLevel::fetch(Plan& p) const {
  // Lat/lon and plane lattices read runs of samples: the source makes them resident first
  // (a store's pyramid loads them through its prefetcher, on this thread). A polar
  // lattice interpolates between samples anywhere: it reads as it goes.
  if (p.polar == 0) {
    std::vector<topo::SampleSource::Window> windows;
    for (const auto& region : p.regions) appendWindows(region, windows);
    if (!windows.empty()) pyramid_.level(level_).source->load(windows);
  }
  if (p.full) {
    // The anchor sits on the terrain (its centre sample's height), so both the offsets in
    // the texture and anchor − camera stay small near the surface.
    const glm::dvec2 a = lattice(static_cast<double>(p.anchorRow), static_cast<double>(p.anchorCol),
                                 p.polar, p.polarStep);
    const float ah = p.polar != 0 ? interpolate(a) : sampleAt(p.anchorRow, p.anchorCol);
    p.anchor = pyramid_.position(a.x, a.y, std::isnan(ah) ? 0.0 : static_cast<double>(ah));
  }
  for (auto& region : p.regions) fill(p, region);
}

void ClipmapLevel::forEachRun(
    std::int64_t vr, std::int64_t c0, std::size_t w,
    const std::function<void(std::size_t, std::size_t, std::size_t, std::size_t)>& fn) const {
  std::size_t i = 0;
  while (i < w) {
    std::size_t rr = 0, cc = 0;
    if (!realIndex(vr, c0 + static_cast<std::int64_t>(i), rr, cc)) {
      ++i;
      continue;
    }
    std::size_t len = 1;
    std::size_t r2 = 0, c2 = 0;
    while (i + len < w && realIndex(vr, c0 + static_cast<std::int64_t>(i + len), r2, c2) &&
           r2 == rr && c2 == cc + len)
      ++len;
    fn(i, rr, cc, len);
    i += len;
  }
}

void ClipmapLevel::appendWindows(const Plan::Region& region,
                                 std::vector<topo::SampleSource::Window>& out) const {
  const std::size_t first = out.size();
  const auto w = static_cast<std::size_t>(region.c1 - region.c0);
  for (std::int64_t vr = region.r0; vr < region.r1; ++vr) {
    forEachRun(vr, region.c0, w, [&](std::size_t, std::size_t rr, std::size_t cc, std::size_t len) {
      // A run that continues a window of this region by a row above or below joins it
      // (rows run backwards beyond a pole).
      for (std::size_t k = first; k < out.size(); ++k) {
        topo::SampleSource::Window& x = out[k];
        if (x.col0 != cc || x.cols != len) continue;
        if (rr == x.row0 + x.rows) {
          ++x.rows;
          return;
        }
        if (rr + 1 == x.row0) {
          --x.row0;
          ++x.rows;
          return;
        }
      }
      out.push_back({rr, cc, 1, len});
    });
  }
}

void ClipmapLevel::fill(const Plan& p, Plan::Region& region) const {
  const auto& lvl = pyramid_.level(level_);
  const auto& g = lvl.grid;
  const auto w = static_cast<std::size_t>(region.c1 - region.c0);
  const auto h = static_cast<std::size_t>(region.r1 - region.r0);
  region.texels.assign(w * h * 4, 0.0F);
  const auto put = [&](std::size_t j, std::size_t k, const glm::dvec2& gp, float hgt) {
    const double hd = std::isnan(hgt) ? 0.0 : static_cast<double>(hgt);
    const glm::dvec3 q = pyramid_.position(gp.x, gp.y, hd) - p.anchor;
    float* t = region.texels.data() + (j * w + k) * 4;
    t[0] = static_cast<float>(q.x);
    t[1] = static_cast<float>(q.y);
    t[2] = static_cast<float>(q.z);
    t[3] = hgt;
  };
  if (p.polar != 0) {
    for (std::size_t j = 0; j < h; ++j)
      for (std::size_t k = 0; k < w; ++k) {
        const glm::dvec2 gp = lattice(static_cast<double>(region.r0 + static_cast<std::int64_t>(j)),
                                      static_cast<double>(region.c0 + static_cast<std::int64_t>(k)),
                                      p.polar, p.polarStep);
        put(j, k, gp, interpolate(gp));
      }
    return;
  }
  std::vector<float> row(w);
  for (std::size_t j = 0; j < h; ++j) {
    const std::int64_t vr = region.r0 + static_cast<std::int64_t>(j);
    // Read the row's samples as runs of consecutive real columns; NaN where none is real.
    std::fill(row.begin(), row.end(), kNaN);
    forEachRun(vr, region.c0, w,
               [&](std::size_t i, std::size_t rr, std::size_t cc, std::size_t len) {
                 lvl.source->readWindow(rr, cc, 1, len, std::span<float>(row.data() + i, len));
               });
    for (std::size_t k = 0; k < w; ++k) {
      const std::int64_t vc = region.c0 + static_cast<std::int64_t>(k);
      const float hgt = g.isNodata(row[k]) ? kNaN : row[k];
      // Position of the real sample (so a wrapped or reflected sample lands on its own
      // point), else of the virtual one.
      std::size_t rr = 0, cc = 0;
      glm::dvec2 gp;
      if (realIndex(vr, vc, rr, cc)) {
        gp = g.sampleCentre(static_cast<double>(rr), static_cast<double>(cc));
      } else {
        gp = g.sampleCentre(static_cast<double>(vr), static_cast<double>(vc));
        if (pyramid_.kind() == SurfaceKind::Planet) gp.y = std::clamp(gp.y, -90.0, 90.0);
      }
      put(j, k, gp, hgt);
    }
  }
}

std::size_t ClipmapLevel::apply(const Plan& p) {
  if (p.empty()) {
    row0_ = p.row0;  // (unchanged)
    col0_ = p.col0;
    return 0;
  }
  row0_ = p.row0;
  col0_ = p.col0;
  polar_ = p.polar;
  polarStep_ = p.polarStep;
  anchorRow_ = p.anchorRow;
  anchorCol_ = p.anchorCol;
  anchor_ = p.anchor;
  valid_ = true;
  const std::int64_t n = n_;
  std::size_t count = 0;
  for (const auto& region : p.regions) {
    const auto w = static_cast<std::size_t>(region.c1 - region.c0);
    const auto h = static_cast<std::size_t>(region.r1 - region.r0);
    for (std::size_t j = 0; j < h; ++j)
      for (std::size_t k = 0; k < w; ++k)
        heights_[static_cast<std::size_t>(floorMod(region.r0 + static_cast<std::int64_t>(j), n)) *
                     static_cast<std::size_t>(n) +
                 static_cast<std::size_t>(floorMod(region.c0 + static_cast<std::int64_t>(k), n))] =
            region.texels[(j * w + k) * 4 + 3];
    // Upload in up to four pieces where the region wraps around the texture's edges.
    std::int64_t y = 0;
    while (y < static_cast<std::int64_t>(h)) {
      const std::int64_t ty = floorMod(region.r0 + y, n);
      const std::int64_t hy = std::min<std::int64_t>(static_cast<std::int64_t>(h) - y, n - ty);
      std::int64_t x = 0;
      while (x < static_cast<std::int64_t>(w)) {
        const std::int64_t tx = floorMod(region.c0 + x, n);
        const std::int64_t wx = std::min<std::int64_t>(static_cast<std::int64_t>(w) - x, n - tx);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, static_cast<GLint>(w));
        glTextureSubImage2D(
            texture_.id(), 0, static_cast<GLint>(tx), static_cast<GLint>(ty),
            static_cast<GLsizei>(wx), static_cast<GLsizei>(hy), GL_RGBA, GL_FLOAT,
            region.texels.data() +
                (static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)) * 4);
        x += wx;
      }
      y += hy;
    }
    count += w * h;
  }
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  gl::checkGl("ClipmapLevel::apply()");
  updateRange();
  return count;
}

void ClipmapLevel::prefetch(const Plan& p, int margin) const {
  if (p.polar != 0 || margin <= 0) return;
  const auto& lvl = pyramid_.level(level_);
  const auto rows = static_cast<std::int64_t>(lvl.grid.rows());
  const auto cols = static_cast<std::int64_t>(lvl.grid.cols());
  const std::int64_t n = n_, m = margin;
  const std::int64_t R0 = p.row0 - m, R1 = p.row0 + n + m, C0 = p.col0 - m, C1 = p.col0 + n + m;
  const std::array<std::array<std::int64_t, 4>, 4> ring = {{{R0, p.row0, C0, C1},
                                                            {p.row0 + n, R1, C0, C1},
                                                            {p.row0, p.row0 + n, C0, p.col0},
                                                            {p.row0, p.row0 + n, p.col0 + n, C1}}};
  std::vector<topo::SampleSource::Window> windows;
  for (const auto& r : ring) {
    const std::int64_t r0 = std::max<std::int64_t>(r[0], 0), r1 = std::min(r[1], rows);
    const std::int64_t c0 = std::max<std::int64_t>(r[2], 0), c1 = std::min(r[3], cols);
    if (r1 <= r0 || c1 <= c0) continue;
    windows.push_back({static_cast<std::size_t>(r0), static_cast<std::size_t>(c0),
                       static_cast<std::size_t>(r1 - r0), static_cast<std::size_t>(c1 - c0)});
  }
  // A hint: a paged source loads the ring in the background (a store's pyramid: its
  // store::Prefetcher), so the loader goes on to the next level at once.
  lvl.source->prefetch(windows);
}

std::size_t ClipmapLevel::moveTo(double gx, double gy, int polar) {
  Plan p = plan(gx, gy, polar);
  fetch(p);
  return apply(p);
}

glm::dvec2 ClipmapLevel::indexIn(const ClipmapLevel& coarser, double r, double c) const {
  if (polar_ != 0) return {0.5 * c, 0.5 * r};  // polar lattices halve their step per level
  const glm::dvec2 g = grid().sampleCentre(r, c);
  return coarser.grid().fractionalIndex(g.x, g.y);
}

glm::dvec2 ClipmapLevel::centreIndexIn(const ClipmapLevel& coarser) const {
  const std::int64_t half = (n_ - 1) / 2;
  return indexIn(coarser, static_cast<double>(row0_ + half), static_cast<double>(col0_ + half));
}

glm::dvec4 ClipmapLevel::footprintIn(const ClipmapLevel& coarser) const {
  const auto last = static_cast<double>(n_ - 1);
  const glm::dvec2 a = indexIn(coarser, static_cast<double>(row0_), static_cast<double>(col0_));
  const glm::dvec2 b =
      indexIn(coarser, static_cast<double>(row0_) + last, static_cast<double>(col0_) + last);
  double i0 = a.x - static_cast<double>(coarser.col0_),
         i1 = b.x - static_cast<double>(coarser.col0_);
  const double j0 = a.y - static_cast<double>(coarser.row0_);
  const double j1 = b.y - static_cast<double>(coarser.row0_);
  if (coarser.wrapLon_ && polar_ == 0) {  // bring the footprint next to the window
    const auto cols = static_cast<double>(coarser.grid().cols());
    const double shift = cols * std::round((0.5 * (i0 + i1) - 0.5 * last) / cols);
    i0 -= shift;
    i1 -= shift;
  }
  return {std::min(i0, i1), std::min(j0, j1), std::max(i0, i1), std::max(j0, j1)};
}

bool ClipmapLevel::covers(const ClipmapLevel& coarser, int hole) const {
  if (!valid_ || !coarser.valid_ || polar_ != coarser.polar_) return false;
  const glm::dvec2 m = centreIndexIn(coarser);
  const std::int64_t half = (n_ - 1) / 2;
  double dc = static_cast<double>(coarser.col0_ + half) - m.x;
  const double dr = static_cast<double>(coarser.row0_ + half) - m.y;
  if (coarser.wrapLon_ && polar_ == 0) {
    const auto cols = static_cast<double>(coarser.grid().cols());
    dc -= cols * std::round(dc / cols);
  }
  const double slack = 0.25 * static_cast<double>(n_ - 1) - static_cast<double>(hole);
  return std::abs(dc) <= slack && std::abs(dr) <= slack;
}

void ClipmapLevel::updateRange() {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float v : heights_)
    if (!std::isnan(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (lo > hi) lo = hi = 0.0F;
  minH_ = lo;
  maxH_ = hi;
}

}  // namespace regolith::clod
