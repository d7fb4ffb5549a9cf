// TopoGrid geometry (pixel-centre convention) and the in-memory sample source.
#include <regolith/core/Error.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace regolith;
using namespace regolith::topo;

TEST(TopoGrid, SampleCentresFollowTheGeoTransformPixelCentreConvention) {
  // GDAL: Xgeo = GT0 + (col + 0.5)·GT1, Ygeo = GT3 + (row + 0.5)·GT5 at the pixel centre.
  const std::array<double, 6> gt{1000.0, 2.0, 0.0, 5000.0, 0.0, -4.0};
  const TopoGrid g = TopoGrid::fromGeoTransform(gt, 10, 20);
  for (std::size_t r : {0u, 3u, 9u}) {
    for (std::size_t c : {0u, 7u, 19u}) {
      const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      EXPECT_DOUBLE_EQ(p.x, gt[0] + (static_cast<double>(c) + 0.5) * gt[1]);
      EXPECT_DOUBLE_EQ(p.y, gt[3] + (static_cast<double>(r) + 0.5) * gt[5]);
    }
  }
  EXPECT_DOUBLE_EQ(g.west(), 1000.0);
  EXPECT_DOUBLE_EQ(g.east(), 1040.0);
  EXPECT_DOUBLE_EQ(g.north(), 5000.0);
  EXPECT_DOUBLE_EQ(g.south(), 4960.0);
  EXPECT_EQ(g.geoTransform(), gt);
}

TEST(TopoGrid, RowZeroIsNorth) {
  const TopoGrid g(3, 3, 0.0, 100.0, 1.0, 1.0);
  EXPECT_GT(g.sampleCentre(0, 0).y, g.sampleCentre(2, 0).y);
  const glm::dvec2 f = g.fractionalIndex(1.0, 98.0);
  EXPECT_DOUBLE_EQ(f.x, 1.0);
  EXPECT_DOUBLE_EQ(f.y, 2.0);
}

TEST(TopoGrid, ContainsThePixelExtentIncludingItsEdges) {
  const TopoGrid g(2, 2, 0.5, 1.5, 1.0, 1.0);  // pixels cover x 0..2, y 0..2
  EXPECT_TRUE(g.contains(0.0, 0.0));
  EXPECT_TRUE(g.contains(2.0, 2.0));
  EXPECT_TRUE(g.contains(1.0, 1.0));
  EXPECT_FALSE(g.contains(-1e-9, 1.0));
  EXPECT_FALSE(g.contains(1.0, 2.0 + 1e-9));
}

TEST(TopoGrid, RejectsRotatedAndSouthUpGeoTransformsWithAClearMessage) {
  try {
    (void)TopoGrid::fromGeoTransform({0, 1, 0.1, 0, 0, -1}, 2, 2);
    FAIL() << "rotated transform accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "TopoGrid::fromGeoTransform(): rotation terms are (0.1, 0), "
                 "expected 0 (north-up rasters only)");
  }
  EXPECT_THROW((void)TopoGrid::fromGeoTransform({0, 1, 0, 0, 0, 1}, 2, 2), InvalidArgument);
}

TEST(TopoGrid, RejectsEmptyGridsAndBadSpacing) {
  EXPECT_THROW(TopoGrid(0, 5, 0, 0, 1, 1), InvalidArgument);
  try {
    TopoGrid(2, 2, 0, 0, -1.0, 1.0);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("spacing is (-1, 1), expected both > 0"),
              std::string::npos);
  }
  EXPECT_THROW(TopoGrid(2, 2, std::nan(""), 0, 1, 1), InvalidArgument);
  EXPECT_THROW(TopoGrid(2, 2, 0, 0, 1, std::numeric_limits<double>::infinity()), InvalidArgument);
}

TEST(TopoGrid, NodataIsTheDeclaredValueOrNan) {
  const TopoGrid g(1, 1, 0, 0, 1, 1, -32768.0f);
  EXPECT_TRUE(g.isNodata(-32768.0f));
  EXPECT_TRUE(g.isNodata(std::nanf("")));
  EXPECT_FALSE(g.isNodata(0.0f));
  const TopoGrid h(1, 1, 0, 0, 1, 1);
  EXPECT_TRUE(h.isNodata(std::nanf("")));
  EXPECT_FALSE(h.isNodata(-32768.0f));
}

TEST(InMemorySamples, StoresRowMajorAndReadsWindows) {
  auto s = InMemorySamples::fromFunction(
      3, 4, [](std::size_t r, std::size_t c) { return static_cast<float>(10 * r + c); });
  EXPECT_EQ(s->sample(2, 1), 21.0f);
  std::vector<float> w(4);
  s->readWindow(1, 2, 2, 2, w);
  EXPECT_EQ(w, (std::vector<float>{12.0f, 13.0f, 22.0f, 23.0f}));
  EXPECT_THROW(InMemorySamples(2, 2, std::vector<float>(3)), InvalidArgument);
  // rows × cols wraps to 0 (or to 1): the sizes must not be taken as an empty (or a 1-sample)
  // grid, which every read would then overrun.
  constexpr std::size_t k32 = std::size_t{1} << 32;
  EXPECT_THROW(InMemorySamples(k32, k32, {}), InvalidArgument);
  EXPECT_THROW(InMemorySamples(k32 + 1, k32 * (k32 - 1) + 1, std::vector<float>(1)),
               InvalidArgument);
  EXPECT_THROW((void)InMemorySamples::fromFunction(k32, k32, [](auto, auto) { return 0.0f; }),
               InvalidArgument);
}
