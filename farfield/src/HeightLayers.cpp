#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/farfield/HeightLayers.hpp>
#include <regolith/farfield/PgmMath.hpp>

#include "Checks.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <thread>

namespace regolith::farfield {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr const char* kOp = "farfield::HeightLayers::build()";

void requireRange(const char* field, double v, double lo, double hi) {
  detail::requireRange(kOp, field, v, lo, hi);
}

/// Bilinear read of a row-major layer at fractional texel coordinates (texel centres at
/// integers), columns wrapping when `wrapColumns`, rows (and otherwise columns) clamped.
double bilinear(const std::vector<float>& layer, int cols, int rows, double x, double y,
                bool wrapColumns) {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const auto col = [&](long c) {
    if (wrapColumns) return static_cast<std::size_t>(((c % cols) + cols) % cols);
    return static_cast<std::size_t>(std::clamp<long>(c, 0, cols - 1));
  };
  const auto row = [&](long r) {
    return static_cast<std::size_t>(std::clamp<long>(r, 0, rows - 1));
  };
  const long c0 = static_cast<long>(fx), r0 = static_cast<long>(fy);
  const auto at = [&](long r, long c) {
    return static_cast<double>(layer[row(r) * static_cast<std::size_t>(cols) + col(c)]);
  };
  return (1 - ty) * ((1 - tx) * at(r0, c0) + tx * at(r0, c0 + 1)) +
         ty * ((1 - tx) * at(r0 + 1, c0) + tx * at(r0 + 1, c0 + 1));
}

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

/// Planetodetic latitude and longitude (degrees) of polar stereographic (p, q).
void capLatLon(double p, double q, bool north, double& latDeg, double& lonDeg) {
  const double rho = std::hypot(p, q);
  const double lat = 0.5 * kPi - 2.0 * std::atan(0.5 * rho);
  latDeg = (north ? lat : -lat) / kDeg;
  lonDeg = (north ? std::atan2(p, -q) : std::atan2(p, q)) / kDeg;
}

}  // namespace

HeightLayers::HeightLayers(topo::Body body, LayerOptions options)
    : body_(std::move(body)), options_(std::move(options)) {}

HeightLayers HeightLayers::build(const topo::Body& body, const HeightFunction& height,
                                 const LayerOptions& options) {
  requireRange("equirectWidth", options.equirectWidth, 64, 16384);
  if (options.equirectWidth % 2 != 0) {
    throw InvalidArgument(core::format({.operation = kOp,
                                        .field = "equirectWidth",
                                        .value = core::number(options.equirectWidth),
                                        .expected = "even"}));
  }
  requireRange("capSize", options.capSize, 16, 8192);
  requireRange("capLatitude", options.capLatitude, 30.0, 85.0);
  requireRange("blendDegrees", options.blendDegrees, 0.5, 10.0);
  if (!height) {
    throw InvalidArgument(core::format({.operation = kOp,
                                        .field = "height function",
                                        .value = "empty",
                                        .expected = "a callable"}));
  }
  HeightLayers layers(body, options);
  const int w = options.equirectWidth, h = w / 2, n = options.capSize;
  const double edgeLat = (options.capLatitude - options.blendDegrees - 1.0) * kDeg;
  layers.capRadius_ = 2.0 * std::cos(edgeLat) / (1.0 + std::sin(edgeLat));
  layers.equirect_.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0.0F);
  layers.north_.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), 0.0F);
  layers.south_ = layers.north_;

  const double a = body.equatorialRadius();
  const double equirectSpacing = kPi * a / h;
  const double capSpacing = 2.0 * layers.capRadius_ / n * a;
  // Rows of all three layers in one index space: equirect rows, then north, then south.
  const std::size_t rows = static_cast<std::size_t>(h) + 2 * static_cast<std::size_t>(n);
  std::atomic<std::size_t> missing{0};
  const auto fillRow = [&](std::size_t index) {
    std::size_t localMissing = 0;
    const auto put = [&](float& texel, double v) {
      if (std::isfinite(v)) {
        texel = static_cast<float>(v);
      } else {
        texel = 0.0F;
        ++localMissing;
      }
    };
    if (index < static_cast<std::size_t>(h)) {
      const double lat = -90.0 + (static_cast<double>(index) + 0.5) * 180.0 / h;
      for (int i = 0; i < w; ++i) {
        const double lon = -180.0 + (i + 0.5) * 360.0 / w;
        put(layers.equirect_[index * static_cast<std::size_t>(w) + static_cast<std::size_t>(i)],
            height(lat, lon, equirectSpacing));
      }
    } else {
      const std::size_t capRow =
          (index - static_cast<std::size_t>(h)) % static_cast<std::size_t>(n);
      const bool north = index - static_cast<std::size_t>(h) < static_cast<std::size_t>(n);
      std::vector<float>& cap = north ? layers.north_ : layers.south_;
      const double q =
          -layers.capRadius_ + (static_cast<double>(capRow) + 0.5) * 2.0 * layers.capRadius_ / n;
      for (int i = 0; i < n; ++i) {
        const double p = -layers.capRadius_ + (i + 0.5) * 2.0 * layers.capRadius_ / n;
        double lat = 0.0, lon = 0.0;
        capLatLon(p, q, north, lat, lon);
        put(cap[capRow * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)],
            height(lat, lon, capSpacing));
      }
    }
    missing += localMissing;
  };
  // In slices, so that progress is reported from the calling thread between them.
  const unsigned threads = core::availableCores();
  constexpr std::size_t kSlices = 20;
  for (std::size_t slice = 0; slice < kSlices; ++slice) {
    const std::size_t r0 = rows * slice / kSlices, r1 = rows * (slice + 1) / kSlices;
    core::parallelFor(
        options.executor, r1 - r0, [&](std::size_t i) { fillRow(r0 + i); }, threads);
    if (options.progress) options.progress(static_cast<double>(r1) / static_cast<double>(rows));
  }
  layers.missing_ = missing.load();

  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const auto* layer : {&layers.equirect_, &layers.north_, &layers.south_}) {
    for (const float v : *layer) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  layers.minHeight_ = lo;
  layers.maxHeight_ = hi;
  return layers;
}

