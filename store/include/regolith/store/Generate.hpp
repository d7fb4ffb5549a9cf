#pragma once
/// \file
/// Procedural terrain, written as stores: a global Mars-like planet, its polar caps and
/// inclined strips at finer resolutions (datasets that overlap it, for composition), and a
/// Victoria-crater-like local DEM. All are deterministic functions of their options (same seed →
/// bit-identical samples, whatever the patch size or the number of threads), are defined at any
/// resolution, and are computed window by window as the writer asks for them, so an output
/// far larger than RAM never exists as a whole grid in memory.
///
/// Determinism holds on one platform (same compiler flags, same libm): the noise and the
/// random draws use only integer hashing and IEEE arithmetic, but sin/cos/pow come from
/// the C library.

#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Projection.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace regolith::store {

// ---- Victoria-like crater --------------------------------------------------------------

/// The analytic shape of a Victoria-like crater on a local plane: x east, y north, metres
/// from the crater's centre; heights in metres relative to the surrounding plains.
///
/// - bowl: inside the rim crest, h = rimHeight − (depth + rimHeight)·(1 − q⁴), q = r/R(θ),
///   flat-floored, steepest (≈ 40°) just inside the crest;
/// - rim and ejecta: outside, h = rimHeight·(R(θ)/r)³;
/// - scalloped wall: the crest radius R(θ) = rimRadius·(1 + bayAmplitude·cos(bays·(θ − bayPhase))
///   + roughAmplitude·cos(roughHarmonic·θ + roughPhase)): `bays` bays (crest farther out)
///   alternating with as many promontories, with a weaker irregularity that adds no extra
///   bay (bays·bayAmplitude > roughHarmonic·roughAmplitude);
/// - dunes: on the floor (q < 0.6, fading out to q = 0.6 from q = 0.3), sinuous ridges
///   duneAmplitude·sin²(π·s/duneWavelength + dunePhase + 0.3·sin(t/40 m)), where s is the
///   distance along the unit vector at azimuth duneAzimuth (radians, counter-clockwise from
///   +x) and t across it: crests repeat every duneWavelength metres along that direction;
/// - plains: a gentle regional slope and undulation, and fine seeded roughness of
///   roughnessAmplitude metres at wavelengths ≥ 20 m.
///
/// The default values are the analytic crater of the topo demo; fromSeed() varies the
/// phases, the dune direction and the roughness. Thread-safety: a value type; height() is
/// const and pure.
struct VictoriaShape {
  double rimRadius = 375.0;  // mean crest radius, m (≈ 750 m across)
  double rimHeight = 8.0;    // crest above the plains, m
  double depth = 70.0;       // floor below the plains, m
  int bays = 7;
  double bayAmplitude = 0.035;  // relative to rimRadius
  double bayPhase = 0.0;        // radians
  int roughHarmonic = 13;
  double roughAmplitude = 0.008;
  double roughPhase = 1.0;
  double duneWavelength = 37.7;  // m
  double duneAmplitude = 2.5;    // m
  double duneAzimuth = 0.0;      // radians from +x
  double dunePhase = 0.0;        // radians
  double regionalSlope = 0.002;  // along +x
  double regionalAmplitude = 1.5;
  double regionalPhaseX = 0.0, regionalPhaseY = 0.0;
  double roughnessAmplitude = 0.0;  // m; fromSeed() sets 0.1
  std::uint64_t roughnessSeed = 0;

  /// A crater with the default dimensions and the seed's phases, dune direction and
  /// roughness.
  [[nodiscard]] static VictoriaShape fromSeed(std::uint64_t seed);

  /// Crest radius at azimuth theta (radians from +x), m.
  [[nodiscard]] double crestRadius(double theta) const noexcept;
  /// Height at (x, y), m.
  [[nodiscard]] double height(double x, double y) const noexcept;
};

struct VictoriaOptions {
  /// Samples per side of the square grid, and their spacing in metres; the grid is centred
  /// on the crater.
  std::size_t size = 1201;
  double spacing = 1.0;
  std::uint64_t seed = 1;
  std::string gridName = "victoria";
  /// Ellipsoid height of the plane's origin (the crater's centre), m.
  double originHeight = -1400.0;
  /// Patch size, pyramid levels, deflate, progress and cancellation of the write.
  WriteOptions write{};
};

