// VictoriaGenerator: the store it writes, measured like a field geologist would from the
// stored samples (paged TopoDem queries): rim diameter, raised rim, floor, scalloped wall
// with its count of bays, dunes on the floor; placement on Mars; determinism; errors.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/Pager.hpp>

#include "support/StoreScratch.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::store;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = std::numbers::pi;

fs::path scratch(const std::string& name) { return test::scratchFile("genvictoria", name); }

VictoriaOptions options(std::size_t size, double spacing, std::uint64_t seed = 1) {
  VictoriaOptions o;
  o.size = size;
  o.spacing = spacing;
  o.seed = seed;
  o.write.patchRows = 64;
  o.write.patchCols = 64;
  return o;
}

using test::readLevel0;

/// A written Victoria store, paged.
struct Written {
  VictoriaGenerator generator;
  std::shared_ptr<const Store> store;
  topo::TopoDem dem;
};

Written writeAndOpen(const VictoriaOptions& o, const std::string& file) {
  VictoriaGenerator g(o);
  const fs::path path = scratch(file);
  g.write(path);
  auto store = std::make_shared<const Store>(Store::open(path));
  const Pager pager(store, std::make_shared<PatchCache>(std::size_t{16} << 20));
  return {g, store, pager.dem("victoria")};
}

double heightAt(const topo::TopoDem& dem, double x, double y) {
  const topo::HeightSample s = dem.height(x, y, topo::Interpolation::Bilinear);
  EXPECT_TRUE(s.valid()) << x << ", " << y;
  return s.height;
}

/// Crest radius at each of n azimuths: where the height peaks between 250 and 500 m.
std::vector<double> crestRadii(const topo::TopoDem& dem, std::size_t n) {
  std::vector<double> radii(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double th = 2.0 * kPi * static_cast<double>(i) / static_cast<double>(n);
    double best = -1e9, bestR = 0.0;
    for (double r = 250.0; r <= 500.0; r += 0.25) {
      const double h = heightAt(dem, r * std::cos(th), r * std::sin(th));
      if (h > best) {
        best = h;
        bestR = r;
      }
    }
    radii[i] = bestR;
  }
  return radii;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Periodogram power of a detrended profile (sample step `step`) at wavelength w.
double powerAt(const std::vector<double>& p, double step, double w) {
  std::complex<double> sum{0.0, 0.0};
  for (std::size_t i = 0; i < p.size(); ++i) {
    sum += p[i] * std::polar(1.0, -2.0 * kPi * static_cast<double>(i) * step / w);
  }
  return std::norm(sum) / static_cast<double>(p.size());
}

/// Removes a least-squares quadratic from a profile sampled at s.
std::vector<double> detrend(const std::vector<double>& s, const std::vector<double>& h) {
  // Normal equations of h ≈ a + b s + c s² (3×3, by Cramer's rule).
  double m[3][4] = {};
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double b[3] = {1.0, s[i], s[i] * s[i]};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] += b[r] * b[c];
      m[r][3] += b[r] * h[i];
    }
  }
  for (int k = 0; k < 3; ++k) {  // Gaussian elimination
    for (int r = k + 1; r < 3; ++r) {
      const double f = m[r][k] / m[k][k];
      for (int c = k; c < 4; ++c) m[r][c] -= f * m[k][c];
    }
  }
  double coef[3];
  for (int k = 2; k >= 0; --k) {
    double v = m[k][3];
    for (int c = k + 1; c < 3; ++c) v -= m[k][c] * coef[c];
    coef[k] = v / m[k][k];
  }
  std::vector<double> out(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) {
    out[i] = h[i] - (coef[0] + coef[1] * s[i] + coef[2] * s[i] * s[i]);
  }
  return out;
}

}  // namespace

