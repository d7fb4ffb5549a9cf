// The ray-marching oracle (RayMarchOracle.hpp) against closed forms: ray–sphere and
// ray–ellipsoid roots in long double for constant heights, a mountain's silhouette from the
// elevation angle of its profile for a mountain behind the horizon and beside the camera, the
// same scene moved across the ±180° seam and onto the pole by exact rotations, and the
// silhouette comparison on hand-made images.

#include <regolith/core/Error.hpp>
#include <regolith/topo/Body.hpp>

#include "farfield/RayMarchOracle.hpp"
#include "gl/GlContext.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <optional>
#include <string>

namespace regolith::test {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kMars = 3396190.0;

/// Oracle for constant heights: the first root of the ray with the ellipsoid of semi-axes
/// (a, a, b), solved in long double after scaling z by a / b. nullopt if it misses.
std::optional<long double> rayEllipsoid(const glm::dvec3& o, const glm::dvec3& d, long double a,
                                        long double b) {
  const long double k = a / b;
  const long double ox = o.x, oy = o.y, oz = o.z * k;
  const long double dx = d.x, dy = d.y, dz = d.z * k;
  const long double qa = dx * dx + dy * dy + dz * dz;
  const long double qb = ox * dx + oy * dy + oz * dz;
  const long double qc = ox * ox + oy * oy + oz * oz - a * a;
  const long double disc = qb * qb - qa * qc;
  if (disc < 0) return std::nullopt;
  const long double t = (-qb - std::sqrt(disc)) / qa;
  if (t < 0) return std::nullopt;
  return t;
}

/// Every pixel of the oracle against rayEllipsoid: the same pixels hit, distances within
/// 1e-6 relative (or 1 µm) and 1 cm.
void expectMatchesEllipsoid(const clod::Camera& camera, const OracleSurface& surface, long double a,
                            long double b, const std::string& what) {
  const OracleImage image = rayMarch(camera, surface, 200.0);
  const glm::dvec3 forward = camera.forward();
  std::size_t hits = 0, misses = 0;
  double worstRelative = 0.0, worstMetres = 0.0;
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      const glm::dvec3 d = camera.ray(x + 0.5, y + 0.5);
      const auto t = rayEllipsoid(camera.position, d, a, b);
      ASSERT_EQ(image.hit(x, y), t.has_value()) << what << " pixel " << x << ", " << y;
      if (!t) {
        ++misses;
        continue;
      }
      ++hits;
      const double expected = static_cast<double>(*t) * glm::dot(d, forward);
      const double error = std::abs(image.distanceAt(x, y) - expected);
      worstRelative = std::max(worstRelative, error / expected);
      worstMetres = std::max(worstMetres, error);
      // 1e-6 relative, but not below 1 µm: 1 mm from the camera, body-fixed coordinates
      // of 3.4e6 m resolve 0.5 nm, toGeodetic's height ~1 nm, and a ray at 1° to the ground
      // turns that into ~0.1 µm along it.
      EXPECT_LE(error, std::max(1e-6 * expected, 1e-6)) << what << " pixel " << x << ", " << y;
      EXPECT_LE(error, 0.01) << what << " pixel " << x << ", " << y;
    }
  }
  // Each view shows the limb or the horizon: both kinds of pixel.
  EXPECT_GT(hits, 0U) << what;
  EXPECT_GT(misses, 0U) << what;
  std::cout << what << ": " << hits << " hits, " << misses << " sky; worst distance error "
            << worstMetres << " m (" << worstRelative << " relative)\n";
}

clod::Camera lookingAt(const glm::dvec3& position, const glm::dvec3& target, const glm::dvec3& up,
                       double fovY, int width, int height) {
  clod::Camera c;
  c.position = position;
  c.target = target;
  c.up = up;
  c.fovYDegrees = fovY;
  c.width = width;
  c.height = height;
  c.near = 1.0;
  return c;
}

OracleSurface constant(const topo::Body& body, double h) {
  return {body, [h](double, double) { return h; }, h, h};
}

