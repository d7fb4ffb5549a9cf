// topo::viewUp(): the one up-vector rule of every camera (clod::Camera, scenegraph::Pose).
// Oracles: the given up itself where it is usable, and the geometry of the replacement
// (unit length, perpendicular to the view, along the frame axis least aligned with it).
#include <regolith/topo/ViewUp.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace regolith::topo {
namespace {

TEST(ViewUp, AnUpOffTheViewIsKeptBitForBit) {
  for (const glm::dvec3& forward :
       {glm::dvec3(0, 0, -1), glm::dvec3(1, 2, 3), glm::dvec3(-3396190.0, 0.0, 1e-3)}) {
    for (const glm::dvec3& up : {glm::dvec3(0, 1, 0), glm::dvec3(5, -7, 0.25)}) {
      const glm::dvec3 u = viewUp(forward, up);
      EXPECT_EQ(u.x, up.x);
      EXPECT_EQ(u.y, up.y);
      EXPECT_EQ(u.z, up.z);
    }
  }
  // 1e-5 rad from the view is still usable (the threshold is 1e-6 rad).
  const glm::dvec3 up(1e-5, 0.0, 1.0);
  EXPECT_EQ(viewUp({0.0, 0.0, -1.0}, up).x, up.x);
}

TEST(ViewUp, AnUpAlongTheViewZeroOrNotFiniteIsReplacedByThePerpendicularFrameAxis) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const glm::dvec3& forward : {glm::dvec3(0, 0, -1), glm::dvec3(0.3, -0.2, 5.0),
                                    glm::dvec3(-3396190.0, 1.0, 0.0), glm::dvec3(1, 1, 1)}) {
    const glm::dvec3 f = glm::normalize(forward);
    for (const glm::dvec3& up :
         {forward, -2.0 * forward, forward + glm::dvec3(1e-9 * glm::length(forward)),
          glm::dvec3(0.0), glm::dvec3(nan, 0, 1), glm::dvec3(0, inf, 0)}) {
      const glm::dvec3 u = viewUp(forward, up);
      EXPECT_NEAR(glm::length(u), 1.0, 1e-15);
      EXPECT_NEAR(glm::dot(u, f), 0.0, 1e-15);
      // Along the axis least aligned with the view, made perpendicular: the component on
      // that axis is the largest of the three.
      int k = 0;
      for (int i = 1; i < 3; ++i) {
        if (std::abs(f[i]) < std::abs(f[k])) k = i;
      }
      for (int i = 0; i < 3; ++i) {
        if (i != k) {
          EXPECT_GE(u[k], std::abs(u[i]));
        }
      }
    }
  }
}

}  // namespace
}  // namespace regolith::topo
