// The stability suite (issue 16): random and adversarial queries per grid kind, at the edges
// of every domain: poles, lat = ±(90 − 1e-12), the seam 1e-9° from every sample line,
// longitude aliases, points on every edge and corner, DEMs placed at a pole and across ±180°.
// Properties: no false invalids, nothing but finite values where a status says valid, unit
// normals to 1e-12, continuity across poles and the seam, round trips against PROJ.
// ctest -L stability runs it; REGOLITH_STABILITY_CASES (default 1000000) sets the number of
// cases per grid kind. docs/queries.md quotes its measured figures.
#include <regolith/core/Error.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include "support/ProjOracle.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>
#include <string>
#include <vector>

using namespace regolith;
using namespace regolith::topo;
using regolith::test::num;
using regolith::test::Proj;
using regolith::test::projEllipsoid;
using regolith::test::report;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr Interpolation kAll[] = {Interpolation::Nearest, Interpolation::Bilinear,
                                  Interpolation::Bicubic};

std::size_t cases() {
  const char* env = std::getenv("REGOLITH_STABILITY_CASES");
  return env != nullptr ? static_cast<std::size_t>(std::strtoull(env, nullptr, 10)) : 1000000U;
}

// A field smooth on the sphere (one value and one gradient at each pole), in metres.
double field(double latDeg, double lonDeg) {
  const double la = latDeg * kDeg, lo = lonDeg * kDeg;
  const glm::dvec3 u(std::cos(la) * std::cos(lo), std::cos(la) * std::sin(lo), std::sin(la));
  return 1000.0 * u.x + 700.0 * u.y * u.z + 300.0 * u.z * u.z +
         50.0 * std::sin(7.0 * lo) * std::cos(la) * std::cos(la);
}

std::shared_ptr<InMemorySamples> sampled(const TopoGrid& g,
                                         const std::function<double(double, double)>& f) {
  return InMemorySamples::fromFunction(g.rows(), g.cols(), [&](std::size_t r, std::size_t c) {
    const glm::dvec2 p = g.sampleCentre(static_cast<double>(r), static_cast<double>(c));
    return static_cast<float>(f(p.x, p.y));
  });
}

// What a run found: cases, invalids that should not be, non-finite valid values, the worst
// departure of a normal's length from 1.
struct Tally {
  std::size_t cases = 0, falseInvalid = 0, nonFinite = 0, normalInvalid = 0;
  double worstUnit = 0.0;
  void add(const SurfaceSample& s, bool expectValid) {
    ++cases;
    if (expectValid && !s.valid()) ++falseInvalid;
    if (s.valid() && !std::isfinite(s.height)) ++nonFinite;
    if (s.valid() && !s.normalValid()) ++normalInvalid;
    if (s.normalValid()) {
      const double len = glm::length(s.normal);
      if (!std::isfinite(len)) {
        ++nonFinite;
      } else {
        worstUnit = std::max(worstUnit, std::abs(len - 1.0));
      }
    }
  }
  void check(const std::string& name) const {
    EXPECT_EQ(falseInvalid, 0U) << name;
    EXPECT_EQ(nonFinite, 0U) << name;
    EXPECT_EQ(normalInvalid, 0U) << name;  // no holes in these grids
    EXPECT_LE(worstUnit, 1e-12) << name;
    report("stability." + name + ".cases", static_cast<double>(cases));
    report("stability." + name + ".normal_length_minus_1_max", worstUnit);
  }
};