TEST(RayMarchOracle, ConstantHeightOnASphereMatchesRaySphereRoots) {
  const topo::Body body = topo::Body::marsSphere();
  const double h = 5000.0, r = kMars + h;
  const OracleSurface surface = constant(body, h);
  const auto at = [&](double lat, double lon, double alt) {
    return body.toBodyFixed({lat, lon, alt});
  };
  // From 10^8 m, the whole disc in a 5° view.
  expectMatchesEllipsoid(
      lookingAt({6.0e7, -5.0e7, 6.0e7}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, 5.0, 64, 48), surface, r,
      r, "sphere from 1e8 m");
  // From 1000 km, the horizon in an oblique view.
  expectMatchesEllipsoid(lookingAt(at(30.0, 40.0, 1.0e6), at(30.0, 75.0, 0.0),
                                   glm::normalize(at(30.0, 40.0, 0.0)), 60.0, 64, 48),
                         surface, r, r, "sphere from 1000 km");
  // 2 km up, looking east along the horizon across the ±180° seam.
  const glm::dvec3 seamCamera = at(-20.0, 179.9, h + 2000.0);
  expectMatchesEllipsoid(lookingAt(seamCamera, seamCamera + body.enuFrame(-20.0, 179.9)[0],
                                   body.enuFrame(-20.0, 179.9)[2], 45.0, 64, 48),
                         surface, r, r, "sphere 2 km up at the seam");
  // 1 mm up near the pole, looking north over it along the ground.
  const glm::dvec3 poleCamera = at(89.99, 30.0, h + 1e-3);
  expectMatchesEllipsoid(lookingAt(poleCamera, poleCamera + body.enuFrame(89.99, 30.0)[1],
                                   body.enuFrame(89.99, 30.0)[2], 45.0, 64, 48),
                         surface, r, r, "sphere 1 mm up by the pole");
}

TEST(RayMarchOracle, ZeroHeightOnTheMarsEllipsoidMatchesRayEllipsoidRoots) {
  const topo::Body body = topo::Body::marsEllipsoid();
  const long double a = body.equatorialRadius(), b = body.polarRadius();
  const OracleSurface surface = constant(body, 0.0);
  const auto at = [&](double lat, double lon, double alt) {
    return body.toBodyFixed({lat, lon, alt});
  };
  // Side-on from 10^8 m (the flattening shows in the limb).
  expectMatchesEllipsoid(
      lookingAt({0.0, 1.0e8, 2.0e7}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, 5.0, 64, 48), surface, a, b,
      "ellipsoid from 1e8 m");
  // 500 km over 60°N, looking north at the horizon beyond the pole.
  expectMatchesEllipsoid(lookingAt(at(60.0, -170.0, 5.0e5), at(85.0, -170.0, 0.0),
                                   glm::normalize(at(60.0, -170.0, 0.0)), 60.0, 64, 48),
                         surface, a, b, "ellipsoid from 500 km");
  // 2 km over the north pole exactly (inside the marched shell: b + 2 km < a), horizontal.
  const glm::dvec3 pole = at(90.0, 0.0, 2000.0);
  expectMatchesEllipsoid(
      lookingAt(pole, pole + glm::dvec3(1000.0, 0.0, 0.0), {0.0, 0.0, 1.0}, 45.0, 64, 48), surface,
      a, b, "ellipsoid 2 km over the pole");
  // 1 mm up at 45°S by the seam, looking east along the ground.
  const glm::dvec3 low = at(-45.0, -179.999, 1e-3);
  expectMatchesEllipsoid(lookingAt(low, low + body.enuFrame(-45.0, -179.999)[0],
                                   body.enuFrame(-45.0, -179.999)[2], 30.0, 64, 48),
                         surface, a, b, "ellipsoid 1 mm up at the seam");
}

/// A Gaussian mountain on a sphere: height H·exp(−s² / 2σ²) with s the great-circle distance
/// from `centre` (a unit vector), computed from unit vectors so that the seam and the poles
/// mean nothing to it.
struct Mountain {
  glm::dvec3 centre;
  double peak = 20000.0;
  double sigma = 20000.0;
  double radius = kMars;

  [[nodiscard]] double angleFrom(double latDeg, double lonDeg) const {
    const double phi = latDeg * kDeg, lambda = lonDeg * kDeg;
    const glm::dvec3 n(std::cos(phi) * std::cos(lambda), std::cos(phi) * std::sin(lambda),
                       std::sin(phi));
    return std::atan2(glm::length(glm::cross(n, centre)), glm::dot(n, centre));
  }
  [[nodiscard]] double heightAtAngle(double angle) const {
    const double s = radius * angle;
    return peak * std::exp(-s * s / (2.0 * sigma * sigma));
  }
  [[nodiscard]] OracleSurface surface() const {
    const Mountain m = *this;
    return {topo::Body::sphere("Mars", radius),
            [m](double lat, double lon) { return m.heightAtAngle(m.angleFrom(lat, lon)); }, 0.0,
            peak};
  }
};

