// The Victoria-like crater: its analytic shape and the generator that places it on Mars.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>

#include "GenerateNoise.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace regolith::store {

namespace {

constexpr double kPi = std::numbers::pi;

/// The samples of a VictoriaShape on a grid, computed window by window.
class VictoriaSamples final : public topo::SampleSource {
 public:
  VictoriaSamples(const VictoriaShape& shape, const topo::TopoGrid& grid)
      : shape_(shape), grid_(grid) {}
  [[nodiscard]] std::size_t rows() const noexcept override { return grid_.rows(); }
  [[nodiscard]] std::size_t cols() const noexcept override { return grid_.cols(); }
  [[nodiscard]] float sample(std::size_t row, std::size_t col) const override {
    const glm::dvec2 p = grid_.sampleCentre(static_cast<double>(row), static_cast<double>(col));
    return static_cast<float>(shape_.height(p.x, p.y));
  }
  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override {
    for (std::size_t r = 0; r < nrows; ++r) {
      for (std::size_t c = 0; c < ncols; ++c) out[r * ncols + c] = sample(row0 + r, col0 + c);
    }
  }

 private:
  VictoriaShape shape_;
  topo::TopoGrid grid_;
};

topo::TopoGrid victoriaGrid(const VictoriaOptions& o) {
  const double half = 0.5 * static_cast<double>(o.size - 1) * o.spacing;
  return {o.size, o.size, -half, half, o.spacing, o.spacing};
}

}  // namespace

VictoriaShape VictoriaShape::fromSeed(std::uint64_t seed) {
  gen::Random rng(gen::hashOf(seed, 0x5649435430524941ULL));  // "VICT0RIA"
  VictoriaShape s;
  s.bayPhase = rng.uniform(0.0, 2.0 * kPi / s.bays);
  s.roughPhase = rng.uniform(0.0, 2.0 * kPi);
  s.duneAzimuth = rng.uniform(0.0, kPi);
  s.dunePhase = rng.uniform(0.0, kPi);
  s.regionalPhaseX = rng.uniform(0.0, 2.0 * kPi);
  s.regionalPhaseY = rng.uniform(0.0, 2.0 * kPi);
  s.roughnessAmplitude = 0.1;
  s.roughnessSeed = rng.next();
  return s;
}

double VictoriaShape::crestRadius(double theta) const noexcept {
  return rimRadius * (1.0 + bayAmplitude * std::cos(bays * (theta - bayPhase)) +
                      roughAmplitude * std::cos(roughHarmonic * theta + roughPhase));
}

double VictoriaShape::height(double x, double y) const noexcept {
  double regional = regionalSlope * x + regionalAmplitude * std::sin(x / 310.0 + regionalPhaseX) *
                                            std::cos(y / 270.0 + regionalPhaseY);
  if (roughnessAmplitude != 0.0) {
    // Three octaves, 80 m down to 20 m wavelength.
    regional += roughnessAmplitude * gen::fbm({x / 80.0, y / 80.0, 0.5}, 3, 0.5, roughnessSeed);
  }
  const double r = std::hypot(x, y);
  const double rim = crestRadius(std::atan2(y, x));
  if (r >= rim) return regional + rimHeight * std::pow(rim / r, 3.0);
  const double q = r / rim;
  const double q2 = q * q;
  const double bowl = rimHeight - (depth + rimHeight) * (1.0 - q2 * q2);
  const double floorWeight = std::clamp((0.6 - q) / 0.3, 0.0, 1.0);
  if (floorWeight == 0.0) return regional + bowl;
  const double ca = std::cos(duneAzimuth), sa = std::sin(duneAzimuth);
  const double s = x * ca + y * sa, t = -x * sa + y * ca;
  const double d = std::sin(kPi * s / duneWavelength + dunePhase + 0.3 * std::sin(t / 40.0));
  return regional + bowl + floorWeight * duneAmplitude * d * d;
}

VictoriaGenerator::VictoriaGenerator(VictoriaOptions options)
    : options_(std::move(options)), shape_(VictoriaShape::fromSeed(options_.seed)) {
  const std::string op = "store::VictoriaGenerator(): ";
  if (options_.size < 2) {
    throw InvalidArgument(op + "size " + std::to_string(options_.size) +
                          " samples per side, expected >= 2");
  }
  if (!(std::isfinite(options_.spacing) && options_.spacing > 0.0)) {
    throw InvalidArgument(op + "spacing " + std::to_string(options_.spacing) +
                          " m, expected a finite number > 0");
  }
  if (!std::isfinite(options_.originHeight)) {
    throw InvalidArgument(op + "origin height is not finite");
  }
  if (options_.gridName.empty()) throw InvalidArgument(op + "empty grid name");
}

GridInfo VictoriaGenerator::gridInfo() const {
  const topo::TopoGrid g = victoriaGrid(options_);
  GridInfo info;
  info.name = options_.gridName;
  info.kind = GridKind::Dem;
  info.rows = g.rows();
  info.cols = g.cols();
  info.x0 = g.x0();
  info.y0 = g.y0();
  info.spacingX = g.spacingX();
  info.spacingY = g.spacingY();
  const topo::Body mars = topo::Body::marsEllipsoid();
  info.bodyName = mars.name();
  info.equatorialRadius = mars.equatorialRadius();
  info.polarRadius = mars.polarRadius();
  info.latitudeType = topo::LatitudeType::Planetodetic;
  info.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  info.placement.originLatDeg = kOriginLatDeg;
  info.placement.originLonDeg = kOriginLonDeg;
  info.placement.originHeight = options_.originHeight;
  info.placement.headingDeg = 0.0;
  return info;
}

std::shared_ptr<const topo::SampleSource> VictoriaGenerator::samples() const {
  return std::make_shared<VictoriaSamples>(shape_, victoriaGrid(options_));
}

void VictoriaGenerator::write(const std::filesystem::path& path) const {
  const GridSource grid{gridInfo(), samples()};
  writeStore(path, std::span(&grid, 1), options_.write);
}

}  // namespace regolith::store
