#include <regolith/clod/Camera.hpp>
#include <regolith/topo/ViewUp.hpp>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace regolith::clod {

glm::dvec3 Camera::forward() const noexcept { return glm::normalize(target - position); }

glm::dmat3 Camera::rotation() const noexcept {
  const glm::dvec3 f = forward();
  // At nadir, or looking at the body's centre, the local vertical is parallel to the view:
  // another up then (topo::viewUp()), not a NaN matrix and an empty image.
  const glm::dvec3 r = glm::normalize(glm::cross(f, topo::viewUp(f, up)));
  const glm::dvec3 u = glm::cross(r, f);
  // glm is column-major: m[col][row]; rows are r, u, −f.
  glm::dmat3 m(1.0);
  for (int c = 0; c < 3; ++c) {
    m[c][0] = r[c];
    m[c][1] = u[c];
    m[c][2] = -f[c];
  }
  return m;
}

double Camera::focalPixels() const noexcept {
  return 0.5 * height / std::tan(0.5 * fovYDegrees * std::numbers::pi / 180.0);
}

glm::mat4 Camera::viewProjection() const noexcept {
  const double f = 1.0 / std::tan(0.5 * fovYDegrees * std::numbers::pi / 180.0);
  const double aspect = static_cast<double>(width) / height;
  glm::dmat4 p(0.0);
  p[0][0] = f / aspect;
  p[1][1] = f;
  p[2][3] = -1.0;  // w = −z_eye = distance along the view axis
  p[3][2] = near;  // z = near, so depth = near / distance
  return glm::mat4(p * glm::dmat4(rotation()));
}

glm::dvec3 Camera::project(const glm::dvec3& world) const noexcept {
  const glm::dvec3 e = rotation() * (world - position);
  const double d = -e.z;
  const double fp = focalPixels();
  return {0.5 * width + fp * e.x / d, 0.5 * height - fp * e.y / d, near / d};
}

glm::dvec3 Camera::ray(double x, double y) const noexcept {
  const double fp = focalPixels();
  const glm::dvec3 e{(x - 0.5 * width) / fp, (0.5 * height - y) / fp, -1.0};
  return glm::normalize(glm::transpose(rotation()) * e);
}

}  // namespace regolith::clod
