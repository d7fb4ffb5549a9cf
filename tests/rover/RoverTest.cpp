// Rover kinematics: wheel footprints and the chassis settled on analytic planes.
#include <regolith/core/Error.hpp>
#include <regolith/rover/Rover.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using namespace regolith;
using namespace regolith::rover;

constexpr double kDeg = std::numbers::pi / 180.0;

/// The chassis frame built independently of Rover::settle: yaw (heading clockwise from
/// north), then pitch nose-up about the left axis, then roll (right side down) about the
/// forward axis. Returns the up axis = the normal of the plane the wheels stand on.
glm::dvec3 upAfter(double heading, double pitch, double roll) {
  const glm::dvec3 f0{std::sin(heading), std::cos(heading), 0.0};
  const glm::dvec3 l0{-f0.y, f0.x, 0.0};
  const glm::dvec3 u0{0.0, 0.0, 1.0};
  const glm::dvec3 u1 = -std::sin(pitch) * f0 + std::cos(pitch) * u0;  // up after pitch
  return -std::sin(roll) * l0 + std::cos(roll) * u1;                   // up after roll
}

/// Contacts on the plane through (cx, cy, h0) with unit normal n.
std::array<WheelContact, kWheels> onPlane(const Rover& rover, const GroundPose& pose, double h0,
                                          const glm::dvec3& n) {
  std::array<WheelContact, kWheels> c{};
  const auto w = rover.wheelPositions(pose);
  for (std::size_t i = 0; i < kWheels; ++i) {
    const double h = h0 - (n.x * (w[i].x - pose.x) + n.y * (w[i].y - pose.y)) / n.z;
    c[i] = {w[i].x, w[i].y, h, n, topo::QueryStatus::Ok};
  }
  return c;
}

TEST(RoverTest, WheelPositionsFollowTheHeading) {
  const Rover rover;  // axles +1.10, 0, −1.00; track 2.20
  const auto north = rover.wheelPositions({10.0, 20.0, 0.0});
  EXPECT_NEAR(north[0].x, 10.0 - 1.1, 1e-12);  // front left: west of the centre
  EXPECT_NEAR(north[0].y, 20.0 + 1.1, 1e-12);
  EXPECT_NEAR(north[1].x, 10.0 + 1.1, 1e-12);  // front right
  EXPECT_NEAR(north[5].y, 20.0 - 1.0, 1e-12);  // rear right
  EXPECT_NEAR(north[5].x, 10.0 + 1.1, 1e-12);
  const auto east = rover.wheelPositions({0.0, 0.0, 90.0 * kDeg});
  EXPECT_NEAR(east[0].x, 1.1, 1e-12);  // front left: ahead (east) and north
  EXPECT_NEAR(east[0].y, 1.1, 1e-12);
  EXPECT_NEAR(east[3].x, 0.0, 1e-12);  // middle right: south of the centre
  EXPECT_NEAR(east[3].y, -1.1, 1e-12);
  EXPECT_NEAR(rover.geometry().reach(), std::hypot(1.1, 1.1), 1e-12);
}

TEST(RoverTest, FlatGroundIsLevel) {
  const Rover rover;
  const GroundPose pose{3.0, -4.0, 37.0 * kDeg};
  const ChassisPose p = rover.settle(pose, onPlane(rover, pose, -1400.5, {0.0, 0.0, 1.0}));
  EXPECT_EQ(p.pitch, 0.0);
  EXPECT_EQ(p.roll, 0.0);
  EXPECT_DOUBLE_EQ(p.height, -1400.5);
  EXPECT_EQ(p.up, glm::dvec3(0.0, 0.0, 1.0));
  EXPECT_NEAR(p.position.z, -1400.5 + rover.geometry().clearance, 1e-12);
  EXPECT_EQ(p.residual, 0.0);
}

TEST(RoverTest, TiltedPlaneGivesItsPitchAndRoll) {
  const Rover rover;
  for (const double heading : {0.0, 30.0, 135.0, -100.0}) {
    for (const double pitch : {-12.0, 0.0, 7.5, 25.0}) {
      for (const double roll : {-18.0, 0.0, 4.0, 30.0}) {
        const GroundPose pose{100.0, -50.0, heading * kDeg};
        const glm::dvec3 n = upAfter(pose.heading, pitch * kDeg, roll * kDeg);
        const ChassisPose p = rover.settle(pose, onPlane(rover, pose, 12.25, n));
        SCOPED_TRACE(testing::Message()
                     << "heading " << heading << " pitch " << pitch << " roll " << roll);
        EXPECT_NEAR(p.pitch, pitch * kDeg, 1e-12);
        EXPECT_NEAR(p.roll, roll * kDeg, 1e-12);
        EXPECT_NEAR(p.height, 12.25, 1e-9);
        EXPECT_NEAR(glm::distance(p.up, n), 0.0, 1e-12);
        EXPECT_NEAR(p.residual, 0.0, 1e-9);
        // The chassis reference point sits `clearance` above the plane along its normal.
        EXPECT_NEAR(glm::distance(p.position, glm::dvec3(100.0, -50.0, 12.25) + 0.66 * n), 0.0,
                    1e-9);
      }
    }
  }
}

TEST(RoverTest, ARaisedWheelLeavesAResidual) {
  const Rover rover;
  const GroundPose pose{0.0, 0.0, 0.0};
  auto c = onPlane(rover, pose, 0.0, {0.0, 0.0, 1.0});
  c[2].height = 0.6;  // middle-left wheel on a rock
  const ChassisPose p = rover.settle(pose, c);
  EXPECT_GT(p.residual, 0.05);
  EXPECT_GT(p.roll, 0.0);  // the left side rises: right side down is positive roll
  // A least-squares plane passes through the centroid of the contacts: (0, 0.2/6) at the
  // mean height 0.6/6.
  const double gy = -p.up.y / p.up.z;
  EXPECT_NEAR(p.height + gy * (0.2 / 6.0), 0.1, 1e-12);
}

TEST(RoverTest, AWheelOverNodataIsAnError) {
  const Rover rover;
  const GroundPose pose{0.0, 0.0, 0.0};
  auto c = onPlane(rover, pose, 0.0, {0.0, 0.0, 1.0});
  c[4].status = topo::QueryStatus::Nodata;
  c[4].height = std::nan("");
  try {
    (void)rover.settle(pose, c);
    FAIL() << "expected DomainError";
  } catch (const DomainError& e) {
    EXPECT_STREQ(e.what(),
                 "rover::Rover::settle(): wheel 4 at (-1.1, -1) has no terrain under it (nodata)");
  }
}

TEST(RoverTest, BadGeometryIsRejected) {
  RoverGeometry g;
  g.trackWidth = 0.0;
  EXPECT_THROW(Rover{g}, InvalidArgument);
  g = {};
  g.axleOffsets = {0.0, 1.0, -1.0};
  EXPECT_THROW(Rover{g}, InvalidArgument);
  g = {};
  g.clearance = std::nan("");
  EXPECT_THROW(Rover{g}, InvalidArgument);
}

}  // namespace
