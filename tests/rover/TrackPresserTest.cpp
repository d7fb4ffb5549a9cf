// TrackPresser: when a traverse's steps become imprints, and what they press.
#include <regolith/core/Error.hpp>
#include <regolith/rover/TrackPresser.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace regolith;
using namespace regolith::rover;

/// A step at `distance` m along a straight drive north, wheels at x = ±1 and y = distance +
/// {1, 0, −1} (no terrain needed: the presser reads the contacts' x, y only).
StepState stepAt(double distance) {
  StepState s;
  s.distance = distance;
  for (std::size_t w = 0; w < kWheels; ++w) {
    s.wheels[w].x = w % 2 == 0 ? -1.0 : 1.0;
    const std::size_t axle = w / 2;  // 0 front, 1 middle, 2 rear
    s.wheels[w].y = distance + 1.0 - static_cast<double>(axle);
  }
  return s;
}

TEST(TrackPresserTest, PressesAtTheStartAndThenEverySpacingOfTravel) {
  TrackLayer layer(RoverRuts::kTexelMetres);
  TrackPresser presser(layer);
  EXPECT_EQ(presser.options().spacingMetres, RoverRuts::kSpacingMetres);
  // 2 cm steps: imprints at 0, then at the first step ≥ 5 cm beyond the last imprint.
  std::vector<double> pressedAt;
  for (int k = 0; k <= 10; ++k) {
    const double d = 0.02 * k;
    const auto v = layer.version();
    if (presser.press(stepAt(d))) {
      pressedAt.push_back(d);
      EXPECT_GT(layer.version(), v);
    } else {
      EXPECT_EQ(layer.version(), v) << d;  // nothing pressed between imprints
    }
  }
  // 0 → next 0.05: 0.06 → next 0.11: 0.12 → next 0.17: 0.18 → next 0.23.
  ASSERT_EQ(pressedAt.size(), 4U);
  EXPECT_DOUBLE_EQ(pressedAt[1], 0.06);
  EXPECT_DOUBLE_EQ(pressedAt[2], 0.12);
  EXPECT_DOUBLE_EQ(pressedAt[3], 0.18);
  EXPECT_EQ(presser.imprints(), 4U);
}

TEST(TrackPresserTest, EachWheelPressesAContinuousRutOfTheGivenDepth) {
  TrackLayer layer(0.01);
  TrackPressOptions o;
  o.spacingMetres = 0.5;
  o.wheelWidthMetres = 0.3;
  o.depthMetres = 0.02;
  TrackPresser presser(layer, o);
  for (int k = 0; k <= 400; ++k) (void)presser.press(stepAt(0.05 * k));  // 20 m north
  EXPECT_EQ(presser.imprints(), 41U);
  // Texel centres sit at (k + ½)·1 cm: (−0.995, y) is 5 mm from the left wheels' path, so
  // the rut there is depth·cos²(π·0.005 / 0.3), continuous between imprints 0.5 m apart.
  const double nearCentre = 0.02 * std::pow(std::cos(std::numbers::pi * 0.005 / 0.3), 2.0);
  for (double y = 0.005; y < 20.0; y += 0.37) {
    EXPECT_NEAR(layer.depthAt({-0.995, y}), nearCentre, 1e-7) << y;
    EXPECT_NEAR(layer.depthAt({0.995, y}), nearCentre, 1e-7) << y;
    EXPECT_EQ(layer.depthAt({0.005, y}), 0.0) << y;  // between the wheels
  }
}

std::string errorOf(const TrackPressOptions& o) {
  TrackLayer layer;
  try {
    const TrackPresser p(layer, o);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(TrackPresserTest, BadOptionsGiveClearErrors) {
  TrackPressOptions o;
  o.spacingMetres = -0.05;
  EXPECT_EQ(errorOf(o), "rover::TrackPresser(): spacing is -0.05 m, expected finite and ≥ 0");
  o = {};
  o.wheelWidthMetres = 0.0;
  EXPECT_EQ(errorOf(o), "rover::TrackPresser(): wheel width is 0 m, expected finite and > 0");
  o = {};
  o.depthMetres = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(errorOf(o), "rover::TrackPresser(): rut depth is nan m, expected finite and ≥ 0");
  o = {};
  EXPECT_EQ(errorOf(o), "no error");
}

}  // namespace
