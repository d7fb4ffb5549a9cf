#include <regolith/farfield/PgmMath.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace regolith::farfield {

namespace {

constexpr double kPi = std::numbers::pi;

double clamp1(double x) noexcept { return std::clamp(x, -1.0, 1.0); }

/// A unit vector perpendicular to `n` (any one).
glm::dvec3 anyPerpendicular(const glm::dvec3& n) noexcept {
  const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
  return glm::normalize(glm::cross(n, a));
}

/// The unit component of v perpendicular to the unit vector n, or nullopt if v ∥ n.
std::optional<glm::dvec3> perpendicularPart(const glm::dvec3& v, const glm::dvec3& n) noexcept {
  const glm::dvec3 p = v - glm::dot(v, n) * n;
  const double len = glm::length(p);
  if (!(len > 1e-9 * glm::length(v))) return std::nullopt;
  return p / len;
}

/// Clips the convex cone of rays `poly` (apex at the eye) by the half-space m·r ≥ 0
/// (Sutherland–Hodgman on the rays as vectors: interpolating two rays linearly stays on the
/// cone's face between them).
std::vector<glm::dvec3> clipCone(const std::vector<glm::dvec3>& poly, const glm::dvec3& m) {
  std::vector<glm::dvec3> out;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3& p = poly[i];
    const glm::dvec3& q = poly[(i + 1) % n];
    const double sp = glm::dot(m, p), sq = glm::dot(m, q);
    const bool inP = sp >= 0.0, inQ = sq >= 0.0;
    if (inP != inQ) {
      const double t = sp / (sp - sq);
      out.push_back(glm::normalize(p + t * (q - p)));
    }
    if (inQ) out.push_back(q);
  }
  return out;
}

}  // namespace

std::optional<double> frontNormalAngle(double omega, double d, double r) noexcept {
  if (!(d > r) || !(r > 0.0)) return std::nullopt;
  const double s = std::sin(omega), c = std::cos(omega);
  const double disc = (r - d * s) * (r + d * s);
  if (disc < 0.0 || c <= 0.0) return std::nullopt;
  const double t = (d - r) * (d + r) / (d * c + std::sqrt(disc));
  return std::asin(clamp1(t * s / r));
}

std::optional<double> backNormalAngle(double omega, double d, double r) noexcept {
  if (!(r > 0.0)) return std::nullopt;
  const double s = std::sin(omega), x = d * s / r;
  if (x > 1.0) return std::nullopt;
  if (d > r && std::cos(omega) <= 0.0) return std::nullopt;
  return kPi - omega - std::asin(clamp1(x));
}

glm::dvec3 eyeSpacePoint(double gamma, double d, double r, const glm::dvec3& nadir,
                         const glm::dvec3& k) noexcept {
  const double h = std::sin(0.5 * gamma);
  return ((d - r) + 2.0 * r * h * h) * nadir + r * std::sin(gamma) * k;
}

ReferenceSpheres referenceSpheres(double d, double primary, double maximum, double zeta) noexcept {
  ReferenceSpheres s;
  s.d = d;
  s.primary = std::clamp(primary, 1e-9 * d, d * (1.0 - 1e-12));
  s.maximum = std::max(maximum, s.primary);
  s.zeta = std::clamp(zeta, 0.05, 1.0);
  s.tau0 = std::asin(s.primary / d);
  s.tauTop = d > s.maximum ? std::asin(s.maximum / d) : 0.5 * kPi;
  // The primary tangent ray (ω = τ₀, d·sin ω = r_p) leaves the maximum sphere at its back hit.
  s.gamma0 = kPi - s.tau0 - std::asin(clamp1(s.primary / s.maximum));
  s.secondary = d * std::cos(s.gamma0);
  s.begin = s.zeta * s.tau0;
  s.gammaBegin = frontNormalAngle(s.begin, d, s.primary).value_or(0.5 * kPi - s.tau0);
  if (s.secondaryExists()) {
    s.tauS = std::asin(std::min(1.0, s.secondary / d));
    s.omegaSBegin = std::min(s.begin, s.tauS);
  }
  return s;
}

double blendedNormalAngle(const ReferenceSpheres& s, double omega) noexcept {
  omega = std::max(omega, 0.0);
  const auto primaryAt = [&](double w) {
    return frontNormalAngle(std::min(w, s.tau0), s.d, s.primary).value_or(0.5 * kPi - s.tau0);
  };
  if (omega <= s.begin) return primaryAt(omega);
  const double span = s.tauTop - s.begin;
  const double f = span > 0.0 ? std::clamp((omega - s.begin) / span, 0.0, 1.0) : 1.0;
  const double u = s.omegaSBegin + f * (s.tauS - s.omegaSBegin);
  const double gammaS = std::asin(std::min(1.0, s.d * std::sin(u) / s.secondary)) - u;
  return primaryAt(omega) + f * (gammaS - primaryAt(omega));
}

