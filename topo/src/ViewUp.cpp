#include <regolith/topo/ViewUp.hpp>

#include <glm/geometric.hpp>

#include <cmath>

namespace regolith::topo {

glm::dvec3 viewUp(const glm::dvec3& forward, const glm::dvec3& up) noexcept {
  const double lf = glm::length(forward), lu = glm::length(up);
  // sin of the angle between them; NaN (not finite input) fails the test too.
  const double s = glm::length(glm::cross(forward, up)) / (lf * lu);
  if (s > 1e-6) return up;
  const glm::dvec3 f = forward / lf;
  int k = 0;  // the axis least aligned with the view
  for (int i = 1; i < 3; ++i) {
    if (std::abs(f[i]) < std::abs(f[k])) k = i;
  }
  glm::dvec3 e(0.0);
  e[k] = 1.0;
  return glm::normalize(e - f * glm::dot(f, e));
}

}  // namespace regolith::topo