/// Places Victoria-like craters on Mars: a local tangent plane on the IAU Mars ellipsoid at
/// 2.05°S, 5.5°W (planetodetic), heading 0 (y north).
class VictoriaGenerator {
 public:
  static constexpr double kOriginLatDeg = -2.05;
  static constexpr double kOriginLonDeg = -5.5;

  /// Throws regolith::InvalidArgument for a size < 2, a spacing that is not finite and > 0,
  /// or an empty grid name.
  explicit VictoriaGenerator(VictoriaOptions options);

  [[nodiscard]] const VictoriaOptions& options() const noexcept { return options_; }
  [[nodiscard]] const VictoriaShape& shape() const noexcept { return shape_; }
  /// The grid as it will be stored (kind Dem, local tangent plane placement).
  [[nodiscard]] GridInfo gridInfo() const;
  /// The samples, computed window by window on demand (nothing is held in memory).
  [[nodiscard]] std::shared_ptr<const topo::SampleSource> samples() const;
  /// Writes the store crash-safely (writeStore). Throws StoreError or InvalidArgument.
  void write(const std::filesystem::path& path) const;

 private:
  VictoriaOptions options_;
  VictoriaShape shape_;
};

// ---- Mars-like planet ------------------------------------------------------------------

struct MarsPlanetOptions {
  /// Latitude samples from pole to pole; the grid has 2·rows longitude samples and a spacing
  /// of 180/rows degrees, sample centres half a spacing from the poles and the ±180° seam.
  std::size_t rows = 720;
  std::uint64_t seed = 1;
  /// The IAU Mars ellipsoid (3,396,190 / 3,376,200 m) instead of the sphere (3,396,190 m).
  /// Latitudes are planetocentric either way; heights are above that reference surface.
  bool ellipsoid = false;
  std::string gridName = "mars";
  /// Multiplies the number of craters in every size band (0: no craters).
  double craterDensity = 1.0;
  /// Threads computing each window, the caller's included (0: write.executor's concurrency + 1,
  /// or hardware concurrency without an executor), on write.executor or on a pool made for
  /// the call. Does not change the samples.
  std::size_t threads = 0;
  WriteOptions write{};
};

/// One crater of a generated planet.
struct GeneratedCrater {
  std::size_t band = 0;               // size band: diameters 1200/2^(band+1) … 1200/2^band km
  double latDeg = 0.0, lonDeg = 0.0;  // centre, planetocentric
  double diameterKm = 0.0;            // rim to rim
  double depth = 0.0, rim = 0.0;      // floor below and rim above the surroundings, m
};

/// A global Mars-like planet: a crustal dichotomy (low northern plains, high southern
/// highlands, along a seeded tilted boundary), a Tharsis-like bulge with three shield
/// volcanoes, fractal relief (3D gradient noise, fBm) and craters with a power-law size
/// distribution (cumulative N(>D) ∝ D⁻², diameters from 1200 km down to about 3 samples;
/// a third as many on the younger northern lowlands) that have a bowl (flat floor and
/// central peak when large), a raised rim and ejecta.
///
/// Heights are a function of the body-fixed unit vector of each point, so they are
/// continuous across the ±180° seam and at both poles. Octaves and crater bands finer than
/// the grid resolves are left out; coarser ones are the same at every resolution, so a
/// finer planet refines a coarser one of the same seed.
///
/// Thread-safety: immutable after construction; all members may be called concurrently.
class MarsPlanetGenerator {
 public:
  /// Throws regolith::InvalidArgument for rows < 2, a negative or non-finite crater
  /// density, or an empty grid name.
  explicit MarsPlanetGenerator(MarsPlanetOptions options);