RaySpread evenErrorSpread(const ReferenceSpheres& s, int entries) {
  RaySpread out;
  if (!(s.tauTop > 0.0) || entries < 2) return out;
  // The cumulative of dγ/√distance on a fine even grid of ray angles (1024 steps: under
  // 0.1 ms a frame, and recomputed only when the spheres change), then inverted at
  // `entries` even values by linear interpolation.
  constexpr std::size_t kSteps = 1024;
  constexpr double kStepsD = 1024.0;
  std::vector<double> cumulative(kSteps + 1, 0.0);
  double previous = 0.0;  // γ(0)
  for (std::size_t j = 1; j <= kSteps; ++j) {
    const double gamma = blendedNormalAngle(s, s.tauTop * static_cast<double>(j) / kStepsD);
    const double mid = 0.5 * (gamma + previous);
    const double h = std::sin(0.5 * mid);
    const double along = (s.d - s.primary) + 2.0 * s.primary * h * h;  // d − r·cos γ
    const double across = s.primary * std::sin(mid);
    const double distance = std::sqrt(along * along + across * across);
    cumulative[j] = cumulative[j - 1] + std::max(gamma - previous, 0.0) / std::sqrt(distance);
    previous = gamma;
  }
  const double total = cumulative[kSteps];
  if (!(total > 0.0) || !std::isfinite(total)) return out;
  out.top = s.tauTop;
  out.table.resize(static_cast<std::size_t>(entries));
  std::size_t j = 0;
  for (std::size_t i = 0; i < out.table.size(); ++i) {
    const double x = static_cast<double>(i) / static_cast<double>(entries - 1);
    const double target = total * x;
    while (j + 1 < kSteps && cumulative[j + 1] < target) ++j;
    const double step = cumulative[j + 1] - cumulative[j];
    const double f = step > 0.0 ? std::clamp((target - cumulative[j]) / step, 0.0, 1.0) : 0.0;
    const double omega = s.tauTop * (static_cast<double>(j) + f) / kStepsD;
    out.table[i] = std::max(omega, s.tauTop * x);  // never below the identity: coverage
  }
  out.table.front() = 0.0;
  out.table.back() = s.tauTop;
  return out;
}

double RaySpread::angle(double omega) const noexcept {
  if (!active() || !(omega < top) || !(omega > 0.0)) return omega;
  const double x = omega / top * static_cast<double>(table.size() - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(x), table.size() - 2);
  const double f = x - static_cast<double>(i);
  return table[i] + f * (table[i + 1] - table[i]);
}

glm::dvec3 RaySpread::ray(const glm::dvec3& r, const glm::dvec3& nadir) const noexcept {
  const double c = glm::dot(r, nadir);
  const glm::dvec3 across = r - c * nadir;
  const double sl = glm::length(across);
  if (!(sl > 1e-12)) return r;
  const double omega = std::atan2(sl, c);
  const double turned = angle(omega);
  return std::cos(turned) * nadir + std::sin(turned) * (across / sl);
}

glm::dvec3 SamplingCamera::ray(double u, double v) const noexcept {
  return glm::normalize(forward + (left + u * (right - left)) * rightAxis +
                        (bottom + v * (top - bottom)) * up);
}

bool SamplingCamera::holds(const glm::dvec3& direction) const noexcept {
  const double z = glm::dot(direction, forward);
  if (!(z > 0.0)) return false;
  const double x = glm::dot(direction, rightAxis) / z, y = glm::dot(direction, up) / z;
  const double eps = 1e-9 * (1.0 + std::abs(x) + std::abs(y));
  return x >= left - eps && x <= right + eps && y >= bottom - eps && y <= top + eps;
}

Frustum viewFrustum(const glm::dvec3& forward, const glm::dvec3& right, const glm::dvec3& up,
                    double fovYRadians, double aspect) noexcept {
  const double th = std::tan(0.5 * fovYRadians), tw = th * aspect;
  return Frustum{{glm::normalize(forward - tw * right - th * up),
                  glm::normalize(forward + tw * right - th * up),
                  glm::normalize(forward + tw * right + th * up),
                  glm::normalize(forward - tw * right + th * up)}};
}

