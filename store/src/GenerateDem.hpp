#pragma once
// DEMs whose heights are the generated planet's (Generate.hpp: polar caps, strips): the unit
// vector under each sample, and a window-by-window sample source over any placement.

#include <regolith/store/Generate.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/topo/Placement.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <string>

namespace regolith::store::gen {

/// The body-fixed unit vector of the reference-surface point under grid point (x, y): from
/// its planetocentric latitude and its longitude wrapped into [−180°, 180°), with the same
/// arithmetic as the planet's lattice, so MarsPlanetGenerator::heightsAt() there equals
/// height() at that latitude and longitude to the bit.
[[nodiscard]] glm::dvec3 unitUnder(const topo::Placement& placement, double x, double y);

/// The rows of a planet grid whose resolution matches a DEM spacing of `spacing` metres on a
/// body of equatorial radius `radius`: ⌈π·radius / spacing⌉. Throws InvalidArgument naming
/// `operation` if that exceeds 2^31 (a spacing below about 5 mm on Mars).
[[nodiscard]] std::size_t planetRowsFor(double spacing, double radius,
                                        const std::string& operation);

/// The stored description of a generated DEM: grid `name` of kind Dem with `grid`'s
/// geometry, on `placement`'s body (planetodetic), no nodata value.
[[nodiscard]] GridInfo demGridInfo(const std::string& name, const topo::TopoGrid& grid,
                                   const topo::Placement& placement);

/// A planet at `rows` with `planet`'s seed, body and crater density.
[[nodiscard]] MarsPlanetGenerator planetAt(const PlanetOf& planet, std::size_t rows,
                                           std::size_t threads, const WriteOptions& write);

/// The samples of a DEM (grid in placement's map metres): the planet's height at the unit
/// vector under each sample, plus extra(unit) if set, and NaN where covers(x, y) is false
/// (if set). Computed window by window; nothing is held.
class PlanetDemSamples final : public topo::SampleSource {
 public:
  using Extra = std::function<double(const glm::dvec3&)>;
  using Covers = std::function<bool(double, double)>;
  PlanetDemSamples(MarsPlanetGenerator planet, topo::Placement placement, topo::TopoGrid grid,
                   Extra extra, Covers covers);
  [[nodiscard]] std::size_t rows() const noexcept override { return grid_.rows(); }
  [[nodiscard]] std::size_t cols() const noexcept override { return grid_.cols(); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override;
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override;

 private:
  MarsPlanetGenerator planet_;
  topo::Placement placement_;
  topo::TopoGrid grid_;
  Extra extra_;
  Covers covers_;
};

}  // namespace regolith::store::gen
