#pragma once
// A test-only oracle for the far field (issue 19): the image of a height field over a body,
// made by brute-force ray-marching in double on the CPU, and the comparison of a GPU depth
// image against it (silhouettes within 1 px, depths away from silhouettes).
//
// Frame: body-fixed metres, body centre at the origin (topo::Body), as clod::Camera's
// position, target and up. Heights: metres above the body along its normal (planetodetic).
// Thread-safety: rayMarch() calls surface.height from several threads at once (it must be
// safe to call concurrently); everything else is pure.

#include <regolith/clod/Camera.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/gl/Image.hpp>
#include <regolith/topo/Body.hpp>

#include <glm/vec3.hpp>

#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace regolith::test {

/// A height field over a body. The surface is the set of points p whose planetodetic height
/// (Body::toGeodetic(p).height) equals height(lat, lon) at p's own latitude/longitude.
struct OracleSurface {
  topo::Body body;  ///< sphere or biaxial ellipsoid
  /// Metres above the body along the normal at planetodetic (latDeg, lonDeg). Called with
  /// whatever toGeodetic returns: longitude in (−180, 180], 0 at the poles. Must be thread-safe.
  std::function<double(double latDeg, double lonDeg)> height;
  /// Bounds of `height` everywhere, metres. The oracle relies on them (the shell it marches
  /// in, the sphere-tracing step above maxHeight) and throws InvalidArgument if `height`
  /// returns a value outside them.
  double minHeight = 0.0;
  double maxHeight = 0.0;
};

/// How the oracle marches. Each pixel ray is marched only inside the sphere of radius
/// equatorialRadius + maxHeight (outside it every point lies above maxHeight), from the camera
/// if it is inside, else from the ray's entry, found analytically. The step rule (the bound
/// that keeps a feature from being skipped), with f = altitude − height along the ray:
/// - above maxHeight (geodetic altitude a > maxHeight) the step is
///   max(maxStepMetres, aboveBoundFraction·(a − maxHeight)). No surface point lies closer
///   than a − maxHeight (the points at altitude ≤ maxHeight form the body grown by maxHeight,
///   a convex set, and a is p's distance to the body), so this skips nothing while a − maxHeight
///   is the larger term; fraction < 1 leaves a margin for rounding.
/// - below the sphere of radius polarRadius + minHeight every point is below the surface; the
///   march ends in the middle of the ray's chord through it.
/// - in the band [minHeight, maxHeight] the step is maxStepMetres: a feature narrower than
///   that along the ray may be missed. Choose it well below the height field's smallest
///   feature: a grid's spacing or less (the tests use 200 m for a Gaussian of σ = 20 km).
/// - a crossing (f > 0 then f ≤ 0) is bisected until its bracket is below toleranceMetres,
///   or below relativeTolerance × the distance if that is smaller (a hit millimetres from the
///   camera), or the doubles can split it no further.
/// - a ray that grazes the surface between samples (a local minimum of f at a sample, below
///   grazeRefineMetres) is refined by golden-section search for the minimum of f over the
///   two steps around it; if that minimum is ≤ 0 the ray hits. Tangent rays at the horizon
///   and over peaks are found this way, not only when a sample happens to fall below.
struct RayMarchOptions {
  double aboveBoundFraction = 0.9;  ///< in (0, 1]
  double toleranceMetres = 1e-3;    ///< bisection bracket along the ray, metres
  double relativeTolerance = 1e-9;  ///< … or this fraction of the distance, if smaller
  double grazeRefineMetres = 0.0;   ///< 0: maxStepMetres
  /// Rows run in parallel (core::parallelFor) on `executor`, or on a core::ThreadPool made
  /// for the call when it is null, with `threads` counting the calling thread (≥ 1).
  core::Executor* executor = nullptr;
  unsigned threads = 2;
};

/// The oracle's image, row-major, row 0 at the top (as clod::Camera::ray and gl::DepthImage).
struct OracleImage {
  int width = 0, height = 0;
  double near = 0.1;  ///< the camera's near plane, metres (to read a GPU depth image)
  /// Distance along the camera's view axis to the first hit (as Camera::viewDistance
  /// measures: near / depth), metres; NaN where the ray sees sky.
  std::vector<double> distance;
  /// The body-fixed hit point, metres; NaN where the ray sees sky.
  std::vector<glm::dvec3> point;

