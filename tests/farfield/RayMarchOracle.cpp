#include "farfield/RayMarchOracle.hpp"

#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cstdint>
#include <sstream>

namespace regolith::test {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// The two roots t1 ≤ t2 of |o + t·d|² = r² for a unit d, or nullopt if the line misses the
/// sphere. The discriminant comes from the line's closest point to the centre and the small
/// root from c / (large root), so both stay accurate for a camera 10^8 m away and for one
/// 1 mm from the sphere.
std::optional<std::pair<double, double>> sphereRoots(const glm::dvec3& o, const glm::dvec3& d,
                                                     double r) {
  const double b = glm::dot(o, d);
  const double q = glm::length(o - b * d);
  const double disc = (r - q) * (r + q);
  if (disc < 0.0) return std::nullopt;
  const double s = std::sqrt(disc);
  const double lo = glm::length(o);
  const double c = (lo - r) * (lo + r);
  if (b <= 0.0) {
    const double t2 = -b + s;
    return std::pair{t2 > 0.0 ? c / t2 : -b - s, t2};
  }
  const double t1 = -b - s;
  return std::pair{t1, c / t1};
}

/// f along one ray, and the search for its first crossing.
class Ray {
 public:
  Ray(const glm::dvec3& origin, const glm::dvec3& direction, const OracleSurface& surface,
      double maxStep, const RayMarchOptions& options)
      : o_(origin),
        d_(direction),
        s_(surface),
        maxStep_(maxStep),
        graze_(options.grazeRefineMetres > 0.0 ? options.grazeRefineMetres : maxStep),
        fraction_(options.aboveBoundFraction),
        tolerance_(options.toleranceMetres),
        relative_(options.relativeTolerance) {}

  std::optional<double> march() const {
    const topo::Body& body = s_.body;
    const auto outer = sphereRoots(o_, d_, body.equatorialRadius() + s_.maxHeight);
    if (!outer || outer->second < 0.0) return std::nullopt;
    const double tIn = std::max(0.0, outer->first);
    double tOut = outer->second;
    // Inside the inner sphere every point is at or below minHeight, so f ≤ 0 there: the march
    // ends at the middle of the ray's chord through it, where f is lowest (not at its entry,
    // where rounding may leave f > 0 when the shell is thin or the ray grazes it).
    const double innerRadius = body.polarRadius() + s_.minHeight;
    if (innerRadius > 0.0) {
      const auto inner = sphereRoots(o_, d_, innerRadius);
      if (inner && inner->second >= 0.0) {
        tOut = std::min(tOut, std::max(0.0, 0.5 * (inner->first + inner->second)));
      }
    }

    double t0 = tIn;
    Sample e0 = at(t0);
    if (e0.f <= 0.0) {
      if (tIn == 0.0) throwCameraBelow(e0);
      return tIn;  // a summit touching the outer sphere
    }
    double tp = t0, fp = kInf;  // the sample before t0 (none yet)
    for (;;) {
      const double step = std::max(maxStep_, fraction_ * (e0.altitude - s_.maxHeight));
      const double t1 = std::min(std::max(t0 + step, std::nextafter(t0, kInf)), tOut);
      const Sample e1 = at(t1);
      if (e1.f <= 0.0) return bisect(t0, t1);
      // A local minimum of f at t0 close to the surface: the ray may graze it between samples.
      if (e0.f < fp && e0.f <= e1.f && e0.f < graze_) {
        const auto [tm, fm] = minimum(tp, t1);
        if (fm <= 0.0) return bisect(tp, tm);
      }
      if (t1 >= tOut) return std::nullopt;
      tp = t0;
      fp = e0.f;
      t0 = t1;
      e0 = e1;
    }
  }

 private:
  struct Sample {
    double f;         ///< altitude − height, metres
    double altitude;  ///< planetodetic height of the point, metres
    double latDeg, lonDeg;
  };

  Sample at(double t) const {
    const topo::Geodetic g = s_.body.toGeodetic(o_ + t * d_);
    const double h = s_.height(g.latDeg, g.lonDeg);
    if (!(h >= s_.minHeight && h <= s_.maxHeight)) {
      const std::string field =
          "surface.height(" + core::number(g.latDeg) + ", " + core::number(g.lonDeg) + ")";
      const std::string value = core::number(h) + " m";
      const std::string expected = "within [minHeight, maxHeight] = [" +
                                   core::number(s_.minHeight) + ", " + core::number(s_.maxHeight) +
                                   "] m";
      throw InvalidArgument(core::format(
          {.operation = "test::rayMarch()", .field = field, .value = value, .expected = expected}));
    }
    return {g.height - h, g.height, g.latDeg, g.lonDeg};
  }

  [[noreturn]] void throwCameraBelow(const Sample& e) const {
    const std::string field = "camera at lat " + core::number(e.latDeg) + ", lon " +
                              core::number(e.lonDeg) + ", altitude " + core::number(e.altitude) +
                              " m";
    const std::string value = core::number(e.f) + " m above the surface";
    throw InvalidArgument(core::format(
        {.operation = "test::rayMarch()", .field = field, .value = value, .expected = "> 0"}));
  }

