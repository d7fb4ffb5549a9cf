#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/rover/Rover.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace regolith::rover {

namespace {

std::string formatPoint(double x, double y) {
  return "(" + core::number(x) + ", " + core::number(y) + ")";
}

const char* contactStatusName(topo::QueryStatus s) noexcept {
  switch (s) {
    case topo::QueryStatus::Ok: return "ok";
    case topo::QueryStatus::Nodata: return "nodata";
    case topo::QueryStatus::OutsideGrid: return "outside the grid";
    case topo::QueryStatus::Unmappable: return "beyond the placement's projection";
  }
  return "unknown";
}

}  // namespace

double RoverGeometry::reach() const noexcept {
  double r = 0.0;
  for (const double a : axleOffsets) r = std::max(r, std::hypot(a, 0.5 * trackWidth));
  return r;
}

Rover::Rover(RoverGeometry geometry) : geometry_(geometry) {
  const auto& g = geometry_;
  if (!(std::isfinite(g.trackWidth) && g.trackWidth > 0.0)) {
    throw InvalidArgument("rover::Rover(): trackWidth is " + std::to_string(g.trackWidth) +
                          " m, expected finite and > 0");
  }
  if (!std::isfinite(g.clearance)) {
    throw InvalidArgument("rover::Rover(): clearance is not finite");
  }
  for (const double a : g.axleOffsets) {
    if (!std::isfinite(a)) throw InvalidArgument("rover::Rover(): an axle offset is not finite");
  }
  if (!(g.axleOffsets[0] > g.axleOffsets[1] && g.axleOffsets[1] > g.axleOffsets[2])) {
    throw InvalidArgument(
        "rover::Rover(): axleOffsets must decrease strictly (front, middle, rear)");
  }
}

std::array<glm::dvec2, kWheels> Rover::wheelPositions(const GroundPose& pose) const {
  const glm::dvec2 forward{std::sin(pose.heading), std::cos(pose.heading)};
  const glm::dvec2 left{-forward.y, forward.x};
  const glm::dvec2 centre{pose.x, pose.y};
  const double half = 0.5 * geometry_.trackWidth;
  std::array<glm::dvec2, kWheels> out{};
  for (std::size_t axle = 0; axle < 3; ++axle) {
    const glm::dvec2 a = centre + geometry_.axleOffsets[axle] * forward;
    out[2 * axle] = a + half * left;
    out[2 * axle + 1] = a - half * left;
  }
  return out;
}

ChassisPose Rover::settle(const GroundPose& pose,
                          const std::array<WheelContact, kWheels>& contacts) const {
  // Least-squares plane z = c0 + gx·dx + gy·dy, fitted on values centred on their means
  // (so a level plane gives slopes of exactly 0 whatever its height), then c0 from the
  // centroid. The six footprints span two directions (three axles, two sides), so the 2×2
  // system is well conditioned for any valid geometry.
  double mx = 0, my = 0, mz = 0;
  for (std::size_t i = 0; i < kWheels; ++i) {
    const WheelContact& c = contacts[i];
    if (c.status != topo::QueryStatus::Ok) {
      throw DomainError("rover::Rover::settle(): wheel " + std::to_string(i) + " at " +
                        formatPoint(c.x, c.y) + " has no terrain under it (" +
                        contactStatusName(c.status) + ")");
    }
    mx += c.x - pose.x, my += c.y - pose.y, mz += c.height;
  }
  const double n = static_cast<double>(kWheels);
  mx /= n, my /= n, mz /= n;
  double sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0;
  for (const WheelContact& c : contacts) {
    const double dx = c.x - pose.x - mx, dy = c.y - pose.y - my, dz = c.height - mz;
    sxx += dx * dx, sxy += dx * dy, syy += dy * dy, sxz += dx * dz, syz += dy * dz;
  }
  const double det = sxx * syy - sxy * sxy;
  const double gx = (sxz * syy - syz * sxy) / det;
  const double gy = (syz * sxx - sxz * sxy) / det;
  const double c0 = mz - gx * mx - gy * my;

  ChassisPose p;
  p.x = pose.x;
  p.y = pose.y;
  p.heading = pose.heading;
  p.height = c0;
  p.up = glm::normalize(glm::dvec3{-gx, -gy, 1.0});
  const glm::dvec3 fh{std::sin(pose.heading), std::cos(pose.heading), 0.0};
  const glm::dvec3 lh{-fh.y, fh.x, 0.0};
  const double slopeForward = gx * fh.x + gy * fh.y;
  p.forward = glm::normalize(fh + glm::dvec3{0.0, 0.0, slopeForward});
  p.pitch = std::atan(slopeForward);
  // Roll about the pitched forward axis: after pitch alone the left axis is lh and the up
  // axis forward × lh; after roll, left = up × forward (right-handed: forward × left = up).
  const glm::dvec3 left = glm::cross(p.up, p.forward);
  const glm::dvec3 upPitched = glm::cross(p.forward, lh);  // the up axis after pitch alone
  p.roll = std::atan2(glm::dot(left, upPitched), glm::dot(left, lh));
  p.position = glm::dvec3{pose.x, pose.y, c0} + geometry_.clearance * p.up;

  double ss = 0.0;
  for (const WheelContact& c : contacts) {
    const double r = c.height - (c0 + gx * (c.x - pose.x) + gy * (c.y - pose.y));
    ss += r * r;
  }
  p.residual = std::sqrt(ss / n);
  return p;
}

}  // namespace regolith::rover