  [[nodiscard]] const MarsPlanetOptions& options() const noexcept;
  [[nodiscard]] GridInfo gridInfo() const;
  /// fBm octaves and crater size bands used at this resolution.
  [[nodiscard]] std::size_t octaves() const noexcept;
  [[nodiscard]] std::size_t craterBands() const noexcept;
  /// Every crater of the bands in use, band by band (a band has 4× the craters of the one
  /// before it; for inspection and tests, not needed to write the store).
  [[nodiscard]] std::vector<GeneratedCrater> craters() const;
  /// Height in metres at planetocentric latitude and east longitude (degrees; any
  /// longitude). At a sample centre it equals the stored sample (before the float cast).
  [[nodiscard]] double height(double latDeg, double lonDeg) const;
  /// Heights in metres at body-fixed unit vectors (directions from the body's centre to
  /// surface points), for the samples of a DEM in any placement. `units` holds rows × cols
  /// points row-major and `out` receives as many heights (a caller bug otherwise). Points
  /// that are neighbours in the grid should be near each other on the body, which keeps the
  /// crater search local; any set of points gives the same heights. At the unit vector
  /// (cos φ cos λ, cos φ sin λ, sin φ), with λ in [−180°, 180°) and both in radians as
  /// degrees · (π/180), it equals height(φ, λ) to the bit. Runs on options().write.executor with
  /// options().threads threads, as write().
  void heightsAt(std::span<const glm::dvec3> units, std::size_t cols, std::span<double> out) const;
  /// The samples, computed window by window on demand.
  [[nodiscard]] std::shared_ptr<const topo::SampleSource> samples() const;
  /// Writes the store crash-safely (writeStore). Throws StoreError or InvalidArgument.
  void write(const std::filesystem::path& path) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

// ---- Polar caps and inclined strips of the planet ------------------------------------------

/// The planet a cap or a strip refines: MarsPlanetGenerator's seed, body and crater density.
/// A cap or strip agrees with a planet made with the same three.
struct PlanetOf {
  std::uint64_t seed = 1;
  bool ellipsoid = false;
  double craterDensity = 1.0;
};

struct PolarCapOptions {
  using Pole = topo::PolarStereographic::Pole;
  Pole pole = Pole::North;
  /// The cap holds every point with |planetocentric latitude| ≥ this, degrees in (0, 90).
  double minLatitudeDeg = 75.0;
  /// Sample spacing in map metres (true at the pole; at 75° a sample spans 0.98 of it).
  double spacing = 1000.0;
  PlanetOf planet{};
  /// Depth of the layered deposits' spiral troughs, m (0: no deposits).
  double troughDepth = 500.0;
  /// Empty: "north_cap" or "south_cap".
  std::string gridName;
  /// Threads computing each window (as MarsPlanetOptions::threads).
  std::size_t threads = 0;
  WriteOptions write{};
};

/// A polar cap of the generated Mars: a square DEM in polar stereographic map metres (true
/// scale at the pole, central meridian 0°, no false easting or northing, on the planet's
/// body) centred on the pole, whose outermost sample centres lie at or beyond the circle of
/// the minimum latitude (it holds that circle). An odd number of samples per side puts a
/// sample on the pole.
///
/// Heights: the planet's (MarsPlanetGenerator::heightsAt() at the unit vector under each
/// sample) with the octaves and crater bands of a planet grid of the cap's spacing (rows =
/// ⌈π·a / spacing⌉, a the equatorial radius, planet()): the same function as the global
/// grid, with the detail that a coarser grid leaves out. Plus, optionally, polar layered
/// deposits: spiral troughs (depositHeight()) that a grid coarser than about 10 km does not
/// resolve, fading out at 80 % of the cap's angular radius so that the cap's border agrees
/// with the planet.
///
/// Thread-safety: immutable after construction; all members may be called concurrently.
class PolarCapGenerator {
 public:
  /// Trough spacing along a radius, and the number of interleaved spiral arms.
  static constexpr double kTroughSpacing = 60000.0;  // m
  static constexpr int kTroughArms = 3;

  /// Throws regolith::InvalidArgument for a minimum latitude outside (0, 90), a spacing that
  /// is not finite and > 0 (or so small that the grid exceeds kMaxGridSide), a trough depth
  /// that is not finite and ≥ 0, or a bad crater density.
  explicit PolarCapGenerator(PolarCapOptions options);