  /// The bracket width to stop at, near t: tolerance_, or relative_·t if that is smaller.
  [[nodiscard]] double bracket(double t) const { return std::min(tolerance_, relative_ * t); }

  /// A crossing between lo (f > 0) and hi (f ≤ 0), to bracket(hi) or the doubles' resolution.
  double bisect(double lo, double hi) const {
    while (hi - lo > bracket(hi)) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      (at(mid).f > 0.0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }

  /// Golden-section search for the minimum of f on [a, b]; returns as soon as f ≤ 0.
  std::pair<double, double> minimum(double a, double b) const {
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = at(x1).f, f2 = at(x2).f;
    while (b - a > bracket(b) && f1 > 0.0 && f2 > 0.0) {
      if (!(x1 > a && x2 < b)) break;  // the doubles' resolution
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - g * (b - a);
        f1 = at(x1).f;
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + g * (b - a);
        f2 = at(x2).f;
      }
    }
    return f1 <= f2 ? std::pair{x1, f1} : std::pair{x2, f2};
  }

  glm::dvec3 o_, d_;
  const OracleSurface& s_;
  double maxStep_, graze_, fraction_, tolerance_, relative_;
};

void requireOptions(const OracleSurface& surface, double maxStepMetres,
                    const RayMarchOptions& options) {
  const auto fail = [](const char* field, double v, const char* expected) {
    throw InvalidArgument(core::format({.operation = "test::rayMarch()",
                                        .field = field,
                                        .value = core::number(v),
                                        .expected = expected}));
  };
  if (!(maxStepMetres > 0.0 && std::isfinite(maxStepMetres))) {
    fail("maxStepMetres", maxStepMetres, "finite and > 0");
  }
  if (!std::isfinite(surface.minHeight)) fail("minHeight", surface.minHeight, "finite");
  if (!(std::isfinite(surface.maxHeight) && surface.maxHeight >= surface.minHeight)) {
    fail("maxHeight", surface.maxHeight, "finite and >= minHeight");
  }
  if (!(options.aboveBoundFraction > 0.0 && options.aboveBoundFraction <= 1.0)) {
    fail("aboveBoundFraction", options.aboveBoundFraction, "in (0, 1]");
  }
  if (!(options.toleranceMetres > 0.0)) fail("toleranceMetres", options.toleranceMetres, "> 0");
  if (!(options.relativeTolerance > 0.0)) {
    fail("relativeTolerance", options.relativeTolerance, "> 0");
  }
  if (!surface.height) {
    throw InvalidArgument(core::format({.operation = "test::rayMarch()",
                                        .field = "surface.height",
                                        .value = "empty",
                                        .expected = "a function"}));
  }
}

}  // namespace

std::size_t OracleImage::hitCount() const noexcept {
  return static_cast<std::size_t>(
      std::count_if(distance.begin(), distance.end(), [](double d) { return !std::isnan(d); }));
}

int OracleImage::topmostHit(int x) const noexcept {
  for (int y = 0; y < height; ++y) {
    if (hit(x, y)) return y;
  }
  return -1;
}

std::optional<double> marchRay(const glm::dvec3& origin, const glm::dvec3& direction,
                               const OracleSurface& surface, double maxStepMetres,
                               const RayMarchOptions& options) {
  requireOptions(surface, maxStepMetres, options);
  return Ray(origin, direction, surface, maxStepMetres, options).march();
}

OracleImage rayMarch(const clod::Camera& camera, const OracleSurface& surface, double maxStepMetres,
                     const RayMarchOptions& options) {
  requireOptions(surface, maxStepMetres, options);
  if (options.threads < 1) {
    throw InvalidArgument(core::format({.operation = "test::rayMarch()",
                                        .field = "threads",
                                        .value = core::number(options.threads),
                                        .expected = ">= 1"}));
  }
  OracleImage image;
  image.width = camera.width;
  image.height = camera.height;
  image.near = camera.near;
  const std::size_t n =
      static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
  image.distance.assign(n, kNaN);
  image.point.assign(n, glm::dvec3(kNaN));
  const glm::dvec3 forward = camera.forward();
  core::parallelFor(
      options.executor, static_cast<std::size_t>(camera.height),
      [&](std::size_t row) {
        const int y = static_cast<int>(row);
        for (int x = 0; x < camera.width; ++x) {
          const glm::dvec3 d = camera.ray(x + 0.5, y + 0.5);
          const auto t = Ray(camera.position, d, surface, maxStepMetres, options).march();
          if (!t) continue;
          image.distance[image.index(x, y)] = *t * glm::dot(d, forward);
          image.point[image.index(x, y)] = camera.position + *t * d;
        }
      },
      options.threads);
  return image;
}

gl::DepthImage toDepthImage(const OracleImage& image) {
  gl::DepthImage depth;
  depth.width = image.width;
  depth.height = image.height;
  depth.depth.resize(image.distance.size());
  std::transform(image.distance.begin(), image.distance.end(), depth.depth.begin(), [&](double d) {
    return std::isnan(d) ? 0.0F : static_cast<float>(image.near / d);
  });
  return depth;
}

