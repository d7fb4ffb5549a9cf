// Polar caps of the generated planet (Generate.hpp): polar stereographic DEMs at a finer
// resolution than the global grid, with optional layered deposits.
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/Generate.hpp>

#include "GenerateDem.hpp"
#include "GenerateNoise.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace regolith::store {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDegToRad = kPi / 180.0;
constexpr const char* kOp = "store::PolarCapGenerator()";

double smoothstep(double t) noexcept {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

void refuse(const std::string& field, const std::string& value, const std::string& expected) {
  throw InvalidArgument(
      core::format({.operation = kOp, .field = field, .value = value, .expected = expected}));
}

}  // namespace

struct PolarCapGenerator::Impl {
  PolarCapOptions options;
  topo::Body body;
  topo::Placement placement;
  MarsPlanetGenerator planet;
  GridInfo info;
  topo::TopoGrid grid;
  double sign = 1.0;   // +1 north, −1 south
  double reach = 0.0;  // deposits' reach from the pole, radians
  std::uint64_t troughSeed = 0;

  static PolarCapOptions checked(PolarCapOptions o);
  explicit Impl(PolarCapOptions o);
  [[nodiscard]] double deposit(const glm::dvec3& u) const noexcept;
};

PolarCapOptions PolarCapGenerator::Impl::checked(PolarCapOptions o) {
  if (!(std::isfinite(o.minLatitudeDeg) && o.minLatitudeDeg > 0.0 && o.minLatitudeDeg < 90.0)) {
    refuse("minimum latitude", core::number(o.minLatitudeDeg) + " degrees", "> 0 and < 90");
  }
  if (!(std::isfinite(o.spacing) && o.spacing > 0.0)) {
    refuse("spacing", core::number(o.spacing) + " m", "a finite number > 0");
  }
  if (!(std::isfinite(o.troughDepth) && o.troughDepth >= 0.0)) {
    refuse("trough depth", core::number(o.troughDepth) + " m", "a finite number >= 0");
  }
  if (!(std::isfinite(o.planet.craterDensity) && o.planet.craterDensity >= 0.0)) {
    refuse("crater density", core::number(o.planet.craterDensity), "a finite number >= 0");
  }
  if (o.gridName.empty())
    o.gridName = o.pole == PolarCapOptions::Pole::North ? "north_cap" : "south_cap";
  return o;
}

PolarCapGenerator::Impl::Impl(PolarCapOptions o)
    : options(checked(std::move(o))),
      body(options.planet.ellipsoid ? topo::Body::marsEllipsoid() : topo::Body::marsSphere()),
      placement(body, topo::PolarStereographic::withScaleFactor(body, options.pole, 1.0, 0.0)),
      planet(gen::planetAt(options.planet,
                           gen::planetRowsFor(options.spacing, body.equatorialRadius(), kOp),
                           options.threads, options.write)),
      grid(2, 2, 0.0, 0.0, 1.0, 1.0),
      sign(options.pole == PolarCapOptions::Pole::North ? 1.0 : -1.0) {
  // The square's half side: the map radius of the minimum latitude's circle.
  const topo::PolarStereographic& ps = *placement.polarStereographic();
  const double latDet = body.planetodeticFromPlanetocentric(sign * options.minLatitudeDeg);
  const double half = std::abs(ps.forward({latDet, 0.0}).y);
  const double cells = std::ceil(2.0 * half / options.spacing * (1.0 - 1e-12));
  if (!(cells + 1.0 <= static_cast<double>(kMaxGridSide))) {
    refuse("spacing", core::number(options.spacing) + " m",
           "at least " + core::number(2.0 * half / static_cast<double>(kMaxGridSide - 1)) +
               " m (the grid would exceed 2^31 samples per side)");
  }
  const auto n = static_cast<std::size_t>(cells) + 1;
  const double edge = 0.5 * static_cast<double>(n - 1) * options.spacing;
  grid = topo::TopoGrid(n, n, -edge, edge, options.spacing, options.spacing);

  info = gen::demGridInfo(options.gridName, grid, placement);

  reach = 0.8 * (90.0 - options.minLatitudeDeg) * kDegToRad;
  troughSeed = gen::hashOf(options.planet.seed, 0x504C44ULL);  // "PLD"
}

double PolarCapGenerator::Impl::deposit(const glm::dvec3& u) const noexcept {
  if (options.troughDepth == 0.0) return 0.0;
  const double theta = std::atan2(std::hypot(u.x, u.y), sign * u.z);  // from the pole
  if (theta >= reach) return 0.0;
  // Faded in from 10 % to 25 % of the reach (the spiral's arms meet at the pole), and out
  // over its last quarter.
  const double envelope = smoothstep((theta - 0.1 * reach) / (0.15 * reach)) *
                          smoothstep((reach - theta) / (0.25 * reach));
  if (envelope == 0.0) return 0.0;
  // Spiral troughs: phase 2π·(distance from the pole)/spacing + arms·azimuth, turning
  // counter-clockwise outwards seen from above either pole, with a seeded wander of a
  // radian or two at 200 km scales and a depth that varies along them (40–100 %).
  const double azimuth = std::atan2(u.y, u.x);
  const double radius = body.equatorialRadius();
  const double distance = theta * radius;
  const double wander = 2.5 * gen::fbm(u * (radius / 200000.0), 3, 0.5, troughSeed);
  const double strength =
      std::clamp(0.7 + 0.6 * gen::fbm(u * (radius / 250000.0), 3, 0.5, troughSeed + 1), 0.4, 1.0);
  const double phase = 2.0 * kPi * distance / kTroughSpacing +
                       sign * static_cast<double>(kTroughArms) * azimuth + wander;
  const double c = std::max(0.0, std::cos(phase));
  const double c2 = c * c;
  return -options.troughDepth * envelope * strength * c2 * c2 * c2;
}

PolarCapGenerator::PolarCapGenerator(PolarCapOptions options)
    : impl_(std::make_shared<const Impl>(std::move(options))) {}

const PolarCapOptions& PolarCapGenerator::options() const noexcept { return impl_->options; }
GridInfo PolarCapGenerator::gridInfo() const { return impl_->info; }
const topo::Placement& PolarCapGenerator::placement() const noexcept { return impl_->placement; }
const MarsPlanetGenerator& PolarCapGenerator::planet() const noexcept { return impl_->planet; }
double PolarCapGenerator::depositReachDeg() const noexcept { return impl_->reach / kDegToRad; }
double PolarCapGenerator::depositHeight(const glm::dvec3& unit) const noexcept {
  return impl_->deposit(unit);
}

std::shared_ptr<const topo::SampleSource> PolarCapGenerator::samples() const {
  gen::PlanetDemSamples::Extra extra;
  if (impl_->options.troughDepth > 0.0) {
    extra = [impl = impl_](const glm::dvec3& u) { return impl->deposit(u); };
  }
  return std::make_shared<gen::PlanetDemSamples>(impl_->planet, impl_->placement, impl_->grid,
                                                 std::move(extra), nullptr);
}

void PolarCapGenerator::write(const std::filesystem::path& path) const {
  const GridSource grid{gridInfo(), samples()};
  WriteOptions w = impl_->options.write;
  w.statistics = true;  // the height range a catalogue's bounds need
  writeStore(path, std::span(&grid, 1), w);
}

}  // namespace regolith::store
