#pragma once
/// \file
/// A latitude/longitude grid over a whole planet or a region of one.

#include <regolith/topo/Body.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>

namespace regolith::topo {

/// How far a planet grid's pixel extent may reach beyond a pole, in pixels (a fraction of
/// its latitude spacing): the rounding of a geotransform. TopoPlanet refuses a grid that
/// reaches further, and store::importRaster() applies the same bound, so that every store
/// an import writes opens.
inline constexpr double kPoleOverhangPixels = 0.01;

/// A lat/lon grid of heights (metres above the body's reference surface, along its
/// normal). The grid's x is longitude and y latitude, both in degrees, with the pixel-centre
/// convention of TopoGrid; latitudes are planetocentric or planetodetic as declared.
///
/// Longitude wraps: a query's longitude may be given in any range (−180…180, 0…360, …).
/// A grid spanning 360° is periodic, so stencils cross the ±180° seam. A grid whose
/// pixel extent reaches a pole has a polar cap: between the outermost row of centres and
/// the pole, heights blend linearly in latitude towards the mean of that row, so the pole
/// has one height whatever the longitude, and bicubic stencils reach across the pole to
/// the row on the opposite meridian. Points outside a regional grid give OutsideGrid;
/// |lat| > 90 and NaN/inf throw InvalidArgument.
///
/// Thread-safety: as TopoDem.
namespace detail {
struct KernelResult;
}

class TopoPlanet {
 public:
  /// Throws InvalidArgument if samples is null or mis-sized, or the grid's pixel extent
  /// leaves −90…90° latitude by more than kPoleOverhangPixels, or it spans more than 360° of
  /// longitude.
  TopoPlanet(TopoGrid grid, Body body, LatitudeType latitudeType,
             std::shared_ptr<const SampleSource> samples);

  /// The mean of one row's valid samples, summed in double in column order (NaN if none):
  /// a pole height. Given a row index of the grid (its first or last row).
  using RowMean = std::function<double(std::size_t row)>;
  /// As above, with the pole rows' means computed by `rowMean` instead of by reading the rows
  /// sample by sample through `samples`: a paged source 2^17 samples wide would page 2·512
  /// patches through its cache (store::Pager::planet() reads them outside the cache, or
  /// computes them). Equal means give a planet equal to the one above. Throws as above, and
  /// InvalidArgument if rowMean is empty.
  TopoPlanet(TopoGrid grid, Body body, LatitudeType latitudeType,
             std::shared_ptr<const SampleSource> samples, RowMean rowMean);

  [[nodiscard]] const TopoGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const Body& body() const noexcept { return body_; }
  [[nodiscard]] LatitudeType latitudeType() const noexcept { return latType_; }
  [[nodiscard]] const SampleSource& samples() const noexcept { return *samples_; }
  [[nodiscard]] bool isGlobalInLongitude() const noexcept { return global_; }
  [[nodiscard]] bool hasNorthCap() const noexcept { return northCap_; }
  [[nodiscard]] bool hasSouthCap() const noexcept { return southCap_; }

  /// Height at a point whose latitude is in the grid's latitude type.
  [[nodiscard]] HeightSample height(const LatLon& ll,
                                    Interpolation interp = Interpolation::Bilinear) const;
  /// height() without its argument checks, for a caller that has made them (a finite
  /// latitude within [-90, 90] and a finite longitude; anything else is undefined): the
  /// composition, which checks each point once for all its datasets. Throws only what
  /// reading a paged source throws.
  [[nodiscard]] HeightSample heightUnchecked(const LatLon& ll,
                                             Interpolation interp = Interpolation::Bilinear) const;
  /// Height and unit normal. The Grid frame is east-north-up at the point.
  [[nodiscard]] SurfaceSample surface(const LatLon& ll,
                                      Interpolation interp = Interpolation::Bilinear,
                                      NormalFrame frame = NormalFrame::Grid) const;

  /// Asks the processor to fetch the samples of the bilinear cell holding a point into its
  /// cache, if they are in memory (resident, or a published block of a paged source): a hint
  /// that reads no sample and never fails, so that a caller about to read several grids at
  /// one point (a composition) overlaps their memory misses. Any point is accepted; one the
  /// grid does not hold, or a pole cap's, is ignored.
  void prefetch(const LatLon& ll) const noexcept;

  /// Batch heights; spans of equal length (status may be empty).
  void heights(std::span<const double> latsDeg, std::span<const double> lonsDeg,
               std::span<double> out, std::span<QueryStatus> status,
               Interpolation interp = Interpolation::Bilinear) const;
  /// Batch heights and normals; status receives the heights' statuses and normalStatus the
  /// normals' (either may be empty; see SurfaceSample).
  void surfaces(std::span<const double> latsDeg, std::span<const double> lonsDeg,
                std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                std::span<QueryStatus> status, Interpolation interp = Interpolation::Bilinear,
                NormalFrame frame = NormalFrame::Grid,
                std::span<QueryStatus> normalStatus = {}) const;

  /// Planetodetic position of a grid latitude/longitude at height h.
  [[nodiscard]] Geodetic toGeodetic(const LatLon& ll, double h) const;
  /// Body-fixed position of a grid latitude/longitude at height h.
  [[nodiscard]] glm::dvec3 toBodyFixed(const LatLon& ll, double h) const;

  /// Mean of the valid samples of the row nearest the north/south pole (NaN if none, or if
  /// the grid does not reach that pole). Computed once, at the first call or the first query
  /// in that pole's cap, not when the planet is made: opening a planet reads no row, whatever
  /// its width. Throws what reading the source throws (a paged source), and tries again at
  /// the next call.
  [[nodiscard]] double northPoleHeight() const { return poleHeight(true); }
  [[nodiscard]] double southPoleHeight() const { return poleHeight(false); }

 private:
  /// The constructors' work; rowMeanGiven: the second's (an empty rowMean is refused), else
  /// the rows are read sample by sample.
  TopoPlanet(TopoGrid grid, Body body, LatitudeType latitudeType,
             std::shared_ptr<const SampleSource> samples, RowMean rowMean, bool rowMeanGiven);

  struct Located;
  /// The pole heights, computed when first asked for and shared by copies (TopoPlanet.cpp).
  struct Poles;
  [[nodiscard]] double poleHeight(bool north) const;
  [[nodiscard]] Located locate(const LatLon& ll) const;
  [[nodiscard]] SurfaceSample surfaceImpl(const LatLon& ll, Interpolation interp, NormalFrame frame,
                                          bool wantNormal) const;
  [[nodiscard]] glm::dvec3 capNormalEnu(const LatLon& ll, Interpolation interp, double h) const;
  /// The bilinear fast path at grid indices (u, v) (height, and gradient when grad): true and
  /// k filled, or false where the generic kernel must answer (TopoPlanet.cpp).
  [[nodiscard]] bool bilinearFast(double u, double v, bool grad, detail::KernelResult& k) const;

  TopoGrid grid_;
  Body body_;
  LatitudeType latType_;
  std::shared_ptr<const SampleSource> samples_;
  bool global_ = false;
  bool northCap_ = false;
  bool southCap_ = false;
  double northPoleV_ = 0.0;  // fractional row of the north pole
  double southPoleV_ = 0.0;
  glm::dvec2 slack_{0.0};  // grid_.edgeSlack()
  std::shared_ptr<Poles> poles_;
  // The bilinear fast path (TopoPlanet.cpp, bilinearFast): the samples when resident, else
  // the paged source's fast paths, as the source gives them; cached.
  const float* resident_ = nullptr;
  const PagedQueries* paged_ = nullptr;
};

}  // namespace regolith::topo