gl::RgbaImage depthPicture(const OracleImage& image) {
  double lo = kInf, hi = 0.0;
  for (const double d : image.distance) {
    if (std::isnan(d)) continue;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  const double span = hi > lo ? std::log(hi / lo) : 1.0;
  gl::RgbaImage picture;
  picture.width = image.width;
  picture.height = image.height;
  picture.rgba.resize(4 * image.distance.size());
  for (std::size_t i = 0; i < image.distance.size(); ++i) {
    std::uint8_t* p = picture.rgba.data() + 4 * i;
    const double d = image.distance[i];
    if (std::isnan(d)) {
      p[0] = 20;
      p[1] = 30;
      p[2] = 90;
    } else {
      const auto grey =
          static_cast<std::uint8_t>(std::lround(255.0 - 200.0 * std::log(d / lo) / span));
      p[0] = p[1] = p[2] = grey;
    }
    p[3] = 255;
  }
  return picture;
}

std::string SilhouetteReport::describe() const {
  std::ostringstream out;
  out << "coverage mismatches " << coverageMismatches << " ("
      << coverageMismatchesAwayFromSilhouette << " away from the silhouette), depth mismatches "
      << depthMismatches << " (" << depthMismatchesAwayFromSilhouette << " away), compared "
      << comparedPixels << " pixels: median relative depth difference "
      << medianRelativeDepthDifference << ", max " << maxRelativeDepthDifference;
  if (!misplaced.empty()) {
    out << "; misplaced pixels (x, y):";
    for (const auto& [x, y] : misplaced) out << " (" << x << ", " << y << ")";
  }
  return out.str();
}

SilhouetteReport compareSilhouettes(const OracleImage& oracle, const gl::DepthImage& gpu,
                                    const SilhouetteOptions& options) {
  if (gpu.width != oracle.width || gpu.height != oracle.height) {
    throw InvalidArgument(
        core::format({.operation = "test::compareSilhouettes()",
                      .field = "GPU depth image size",
                      .value = core::number(gpu.width) + " x " + core::number(gpu.height),
                      .expected = "the oracle's " + core::number(oracle.width) + " x " +
                                  core::number(oracle.height)}));
  }
  const int w = oracle.width, h = oracle.height;
  const double ratio = options.discontinuityRatio;
  // Oracle pixels that differ from one of their 8 neighbours (sky against body, or a depth
  // step larger than the ratio) lie on the silhouette; grown by radiusPixels − 1.
  const auto differ = [&](int x0, int y0, int x1, int y1) {
    const double a = oracle.distanceAt(x0, y0), b = oracle.distanceAt(x1, y1);
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) != std::isnan(b);
    return std::max(a, b) > (1.0 + ratio) * std::min(a, b);
  };
  std::vector<std::uint8_t> edge(oracle.distance.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int dy = -1; dy <= 1 && edge[oracle.index(x, y)] == 0; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          if (differ(x, y, nx, ny)) {
            edge[oracle.index(x, y)] = 1;
            break;
          }
        }
      }
    }
  }
  std::vector<std::uint8_t> near = edge;
  for (int grow = 1; grow < options.radiusPixels; ++grow) {
    std::vector<std::uint8_t> next = near;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx >= 0 && ny >= 0 && nx < w && ny < h && near[oracle.index(nx, ny)] != 0) {
              next[oracle.index(x, y)] = 1;
            }
          }
        }
      }
    }
    near.swap(next);
  }

  SilhouetteReport report;
  std::vector<double> differences;
  const auto misplace = [&](int x, int y) {
    if (report.misplaced.size() < 16) report.misplaced.emplace_back(x, y);
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double d = oracle.distanceAt(x, y);
      const float z = gpu.at(x, y);
      const bool atSilhouette = near[oracle.index(x, y)] != 0;
      const bool oracleHit = !std::isnan(d), gpuHit = z > 0.0F;
      if (oracleHit != gpuHit) {
        ++report.coverageMismatches;
        if (!atSilhouette) {
          ++report.coverageMismatchesAwayFromSilhouette;
          misplace(x, y);
        }
        continue;
      }
      if (!oracleHit) continue;
      const double relative = std::abs(oracle.near / static_cast<double>(z) - d) / d;
      if (relative > ratio) {
        ++report.depthMismatches;
        if (!atSilhouette) {
          ++report.depthMismatchesAwayFromSilhouette;
          misplace(x, y);
        }
      }
      if (!atSilhouette) differences.push_back(relative);
    }
  }
  report.comparedPixels = differences.size();
  if (!differences.empty()) {
    const auto mid = differences.begin() + static_cast<std::ptrdiff_t>(differences.size() / 2);
    std::nth_element(differences.begin(), mid, differences.end());
    report.medianRelativeDepthDifference = *mid;
    report.maxRelativeDepthDifference = *std::max_element(differences.begin(), differences.end());
  }
  return report;
}

}  // namespace regolith::test
