#include <regolith/core/Error.hpp>
#include <regolith/rover/TrackLayer.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace regolith::rover {

namespace {

constexpr std::size_t kHistory = 4096;  // stamps remembered for dirtySince()

std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

std::uint64_t tileKey(std::int64_t tx, std::int64_t ty) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(tx)) << 32U) |
         static_cast<std::uint64_t>(static_cast<std::uint32_t>(ty));
}

void check(const char* op, glm::dvec2 p, double width, double depth) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y))
    throw InvalidArgument(std::string("TrackLayer::") + op + "(): contact position (" +
                          std::to_string(p.x) + ", " + std::to_string(p.y) +
                          "), expected finite grid coordinates");
  if (!(width > 0.0) || !std::isfinite(width))
    throw InvalidArgument(std::string("TrackLayer::") + op + "(): wheel width " +
                          std::to_string(width) + " m, expected > 0");
  if (!(depth >= 0.0) || !std::isfinite(depth))
    throw InvalidArgument(std::string("TrackLayer::") + op + "(): rut depth " +
                          std::to_string(depth) + " m, expected ≥ 0");
}

}  // namespace

TrackLayer::TrackLayer(double texelMetres) : texel_(texelMetres) {
  if (!(texelMetres > 0.0) || !std::isfinite(texelMetres))
    throw InvalidArgument("TrackLayer(): texel size " + std::to_string(texelMetres) +
                          " m, expected > 0");
}

void TrackLayer::stamp(glm::dvec2 gridXY, double wheelWidthMetres, double depthMetres) {
  check("stamp", gridXY, wheelWidthMetres, depthMetres);
  const std::lock_guard lock(mutex_);
  press(gridXY, gridXY, wheelWidthMetres, depthMetres);
}

void TrackLayer::stampSegment(glm::dvec2 from, glm::dvec2 to, double wheelWidthMetres,
                              double depthMetres) {
  check("stampSegment", from, wheelWidthMetres, depthMetres);
  check("stampSegment", to, wheelWidthMetres, depthMetres);
  const std::lock_guard lock(mutex_);
  press(from, to, wheelWidthMetres, depthMetres);
}

void TrackLayer::step(std::span<const WheelImprint> wheels) {
  for (const auto& w : wheels) check("step", w.gridXY, w.wheelWidthMetres, w.depthMetres);
  const std::lock_guard lock(mutex_);
  if (last_.size() != wheels.size()) last_.clear();
  for (std::size_t i = 0; i < wheels.size(); ++i) {
    const auto& w = wheels[i];
    press(last_.empty() ? w.gridXY : last_[i], w.gridXY, w.wheelWidthMetres, w.depthMetres);
  }
  last_.resize(wheels.size());
  for (std::size_t i = 0; i < wheels.size(); ++i) last_[i] = wheels[i].gridXY;
}

float* TrackLayer::tileFor(std::int64_t tx, std::int64_t ty) {
  auto& tile = tiles_[tileKey(floorDiv(tx, kTile), floorDiv(ty, kTile))];
  if (tile.empty()) tile.assign(static_cast<std::size_t>(kTile) * kTile, 0.0F);
  const std::int64_t lx = tx - floorDiv(tx, kTile) * kTile;
  const std::int64_t ly = ty - floorDiv(ty, kTile) * kTile;
  return tile.data() + static_cast<std::size_t>(ly * kTile + lx);
}

void TrackLayer::press(glm::dvec2 a, glm::dvec2 b, double width, double depth) {
  const double half = 0.5 * width;
  const double lo[2] = {std::min(a.x, b.x) - half, std::min(a.y, b.y) - half};
  const double hi[2] = {std::max(a.x, b.x) + half, std::max(a.y, b.y) + half};
  // Texel (tx, ty) has its centre at ((tx + ½)·texel, (ty + ½)·texel).
  const auto first = [&](double v) {
    return static_cast<std::int64_t>(std::ceil(v / texel_ - 0.5));
  };
  const auto last = [&](double v) {
    return static_cast<std::int64_t>(std::floor(v / texel_ - 0.5));
  };
  const std::int64_t tx0 = first(lo[0]), tx1 = last(hi[0]);
  const std::int64_t ty0 = first(lo[1]), ty1 = last(hi[1]);
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  for (std::int64_t ty = ty0; ty <= ty1; ++ty)
    for (std::int64_t tx = tx0; tx <= tx1; ++tx) {
      const glm::dvec2 p{(static_cast<double>(tx) + 0.5) * texel_,
                         (static_cast<double>(ty) + 0.5) * texel_};
      const double t = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
      const double d = glm::length(p - (a + t * ab));
      if (d >= half) continue;
      const double c = std::cos(std::numbers::pi * d / width);
      const auto v = static_cast<float>(depth * c * c);
      float* cell = tileFor(tx, ty);
      *cell = std::max(*cell, v);
    }
  ++version_;
  history_.push_back(Stamp{version_, {tx0, ty0, tx1 + 1, ty1 + 1}});
  if (history_.size() > kHistory) history_.erase(history_.begin(), history_.begin() + kHistory / 2);
}

