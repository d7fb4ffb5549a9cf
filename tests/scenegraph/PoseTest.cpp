#include <regolith/core/Error.hpp>
#include <regolith/scenegraph/Pose.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace regolith::scenegraph {
namespace {

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

Pose somePose() {
  Pose p;
  p.translation = {10.0, -20.0, 30.0};
  p.rotation = glm::angleAxis(0.7, glm::normalize(glm::dvec3(1.0, 2.0, 3.0)));
  return p;
}

TEST(PoseTest, ApplyMatchesRotationMatrixAndTranslation) {
  // A quarter turn about +z takes +x to +y.
  Pose p;
  p.translation = {1.0, 2.0, 3.0};
  p.rotation = glm::angleAxis(std::numbers::pi / 2.0, glm::dvec3(0.0, 0.0, 1.0));
  expectNear(p.apply({1.0, 0.0, 0.0}), {1.0, 3.0, 3.0}, 1e-12);
  expectNear(p.applyVector({1.0, 0.0, 0.0}), {0.0, 1.0, 0.0}, 1e-12);
  expectNear(p.matrix()[0], {0.0, 1.0, 0.0}, 1e-12);  // column: the child's x axis
}

TEST(PoseTest, InverseAndCompositionRoundTrip) {
  const Pose a = somePose();
  Pose b;
  b.translation = {-5.0, 0.5, 2.0};
  b.rotation = glm::angleAxis(-1.3, glm::normalize(glm::dvec3(0.0, 1.0, 0.2)));
  const glm::dvec3 q{3.0, -4.0, 5.0};
  expectNear((a * b).apply(q), a.apply(b.apply(q)), 1e-12);
  expectNear(a.inverse().apply(a.apply(q)), q, 1e-12);
  expectNear((a * a.inverse()).translation, glm::dvec3(0.0), 1e-12);
}

TEST(PoseTest, FromAxesRejectsNonOrthonormal) {
  EXPECT_THROW((void)Pose::fromAxes({}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}), InvalidArgument);
  EXPECT_THROW((void)Pose::fromAxes({}, {2, 0, 0}, {0, 1, 0}, {0, 0, 1}), InvalidArgument);
  const Pose p = Pose::fromAxes({1, 1, 1}, {0, 1, 0}, {-1, 0, 0}, {0, 0, 1});
  expectNear(p.apply({1.0, 0.0, 0.0}), {1.0, 2.0, 1.0}, 1e-12);
}

TEST(PoseTest, LookAtPutsTheTargetOnTheMinusZAxis) {
  const glm::dvec3 eye{100.0, 50.0, 20.0}, target{0.0, 0.0, 0.0};
  const Pose cam = Pose::lookAt(eye, target, {0.0, 0.0, 1.0});
  const glm::dvec3 inEye = cam.inverse().apply(target);
  EXPECT_NEAR(inEye.x, 0.0, 1e-9);
  EXPECT_NEAR(inEye.y, 0.0, 1e-9);
  EXPECT_NEAR(inEye.z, -glm::length(eye - target), 1e-9);
  // The world's up is up in the image: a point above the target has eye y > 0.
  EXPECT_GT(cam.inverse().apply({0.0, 0.0, 10.0}).y, 0.0);
  EXPECT_THROW((void)Pose::lookAt(eye, eye, {0, 0, 1}), InvalidArgument);
}

// Issue 16 item 9: a camera at nadir (or looking at the body's centre) with the local
// vertical as up gets another up, not an exception or a NaN pose; an up 1e-5 rad off the
// view direction is still used as given.
TEST(PoseTest, LookAtWithUpParallelToTheViewChoosesAnotherUp) {
  const double r = 3396190.0;
  for (const glm::dvec3& eye :
       {glm::dvec3(0, 0, r + 1000.0), glm::dvec3(r + 0.001, 0, 0), glm::dvec3(0, -1e12, 0)}) {
    for (const double tilt : {0.0, 1e-9, 1e-7}) {
      const glm::dvec3 up = glm::normalize(eye) + glm::dvec3(tilt, tilt, 0.0);
      const Pose cam = Pose::lookAt(eye, {0.0, 0.0, 0.0}, up);
      const glm::dmat3 m = cam.matrix();
      for (int c = 0; c < 3; ++c) {
        EXPECT_TRUE(std::isfinite(m[c].x) && std::isfinite(m[c].y) && std::isfinite(m[c].z));
        EXPECT_NEAR(glm::length(m[c]), 1.0, 1e-12);
      }
      EXPECT_NEAR(glm::determinant(m), 1.0, 1e-12);
      const glm::dvec3 centre = cam.inverse().apply({0.0, 0.0, 0.0});
      EXPECT_NEAR(glm::length(glm::dvec3(centre.x, centre.y, 0.0)) / glm::length(eye), 0.0, 1e-12);
      EXPECT_LT(centre.z, 0.0);
    }
  }
  // 1e-5 rad from parallel: the given up decides the image's up.
  const glm::dvec3 eye{0.0, 0.0, 10.0};
  const Pose cam = Pose::lookAt(eye, {0.0, 0.0, 0.0}, {1e-5, 0.0, 1.0});
  EXPECT_GT(glm::dot(cam.applyVector({0.0, 1.0, 0.0}), glm::dvec3(1.0, 0.0, 0.0)), 0.99);
}

}  // namespace
}  // namespace regolith::scenegraph