SamplingCamera samplingCamera(const Frustum& view, const glm::dvec3& nadir, double tauTop,
                              double maxHalfAngle) noexcept {
  const glm::dvec3 n = glm::normalize(nadir);
  const glm::dvec3 viewForward =
      glm::normalize(view.corners[0] + view.corners[1] + view.corners[2] + view.corners[3]);
  const glm::dvec3 viewUp =
      glm::normalize((view.corners[2] + view.corners[3]) - (view.corners[0] + view.corners[1]));
  const glm::dvec3 viewRight = glm::normalize(glm::cross(viewForward, viewUp));

  // The planet frustum: a square frustum about the nadir whose sides touch the cone of
  // half-angle τ (at τ = π/2 every side is the horizontal plane through the eye). Its up lies
  // in the plane of the view's up and forward, i.e. along viewRight × n.
  const double tau = std::clamp(tauTop, 0.0, 0.5 * kPi);
  const glm::dvec3 eUp =
      perpendicularPart(glm::cross(viewRight, n), n)
          .value_or(perpendicularPart(viewForward, n).value_or(anyPerpendicular(n)));
  const glm::dvec3 eRight = glm::normalize(glm::cross(eUp, n));
  const std::array<glm::dvec3, 4> sides{eUp, eRight, -eUp, -eRight};

  SamplingCamera cam;
  std::vector<glm::dvec3> poly(std::begin(view.corners), std::end(view.corners));
  for (const glm::dvec3& e : sides) {
    if (poly.empty()) break;
    poly = clipCone(poly, std::sin(tau) * n - std::cos(tau) * e);  // inward side normal
  }
  if (poly.size() < 3) {
    cam.lookedAway = true;
    const double t = std::tan(std::min(tau, maxHalfAngle));
    poly = {glm::normalize(n + t * (eUp + eRight)), glm::normalize(n + t * (eUp - eRight)),
            glm::normalize(n + t * (-eUp - eRight)), glm::normalize(n + t * (-eUp + eRight))};
  }
  cam.corners = poly;

  // Horizon-aligned frame of the view: its up is the antinadir's part across the forward axis.
  const glm::dvec3 hUp = perpendicularPart(-n, viewForward).value_or(viewUp);
  double sy = 0.0, sz = 0.0;
  std::vector<glm::dvec3> rays = poly;
  rays.push_back(n);
  for (const glm::dvec3& r : rays) {
    sy += glm::dot(r, hUp);
    sz += glm::dot(r, viewForward);
  }
  glm::dvec3 fwd = sy * hUp + sz * viewForward;
  fwd = glm::length(fwd) > 1e-9 ? glm::normalize(fwd) : n;
  cam.forward = fwd;
  cam.up = perpendicularPart(-n, fwd).value_or(
      perpendicularPart(viewUp, fwd).value_or(anyPerpendicular(fwd)));
  cam.rightAxis = glm::normalize(glm::cross(fwd, cam.up));

  const double cosMax = std::cos(maxHalfAngle), sinMax = std::sin(maxHalfAngle);
  cam.left = cam.bottom = 1e300;
  cam.right = cam.top = -1e300;
  for (glm::dvec3 r : rays) {
    const double z = glm::dot(r, fwd);
    if (z < cosMax) {
      const glm::dvec3 side = perpendicularPart(r, fwd).value_or(cam.up);
      r = cosMax * fwd + sinMax * side;
    }
    const double zr = glm::dot(r, fwd);
    const double x = glm::dot(r, cam.rightAxis) / zr, y = glm::dot(r, cam.up) / zr;
    cam.left = std::min(cam.left, x);
    cam.right = std::max(cam.right, x);
    cam.bottom = std::min(cam.bottom, y);
    cam.top = std::max(cam.top, y);
  }
  return cam;
}

MapCoords equirectangular(const glm::dvec3& surfaceNormal, double lon0, double lat0) noexcept {
  const double lat = std::atan2(surfaceNormal.z, std::hypot(surfaceNormal.x, surfaceNormal.y));
  const double lon = std::atan2(surfaceNormal.y, surfaceNormal.x);
  double dl = std::remainder(lon - lon0, 2.0 * kPi);
  if (dl >= kPi) dl -= 2.0 * kPi;
  return {dl * std::cos(lat0), lat};
}

MapCoords polarStereographic(const glm::dvec3& surfaceNormal, bool north) noexcept {
  // 2·tan(π/4 − |φ|/2) = 2·cos φ / (1 + |sin φ|), and (sin λ, cos λ)·cos φ = (y, x): no trig.
  const double k = 2.0 / (1.0 + (north ? surfaceNormal.z : -surfaceNormal.z));
  return {k * surfaceNormal.y, (north ? -k : k) * surfaceNormal.x};
}

glm::dvec3 geodeticNormal(const glm::dvec3& s, double a, double b) noexcept {
  return glm::normalize(glm::dvec3(s.x / (a * a), s.y / (a * a), s.z / (b * b)));
}

double ellipsoidRadiusAbove(const glm::dvec3& s, double a, double b, double reference) noexcept {
  const double sin2 = s.z * s.z / glm::dot(s, s);
  const double q = std::sqrt(b * b * (1.0 - sin2) + a * a * sin2);
  return a * (b - a) * (b + a) * sin2 / (q * (b + q)) + (a - reference);
}

}  // namespace regolith::farfield
