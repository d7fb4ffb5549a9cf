#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/scenegraph/Pose.hpp>
#include <regolith/topo/ViewUp.hpp>

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
  const auto finite = [](const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  const auto refuse = [](const char* field, const glm::dvec3& v) {
    throw InvalidArgument(
        core::format({"Pose::lookAt()",
                      {},
                      field,
                      core::number(v.x) + ", " + core::number(v.y) + ", " + core::number(v.z),
                      "finite"}));
  };
  if (!finite(eye)) refuse("eye", eye);
  if (!finite(target)) refuse("target", target);
  if (!finite(up)) refuse("up", up);
  const glm::dvec3 d = target - eye;
  if (!(glm::length(d) > 0.0))
    throw InvalidArgument("Pose::lookAt(): eye and target coincide, expected distinct points");
  const glm::dvec3 f = glm::normalize(d);
  const glm::dvec3 r = glm::normalize(glm::cross(f, topo::viewUp(f, up)));
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