TEST(GenerateVictoria, PlacedOnMarsNearVictoriaCrater) {
  const VictoriaGenerator g(options(601, 2.0));
  const GridInfo info = g.gridInfo();
  EXPECT_EQ(info.kind, GridKind::Dem);
  EXPECT_EQ(info.name, "victoria");
  EXPECT_EQ(info.rows, 601U);
  EXPECT_EQ(info.cols, 601U);
  EXPECT_DOUBLE_EQ(info.x0, -600.0);
  EXPECT_DOUBLE_EQ(info.y0, 600.0);
  EXPECT_DOUBLE_EQ(info.spacingX, 2.0);
  EXPECT_EQ(info.placement.kind, PlacementInfo::Kind::LocalTangentPlane);
  EXPECT_DOUBLE_EQ(info.placement.originLatDeg, -2.05);
  EXPECT_DOUBLE_EQ(info.placement.originLonDeg, -5.5);
  EXPECT_DOUBLE_EQ(info.placement.headingDeg, 0.0);
  EXPECT_DOUBLE_EQ(info.equatorialRadius, 3396190.0);
  EXPECT_DOUBLE_EQ(info.polarRadius, 3376200.0);
  // The crater's centre is at 2.05°S 5.5°W on the body.
  const topo::Placement placement = placementOf(info);
  const topo::Geodetic centre = placement.toGeodetic(0.0, 0.0, 0.0);
  EXPECT_NEAR(centre.latDeg, -2.05, 1e-9);
  EXPECT_NEAR(centre.lonDeg, -5.5, 1e-9);
}

TEST(GenerateVictoria, StoredSamplesAreTheShapeAtSampleCentres) {
  const VictoriaOptions o = options(301, 4.0, 9);
  const VictoriaGenerator g(o);
  const fs::path path = scratch("shape.h5");
  g.write(path);
  const std::vector<float> v = readLevel0(path, "victoria");
  std::size_t mismatches = 0;
  for (std::size_t r = 0; r < 301; ++r) {
    for (std::size_t c = 0; c < 301; ++c) {
      // x east from the west edge, y north from the top row (row 0 north).
      const double x = -600.0 + 4.0 * static_cast<double>(c);
      const double y = 600.0 - 4.0 * static_cast<double>(r);
      const auto expected = static_cast<float>(g.shape().height(x, y));
      if (std::memcmp(&expected, &v[r * 301 + c], sizeof(float)) != 0) ++mismatches;
    }
  }
  EXPECT_EQ(mismatches, 0U);
}

TEST(GenerateVictoria, SameSeedIsBitIdenticalDifferentSeedIsNot) {
  VictoriaOptions a = options(257, 4.0, 5), b = options(257, 4.0, 5), c = options(257, 4.0, 6);
  b.write.patchRows = 100;
  b.write.patchCols = 33;
  VictoriaGenerator(a).write(scratch("va.h5"));
  VictoriaGenerator(b).write(scratch("vb.h5"));
  VictoriaGenerator(c).write(scratch("vc.h5"));
  const std::vector<float> va = readLevel0(scratch("va.h5"), "victoria");
  const std::vector<float> vb = readLevel0(scratch("vb.h5"), "victoria");
  const std::vector<float> vc = readLevel0(scratch("vc.h5"), "victoria");
  ASSERT_EQ(va.size(), vb.size());
  EXPECT_EQ(std::memcmp(va.data(), vb.data(), va.size() * sizeof(float)), 0);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < va.size(); ++i) differ += va[i] != vc[i] ? 1U : 0U;
  EXPECT_GT(differ, va.size() * 9 / 10);
}

// The crater's geometry, at two resolutions.
class GenerateVictoriaGeometry : public ::testing::TestWithParam<double> {};

