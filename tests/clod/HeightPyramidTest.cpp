#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/core/Error.hpp>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace regolith::clod {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const regolith::Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(HeightPyramidTest, FromSamplesAveragesTwoByTwoAndKeepsNodata) {
  // 5 × 4 samples; -9999 marks nodata. Level 1 is 3 × 2, level 2 2 × 1 (at most 2 × 2:
  // the last).
  const topo::TopoGrid grid(5, 4, 100.0, 200.0, 1.0, 2.0, -9999.0F);
  std::vector<float> v = {1,  2,  3,     4,      //
                          5,  6,  -9999, -9999,  //
                          9,  10, 11,    12,     //
                          13, 14, 15,    16,     //
                          17, 18, -9999, -9999};
  const auto samples = std::make_shared<topo::InMemorySamples>(5, 4, v);
  const auto p = HeightPyramid::fromSamples(grid, samples, SurfaceKind::Plane);
  ASSERT_EQ(p.levelCount(), 3U);
  const auto& l1 = p.level(1);
  EXPECT_EQ(l1.grid.rows(), 3U);
  EXPECT_EQ(l1.grid.cols(), 2U);
  EXPECT_DOUBLE_EQ(l1.grid.spacingX(), 2.0);
  EXPECT_DOUBLE_EQ(l1.grid.spacingY(), 4.0);
  // Sample (0, 0) of level 1 sits at the centre of level-0 samples (0..1, 0..1).
  EXPECT_DOUBLE_EQ(l1.grid.x0(), 100.5);
  EXPECT_DOUBLE_EQ(l1.grid.y0(), 199.0);
  EXPECT_FLOAT_EQ(l1.source->sample(0, 0), (1 + 2 + 5 + 6) / 4.0F);
  EXPECT_FLOAT_EQ(l1.source->sample(0, 1), (3 + 4) / 2.0F);  // nodata left out of the mean
  EXPECT_FLOAT_EQ(l1.source->sample(1, 1), (11 + 12 + 15 + 16) / 4.0F);
  EXPECT_FLOAT_EQ(l1.source->sample(2, 0), (17 + 18) / 2.0F);  // last odd row: itself
  EXPECT_TRUE(std::isnan(l1.source->sample(2, 1)));            // all four missing
  EXPECT_EQ(p.level(2).grid.rows(), 2U);
  EXPECT_EQ(p.level(2).grid.cols(), 1U);
  EXPECT_FLOAT_EQ(p.level(2).source->sample(0, 0), (3.5F + 3.5F + 11.5F + 13.5F) / 4.0F);
  // Plane scene frame: (x, y, h) as given.
  EXPECT_EQ(p.position(3.0, 4.0, 5.0), glm::dvec3(3.0, 4.0, 5.0));
  EXPECT_EQ(p.up({1.0, 2.0, 3.0}), glm::dvec3(0.0, 0.0, 1.0));
}

TEST(HeightPyramidTest, PlanetPositionsAreBodyFixed) {
  const topo::TopoGrid grid(180, 360, -179.5, 89.5, 1.0, 1.0);
  const auto samples =
      std::make_shared<topo::InMemorySamples>(180, 360, std::vector<float>(180 * 360, 0.0F));
  const auto p =
      HeightPyramid::fromSamples(grid, samples, SurfaceKind::Planet, topo::Body::marsSphere(),
                                 topo::LatitudeType::Planetocentric, 3);
  EXPECT_EQ(p.levelCount(), 3U);
  const glm::dvec3 q = p.position(90.0, 0.0, 10.0);  // lon 90°, lat 0, 10 m up
  EXPECT_NEAR(q.x, 0.0, 1e-6);
  EXPECT_NEAR(q.y, 3396190.0 + 10.0, 1e-6);
  EXPECT_NEAR(q.z, 0.0, 1e-6);
  const glm::dvec2 g = p.gridPoint(q);
  EXPECT_NEAR(g.x, 90.0, 1e-9);
  EXPECT_NEAR(g.y, 0.0, 1e-9);
  EXPECT_NEAR(glm::length(p.up(q) - glm::dvec3(0, 1, 0)), 0.0, 1e-12);
}

TEST(HeightPyramidTest, RejectsInconsistentLevels) {
  const topo::TopoGrid g0(4, 4, 0.0, 0.0, 1.0, 1.0);
  const topo::TopoGrid g1bad(2, 2, 0.5, -0.5, 3.0, 2.0);
  const auto s4 = std::make_shared<topo::InMemorySamples>(4, 4, std::vector<float>(16, 0.0F));
  const auto s2 = std::make_shared<topo::InMemorySamples>(2, 2, std::vector<float>(4, 0.0F));
  EXPECT_EQ(messageOf([&] { HeightPyramid({}, SurfaceKind::Plane); }),
            "HeightPyramid(): no levels, expected at least one");
  EXPECT_EQ(messageOf([&] {
              HeightPyramid({{g0, s4}}, SurfaceKind::Planet);
            }),
            "HeightPyramid(): a Planet pyramid needs a body");
  EXPECT_EQ(messageOf([&] {
              HeightPyramid({{g0, s2}}, SurfaceKind::Plane);
            }),
            "HeightPyramid(): level 0: source is 2 x 2, grid is 4 x 4");
  EXPECT_EQ(messageOf([&] {
              HeightPyramid({{g0, nullptr}}, SurfaceKind::Plane);
            }),
            "HeightPyramid(): level 0: source is null");
  const std::string m = messageOf([&] {
    HeightPyramid({{g0, s4}, {g1bad, s2}}, SurfaceKind::Plane);
  });
  EXPECT_NE(m.find("HeightPyramid(): level 1: spacing 3"), std::string::npos) << m;
  EXPECT_NE(m.find("expected twice level 0's"), std::string::npos) << m;
}

}  // namespace
}  // namespace regolith::clod