/// A camera on the equator of a sphere at longitude cameraAngle (radians), looking east (or
/// west) along it with the local vertical up: elevation() is the angle above the camera's
/// horizontal of the equator's point at longitude phi and distance `radius` from the centre,
/// in closed form.
struct EquatorView {
  double cameraAngle = 0.0;   ///< radians east of the x axis
  double cameraRadius = 0.0;  ///< metres from the centre
  bool lookEast = true;

  [[nodiscard]] double elevation(double phi, double radius) const {
    const double along = radius * std::sin(phi - cameraAngle);
    const double up = radius * std::cos(phi - cameraAngle) - cameraRadius;
    return std::atan2(up, lookEast ? along : -along);
  }
};

/// The row (pixel units, y down) where a direction of elevation e crosses the centre column.
double rowOf(const clod::Camera& camera, double e) {
  return 0.5 * camera.height - camera.focalPixels() * std::tan(e);
}

/// The highest elevation of the mountain's equatorial profile seen from `view`, by dense
/// sampling of the closed form over ±6σ (a step of 2 m: far below a pixel).
double profileTop(const Mountain& m, double mountainAngle, const EquatorView& view) {
  const double span = 6.0 * m.sigma / m.radius;
  const int n = static_cast<int>(2.0 * 6.0 * m.sigma / 2.0);
  double best = -10.0;
  for (int i = 0; i <= n; ++i) {
    const double phi = mountainAngle - span + 2.0 * span * i / n;
    best = std::max(best, view.elevation(phi, m.radius + m.heightAtAngle(phi - mountainAngle)));
  }
  return best;
}

/// The topmost hit row of a column against the closed-form silhouette row `expected` (pixel
/// units, y down): within 1 px (issue 19's tolerance for the GPU), and more strictly the first
/// row whose pixel centre lies below the silhouette, to 0.01 px (the oracle is exact to far
/// below a pixel, which is what lets it judge the GPU to 1 px).
void expectSilhouetteRow(int topRow, double expected, const char* what) {
  EXPECT_NEAR(topRow + 0.5, expected, 1.0) << what;
  EXPECT_GE(topRow + 0.5, expected - 0.01) << what << ": the top pixel's centre is above it";
  EXPECT_LT(topRow - 0.5, expected + 0.01) << what << ": the pixel above it is below it";
}