TEST_P(GenerateVictoriaGeometry, RimDiameterRaisedRimAndFloor) {
  const double spacing = GetParam();
  const auto size = static_cast<std::size_t>(1200.0 / spacing) + 1;
  const Written w = writeAndOpen(options(size, spacing, 3), "geom.h5");
  const std::vector<double> radii = crestRadii(w.dem, 360);
  // About 750 m across.
  EXPECT_NEAR(2.0 * median(radii), 750.0, 20.0);
  double crest = 0.0, plains = 0.0, floor = 0.0;
  for (std::size_t i = 0; i < 360; ++i) {
    const double th = 2.0 * kPi * static_cast<double>(i) / 360.0;
    crest += heightAt(w.dem, radii[i] * std::cos(th), radii[i] * std::sin(th)) / 360.0;
    plains += heightAt(w.dem, 590.0 * std::cos(th), 590.0 * std::sin(th)) / 360.0;
    floor += heightAt(w.dem, 80.0 * std::cos(th), 80.0 * std::sin(th)) / 360.0;
  }
  EXPECT_GT(crest - plains, 4.0);    // raised rim
  EXPECT_LT(floor - plains, -50.0);  // floor well below the plains
  EXPECT_LT(floor - plains, -(crest - plains));
}

TEST_P(GenerateVictoriaGeometry, ScallopedWallHasTheExpectedBays) {
  const double spacing = GetParam();
  const auto size = static_cast<std::size_t>(1200.0 / spacing) + 1;
  const Written w = writeAndOpen(options(size, spacing, 4), "bays.h5");
  const std::size_t n = 720;
  const std::vector<double> radii = crestRadii(w.dem, n);
  // Circular running mean over ±5° against the crest's pixel-scale jitter.
  std::vector<double> smooth(n);
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0.0;
    for (int d = -10; d <= 10; ++d) s += radii[(i + n + static_cast<std::size_t>(d + 720)) % n];
    smooth[i] = s / 21.0;
  }
  // Bays: maxima of the crest radius (the wall cut back), promontories the minima between
  // them; counted with a 6 m hysteresis against pixel-scale wiggles of the detected crest.
  const std::size_t start =
      static_cast<std::size_t>(std::min_element(smooth.begin(), smooth.end()) - smooth.begin());
  std::vector<double> bayAzimuths;
  bool rising = true;
  double extreme = smooth[start];
  std::size_t extremeAt = start;
  for (std::size_t k = 1; k <= n; ++k) {
    const std::size_t i = (start + k) % n;
    const double v = smooth[i];
    if (rising) {
      if (v > extreme) {
        extreme = v;
        extremeAt = i;
      } else if (v < extreme - 6.0) {
        bayAzimuths.push_back(360.0 * static_cast<double>(extremeAt) / static_cast<double>(n));
        rising = false;
        extreme = v;
      }
    } else if (v < extreme) {
      extreme = v;
    } else if (v > extreme + 6.0) {
      rising = true;
      extreme = v;
      extremeAt = i;
    }
  }
  const VictoriaShape& shape = w.generator.shape();
  EXPECT_EQ(bayAzimuths.size(), static_cast<std::size_t>(shape.bays));
  const auto [lo, hi] = std::minmax_element(smooth.begin(), smooth.end());
  EXPECT_GT(*hi - *lo, 15.0);  // bays reach ≥ 15 m farther out than promontories
  // Each bay sits near an azimuth bayPhase + k·360°/bays.
  for (const double az : bayAzimuths) {
    const double period = 360.0 / shape.bays;
    const double phase = shape.bayPhase * 180.0 / kPi;
    const double off = std::remainder(az - phase, period);
    EXPECT_LT(std::abs(off), 6.0) << az;
  }
}

