#pragma once
/// \file
/// One dataset of a body's catalogue: a height (or colour) grid in its own placement, with
/// the per-point terms of the composition rule (docs/composition.md).

#include <regolith/topo/Body.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/Pyramid.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::compose {

/// What a dataset supplies: heights, an albedo map or an overlay (colour maps are grids of
/// one channel each; they are composed by the renderer's accumulation, not by height
/// queries).
enum class Role : std::uint8_t { Height, Albedo, Overlay };

/// Lower-case name of a role ("height", "albedo", "overlay"), as catalogue files spell it.
[[nodiscard]] const char* roleName(Role role) noexcept;

/// How a dataset enters the composition. Defaults compose like every other dataset.
struct DatasetOptions {
  /// Shown in messages, `info` and the demo's summary; need not be unique.
  std::string name;
  Role role = Role::Height;
  /// Higher tiers are composited over lower ones (docs/composition.md "Priority tiers").
  int priority = 0;
  /// Width of the border feather, in metres on the surface: coverage rises smoothly
  /// (smoothstep) from 0 at the grid's pixel-extent edge to 1 this far inside. 0: a hard
  /// edge. Grids that cover a whole turn of longitude have no longitude edge, and a planet
  /// grid that reaches a pole has no edge there.
  double featherMetres = 0.0;
  /// Optional coverage mask: one value in [0, 1] per sample of level 0 (same size), read
  /// bilinearly; NaN counts as 0. For non-rectangular coverage and feathered data borders
  /// (featherMask() makes one from the nodata border).
  std::shared_ptr<const topo::SampleSource> mask;
  /// Added to every height of the dataset, metres (in its own convention: along its plane's
  /// normal for a tangent-plane DEM): aligns products on different vertical datums.
  double heightOffset = 0.0;
  /// Lowest and highest height of the data, metres (for the catalogue's bounding boxes),
  /// before heightOffset.
  /// Unset: taken from the coarsest level with at most 2^20 samples, widened by a quarter of
  /// its span and 100 m on each side (a coarse level averages extremes away).
  std::optional<std::array<double, 2>> heightRange;
};

/// A dataset's contribution at one point (Dataset::evaluate).
struct Contribution {
  double height = std::numeric_limits<double>::quiet_NaN();  ///< above the body's surface
  topo::QueryStatus status = topo::QueryStatus::OutsideGrid;
  /// Coverage c ∈ [0, 1] (border feather × mask); 0 where the status is not Ok.
  double coverage = 0.0;
  /// Projection quality q ∈ [kMinQuality, 1] (Kooima §4.1 from the placement's own scale
  /// factors: docs/composition.md).
  double quality = 0.0;
  /// Gradient of the height, ∂h/∂east and ∂h/∂north (metres per metre), in the
  /// east-north-up frame of the query point; NaN unless `normalStatus` is Ok.
  glm::dvec2 slope{std::numeric_limits<double>::quiet_NaN()};
  topo::QueryStatus normalStatus = topo::QueryStatus::OutsideGrid;
};

/// The lowest projection quality a dataset is given where it has data, so that a lone
/// dataset at its worst (an equirectangular grid at a pole) still has a weight.
inline constexpr double kMinQuality = 1e-3;

/// A dataset: a grid pyramid (level 0 the finest) on a body, either a latitude/longitude
/// planet grid or a planar DEM with a placement, and its DatasetOptions. Immutable and
/// thread-safe; its queries are as thread-safe as its sample sources (paged ones are).
///
/// Every query takes a planetodetic latitude and a longitude (degrees) on the body and
/// answers a height above the body's reference surface along its normal, whatever the
/// dataset's own latitude type and height convention: a tangent-plane DEM, whose heights are
/// along its plane's normal, is intersected with the normal line of the query point.
class Dataset {
 public:
  /// A planet grid: `pyramid.planetBody` must be set. Throws InvalidArgument for an empty
  /// pyramid, a level that is not a valid TopoPlanet, a mask whose size is not level 0's,
  /// negative or non-finite feather width, or a height range that is not finite and
  /// ordered.
  static std::shared_ptr<const Dataset> planet(const topo::GridPyramid& pyramid,
                                               DatasetOptions options);
  /// A planar DEM placed on its body (the pyramid's levels are planar). Same checks.
  static std::shared_ptr<const Dataset> dem(const topo::GridPyramid& pyramid,
                                            const topo::Placement& placement,
                                            DatasetOptions options);