// Longitudes and latitudes of a planet grid's adversarial cases.
struct PlanetCases {
  const TopoGrid& g;
  std::mt19937_64 rng{16};
  std::size_t i = 0;
  LatLon next() {
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const double west = g.west(), east = g.east(), south = g.south(), north = g.north();
    const auto randLon = [&] { return west + (east - west) * uni(rng); };
    const auto randLat = [&] { return south + (north - south) * uni(rng); };
    const auto alias = [&](double lon) {  // the same meridian, another turn
      return lon + 360.0 * static_cast<double>(static_cast<int>(uni(rng) * 7.0) - 3);
    };
    switch (i++ % 8) {
      case 0: return {randLat(), randLon()};
      case 1: return {randLat(), alias(randLon())};
      case 2: {  // 1e-9° either side of a sample line (meridian), the seam among them
        const double c = std::floor(uni(rng) * static_cast<double>(g.cols()));
        const double lon = g.sampleCentre(0.0, c).x + (uni(rng) < 0.5 ? -1e-9 : 1e-9);
        return {randLat(), alias(lon)};
      }
      case 3: {  // 1e-9° either side of a row of centres
        const double r = std::floor(uni(rng) * static_cast<double>(g.rows()));
        return {std::clamp(g.sampleCentre(r, 0.0).y + (uni(rng) < 0.5 ? -1e-9 : 1e-9), -90.0, 90.0),
                randLon()};
      }
      case 4: {  // the poles, and 1e-12° from them
        const double pole = uni(rng) < 0.5 ? 90.0 : -90.0;
        const double lat = uni(rng) < 0.5 ? pole : pole - std::copysign(1e-12, pole);
        return {std::clamp(lat, south, north), alias(randLon())};
      }
      case 5: {  // on an edge, as TopoGrid reports it
        const double u = uni(rng);
        if (u < 0.25) return {g.north(), randLon()};
        if (u < 0.5) return {g.south(), randLon()};
        if (u < 0.75) return {randLat(), west};
        return {randLat(), east};
      }
      case 6: {  // a corner
        const double u = uni(rng);
        return {u < 0.5 ? g.north() : g.south(), uni(rng) < 0.5 ? west : east};
      }
      default: {  // the seam ±180 itself and its aliases
        return {randLat(), alias(uni(rng) < 0.5 ? 180.0 : -180.0)};
      }
    }
  }
};

void runPlanet(const std::string& name, const TopoPlanet& p) {
  PlanetCases gen{p.grid()};
  Tally t;
  const std::size_t n = cases();
  for (std::size_t i = 0; i < n; ++i) {
    const LatLon ll = gen.next();
    const Interpolation k = kAll[i % 3];
    const NormalFrame f = (i / 3) % 2 == 0 ? NormalFrame::Grid : NormalFrame::BodyFixed;
    t.add(p.surface(ll, k, f), true);
  }
  t.check(name);
}

}  // namespace

TEST(Stability, GlobalPlanetsOnSpheresAndEllipsoids) {
  const TopoGrid g(90, 180, -179.0, 89.0, 2.0, 2.0);
  runPlanet("planet_sphere",
            TopoPlanet(g, Body::marsSphere(), LatitudeType::Planetocentric,
                       sampled(g, [](double x, double y) { return field(y, x); })));
  runPlanet("planet_ellipsoid_planetocentric",
            TopoPlanet(g, Body::marsEllipsoid(), LatitudeType::Planetocentric,
                       sampled(g, [](double x, double y) { return field(y, x); })));
  // An odd column count: stencils do not reflect across the pole.
  const TopoGrid odd(60, 121, -180.0 + 360.0 / 242.0, 88.5, 360.0 / 121.0, 3.0);
  runPlanet("planet_ellipsoid_planetodetic_odd",
            TopoPlanet(odd, Body::marsEllipsoid(), LatitudeType::Planetodetic,
                       sampled(odd, [](double x, double y) { return field(y, x); })));
}

TEST(Stability, RegionalPlanetAnswersExactlyInsideItsExtent) {
  const TopoGrid g(40, 30, 137.123, -4.567, 0.00123, 0.00117);
  const TopoPlanet p(g, Body::marsSphere(), LatitudeType::Planetocentric,
                     sampled(g, [](double x, double y) { return field(y, x); }));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(-0.1, 1.1);
  Tally t;
  std::size_t wrong = 0;
  const std::size_t n = cases();
  for (std::size_t i = 0; i < n; ++i) {
    const double lon = g.west() + (g.east() - g.west()) * uni(rng);
    const double lat = g.south() + (g.north() - g.south()) * uni(rng);
    const bool inside = g.contains(lon, lat);
    const SurfaceSample s = p.surface({lat, lon + 360.0 * static_cast<double>(i % 3)}, kAll[i % 3]);
    t.add(s, inside);
    wrong += inside != (s.status != QueryStatus::OutsideGrid) ? 1U : 0U;
  }
  EXPECT_EQ(wrong, 0U);
  t.check("planet_regional");
}

