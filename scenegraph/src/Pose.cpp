#include <regolith/core/Error.hpp>
#include <regolith/scenegraph/Pose.hpp>

#include <glm/geometric.hpp>

#include <cmath>

namespace regolith::scenegraph {

Pose Pose::fromAxes(const glm::dvec3& origin, const glm::dvec3& xAxis, const glm::dvec3& yAxis,
                    const glm::dvec3& zAxis) {
  const glm::dmat3 m(xAxis, yAxis, zAxis);
  const double det = glm::determinant(m);
  if (!(std::abs(det - 1.0) < 1e-9))
    throw InvalidArgument("Pose::fromAxes(): axes have determinant " + std::to_string(det) +
                          ", expected an orthonormal right-handed frame (1)");
  Pose p;
  p.translation = origin;
  p.rotation = glm::normalize(glm::quat_cast(m));
  return p;
}

Pose Pose::lookAt(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up) {
  const glm::dvec3 d = target - eye;
  if (!(glm::length(d) > 0.0))
    throw InvalidArgument("Pose::lookAt(): eye and target coincide, expected distinct points");
  const glm::dvec3 f = glm::normalize(d);
  const glm::dvec3 rr = glm::cross(f, up);
  if (!(glm::length(rr) > 1e-12 * glm::length(up)))
    throw InvalidArgument("Pose::lookAt(): up is parallel to the view direction");
  const glm::dvec3 r = glm::normalize(rr);
  const glm::dvec3 u = glm::cross(r, f);
  return fromAxes(eye, r, u, -f);
}

Pose Pose::inverse() const noexcept {
  Pose p;
  p.rotation = glm::conjugate(rotation);
  p.translation = -(p.rotation * translation);
  return p;
}

Pose operator*(const Pose& a, const Pose& b) noexcept {
  Pose p;
  p.rotation = glm::normalize(a.rotation * b.rotation);
  p.translation = a.rotation * b.translation + a.translation;
  return p;
}

}  // namespace regolith::scenegraph
