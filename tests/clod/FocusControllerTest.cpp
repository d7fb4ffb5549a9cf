#include <regolith/clod/FocusController.hpp>
#include <regolith/core/Error.hpp>

#include <gtest/gtest.h>

namespace regolith::clod {
namespace {

Camera at(double x, double y) {
  Camera c;
  c.position = {x, y - 100.0, 100.0};
  c.target = {x, y, 0.0};  // 141 m from the camera
  return c;
}

TEST(FocusControllerTest, TheMostActiveCameraControlsTheFocus) {
  FocusController f(2.0);
  const auto a = f.addCamera(at(0, 0), 0.0);
  const auto b = f.addCamera(at(500, 0), 0.0);
  EXPECT_EQ(f.mostActive(0.0), a);  // nobody moved: the first camera
  EXPECT_EQ(f.focus(0.0), glm::dvec3(0, 0, 0));

  // A pans 141 m (one view distance, both position and target): activity 2.
  f.update(a, at(141.42135623730951, 0), 1.0);
  EXPECT_NEAR(f.activity(a, 1.0), 2.0, 1e-9);
  EXPECT_EQ(f.mostActive(1.0), a);
  EXPECT_EQ(f.focus(1.0).x, 141.42135623730951);
  // Two seconds later (one half-life) A's activity has halved.
  EXPECT_NEAR(f.activity(a, 3.0), 1.0, 1e-9);

  // B moves less, but later: at t = 3 B has 0.6, A 1.0: A still leads ...
  f.update(b, at(500 + 0.3 * 141.42135623730951, 0), 3.0);
  EXPECT_EQ(f.mostActive(3.0), a);
  // ... B keeps moving a little every second; A is idle and decays below it.
  for (int t = 4; t <= 6; ++t) f.update(b, at(500 + 0.3 * 141.42135623730951 * (t - 2), 0), t);
  EXPECT_GT(f.activity(b, 6.0), f.activity(a, 6.0));
  EXPECT_EQ(f.mostActive(6.0), b);
  EXPECT_NEAR(f.focus(6.0).x, 500 + 0.3 * 141.42135623730951 * 4, 1e-9);

  // A click on A (explicit input) counts even without motion.
  f.update(a, f.camera(a), 6.0, 5.0);
  EXPECT_EQ(f.mostActive(6.0), a);
}

TEST(FocusControllerTest, TiesGoToTheCameraMovedLastAndTheFocusCanFollowAnObject) {
  FocusController f(1.0);
  const auto a = f.addCamera(at(0, 0), 0.0);
  const auto b = f.addCamera(at(10, 0), 0.0);
  f.update(a, at(0, 141.42135623730951), 1.0);
  f.update(b, at(10, 141.42135623730951), 1.0);
  EXPECT_EQ(f.activity(a, 1.0), f.activity(b, 1.0));
  EXPECT_EQ(f.mostActive(1.0), b);

  glm::dvec3 rover{7.0, 8.0, -1400.0};
  f.tieTo([&] { return rover; });
  EXPECT_TRUE(f.tied());
  EXPECT_EQ(f.focus(1.0), rover);
  rover.x = 9.0;  // the focus follows the object, whatever the cameras do
  EXPECT_EQ(f.focus(50.0).x, 9.0);
  f.untie();
  EXPECT_EQ(f.focus(1.0), f.camera(b).target);
}

TEST(FocusControllerTest, RejectsABadHalfLifeAndAnEmptySet) {
  EXPECT_THROW(FocusController(0.0), InvalidArgument);
  EXPECT_THROW(FocusController(-1.0), InvalidArgument);
  const FocusController f;
  EXPECT_THROW((void)f.mostActive(0.0), InvalidArgument);
}

}  // namespace
}  // namespace regolith::clod