HeightLayers HeightLayers::fromSurface(const compose::ComposedSurface& surface,
                                       const LayerOptions& options) {
  return build(
      surface.body(),
      [&surface](double lat, double lon, double metres) {
        const topo::HeightSample s = surface.heightAt(lat, lon, metres);
        return s.status == topo::QueryStatus::Ok ? s.height
                                                 : std::numeric_limits<double>::quiet_NaN();
      },
      options);
}

HeightLayers HeightLayers::fromPlanetGrid(const topo::Body& body, const topo::TopoGrid& grid,
                                          const topo::SampleSource& source,
                                          topo::LatitudeType latitudeType,
                                          const LayerOptions& options) {
  const std::size_t rows = grid.rows(), cols = grid.cols();
  if (rows < 2 || cols < 2 || rows * cols > (std::size_t{1} << 26)) {
    throw InvalidArgument(core::format({.operation = "farfield::HeightLayers::fromPlanetGrid()",
                                        .field = "grid size",
                                        .value = core::number(rows) + " x " + core::number(cols),
                                        .expected = "2..2^26 samples, at least 2 x 2"}));
  }
  auto samples = std::make_shared<std::vector<float>>(rows * cols);
  source.readWindow(0, 0, rows, cols, *samples);
  const bool wrap = std::abs(static_cast<double>(cols) * grid.spacingX() - 360.0) < 1e-6 * 360.0;
  return build(
      body,
      [samples, grid, body, rows, cols, wrap, latitudeType](double lat, double lon, double) {
        const double y = body.fromPlanetodetic(lat, latitudeType);
        const glm::dvec2 idx = grid.fractionalIndex(topo::wrapLongitude180(lon), y);
        double c = idx.x;
        if (wrap) {
          c = std::fmod(c, static_cast<double>(cols));
          if (c < 0.0) c += static_cast<double>(cols);
        } else {
          c = std::clamp(c, 0.0, static_cast<double>(cols - 1));
        }
        const double r = std::clamp(idx.y, 0.0, static_cast<double>(rows - 1));
        const auto c0 = static_cast<std::size_t>(std::floor(c));
        const auto r0 =
            static_cast<std::size_t>(std::min(std::floor(r), static_cast<double>(rows - 2)));
        const std::size_t c1 = wrap ? (c0 + 1) % cols : std::min(c0 + 1, cols - 1);
        const double fc = c - static_cast<double>(c0), fr = r - static_cast<double>(r0);
        const auto at = [&](std::size_t rr, std::size_t cc) {
          return static_cast<double>((*samples)[rr * cols + cc]);
        };
        return (1 - fr) * ((1 - fc) * at(r0, c0) + fc * at(r0, c1)) +
               fr * ((1 - fc) * at(r0 + 1, c0) + fc * at(r0 + 1, c1));
      },
      options);
}

double HeightLayers::heightAt(double latDeg, double lonDeg) const noexcept {
  const int w = equirectWidth(), h = equirectHeight(), n = capSize();
  const double lon = topo::wrapLongitude180(lonDeg);
  const double x = (lon + 180.0) / 360.0 * w - 0.5, y = (latDeg + 90.0) / 180.0 * h - 0.5;
  const double he = bilinear(equirect_, w, h, x, y, true);
  const double wc = smoothstep(options_.capLatitude, options_.capLatitude + options_.blendDegrees,
                               std::abs(latDeg));
  if (wc <= 0.0) return he;
  const double phi = latDeg * kDeg, lam = lon * kDeg;
  const glm::dvec3 normal(std::cos(phi) * std::cos(lam), std::cos(phi) * std::sin(lam),
                          std::sin(phi));
  const bool north = latDeg > 0.0;
  const MapCoords m = polarStereographic(normal, north);
  const double scale = n / (2.0 * capRadius_);
  const double hc = bilinear(north ? north_ : south_, n, n, (m.p + capRadius_) * scale - 0.5,
                             (m.q + capRadius_) * scale - 0.5, false);
  return he + wc * (hc - he);
}

}  // namespace regolith::farfield