  [[nodiscard]] std::size_t index(int x, int y) const noexcept {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(x);
  }
  [[nodiscard]] bool hit(int x, int y) const noexcept { return !std::isnan(distance[index(x, y)]); }
  [[nodiscard]] double distanceAt(int x, int y) const noexcept { return distance[index(x, y)]; }
  /// How many pixels see the body.
  [[nodiscard]] std::size_t hitCount() const noexcept;
  /// The topmost row of column x that sees the body, or −1 if none does.
  [[nodiscard]] int topmostHit(int x) const noexcept;
};

/// Ray-marches every pixel ray of `camera` (camera.ray(x + 0.5, y + 0.5)) against `surface`
/// with steps of at most maxStepMetres in the band of heights (see RayMarchOptions).
/// The rays start at the camera: no near-plane clipping. Throws InvalidArgument if
/// maxStepMetres is not > 0, if the camera is on or below the surface, or if
/// surface.height leaves [minHeight, maxHeight].
[[nodiscard]] OracleImage rayMarch(const clod::Camera& camera, const OracleSurface& surface,
                                   double maxStepMetres, const RayMarchOptions& options = {});

/// One ray: the distance along the unit direction `direction` from `origin` (body-fixed
/// metres) to its first crossing of the surface, or nullopt if it sees sky. As rayMarch().
[[nodiscard]] std::optional<double> marchRay(const glm::dvec3& origin, const glm::dvec3& direction,
                                             const OracleSurface& surface, double maxStepMetres,
                                             const RayMarchOptions& options = {});

/// The oracle as a GPU would store it: reversed-Z float depth near / distance, 0 for sky.
[[nodiscard]] gl::DepthImage toDepthImage(const OracleImage& image);

/// A picture of the oracle's depth for people to look at: grey from white (nearest hit) to
/// dark grey (farthest), on a log scale of distance; sky dark blue.
[[nodiscard]] gl::RgbaImage depthPicture(const OracleImage& image);

/// How compareSilhouettes() draws the oracle's silhouettes.
struct SilhouetteOptions {
  /// Two neighbouring oracle pixels that both see the body lie on a silhouette if their
  /// distances differ by more than this ratio of the nearer (a mountain in front of farther
  /// terrain). A GPU pixel whose distance differs from the oracle's by more than this ratio is
  /// a depth mismatch.
  double discontinuityRatio = 0.05;
  /// A mismatch within this many pixels of the oracle's silhouette is tolerated: 1 means the
  /// pixel touches (8-neighbourhood) an oracle pixel on the other side of a silhouette.
  int radiusPixels = 1;
};

/// A GPU depth image against the oracle.
struct SilhouetteReport {
  /// Pixels where exactly one of the two sees the body.
  std::size_t coverageMismatches = 0;
  /// Of those, pixels farther than radiusPixels from the oracle's silhouette.
  std::size_t coverageMismatchesAwayFromSilhouette = 0;
  /// Pixels both see whose distances differ by more than discontinuityRatio (one sees a
  /// mountain, the other the terrain behind it).
  std::size_t depthMismatches = 0;
  /// Of those, pixels farther than radiusPixels from the oracle's silhouette.
  std::size_t depthMismatchesAwayFromSilhouette = 0;
  /// Pixels both see, away from the oracle's silhouettes, over which the statistics below run.
  std::size_t comparedPixels = 0;
  /// |gpu − oracle| / oracle distance over comparedPixels; NaN if there are none.
  double medianRelativeDepthDifference = std::numeric_limits<double>::quiet_NaN();
  double maxRelativeDepthDifference = std::numeric_limits<double>::quiet_NaN();
  /// The first (up to 16) misplaced pixels, (x, y), for messages.
  std::vector<std::pair<int, int>> misplaced;

  /// Silhouette pixels more than radiusPixels off: what a test asserts is 0.
  [[nodiscard]] std::size_t misplacedPixels() const noexcept {
    return coverageMismatchesAwayFromSilhouette + depthMismatchesAwayFromSilhouette;
  }
  /// One line with every figure and the first misplaced pixels.
  [[nodiscard]] std::string describe() const;
};

/// Compares a GPU depth image (reversed Z: depth = oracle.near / distance, 0 = nothing drawn)
/// with the oracle, pixel by pixel. Throws InvalidArgument if the sizes differ.
[[nodiscard]] SilhouetteReport compareSilhouettes(const OracleImage& oracle,
                                                  const gl::DepthImage& gpu,
                                                  const SilhouetteOptions& options = {});

}  // namespace regolith::test