  [[nodiscard]] const DatasetOptions& options() const noexcept { return options_; }
  [[nodiscard]] const std::string& name() const noexcept { return options_.name; }
  [[nodiscard]] const topo::Body& body() const noexcept { return body_; }
  [[nodiscard]] bool isPlanet() const noexcept { return !placement_.has_value(); }
  /// No feather and no mask: the coverage is 1 wherever the dataset answers.
  [[nodiscard]] bool unfeathered() const noexcept {
    return !options_.mask && !(options_.featherMetres > 0.0);
  }
  [[nodiscard]] const std::optional<topo::Placement>& placement() const noexcept {
    return placement_;
  }
  /// Levels used: the pyramid's, up to the first planet level whose pixel extent reaches
  /// past a pole (coarse levels of a grid with an odd number of rows do).
  [[nodiscard]] std::size_t levelCount() const noexcept { return levels_.size(); }
  [[nodiscard]] const topo::PyramidLevel& level(std::size_t i) const { return levels_.at(i).level; }
  /// The level-0 grid's latitude type (planet grids; planetodetic for DEMs).
  [[nodiscard]] topo::LatitudeType latitudeType() const noexcept { return latType_; }

  /// Nominal ground sample distance of level 0, metres: the pixel's size where the
  /// projection has true scale (a DEM: √(dx·dy); a planet grid: the body's mean meridian
  /// arc of one latitude step). The resolution term of the weight uses it.
  [[nodiscard]] double groundSpacing() const noexcept { return groundSpacing_; }
  /// Height range used for bounds, metres {lowest, highest}.
  [[nodiscard]] const std::array<double, 2>& heightRange() const noexcept { return heightRange_; }
  /// Lowest and highest height above the body's ellipsoid, along its normal, that the
  /// dataset's surface reaches, metres: heightRange() for a planet grid or map projection,
  /// and wider for a tangent-plane DEM, whose plane rises above the ellipsoid away from its
  /// origin (by about d²/2R at a distance d). Padded like bounds().
  [[nodiscard]] const std::array<double, 2>& ellipsoidHeightRange() const noexcept {
    return ellipsoidHeights_;
  }
  /// Body-fixed axis-aligned box holding every point of the dataset from its lowest to its
  /// highest height: {min, max}, metres.
  [[nodiscard]] const std::array<glm::dvec3, 2>& bounds() const noexcept { return bounds_; }