namespace {

struct DemCase {
  std::string name;
  TopoGrid grid;
  Placement placement;
  std::string proj;  // PROJ definition of (x, y) ↔ (lon, lat) in degrees, or empty (LTP)
};

std::vector<DemCase> demCases() {
  const Body mars = Body::marsSphere(), marsE = Body::marsEllipsoid();
  const double r = mars.equatorialRadius();
  std::vector<DemCase> v;
  v.push_back({"dem_tangent_plane", TopoGrid(201, 181, -450.0, 500.0, 5.0, 5.0),
               Placement(LocalTangentPlane(marsE, {-2.05, -5.5, -1400.0}, 20.0)), ""});
  // Polar stereographic centred on the south pole, the pole inside the grid.
  v.push_back({"dem_polar_stereographic_at_pole",
               TopoGrid(120, 100, -49500.0, 59500.0, 1000.0, 1000.0),
               Placement(marsE, PolarStereographic::withTrueScaleLatitude(
                                    marsE, PolarStereographic::Pole::South, -90.0, 0.0)),
               "+proj=stere +lat_0=-90 +lat_ts=-90 +lon_0=0" + projEllipsoid(marsE)});
  // Equirectangular, central meridian 0, its grid on 180° and reaching past it, up to 1 km
  // from the north pole.
  const double mpd = r * kDeg;
  v.push_back({"dem_equirectangular_across_180",
               TopoGrid(100, 120, 180.0 * mpd - 59.0 * 1000.0, 90.0 * mpd - 1500.0, 1000.0, 1000.0),
               Placement(mars, Equirectangular(r, 0.0, 0.0)),
               "+proj=eqc +lon_0=0 +lat_ts=0 +over +R=" + num(r)});
  // UTM-like transverse Mercator, south hemisphere false northing.
  const Body earth = Body::earthWgs84();
  v.push_back({"dem_transverse_mercator_south",
               TopoGrid(100, 100, 450500.0, 5000000.0, 1000.0, 1000.0),
               Placement(earth, TransverseMercator::utm(earth, 10, false)),
               "+proj=utm +zone=10 +south" + projEllipsoid(earth)});
  return v;
}

}  // namespace

TEST(Stability, DemsAtAPoleAcrossTheSeamAndSouthOfTheEquator) {
  for (const DemCase& c : demCases()) {
    const TopoGrid& g = c.grid;
    const TopoDem dem(g, c.placement, sampled(g, [](double x, double y) {
                        return 100.0 + 3e-3 * x + 2e-3 * y +
                               20.0 * std::sin(x * 1e-3) * std::cos(y * 2e-3);
                      }));
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    Tally t;
    const std::size_t n = cases();
    for (std::size_t i = 0; i < n; ++i) {
      double x = g.west() + (g.east() - g.west()) * uni(rng);
      double y = g.south() + (g.north() - g.south()) * uni(rng);
      switch (i % 4) {
        case 1: x = uni(rng) < 0.5 ? g.west() : g.east(); break;  // an edge
        case 2: y = uni(rng) < 0.5 ? g.south() : g.north(); break;
        case 3:  // a corner
          x = uni(rng) < 0.5 ? g.west() : g.east();
          y = uni(rng) < 0.5 ? g.south() : g.north();
          break;
        default: break;
      }
      const NormalFrame f = (i / 4) % 2 == 0 ? NormalFrame::Grid : NormalFrame::BodyFixed;
      t.add(dem.surface(x, y, kAll[i % 3], f), true);
    }
    t.check(c.name);

    // Round trips against PROJ: (x, y) → lon/lat by PROJ, back to (x, y) by the placement
    // (in the turn where the grid lies), and lon/lat from the placement against PROJ's.
    if (c.proj.empty()) continue;
    const Proj proj("+proj=pipeline +step +inv " + c.proj +
                    " +step +proj=unitconvert +xy_in=rad +xy_out=deg");
    ASSERT_TRUE(proj.ok()) << proj.error();
    const double xNear = 0.5 * (g.west() + g.east());
    double worstXy = 0.0, worstLl = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const double x = g.west() + (g.east() - g.west()) * uni(rng);
      const double y = g.south() + (g.north() - g.south()) * uni(rng);
      const glm::dvec3 ll = proj.trans(PJ_FWD, x, y);  // the inverse projection: lon, lat
      ASSERT_EQ(proj.lastError(), 0) << c.name;
      const glm::dvec3 back = c.placement.fromGeodeticNear({ll.y, ll.x, 0.0}, xNear);
      worstXy = std::max(worstXy, glm::length(glm::dvec2(back.x - x, back.y - y)));
      const Geodetic ours = c.placement.toGeodetic(x, y, 0.0);
      const double dLon = std::remainder(ours.lonDeg - ll.x, 360.0) * std::cos(ll.y * kDeg);
      worstLl = std::max(worstLl, std::hypot(dLon, ours.latDeg - ll.y));
    }
    EXPECT_LT(worstXy, 1e-6) << c.name;
    EXPECT_LT(worstLl, 1e-10) << c.name;
    report("stability." + c.name + ".xy_round_trip_via_PROJ_max_m", worstXy);
    report("stability." + c.name + ".inverse_vs_PROJ_max_deg", worstLl);
  }
}