TEST(RayMarchOracle, AMountainBehindTheHorizonRisesAboveTheHorizonLine) {
  const double mountainAngle = 5.0 * kDeg, cameraAltitude = 2000.0;
  const Mountain mountain{{std::cos(mountainAngle), std::sin(mountainAngle), 0.0}};
  const double horizonAngle = std::acos(kMars / (kMars + cameraAltitude));
  // The whole mountain (to 3σ) lies behind the camera's horizon.
  ASSERT_GT(mountainAngle - 3.0 * mountain.sigma / kMars, horizonAngle);

  // Camera on the equator at 0°E, looking east, up = the local vertical. Odd sizes put the
  // centre column's pixel centres on the equator's plane.
  const glm::dvec3 position(kMars + cameraAltitude, 0.0, 0.0);
  const clod::Camera camera =
      lookingAt(position, position + glm::dvec3(0.0, 1000.0, 0.0), {1.0, 0.0, 0.0}, 45.0, 321, 241);
  const int column = camera.width / 2;
  const auto start = std::chrono::steady_clock::now();
  const OracleImage image = rayMarch(camera, mountain.surface(), 200.0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "ray-marched " << camera.width << " x " << camera.height << " in " << seconds
            << " s (step 200 m, 2 threads)\n";
  RecordProperty("seconds_321x241", std::to_string(seconds));
  savePng("farfield_oracle_mountain_behind_horizon", depthPicture(image));

  const EquatorView view{0.0, kMars + cameraAltitude};
  const double top = profileTop(mountain, mountainAngle, view);
  const double peak = view.elevation(mountainAngle, kMars + mountain.peak);
  const double horizonRow = rowOf(camera, -horizonAngle);
  const int topRow = image.topmostHit(column);
  ASSERT_GE(topRow, 0);
  std::cout << "silhouette: oracle row " << topRow << " (centre " << topRow + 0.5
            << "), profile top " << rowOf(camera, top) << ", peak " << rowOf(camera, peak)
            << ", horizon " << horizonRow << "\n";
  expectSilhouetteRow(topRow, rowOf(camera, top), "profile top");
  EXPECT_NEAR(topRow + 0.5, rowOf(camera, peak), 1.0);
  // It rises above the horizon line, and above the horizontal too (at +0.97°).
  EXPECT_LT(topRow + 0.5, horizonRow - 10.0);
  EXPECT_LT(topRow + 0.5, 0.5 * camera.height);
  // What the column sees from its top down to the horizon line is the mountain (within 4σ).
  for (int y = topRow; y + 0.5 < horizonRow - 1.0; ++y) {
    ASSERT_TRUE(image.hit(column, y)) << y;
    const glm::dvec3 p = image.point[image.index(column, y)];
    const double s = kMars * std::acos(glm::dot(glm::normalize(p), mountain.centre));
    EXPECT_LT(s, 4.0 * mountain.sigma) << y;
  }
  // Without the mountain that column shows sky down to the horizon line, which the oracle
  // finds from its grazing rays within a pixel (the column alone, ray by ray).
  Mountain flat = mountain;
  flat.peak = 0.0;
  int bareTop = camera.height;
  for (int y = camera.height - 1; y >= 0; --y) {
    if (marchRay(position, camera.ray(column + 0.5, y + 0.5), flat.surface(), 200.0)) bareTop = y;
  }
  expectSilhouetteRow(bareTop, horizonRow, "bare horizon");
  EXPECT_GT(bareTop, topRow + 10);
}

TEST(RayMarchOracle, FromOrbitAMountainJustBehindTheLimbRisesAboveIt) {
  // From 10^8 m, a 0.05° view of the limb (7 µrad, 0.7 km a pixel); the mountain stands 1.2°
  // beyond the limb, all of it (to 3σ) hidden but for the top 19 km.
  const double cameraRadius = 1.0e8;
  const double limbAngle = std::acos(kMars / cameraRadius);
  const double mountainAngle = limbAngle + 1.2 * kDeg;
  const Mountain mountain{{std::cos(mountainAngle), std::sin(mountainAngle), 0.0}};
  ASSERT_GT(mountainAngle - 3.0 * mountain.sigma / kMars, limbAngle);
  const glm::dvec3 position(cameraRadius, 0.0, 0.0);
  // Up = +y, so the centre column's plane is the equator's.
  const clod::Camera camera =
      lookingAt(position, kMars * glm::dvec3(std::cos(limbAngle), std::sin(limbAngle), 0.0),
                {0.0, 1.0, 0.0}, 0.05, 81, 121);
  const OracleImage image = rayMarch(camera, mountain.surface(), 200.0);
  savePng("farfield_oracle_limb_from_orbit", depthPicture(image));
  // Elevations from the camera's horizontal, and the view's own (the limb's) as the centre row.
  const EquatorView view{0.0, cameraRadius};
  const double pitch = view.elevation(limbAngle, kMars);
  const auto row = [&](double e) { return rowOf(camera, e - pitch); };
  const int column = camera.width / 2;
  const int topRow = image.topmostHit(column);
  const double expected = row(profileTop(mountain, mountainAngle, view));
  std::cout << "limb from 1e8 m: oracle row centre " << topRow + 0.5 << ", profile top " << expected
            << ", bare limb " << row(pitch) << "\n";
  expectSilhouetteRow(topRow, expected, "profile top");
  EXPECT_LT(expected, row(pitch) - 20.0);  // 19 km over the limb: ~27 px
  // Without the mountain the column's top hit is the bare limb, on the boundary of the centre
  // row: its centre ray is tangent to the sphere, so rounding decides whether it hits, and
  // either way the top hit lies where the check allows.
  Mountain flat = mountain;
  flat.peak = 0.0;
  int bareTop = camera.height;
  for (int y = camera.height - 1; y >= 0; --y) {
    if (marchRay(position, camera.ray(column + 0.5, y + 0.5), flat.surface(), 200.0)) bareTop = y;
  }
  expectSilhouetteRow(bareTop, row(pitch), "bare limb");
}

TEST(RayMarchOracle, ZoomedOnTheMountainItsSilhouetteMatchesTheProfileWithinAPixel) {
  // 3° over 121 rows: 0.43 mrad a pixel, finer than the distance between the peak's elevation
  // and the profile's top (the near slope stands higher), so only the profile's top fits.
  const double mountainAngle = 5.0 * kDeg, cameraAltitude = 2000.0;
  const Mountain mountain{{std::cos(mountainAngle), std::sin(mountainAngle), 0.0}};
  const glm::dvec3 position(kMars + cameraAltitude, 0.0, 0.0);
  const clod::Camera camera =
      lookingAt(position, position + glm::dvec3(0.0, 1000.0, 0.0), {1.0, 0.0, 0.0}, 3.0, 161, 121);
  const OracleImage image = rayMarch(camera, mountain.surface(), 200.0);
  savePng("farfield_oracle_mountain_zoomed", depthPicture(image));
  const EquatorView view{0.0, kMars + cameraAltitude};
  const double expected = rowOf(camera, profileTop(mountain, mountainAngle, view));
  const int topRow = image.topmostHit(camera.width / 2);
  std::cout << "zoomed silhouette: oracle row centre " << topRow + 0.5 << ", profile top "
            << expected << ", peak "
            << rowOf(camera, view.elevation(mountainAngle, kMars + mountain.peak)) << "\n";
  expectSilhouetteRow(topRow, expected, "profile top");
}

TEST(RayMarchOracle, ComparingTheMountainToleratesLessThanAPixelAndCatchesTwoAndAHalf) {
  // The zoomed mountain as a stand-in for a GPU image: the oracle itself, marched with 5×
  // longer steps from a camera pitched down by a fraction of a pixel, then by 2.5 pixels.
  const double mountainAngle = 5.0 * kDeg, cameraAltitude = 2000.0;
  const Mountain mountain{{std::cos(mountainAngle), std::sin(mountainAngle), 0.0}};
  const glm::dvec3 position(kMars + cameraAltitude, 0.0, 0.0);
  const auto pitched = [&](double pixels) {
    clod::Camera c = lookingAt(position, {}, {1.0, 0.0, 0.0}, 3.0, 161, 121);
    const double angle = pixels / c.focalPixels();
    c.target = position + 1000.0 * glm::dvec3(-std::sin(angle), std::cos(angle), 0.0);
    return c;
  };
  const OracleImage oracle = rayMarch(pitched(0.0), mountain.surface(), 200.0);
  const SilhouetteReport self = compareSilhouettes(oracle, toDepthImage(oracle));
  EXPECT_EQ(self.coverageMismatches + self.depthMismatches, 0U) << self.describe();

  const OracleImage slightly = rayMarch(pitched(0.4), mountain.surface(), 1000.0);
  const SilhouetteReport near = compareSilhouettes(oracle, toDepthImage(slightly));
  std::cout << "pitched 0.4 px: " << near.describe() << "\n";
  EXPECT_GT(near.coverageMismatches, 0U) << near.describe();
  EXPECT_EQ(near.misplacedPixels(), 0U) << near.describe();
  EXPECT_LT(near.medianRelativeDepthDifference, 0.01) << near.describe();

  const OracleImage far = rayMarch(pitched(2.5), mountain.surface(), 1000.0);
  const SilhouetteReport off = compareSilhouettes(oracle, toDepthImage(far));
  std::cout << "pitched 2.5 px: " << off.describe() << "\n";
  EXPECT_GT(off.misplacedPixels(), 100U) << off.describe();
}

TEST(RayMarchOracle, ACameraBesideAMountainHigherThanItselfSeesItAboveTheHorizontal) {
  // 60 km west of a 20 km summit, 3 km up (the ground below is 222 m high): the camera is
  // inside the shell the oracle marches, below the top of the surface.
  const double mountainAngle = 5.0 * kDeg;
  const double cameraAngle = mountainAngle - 60000.0 / kMars, cameraAltitude = 3000.0;
  const Mountain mountain{{std::cos(mountainAngle), std::sin(mountainAngle), 0.0}};
  const glm::dvec3 up(std::cos(cameraAngle), std::sin(cameraAngle), 0.0);
  const glm::dvec3 east(-std::sin(cameraAngle), std::cos(cameraAngle), 0.0);
  const glm::dvec3 position = (kMars + cameraAltitude) * up;
  const OracleSurface surface = mountain.surface();
  const int column = 80;

  const clod::Camera toward = lookingAt(position, position + 1000.0 * east, up, 60.0, 161, 121);
  const OracleImage image = rayMarch(toward, surface, 100.0);
  savePng("farfield_oracle_beside_mountain", depthPicture(image));
  const EquatorView view{cameraAngle, kMars + cameraAltitude};
  const double expected = rowOf(toward, profileTop(mountain, mountainAngle, view));
  const int topRow = image.topmostHit(column);
  std::cout << "beside: oracle row centre " << topRow + 0.5 << ", profile top " << expected << "\n";
  expectSilhouetteRow(topRow, expected, "profile top");
  EXPECT_LT(expected, 0.5 * toward.height - 20.0);  // well above the horizontal
  for (int y = topRow; y < toward.height; ++y) ASSERT_TRUE(image.hit(column, y)) << y;

  // Looking away, the bare sphere's horizon dips below the horizontal as the closed form says.
  const clod::Camera away = lookingAt(position, position - 1000.0 * east, up, 60.0, 161, 121);
  const OracleImage behind = rayMarch(away, surface, 100.0);
  const double dip = std::acos(kMars / (kMars + cameraAltitude));
  expectSilhouetteRow(behind.topmostHit(column), rowOf(away, -dip), "horizon behind");
}

/// Maps body-fixed vectors by an exact rotation (a permutation of coordinates, or a sign flip
/// of two), so that the same scene can be moved without rounding.
glm::dvec3 seamTurn(const glm::dvec3& v) { return {-v.x, -v.y, v.z}; }  // 180° about z
glm::dvec3 poleTurn(const glm::dvec3& v) { return {v.y, v.z, v.x}; }    // x → z, 0°E → pole

TEST(RayMarchOracle, TheSameSceneAcrossTheSeamAndOverThePoleGivesTheSameImage) {
  const topo::Body body = topo::Body::marsSphere();
  const glm::dvec3 centre(1.0, 0.0, 0.0);
  // 89 km west of the summit, 5 km up, looking at its flank: mountain, ground and sky.
  const glm::dvec3 position = body.toBodyFixed({0.1, -1.5, 5000.0});
  const glm::dvec3 target = body.toBodyFixed({0.3, 0.0, 10000.0});
  const glm::dvec3 up = glm::normalize(position);
  const auto image = [&](auto turn) {
    const Mountain m{turn(centre)};
    return rayMarch(lookingAt(turn(position), turn(target), turn(up), 40.0, 96, 72), m.surface(),
                    200.0);
  };
  const OracleImage reference = image([](const glm::dvec3& v) { return v; });
  const OracleImage seam = image(seamTurn);  // camera at 178.5°E, looking across 180°
  const OracleImage pole = image(poleTurn);  // mountain on the north pole, looking over it
  savePng("farfield_oracle_seam_reference", depthPicture(reference));
  savePng("farfield_oracle_pole", depthPicture(pole));
  // The view holds the mountain, the ground and the sky.
  std::size_t onMountain = 0;
  for (std::size_t i = 0; i < reference.point.size(); ++i) {
    const glm::dvec3 p = reference.point[i];
    if (!std::isnan(p.x) && std::acos(glm::dot(glm::normalize(p), centre)) * kMars < 40000.0) {
      ++onMountain;
    }
  }
  EXPECT_GT(onMountain, 500U);
  EXPECT_LT(reference.hitCount(), reference.distance.size());
  for (const auto* other : {&seam, &pole}) {
    const char* what = other == &seam ? "seam" : "pole";
    for (int y = 0; y < reference.height; ++y) {
      for (int x = 0; x < reference.width; ++x) {
        ASSERT_EQ(other->hit(x, y), reference.hit(x, y)) << what << " " << x << ", " << y;
        if (!reference.hit(x, y)) continue;
        EXPECT_NEAR(other->distanceAt(x, y), reference.distanceAt(x, y), 2e-3)
            << what << " " << x << ", " << y;
      }
    }
  }
}

TEST(RayMarchOracle, RejectsACameraBelowTheSurfaceAndHeightsOutsideTheirBounds) {
  const Mountain mountain{{1.0, 0.0, 0.0}};
  const clod::Camera camera = lookingAt({kMars + 100.0, 0.0, 0.0}, {kMars + 100.0, 1000.0, 0.0},
                                        {1.0, 0.0, 0.0}, 45.0, 8, 6);
  try {
    (void)rayMarch(camera, mountain.surface(), 100.0);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(),
                 "test::rayMarch(): camera at lat 0, lon 0, altitude 100 m is -19900 m above "
                 "the surface, expected > 0");
  }
  OracleSurface low = mountain.surface();
  low.maxHeight = 10000.0;
  const clod::Camera high =
      lookingAt({kMars + 30000.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, 45.0, 8, 6);
  try {
    (void)rayMarch(high, low, 100.0);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("expected within [minHeight, maxHeight] = [0, 10000] m"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)rayMarch(high, mountain.surface(), 0.0), InvalidArgument);
}

/// A 20 × 20 oracle: sky above row 10, ground at 1000 + 10·y m below, and a mountain at
/// 500 m over columns 5–9, rows 6–12 (against the sky above row 10, the ground below).
OracleImage handMadeScene() {
  OracleImage o;
  o.width = o.height = 20;
  o.near = 1.0;
  o.distance.assign(400, std::numeric_limits<double>::quiet_NaN());
  o.point.assign(400, glm::dvec3(0.0));
  for (int y = 10; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) o.distance[o.index(x, y)] = 1000.0 + 10.0 * y;
  }
  for (int y = 6; y <= 12; ++y) {
    for (int x = 5; x <= 9; ++x) o.distance[o.index(x, y)] = 500.0;
  }
  return o;
}