  /// Height, coverage, quality and (if wantSlope) the height's gradient at a planetodetic
  /// latitude and longitude, from level `level` (clamped to the coarsest). Never throws for
  /// a finite point: a point the dataset does not have gets its status and coverage 0.
  /// Requires finite coordinates with |lat| ≤ 90 (a planet grid answers OutsideGrid for a
  /// non-finite one).
  /// `wantQuality` false leaves quality at 0: a composition with one contributor needs no
  /// weight, and the quality costs as much as the height.
  [[nodiscard]] Contribution evaluate(double latDeg, double lonDeg, std::size_t level = 0,
                                      bool wantSlope = false, bool wantQuality = true) const;
  /// evaluate() written into `out`, for callers that keep contributions in their own storage:
  /// a Contribution returned and then copied is read back in wider pieces than it was
  /// written, which the processor cannot forward from its store buffer (a stall of some
  /// ten cycles per piece on the composition's path).
  void evaluateInto(double latDeg, double lonDeg, std::size_t level, bool wantSlope,
                    bool wantQuality, Contribution& out) const;
  /// The height evaluate() gives at a point where it answers Ok with coverage > 0, else
  /// NaN (an answered height is a number: a NaN sample answers Nodata): a composition's
  /// query where the dataset is the only candidate. A planet grid without feather or mask
  /// (coverage 1 wherever it answers) skips the contribution's other fields and, the point
  /// being checked, the grid's argument checks. A plain double in a register (a height
  /// written through a reference, or an optional's flag byte read back with the height,
  /// stalled the query's critical path). Requires finite coordinates with |lat| <= 90. With
  /// `full`, only where the coverage is exactly 1 (a dataset that hides every tier below it).
  [[nodiscard]] double soleHeightOrNan(double latDeg, double lonDeg, std::size_t level,
                                       bool full = false) const;
  /// A height and its coverage, as evaluate() gives them where it answers Ok with coverage
  /// > 0; coverage 0 (and a NaN height) elsewhere.
  struct CoveredHeight {
    double height;
    double coverage;
  };
  /// evaluate()'s height and coverage alone, in registers: a feathered or masked planet
  /// grid's coverage comes from the point's position before its samples are read (a DEM
  /// takes evaluateInto()). Requires finite coordinates with |lat| <= 90.
  [[nodiscard]] CoveredHeight coveredHeight(double latDeg, double lonDeg, std::size_t level) const;
  /// Asks the processor to fetch the samples evaluate() would read at a point of level
  /// `level` into its cache (topo::TopoPlanet::prefetch()): a hint, never failing, so that a
  /// composition overlaps the memory misses of its datasets. Planet grids only (a DEM's
  /// placement costs a projection to locate the point, more than the miss it would hide).
  void prefetch(double latDeg, double lonDeg, std::size_t level = 0) const noexcept;
  /// True if both are planet grids whose quality() is one function of the latitude: the
  /// same body radii and level-0 pixel shape (spacing in longitude over spacing in
  /// latitude), whatever the pixel's size; quality() at a point inside both is then equal,
  /// bit for bit.
  [[nodiscard]] bool samePlanetQuality(const Dataset& other) const noexcept;
  /// The projection quality alone at a point of the pixel extent (kMinQuality outside it).
  [[nodiscard]] double quality(double latDeg, double lonDeg) const;
  /// quality() at a point known to lie in the pixel extent (the dataset answered there): a
  /// planet grid's without locating the point again.
  [[nodiscard]] double qualityInside(double latDeg, double lonDeg) const;
  /// Coverage and quality only (no height read): the weight's spatial terms {c, q}, for
  /// their gradients. Coverage is 0 outside the grid or where the mask is 0.
  [[nodiscard]] std::array<double, 2> coverageQuality(double latDeg, double lonDeg) const;
  /// True if the point lies in the dataset's pixel extent (no sample is read).
  [[nodiscard]] bool contains(double latDeg, double lonDeg) const;

  /// The level whose spacing best serves a target ground spacing of `metres`: the coarsest
  /// whose ground spacing is at most `metres` (0 if even level 0 is coarser).
  [[nodiscard]] std::size_t levelFor(double metres) const noexcept;

 private:
  struct Level {
    topo::PyramidLevel level;
    std::optional<topo::TopoDem> dem;
    std::optional<topo::TopoPlanet> planet;
  };
  struct GridPoint {
    double x = 0.0, y = 0.0;  ///< level-0 grid coordinates (planets: lon, lat in degrees)
    bool inside = false;
    bool mapped = false;
    bool farSide = false;  ///< a tangent plane's (x, y) of a point on the body's far side
  };
  Dataset(const topo::GridPyramid& pyramid, std::optional<topo::Placement> placement,
          DatasetOptions options);
  [[nodiscard]] GridPoint locate(double latDeg, double lonDeg) const;
  /// locate() for a planet grid (from frame_).
  [[nodiscard]] GridPoint locatePlanet(double latDeg, double lonDeg) const noexcept;
  [[nodiscard]] double coverageAt(const GridPoint& g, double latDeg) const;
  void buildFeatherInterior();
  [[nodiscard]] double qualityAt(const GridPoint& g) const;
  [[nodiscard]] double planetQuality(double latDeg) const;
  void buildQualityLattice();
  void computeBounds();