namespace {
double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}
}  // namespace

// Continuity, both kinds: the largest jump in height and in the body-frame normal over a
// 1e-6° step across each pole, the seam and the polar caps' edges is at most twice the
// largest jump over the same step elsewhere (bicubic: C1, so both are continuous).
TEST(Stability, ContinuityAcrossPolesSeamAndCapEdges) {
  const TopoGrid g(90, 180, -179.0, 89.0, 2.0, 2.0);
  const TopoPlanet p(g, Body::marsEllipsoid(), LatitudeType::Planetocentric,
                     sampled(g, [](double x, double y) { return field(y, x); }));
  const double step = 1e-6;
  const Interpolation k = Interpolation::Bicubic;
  struct Jump {
    double h = 0.0, n = 0.0;
  };
  const auto jump = [&](LatLon a, LatLon b) {
    const SurfaceSample sa = p.surface(a, k, NormalFrame::BodyFixed);
    const SurfaceSample sb = p.surface(b, k, NormalFrame::BodyFixed);
    EXPECT_TRUE(sa.normalValid() && sb.normalValid());
    return Jump{std::abs(sa.height - sb.height), angleBetween(sa.normal, sb.normal)};
  };
  Jump elsewhere, special;
  const auto keep = [](Jump& m, Jump j) {
    m.h = std::max(m.h, j.h);
    m.n = std::max(m.n, j.n);
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> lonD(-180.0, 180.0), latD(-87.0, 87.0);
  for (int i = 0; i < 4000; ++i) {
    const double lat = latD(rng), lon = lonD(rng);
    keep(elsewhere, jump({lat - 0.5 * step, lon}, {lat + 0.5 * step, lon}));
    keep(elsewhere, jump({lat, lon - 0.5 * step}, {lat, lon + 0.5 * step}));
  }
  for (int i = 0; i < 2000; ++i) {
    const double lon = lonD(rng), lat = latD(rng);
    for (const double pole : {90.0, -90.0}) {  // across the pole, along one great circle
      const double near = pole - std::copysign(0.5 * step, pole);
      keep(special, jump({near, lon}, {near, lon + 180.0}));
    }
    for (const double edge : {89.0, -89.0}) {  // across the caps' edges
      keep(special, jump({edge - 0.5 * step, lon}, {edge + 0.5 * step, lon}));
    }
    for (const double seam : {180.0, -180.0, 540.0}) {  // across the seam and an alias of it
      keep(special, jump({lat, seam - 0.5 * step}, {lat, seam + 0.5 * step}));
    }
  }
  EXPECT_LE(special.h, 2.0 * elsewhere.h);
  EXPECT_LE(special.n, 2.0 * elsewhere.n);
  report("stability.continuity.height_jump_poles_seam_caps_max_m", special.h);
  report("stability.continuity.height_jump_elsewhere_max_m", elsewhere.h);
  report("stability.continuity.normal_jump_poles_seam_caps_max_rad", special.n);
  report("stability.continuity.normal_jump_elsewhere_max_rad", elsewhere.n);
}
