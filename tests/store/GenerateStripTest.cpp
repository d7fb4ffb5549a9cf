// StripGenerator: the store it writes, read back with Store; its footprint against the orbit's
// geometry (vectors on the sphere, not the generator's formulas) and PROJ's oblique Mercator;
// heights against the planet's point function; the ragged mask; determinism; errors.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/ProjPlacement.hpp>

#include "support/ProjOracle.hpp"
#include "support/StoreScratch.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kR = 3396190.0;

fs::path scratch(const std::string& name) { return test::scratchFile("genstrip", name); }

/// 401 × 21 samples: 200 km × 10 km at 500 m, centred at 20°N 30°E, inclination 60°.
StripOptions smallStrip(std::uint64_t seed = 7) {
  StripOptions o;
  o.centreLatDeg = 20.0;
  o.centreLonDeg = 30.0;
  o.inclinationDeg = 60.0;
  o.length = 200000.0;
  o.width = 10000.0;
  o.spacing = 500.0;
  o.planet.seed = seed;
  o.threads = 1;
  o.write.patchRows = 16;
  o.write.patchCols = 64;
  return o;
}

glm::dvec3 unitOf(double latDeg, double lonDeg) {
  return {std::cos(latDeg * kDeg) * std::cos(lonDeg * kDeg),
          std::cos(latDeg * kDeg) * std::sin(lonDeg * kDeg), std::sin(latDeg * kDeg)};
}

glm::dvec2 pointOf(const GridInfo& info, std::size_t row, std::size_t col) {
  return {info.x0 + static_cast<double>(col) * info.spacingX,
          info.y0 - static_cast<double>(row) * info.spacingY};
}

/// The geometry of the strip's orbit on the sphere, from the options alone: the orbit's
/// pole n is perpendicular to the centre c and makes the inclination with the north pole
/// (n·ẑ = cos i); of the two such poles, the one whose flight direction t = n × c heads
/// north (ascending) or south (descending). n is also the left of the track.
struct Orbit {
  glm::dvec3 c, n, t;
  explicit Orbit(const StripOptions& o) : c(unitOf(o.centreLatDeg, o.centreLonDeg)) {
    const glm::dvec3 north(-std::sin(o.centreLatDeg * kDeg) * std::cos(o.centreLonDeg * kDeg),
                           -std::sin(o.centreLatDeg * kDeg) * std::sin(o.centreLonDeg * kDeg),
                           std::cos(o.centreLatDeg * kDeg));
    const glm::dvec3 east = glm::cross(north, c);
    const double a = std::cos(o.inclinationDeg * kDeg) / north.z;
    const double b = std::sqrt(std::max(0.0, 1.0 - a * a));
    n = a * north + (o.descending ? b : -b) * east;
    t = glm::cross(n, c);
  }
  /// The point `along` metres along the track from the centre and `left` metres (map y,
  /// oblique Mercator: angular distance asin(tanh(y/R))) to its left.
  [[nodiscard]] glm::dvec3 at(double along, double left) const {
    const double s = along / kR, d = std::asin(std::tanh(left / kR));
    const glm::dvec3 e = c * std::cos(s) + t * std::sin(s);
    return e * std::cos(d) + n * std::sin(d);
  }
};

double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  return 2.0 * std::asin(std::min(1.0, 0.5 * glm::length(a - b)));
}

glm::dvec3 unitUnder(const topo::Placement& p, const glm::dvec2& xy) {
  const topo::Geodetic g = p.toGeodetic(xy.x, xy.y, 0.0);
  return unitOf(p.body().planetocentricFromPlanetodetic(g.latDeg), g.lonDeg);
}