TEST(RayMarchOracle, SilhouetteComparisonToleratesOnePixelAndCountsTwo) {
  const OracleImage oracle = handMadeScene();
  const gl::DepthImage same = toDepthImage(oracle);
  const SilhouetteReport exact = compareSilhouettes(oracle, same);
  EXPECT_EQ(exact.coverageMismatches + exact.depthMismatches, 0U) << exact.describe();
  EXPECT_LT(exact.maxRelativeDepthDifference, 1e-6);
  EXPECT_GT(exact.comparedPixels, 100U);

  const auto widened = [&](int columns) {
    gl::DepthImage d = same;
    for (int y = 6; y <= 12; ++y) {
      for (int x = 10; x < 10 + columns; ++x) d.depth[oracle.index(x, y)] = 1.0F / 500.0F;
    }
    return d;
  };
  const SilhouetteReport one = compareSilhouettes(oracle, widened(1));
  EXPECT_EQ(one.coverageMismatches, 4U) << one.describe();
  EXPECT_EQ(one.depthMismatches, 3U) << one.describe();
  EXPECT_EQ(one.misplacedPixels(), 0U) << one.describe();
  // The second column: rows 6–8 against sky and 11–12 against ground are 1.5 px from the
  // silhouette (rows 9 and 10 touch the horizon, a silhouette too).
  const SilhouetteReport two = compareSilhouettes(oracle, widened(2));
  EXPECT_EQ(two.coverageMismatchesAwayFromSilhouette, 3U) << two.describe();
  EXPECT_EQ(two.depthMismatchesAwayFromSilhouette, 2U) << two.describe();
  EXPECT_EQ(two.misplacedPixels(), 5U) << two.describe();
  EXPECT_EQ(two.misplaced.front(), (std::pair{11, 6}));
  EXPECT_EQ(compareSilhouettes(oracle, widened(2), {.radiusPixels = 2}).misplacedPixels(), 0U);

  // The horizon drawn 2 px low: row 11 is away from it but where the mountain's edge is near.
  gl::DepthImage low = same;
  for (int y = 10; y <= 11; ++y) {
    for (int x = 0; x < 20; ++x) {
      if (x < 5 || x > 9) low.depth[oracle.index(x, y)] = 0.0F;
    }
  }
  const SilhouetteReport lowered = compareSilhouettes(oracle, low);
  EXPECT_EQ(lowered.coverageMismatches, 30U) << lowered.describe();
  EXPECT_EQ(lowered.coverageMismatchesAwayFromSilhouette, 13U) << lowered.describe();

  gl::DepthImage small = same;
  small.width = 10;
  EXPECT_THROW((void)compareSilhouettes(oracle, small), InvalidArgument);
}

}  // namespace
}  // namespace regolith::test