  [[nodiscard]] const PolarCapOptions& options() const noexcept;
  /// The grid as it will be stored (kind Dem, polar stereographic placement).
  [[nodiscard]] GridInfo gridInfo() const;
  [[nodiscard]] const topo::Placement& placement() const noexcept;
  /// The planet at the cap's resolution, whose heights the cap stores.
  [[nodiscard]] const MarsPlanetGenerator& planet() const noexcept;
  /// Angular distance from the pole at which the deposits end, degrees: 0.8 (90° − the
  /// minimum latitude).
  [[nodiscard]] double depositReachDeg() const noexcept;
  /// The deposits' height at a body-fixed unit vector, m: in [−troughDepth, 0], 0 beyond
  /// depositReachDeg() from the pole, within 10 % of it (no pinch at the pole) and without
  /// troughs. Troughs follow kTroughArms interleaved spirals kTroughSpacing apart along a
  /// radius, wandering and varying in depth (40–100 %) with the seed, cos⁶-shaped across
  /// (about a fifth of the spacing wide), faded in from 10 % to 25 % of the reach and out
  /// over its last quarter.
  [[nodiscard]] double depositHeight(const glm::dvec3& unit) const noexcept;
  [[nodiscard]] std::shared_ptr<const topo::SampleSource> samples() const;
  /// Writes the store crash-safely (writeStore), with height statistics (format 1.3) whatever
  /// options().write says. Throws StoreError or InvalidArgument.
  void write(const std::filesystem::path& path) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

struct StripOptions {
  /// Centre of the strip: planetocentric latitude and east longitude, degrees.
  double centreLatDeg = 0.0, centreLonDeg = 0.0;
  /// The orbit's inclination to the equator, degrees in [0, 180] (> 90: retrograde). The
  /// centre latitude must be within the orbit's reach, |φ| ≤ min(i, 180° − i), and < 89°.
  double inclinationDeg = 60.0;
  /// A southbound pass instead of a northbound one.
  bool descending = false;
  /// Along and across the track, metres: the outermost sample centres lie at ±length/2 and
  /// ±width/2 (rounded up to whole spacings). length ≤ π·a (half a great circle).
  double length = 300000.0, width = 10000.0;
  /// Sample spacing, metres (true along the centre line).
  double spacing = 50.0;
  /// How far the strip's edges wander inwards, as a fraction of half the width, in [0, 0.9]:
  /// samples beyond the wandering sides and ends are missing (NaN). 0: all samples valid.
  double raggedness = 0.25;
  PlanetOf planet{};
  std::string gridName = "strip";
  /// Threads computing each window (as MarsPlanetOptions::threads).
  std::size_t threads = 0;
  WriteOptions write{};
};

/// A long, narrow DEM along a satellite's ground track (Kooima's LROC example): a rectangle
/// in an oblique Mercator projection (PROJ `omerc`, Hotine variant B, scale 1 on the centre
/// line) whose centre line is the great circle of an orbit of the given inclination through
/// the strip's centre, on the planet's body (the body's rotation during the pass is
/// neglected; on the ellipsoid the line is the projection's, close to the orbit plane's
/// trace). Grid x runs along the track in the direction of flight, y to its left; the
/// store records the CRS as WKT2 (placement kind Projected).
///
/// Heights: the planet's at the strip's resolution (as PolarCapGenerator: rows =
/// ⌈π·a / spacing⌉, planet()), missing beyond the ragged edges (covers()).
///
/// Thread-safety: immutable after construction; all members may be called concurrently.
class StripGenerator {
 public:
  /// Throws regolith::InvalidArgument for a non-finite option, an inclination outside
  /// [0, 180], a centre latitude the orbit does not reach (or ≥ 89°), a length, width or
  /// spacing that is not > 0 (or a length beyond π·a, or a grid beyond kMaxGridSide), a
  /// raggedness outside [0, 0.9], a bad crater density or an empty grid name.
  explicit StripGenerator(StripOptions options);

  [[nodiscard]] const StripOptions& options() const noexcept;
  [[nodiscard]] GridInfo gridInfo() const;
  [[nodiscard]] const topo::Placement& placement() const noexcept;
  [[nodiscard]] const MarsPlanetGenerator& planet() const noexcept;
  /// Direction of flight at the centre, degrees clockwise from north, in (−180, 180].
  [[nodiscard]] double azimuthDeg() const noexcept;
  /// The CRS as a PROJ string (what the store's WKT2 was made from).
  [[nodiscard]] const std::string& projString() const noexcept;
  /// Whether grid point (x, y) (map metres) lies within the ragged edges: always where
  /// |y| ≤ (1 − raggedness)·W/2 and |x| ≤ L/2 − raggedness·W/2 (W, L between the outermost
  /// sample centres), never where |y| > W/2 or |x| > L/2.
  [[nodiscard]] bool covers(double x, double y) const noexcept;
  [[nodiscard]] std::shared_ptr<const topo::SampleSource> samples() const;
  /// Writes the store crash-safely (writeStore), with height statistics (format 1.3) whatever
  /// options().write says. Throws StoreError or InvalidArgument.
  void write(const std::filesystem::path& path) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace regolith::store