/// PROJ's own transformation from the body's geographic CRS (degrees) to a projected CRS,
/// as cs2cs makes it (the path a store's recorded CRS takes).
class ProjCrsToCrs {
 public:
  ProjCrsToCrs(const std::string& geographic, const std::string& projected)
      : ctx_(proj_context_create()) {
    PJ* raw = proj_create_crs_to_crs(ctx_, geographic.c_str(), projected.c_str(), nullptr);
    pj_ = raw != nullptr ? proj_normalize_for_visualization(ctx_, raw) : nullptr;
    if (raw != nullptr) proj_destroy(raw);
  }
  ProjCrsToCrs(const ProjCrsToCrs&) = delete;
  ProjCrsToCrs& operator=(const ProjCrsToCrs&) = delete;
  ~ProjCrsToCrs() {
    if (pj_ != nullptr) proj_destroy(pj_);
    proj_context_destroy(ctx_);
  }
  [[nodiscard]] bool ok() const { return pj_ != nullptr; }
  /// Map metres of a longitude and latitude in degrees.
  [[nodiscard]] glm::dvec2 forward(double lonDeg, double latDeg) const {
    const PJ_COORD out = proj_trans(pj_, PJ_FWD, proj_coord(lonDeg, latDeg, 0.0, 0.0));
    return {out.v[0], out.v[1]};
  }

 private:
  PJ_CONTEXT* ctx_;
  PJ* pj_ = nullptr;
};