float TrackLayer::texel(std::int64_t tx, std::int64_t ty) const {
  const std::lock_guard lock(mutex_);
  const auto it = tiles_.find(tileKey(floorDiv(tx, kTile), floorDiv(ty, kTile)));
  if (it == tiles_.end()) return 0.0F;
  const std::int64_t lx = tx - floorDiv(tx, kTile) * kTile;
  const std::int64_t ly = ty - floorDiv(ty, kTile) * kTile;
  return it->second[static_cast<std::size_t>(ly * kTile + lx)];
}

double TrackLayer::depthAt(glm::dvec2 g) const {
  if (!std::isfinite(g.x) || !std::isfinite(g.y))
    throw InvalidArgument("TrackLayer::depthAt(): point (" + std::to_string(g.x) + ", " +
                          std::to_string(g.y) + "), expected finite grid coordinates");
  const double fx = g.x / texel_ - 0.5, fy = g.y / texel_ - 0.5;
  const double x0 = std::floor(fx), y0 = std::floor(fy);
  const double u = fx - x0, v = fy - y0;
  const auto tx = static_cast<std::int64_t>(x0), ty = static_cast<std::int64_t>(y0);
  const auto t = [&](std::int64_t x, std::int64_t y) { return static_cast<double>(texel(x, y)); };
  return (1 - u) * (1 - v) * t(tx, ty) + u * (1 - v) * t(tx + 1, ty) + (1 - u) * v * t(tx, ty + 1) +
         u * v * t(tx + 1, ty + 1);
}

void TrackLayer::read(std::int64_t tx0, std::int64_t ty0, int w, int h,
                      std::span<float> out) const {
  if (w < 0 || h < 0 || out.size() < static_cast<std::size_t>(w) * static_cast<std::size_t>(h))
    throw InvalidArgument("TrackLayer::read(): window " + std::to_string(w) + " × " +
                          std::to_string(h) + " does not fit the output (" +
                          std::to_string(out.size()) + " values)");
  std::fill(out.begin(), out.end(), 0.0F);
  const std::lock_guard lock(mutex_);
  // Walk the tiles the window touches, copying their overlap row by row.
  const std::int64_t ktx0 = floorDiv(tx0, kTile), ktx1 = floorDiv(tx0 + w - 1, kTile);
  const std::int64_t kty0 = floorDiv(ty0, kTile), kty1 = floorDiv(ty0 + h - 1, kTile);
  for (std::int64_t ky = kty0; ky <= kty1; ++ky)
    for (std::int64_t kx = ktx0; kx <= ktx1; ++kx) {
      const auto it = tiles_.find(tileKey(kx, ky));
      if (it == tiles_.end()) continue;
      const std::int64_t x0 = std::max(tx0, kx * kTile), x1 = std::min(tx0 + w, (kx + 1) * kTile);
      const std::int64_t y0 = std::max(ty0, ky * kTile), y1 = std::min(ty0 + h, (ky + 1) * kTile);
      for (std::int64_t y = y0; y < y1; ++y) {
        const float* src = it->second.data() +
                           static_cast<std::size_t>((y - ky * kTile) * kTile + (x0 - kx * kTile));
        float* dst = out.data() + static_cast<std::size_t>((y - ty0) * w + (x0 - tx0));
        std::copy(src, src + (x1 - x0), dst);
      }
    }
}

std::uint64_t TrackLayer::version() const {
  const std::lock_guard lock(mutex_);
  return version_;
}

std::array<std::int64_t, 4> TrackLayer::dirtySince(std::uint64_t since) const {
  const std::lock_guard lock(mutex_);
  constexpr auto big = std::numeric_limits<std::int64_t>::max() / 4;
  std::array<std::int64_t, 4> r{big, big, -big, -big};
  if (version_ <= since) return {0, 0, 0, 0};
  if (history_.empty() || history_.front().version > since + 1) return {-big, -big, big, big};
  for (const auto& s : history_) {
    if (s.version <= since) continue;
    r[0] = std::min(r[0], s.rect[0]);
    r[1] = std::min(r[1], s.rect[1]);
    r[2] = std::max(r[2], s.rect[2]);
    r[3] = std::max(r[3], s.rect[3]);
  }
  return r;
}

std::size_t TrackLayer::tiles() const {
  const std::lock_guard lock(mutex_);
  return tiles_.size();
}

void TrackLayer::clear() {
  const std::lock_guard lock(mutex_);
  tiles_.clear();
  last_.clear();
  ++version_;
  history_.clear();  // dirtySince() of any older version: everything
}

}  // namespace regolith::rover