  DatasetOptions options_;
  topo::Body body_;
  std::optional<topo::Placement> placement_;
  topo::LatitudeType latType_ = topo::LatitudeType::Planetodetic;
  std::vector<Level> levels_;
  bool globalLon_ = false, northPole_ = false, southPole_ = false;
  /// A planet grid's locate() constants, computed once (the same bits as computing them at
  /// each query): its longitude centre, the turn around it, its extent (latitudes with
  /// locate()'s 1e-9° tolerance), and whether its latitude type is the query's.
  struct PlanetFrame {
    double centre = 0.0, turnLow = 0.0, turnHigh = 0.0;
    double west = 0.0, east = 0.0, south = 0.0, north = 0.0;
    bool sameLatitude = true;
  } frame_;
  /// soleHeightOrNan()'s shortcut applies: a planet grid without feather or mask.
  bool plainPlanet_ = false;
  double groundSpacing_ = 0.0;
  /// A feathered planet grid's interior, in level-0 grid coordinates (lon, lat): where its
  /// feather is exactly 1 (buildFeatherInterior()). Empty otherwise.
  struct FeatherInterior {
    double west = 1.0, east = 0.0, south = 1.0, north = 0.0;
  } featherInterior_;
  double planetAspect_ = 0.0;   // a planet grid's level-0 spacing in longitude / in latitude
  double planetEquator_ = 0.0;  // the body's radii on the equator, a·m₀ (m²)
  std::array<double, 2> heightRange_{0.0, 0.0};
  std::array<double, 2> ellipsoidHeights_{0.0, 0.0};
  std::array<glm::dvec3, 2> bounds_{};
  /// A DEM's quality on a kQualityLattice² lattice over level 0's pixel extent (row-major,
  /// row 0 north), read bilinearly: the placement's scale factors vary slowly, and
  /// evaluating the Jacobian at each query would cost six projections. Planet grids compute
  /// theirs exactly (two trigonometric calls).
  std::vector<double> quality_;
  /// Level 0's grid again, inside the dataset (a planet grid): soleHeightOrNan()'s query reads
  /// its fields one dependent load sooner than through levels_. Last, so that the members
  /// the general path reads keep their cache lines.
  std::optional<topo::TopoPlanet> planet0_;
};

/// Lattice points per side of Dataset's quality table.
inline constexpr std::size_t kQualityLattice = 65;

/// Kooima's projection quality (thesis §4.1), α = 1 − |log k| / log n, clamped to
/// [kMinQuality, 1], for a pixel whose two sides measure `groundX` and `groundY` metres on
/// the surface where its nominal (true-scale) size is `nominal`: k is the larger of the
/// anisotropy groundX/groundY and the scale distortion √(groundX·groundY)/nominal (each
/// taken as its log's magnitude). `n` > 1 is the quality coefficient.
[[nodiscard]] double projectionQuality(double groundX, double groundY, double nominal,
                                       double n) noexcept;

/// The quality coefficient n that Dataset uses (docs/composition.md): an 8:1 anisotropy or
/// scale distortion has quality 0 (then kMinQuality).
inline constexpr double kQualityN = 8.0;

/// A coverage mask's value at fractional sample index (u, v) = (col, row), read bilinearly
/// and clamped to the grid; NaN samples count as 0 and values are clamped to [0, 1]: the
/// mask term of Dataset's coverage (and of the GPU's, render::SurfaceAccumulator).
[[nodiscard]] double maskValue(const topo::SampleSource& mask, double u, double v);

/// A coverage mask for a grid from its missing samples: 0 on missing samples, rising with
/// the distance (in samples, an exact Euclidean distance transform) from the nearest missing
/// sample or grid edge to 1 at `widthSamples`, through smoothstep. In memory: rows × cols
/// floats. Throws InvalidArgument for widthSamples ≤ 0 or a grid of more than 2^28 samples.
[[nodiscard]] std::shared_ptr<const topo::SampleSource> featherMask(
    const topo::TopoGrid& grid, const topo::SampleSource& samples, double widthSamples,
    bool includeGridEdge = false);

}  // namespace regolith::compose
