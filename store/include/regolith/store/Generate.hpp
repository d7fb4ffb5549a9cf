#pragma once
/// \file
/// Procedural terrain, written as stores: a global Mars-like planet and a Victoria-crater-like
/// local DEM. Both are deterministic functions of their options (same seed → bit-identical
/// samples, whatever the patch size or the number of threads), are defined at any
/// resolution, and are computed window by window as the writer asks for them, so an output
/// far larger than RAM never exists as a whole grid in memory.
///
/// Determinism holds on one platform (same compiler flags, same libm): the noise and the
/// random draws use only integer hashing and IEEE arithmetic, but sin/cos/pow come from
/// the C library.

#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
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
  /// The samples, computed window by window on demand.
  [[nodiscard]] std::shared_ptr<const topo::SampleSource> samples() const;
  /// Writes the store crash-safely (writeStore). Throws StoreError or InvalidArgument.
  void write(const std::filesystem::path& path) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace regolith::store
