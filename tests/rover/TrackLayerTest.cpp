#include <regolith/core/Error.hpp>
#include <regolith/rover/TrackLayer.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <vector>

namespace regolith::rover {
namespace {

TEST(TrackLayerTest, AContactPressesACosineSquaredRutOfTheWheelsWidth) {
  TrackLayer layer(0.01);
  layer.stamp({2.005, -3.005}, 0.4, 0.03);  // a texel centre
  EXPECT_NEAR(layer.depthAt({2.005, -3.005}), 0.03, 1e-7);
  // Across the rut: depth·cos²(π d / width), d the distance from the contact.
  for (double d : {0.05, 0.1, 0.15}) {
    const double expected = 0.03 * std::pow(std::cos(std::numbers::pi * d / 0.4), 2.0);
    EXPECT_NEAR(layer.depthAt({2.005 + d, -3.005}), expected, 1e-6) << d;
  }
  EXPECT_EQ(layer.depthAt({2.005 + 0.21, -3.005}), 0.0);  // beyond the wheel's half width
  EXPECT_EQ(layer.depthAt({0.0, 0.0}), 0.0);
  // Driving over it again does not deepen it; a deeper wheel does.
  const auto v = layer.version();
  layer.stamp({2.005, -3.005}, 0.4, 0.02);
  EXPECT_NEAR(layer.depthAt({2.005, -3.005}), 0.03, 1e-7);
  EXPECT_GT(layer.version(), v);
  layer.stamp({2.005, -3.005}, 0.4, 0.05);
  EXPECT_NEAR(layer.depthAt({2.005, -3.005}), 0.05, 1e-7);
}

TEST(TrackLayerTest, StepsPressContinuousRutsThatPersistAlongTheWholeTraverse) {
  TrackLayer layer(0.02);
  // Six wheels driving 300 m east in 0.5 m steps: ruts everywhere along it, however far
  // the rover has gone since.
  for (int s = 0; s <= 600; ++s) {
    std::vector<WheelImprint> wheels;
    for (double y : {-0.6, 0.6})
      for (double dx : {-0.5, 0.0, 0.5}) wheels.push_back({{0.5 * s + dx, y}, 0.3, 0.02});
    layer.step(wheels);
  }
  for (double x = 0.0; x < 300.0; x += 7.3) {
    EXPECT_NEAR(layer.depthAt({x, 0.6}), 0.02, 2e-3) << x;  // continuous between steps
    EXPECT_NEAR(layer.depthAt({x, -0.6}), 0.02, 2e-3) << x;
    EXPECT_EQ(layer.depthAt({x, 0.0}), 0.0) << x;  // between the wheels
  }
  // Sparse: tiles only where the wheels went (512² texels = 10.24 m a side).
  EXPECT_LE(layer.tiles(), 2U * 31U);
  EXPECT_GE(layer.tiles(), 30U);
  // The dirty rectangle since the last step covers that step only.
  const auto v = layer.version();
  layer.stamp({1000.0, 1000.0}, 0.3, 0.02);
  const auto r = layer.dirtySince(v);
  EXPECT_LE(r[0], 1000.0 / 0.02 - 7);
  EXPECT_GE(r[2], 1000.0 / 0.02 + 7);
  EXPECT_LT(r[2] - r[0], 20);
  EXPECT_EQ(layer.dirtySince(layer.version()), (std::array<std::int64_t, 4>{0, 0, 0, 0}));
  // read() sees what depthAt() sees.
  std::vector<float> window(std::size_t{40} * 40);
  layer.read(50000 - 20, 50000 - 20, 40, 40, window);
  EXPECT_FLOAT_EQ(window[20 * 40 + 20], layer.texel(50000, 50000));
  EXPECT_GT(window[20 * 40 + 20], 0.0F);
  layer.clear();
  EXPECT_EQ(layer.tiles(), 0U);
  EXPECT_EQ(layer.depthAt({10.0, 0.6}), 0.0);
}

TEST(TrackLayerTest, BadContactsAreRejectedWithTheirValue) {
  TrackLayer layer;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(layer.stamp({nan, 0.0}, 0.3, 0.02), InvalidArgument);
  EXPECT_THROW(layer.stamp({0.0, 0.0}, 0.0, 0.02), InvalidArgument);
  EXPECT_THROW(layer.stamp({0.0, 0.0}, 0.3, -0.01), InvalidArgument);
  EXPECT_THROW(layer.stampSegment({0.0, 0.0}, {1.0, nan}, 0.3, 0.01), InvalidArgument);
  EXPECT_THROW(TrackLayer(0.0), InvalidArgument);
  try {
    layer.stamp({0.0, 0.0}, -2.0, 0.02);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("wheel width -2"), std::string::npos) << e.what();
  }
  EXPECT_EQ(layer.version(), 0U);  // nothing was pressed
  // A NaN or infinite query point is an error, not an undefined cast to a texel index.
  EXPECT_THROW((void)layer.depthAt({nan, 0.0}), InvalidArgument);
  EXPECT_THROW((void)layer.depthAt({0.0, std::numeric_limits<double>::infinity()}),
               InvalidArgument);
}

}  // namespace
}  // namespace regolith::rover