TEST_P(GenerateVictoriaGeometry, DunesAreRidgesOnTheFloor) {
  const double spacing = GetParam();
  const auto size = static_cast<std::size_t>(1200.0 / spacing) + 1;
  const Written w = writeAndOpen(options(size, spacing, 8), "dunes.h5");
  const VictoriaShape& shape = w.generator.shape();
  const double ca = std::cos(shape.duneAzimuth), sa = std::sin(shape.duneAzimuth);
  // Profiles along and across the dune direction, on the floor (within 100 m of the centre).
  const auto profile = [&](bool along, double offset) {
    std::vector<double> s, h;
    for (double t = -100.0; t <= 100.0; t += 0.5) {
      const double a = along ? t : offset, b = along ? offset : t;
      s.push_back(t);
      h.push_back(heightAt(w.dem, a * ca - b * sa, a * sa + b * ca));
    }
    return detrend(s, h);
  };
  const double lambda = shape.duneWavelength;
  for (const double offset : {-30.0, 0.0, 30.0}) {
    const std::vector<double> along = profile(true, offset);
    // The strongest wavelength between 15 and 100 m is the dunes'.
    double bestW = 0.0, bestP = -1.0;
    for (double wl = 15.0; wl <= 100.0; wl += 0.25) {
      const double p = powerAt(along, 0.5, wl);
      if (p > bestP) {
        bestP = p;
        bestW = wl;
      }
    }
    EXPECT_NEAR(bestW, lambda, 0.1 * lambda) << offset;
    // Ridges of about a metre or more, and none across the dunes at that wavelength.
    double var = 0.0;
    for (const double x : along) var += x * x;
    EXPECT_GT(std::sqrt(var / static_cast<double>(along.size())), 0.4);
    const std::vector<double> across = profile(false, offset);
    EXPECT_GT(bestP, 20.0 * powerAt(across, 0.5, lambda)) << offset;
  }
  // On the plains outside the crater, no dunes: far less power at the dune wavelength.
  std::vector<double> s, h;
  for (double t = -100.0; t <= 100.0; t += 0.5) {
    s.push_back(t);
    h.push_back(heightAt(w.dem, 520.0 * ca + t * ca, 520.0 * sa + t * sa));
  }
  const std::vector<double> plains = detrend(s, h);
  const std::vector<double> floorAlong = profile(true, 0.0);
  EXPECT_GT(powerAt(floorAlong, 0.5, lambda), 50.0 * powerAt(plains, 0.5, lambda));
}

INSTANTIATE_TEST_SUITE_P(Spacing, GenerateVictoriaGeometry, ::testing::Values(1.0, 2.5));

TEST(GenerateVictoria, DefaultShapeIsTheDemoCraterAndSeedsVaryIt) {
  const VictoriaShape def;
  EXPECT_EQ(def.bays, 7);
  EXPECT_DOUBLE_EQ(def.rimRadius, 375.0);
  const VictoriaShape a = VictoriaShape::fromSeed(1), b = VictoriaShape::fromSeed(2);
  EXPECT_NE(a.bayPhase, b.bayPhase);
  EXPECT_NE(a.duneAzimuth, b.duneAzimuth);
  EXPECT_EQ(a.bays, b.bays);
  // The shape's crest radius is what the formula documents.
  for (double th = 0.0; th < 2 * kPi; th += 0.1) {
    EXPECT_DOUBLE_EQ(a.crestRadius(th), 375.0 * (1.0 + 0.035 * std::cos(7.0 * (th - a.bayPhase)) +
                                                 0.008 * std::cos(13.0 * th + a.roughPhase)));
  }
}

TEST(GenerateVictoria, BadOptionsAreRefused) {
  EXPECT_THROW(VictoriaGenerator(options(1, 1.0)), InvalidArgument);
  EXPECT_THROW(VictoriaGenerator(options(100, 0.0)), InvalidArgument);
  EXPECT_THROW(VictoriaGenerator(options(100, -1.0)), InvalidArgument);
  EXPECT_THROW(VictoriaGenerator(options(100, std::nan(""))), InvalidArgument);
  VictoriaOptions o = options(100, 1.0);
  o.gridName = "";
  EXPECT_THROW(VictoriaGenerator{o}, InvalidArgument);
  o = options(100, 1.0);
  o.write.patchRows = 0;
  const fs::path path = scratch("bad.h5");
  EXPECT_THROW(VictoriaGenerator(o).write(path), InvalidArgument);
  EXPECT_FALSE(fs::exists(path));
}