bool bitwiseEqual(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(GenerateStrip, StoredPlacementRoundTrips) {
  const StripGenerator g(smallStrip());
  const fs::path path = scratch("roundtrip.h5");
  g.write(path);
  const Store s = Store::open(path);
  ASSERT_TRUE(s.hasGrid("strip"));
  const GridInfo& info = s.grid("strip");
  EXPECT_EQ(info.kind, GridKind::Dem);
  EXPECT_EQ(info.rows, 21U);
  EXPECT_EQ(info.cols, 401U);
  EXPECT_EQ(info.x0, -100000.0);
  EXPECT_EQ(info.y0, 5000.0);
  EXPECT_EQ(info.spacingX, 500.0);
  EXPECT_EQ(info.equatorialRadius, kR);
  EXPECT_EQ(info.polarRadius, kR);
  EXPECT_FALSE(info.nodata.has_value());  // missing samples are NaN
  ASSERT_EQ(info.placement.kind, PlacementInfo::Kind::Projected);
  EXPECT_NE(info.placement.crs.find("Hotine Oblique Mercator (variant B)"), std::string::npos);
  // The recorded CRS reads back as the oblique Mercator of the options.
  const std::string proj = projString(info.placement.crs);
  EXPECT_NE(proj.find("+proj=omerc"), std::string::npos) << proj;
  EXPECT_NE(proj.find("+lat_0=20 "), std::string::npos) << proj;
  EXPECT_NE(proj.find("+lonc=30 "), std::string::npos) << proj;
  EXPECT_NE(proj.find("+R=3396190 "), std::string::npos) << proj;
  // Clairaut on the sphere: cos 20° · sin β = cos 60°.
  EXPECT_NEAR(g.azimuthDeg(), std::asin(0.5 / std::cos(20.0 * kDeg)) / kDeg, 1e-12);
  EXPECT_EQ(placementOf(info).kind(), topo::Placement::Kind::Projected);
}

TEST(GenerateStrip, FootprintFollowsTheOrbit) {
  // Corners, ends and centre of the stored grid, through the stored placement (PROJ's omerc),
  // against the orbit's geometry on the sphere; and PROJ's forward of the oracle's corners
  // gives back the grid coordinates.
  for (const bool descending : {false, true}) {
    for (const double inclination : {60.0, 93.0, 20.0}) {
      StripOptions o = smallStrip();
      o.inclinationDeg = inclination;
      o.descending = descending;
      o.centreLatDeg = inclination == 20.0 ? 20.0 : -35.0;  // at the turning point, and not
      o.centreLonDeg = -170.0;
      o.length = 900000.0;  // crosses the ±180° meridian
      o.width = 40000.0;
      o.spacing = 5000.0;
      const StripGenerator g(o);
      const GridInfo info = g.gridInfo();
      const topo::Placement placement = placementOf(info);
      const Orbit orbit(o);
      const ProjCrsToCrs omerc("+proj=longlat +R=3396190 +no_defs +type=crs", g.projString());
      ASSERT_TRUE(omerc.ok());
      for (const std::size_t row : {std::size_t{0}, info.rows / 2, info.rows - 1}) {
        for (const std::size_t col : {std::size_t{0}, info.cols / 2, info.cols - 1}) {
          const glm::dvec2 xy = pointOf(info, row, col);
          const glm::dvec3 expected = orbit.at(xy.x, xy.y);
          const double error = angleBetween(unitUnder(placement, xy), expected) * kR;
          EXPECT_LT(error, 1e-3) << "incl " << inclination << (descending ? " desc" : " asc")
                                 << " sample " << row << ", " << col;
          const glm::dvec2 back = omerc.forward(std::atan2(expected.y, expected.x) / kDeg,
                                                std::asin(expected.z) / kDeg);
          EXPECT_NEAR(back.x, xy.x, 1e-3) << inclination << (descending ? " desc" : " asc");
          EXPECT_NEAR(back.y, xy.y, 1e-3);
        }
      }
      // The corners are the options' length and width apart (outermost sample centres).
      EXPECT_EQ(pointOf(info, 0, 0).x, -450000.0);
      EXPECT_EQ(pointOf(info, 0, 0).y, 20000.0);
      // Flying along +x: north on an ascending pass, south on a descending one.
      const double z0 = unitUnder(placement, {-1000.0, 0.0}).z;
      const double z1 = unitUnder(placement, {1000.0, 0.0}).z;
      if (inclination != 20.0) {
        EXPECT_EQ(z1 > z0, !descending);
      }
    }
  }
}

TEST(GenerateStrip, EllipsoidStripIsCentredOnItsOptions) {
  StripOptions o = smallStrip();
  o.planet.ellipsoid = true;
  const StripGenerator g(o);
  const GridInfo info = g.gridInfo();
  EXPECT_EQ(info.polarRadius, 3376200.0);
  const topo::Placement placement = placementOf(info);
  const topo::Geodetic centre = placement.toGeodetic(0.0, 0.0, 0.0);
  EXPECT_NEAR(placement.body().planetocentricFromPlanetodetic(centre.latDeg), 20.0, 1e-9);
  EXPECT_NEAR(centre.lonDeg, 30.0, 1e-9);
}

TEST(GenerateStrip, HeightsAreThePlanetAtTheStripResolutionWithinTheRaggedEdges) {
  const StripOptions o = smallStrip(13);
  const StripGenerator g(o);
  const fs::path path = scratch("heights.h5");
  g.write(path);
  const Store s = Store::open(path);
  const GridInfo info = s.grid("strip");
  const std::vector<float> v = test::readLevel0(path, "strip");
  const topo::Placement placement = placementOf(info);
  MarsPlanetOptions po;
  po.rows = static_cast<std::size_t>(std::ceil(kPi * kR / o.spacing));
  po.seed = 13;
  po.threads = 1;
  const MarsPlanetGenerator planet(po);
  EXPECT_EQ(g.planet().options().rows, po.rows);
  std::size_t wrong = 0, valid = 0;
  for (std::size_t r = 0; r < info.rows; ++r) {
    for (std::size_t c = 0; c < info.cols; ++c) {
      const glm::dvec2 xy = pointOf(info, r, c);
      const float got = v[r * info.cols + c];
      if (!g.covers(xy.x, xy.y)) {
        wrong += std::isnan(got) ? 0U : 1U;
        continue;
      }
      ++valid;
      const topo::Geodetic geo = placement.toGeodetic(xy.x, xy.y, 0.0);
      const double lon = geo.lonDeg - 360.0 * std::floor((geo.lonDeg + 180.0) / 360.0);
      wrong += got == static_cast<float>(planet.height(geo.latDeg, lon)) ? 0U : 1U;
    }
  }
  EXPECT_EQ(wrong, 0U);
  EXPECT_GT(valid, v.size() / 2);
  // Height statistics are stored (a catalogue's height range) and are those of the samples.
  ASSERT_TRUE(info.statistics.has_value());
  EXPECT_EQ(info.statistics->validSamples, valid);
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const float h : v) {
    if (!std::isnan(h)) {
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
  }
  EXPECT_EQ(info.statistics->min, static_cast<double>(lo));
  EXPECT_EQ(info.statistics->max, static_cast<double>(hi));
}

TEST(GenerateStrip, RaggedEdgesMaskTheBorderOnly) {
  const StripGenerator g(smallStrip(3));
  const GridInfo info = g.gridInfo();
  g.write(scratch("ragged.h5"));
  const std::vector<float> v = test::readLevel0(scratch("ragged.h5"), "strip");
  const double halfW = 5000.0, halfL = 100000.0, r = 0.25;
  std::size_t missing = 0;
  std::set<std::size_t> widths;  // valid samples per column
  for (std::size_t c = 0; c < info.cols; ++c) {
    std::size_t column = 0;
    for (std::size_t row = 0; row < info.rows; ++row) {
      const glm::dvec2 xy = pointOf(info, row, c);
      const bool ok = !std::isnan(v[row * info.cols + c]);
      // The core is always covered.
      if (std::abs(xy.y) <= (1.0 - r) * halfW && std::abs(xy.x) <= halfL - r * halfW) {
        EXPECT_TRUE(ok) << row << ", " << c;
      }
      missing += ok ? 0U : 1U;
      column += ok ? 1U : 0U;
    }
    if (c > 10 && c + 10 < info.cols) widths.insert(column);
  }
  EXPECT_GT(missing, 0U);
  EXPECT_LT(missing, v.size() / 4);
  EXPECT_GE(widths.size(), 3U);  // the sides wander

  StripOptions full = smallStrip(3);
  full.raggedness = 0.0;
  StripGenerator(full).write(scratch("full.h5"));
  for (const float h : test::readLevel0(scratch("full.h5"), "strip")) {
    ASSERT_TRUE(std::isfinite(h));
  }
}

TEST(GenerateStrip, SameSeedIsBitIdenticalWhateverThePatchesAndThreads) {
  const StripOptions a = smallStrip(21);
  StripOptions b = a;
  b.write.patchRows = 8;
  b.write.patchCols = 100;
  b.threads = 3;
  StripOptions c = a;
  c.planet.seed = 22;
  StripGenerator(a).write(scratch("a.h5"));
  StripGenerator(b).write(scratch("b.h5"));
  StripGenerator(c).write(scratch("c.h5"));
  const std::vector<float> va = test::readLevel0(scratch("a.h5"), "strip");
  EXPECT_TRUE(bitwiseEqual(va, test::readLevel0(scratch("b.h5"), "strip")));
  EXPECT_FALSE(bitwiseEqual(va, test::readLevel0(scratch("c.h5"), "strip")));
}

TEST(GenerateStrip, BadOptionsAreRefusedWithClearMessages) {
  StripOptions o = smallStrip();
  o.centreLatDeg = 70.0;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { StripGenerator{o}; }),
            "store::StripGenerator(): centre latitude is 70 degrees, expected within the reach "
            "of an orbit inclined 60 degrees (|latitude| <= 60)");
  o = smallStrip();
  o.inclinationDeg = 181.0;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { StripGenerator{o}; }),
            "store::StripGenerator(): inclination is 181 degrees, expected >= 0 and <= 180");
  o = smallStrip();
  o.width = 0.0;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { StripGenerator{o}; }),
            "store::StripGenerator(): width is 0 m, expected a finite number > 0");
  o = smallStrip();
  o.raggedness = 1.0;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { StripGenerator{o}; }),
            "store::StripGenerator(): raggedness is 1, expected >= 0 and <= 0.9");
  o = smallStrip();
  o.length = 2e7;
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { StripGenerator{o}; }),
            "store::StripGenerator(): length is 2e+07 m, expected <= 10669445.554195119 m (half a "
            "great circle)");
  o = smallStrip();
  o.centreLonDeg = std::nan("");
  EXPECT_EQ(test::messageOf<InvalidArgument>([&] { StripGenerator{o}; }),
            "store::StripGenerator(): centre longitude is nan, expected a finite number");
  o = smallStrip();
  o.gridName.clear();
  EXPECT_THROW(StripGenerator{o}, InvalidArgument);
}
