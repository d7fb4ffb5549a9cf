// Inclined strips of the generated planet (Generate.hpp): long, narrow DEMs along an orbit's
// ground track, in an oblique Mercator projection through PROJ, with ragged edges.
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/ProjPlacement.hpp>

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
constexpr double kRadToDeg = 180.0 / kPi;
constexpr const char* kOp = "store::StripGenerator()";

void refuse(const std::string& field, const std::string& value, const std::string& expected) {
  throw InvalidArgument(
      core::format({.operation = kOp, .field = field, .value = value, .expected = expected}));
}

StripOptions checked(StripOptions o) {
  const auto finite = [](const char* field, double v) {
    if (!std::isfinite(v)) refuse(field, core::number(v), "a finite number");
  };
  finite("centre latitude", o.centreLatDeg);
  finite("centre longitude", o.centreLonDeg);
  finite("inclination", o.inclinationDeg);
  if (o.inclinationDeg < 0.0 || o.inclinationDeg > 180.0) {
    refuse("inclination", core::number(o.inclinationDeg) + " degrees", ">= 0 and <= 180");
  }
  const double reachDeg = std::min(o.inclinationDeg, 180.0 - o.inclinationDeg);
  if (std::abs(o.centreLatDeg) > reachDeg) {
    refuse("centre latitude", core::number(o.centreLatDeg) + " degrees",
           "within the reach of an orbit inclined " + core::number(o.inclinationDeg) +
               " degrees (|latitude| <= " + core::number(reachDeg) + ")");
  }
  if (std::abs(o.centreLatDeg) >= 89.0) {
    refuse("centre latitude", core::number(o.centreLatDeg) + " degrees",
           "|latitude| < 89 (the oblique Mercator's centre)");
  }
  for (const auto& [field, v] : {std::pair{"length", o.length}, std::pair{"width", o.width},
                                 std::pair{"spacing", o.spacing}}) {
    if (!(std::isfinite(v) && v > 0.0))
      refuse(field, core::number(v) + " m", "a finite number > 0");
  }
  if (!(std::isfinite(o.raggedness) && o.raggedness >= 0.0 && o.raggedness <= 0.9)) {
    refuse("raggedness", core::number(o.raggedness), ">= 0 and <= 0.9");
  }
  if (!(std::isfinite(o.planet.craterDensity) && o.planet.craterDensity >= 0.0)) {
    refuse("crater density", core::number(o.planet.craterDensity), "a finite number >= 0");
  }
  if (o.gridName.empty()) refuse("grid name", "empty", "a name");
  return o;
}

/// Samples spanning `extent` metres at `spacing` (outermost centres at ±extent/2 or beyond).
std::size_t samplesFor(double extent, double spacing, const char* field) {
  const double cells = std::ceil(extent / spacing * (1.0 - 1e-12));
  if (!(cells + 1.0 <= static_cast<double>(kMaxGridSide))) {
    refuse(field, core::number(extent) + " m at a spacing of " + core::number(spacing) + " m",
           "at most 2^31 samples");
  }
  return static_cast<std::size_t>(cells) + 1;
}

/// How far inwards an edge wanders at position s along it (metres), as a fraction in
/// [0, 1]: seeded fBm with features about `scale` metres long.
double wander(double s, double scale, double lane, std::uint64_t seed) noexcept {
  return std::clamp(0.5 + 0.6 * gen::fbm({s / scale, lane, 0.5}, 4, 0.5, seed), 0.0, 1.0);
}

}  // namespace

struct StripGenerator::Impl {
  StripOptions options;
  topo::Body body;
  double azimuth = 0.0;  // direction of flight at the centre, degrees
  std::string proj;
  topo::Placement placement;
  MarsPlanetGenerator planet;
  GridInfo info;
  topo::TopoGrid grid;
  double halfLength = 0.0, halfWidth = 0.0;
  std::uint64_t edgeSeed = 0;

  explicit Impl(StripOptions o);
  [[nodiscard]] static std::string crsOf(const StripOptions& o, const topo::Body& body,
                                         double azimuthDeg);
  [[nodiscard]] bool covers(double x, double y) const noexcept;
};

namespace {

/// Direction of flight at planetocentric latitude φ on an orbit of inclination i (Clairaut
/// on the sphere: cos φ · sin β = cos i), degrees in (−180, 180].
double flightAzimuth(double latDeg, double inclinationDeg, bool descending) {
  const double s =
      std::clamp(std::cos(inclinationDeg * kDegToRad) / std::cos(latDeg * kDegToRad), -1.0, 1.0);
  const double northbound = std::asin(s) * kRadToDeg;  // [−90, 90]
  return descending ? (northbound >= 0.0 ? 180.0 - northbound : -180.0 - northbound) : northbound;
}

}  // namespace

std::string StripGenerator::Impl::crsOf(const StripOptions& o, const topo::Body& body,
                                        double azimuthDeg) {
  // PROJ's omerc reads the centre line's azimuth in (−90°, 90°] (α and α ± 180° give the same
  // map); gamma = ±90° turns the grid so that x runs along the line, + towards α.
  double alpha = azimuthDeg;
  double gamma = 90.0;
  if (alpha > 90.0 || alpha <= -90.0) {
    alpha = alpha > 0.0 ? alpha - 180.0 : alpha + 180.0;
    gamma = -90.0;
  }
  const std::string ellipsoid = body.isSphere() ? " +R=" + core::number(body.equatorialRadius())
                                                : " +a=" + core::number(body.equatorialRadius()) +
                                                      " +b=" + core::number(body.polarRadius());
  return "+proj=omerc +lat_0=" + core::number(body.planetodeticFromPlanetocentric(o.centreLatDeg)) +
         " +lonc=" + core::number(o.centreLonDeg) + " +alpha=" + core::number(alpha) +
         " +gamma=" + core::number(gamma) + " +k_0=1 +x_0=0 +y_0=0" + ellipsoid +
         " +units=m +no_defs +type=crs";
}

StripGenerator::Impl::Impl(StripOptions o)
    : options(checked(std::move(o))),
      body(options.planet.ellipsoid ? topo::Body::marsEllipsoid() : topo::Body::marsSphere()),
      azimuth(flightAzimuth(options.centreLatDeg, options.inclinationDeg, options.descending)),
      proj(crsOf(options, body, azimuth)),
      placement(projPlacement(body, proj)),
      planet(gen::planetAt(options.planet,
                           gen::planetRowsFor(options.spacing, body.equatorialRadius(), kOp),
                           options.threads, options.write)),
      grid(2, 2, 0.0, 0.0, 1.0, 1.0) {
  if (options.length > kPi * body.equatorialRadius()) {
    refuse("length", core::number(options.length) + " m",
           "<= " + core::number(kPi * body.equatorialRadius()) + " m (half a great circle)");
  }
  const std::size_t cols = samplesFor(options.length, options.spacing, "length");
  const std::size_t rows = samplesFor(options.width, options.spacing, "width");
  halfLength = 0.5 * static_cast<double>(cols - 1) * options.spacing;
  halfWidth = 0.5 * static_cast<double>(rows - 1) * options.spacing;
  grid = topo::TopoGrid(rows, cols, -halfLength, halfWidth, options.spacing, options.spacing);

  info = gen::demGridInfo(options.gridName, grid, placement);
  edgeSeed = gen::hashOf(options.planet.seed, 0x5354524950ULL);  // "STRIP"
}

bool StripGenerator::Impl::covers(double x, double y) const noexcept {
  const double r = options.raggedness;
  if (std::abs(y) > halfWidth || std::abs(x) > halfLength) return false;
  if (r == 0.0) return true;
  const double lane = y >= 0.0 ? 1.0 : -1.0;
  const double side = halfWidth * (1.0 - r * wander(x, 4.0 * halfWidth, 7.0 * lane, edgeSeed));
  if (std::abs(y) > side) return false;
  const double end = x >= 0.0 ? 1.0 : -1.0;
  const double ends =
      halfLength - r * halfWidth * wander(y, 0.5 * halfWidth, 20.0 + 7.0 * end, edgeSeed);
  return std::abs(x) <= ends;
}

StripGenerator::StripGenerator(StripOptions options)
    : impl_(std::make_shared<const Impl>(std::move(options))) {}

const StripOptions& StripGenerator::options() const noexcept { return impl_->options; }
GridInfo StripGenerator::gridInfo() const { return impl_->info; }
const topo::Placement& StripGenerator::placement() const noexcept { return impl_->placement; }
const MarsPlanetGenerator& StripGenerator::planet() const noexcept { return impl_->planet; }
double StripGenerator::azimuthDeg() const noexcept { return impl_->azimuth; }
const std::string& StripGenerator::projString() const noexcept { return impl_->proj; }
bool StripGenerator::covers(double x, double y) const noexcept { return impl_->covers(x, y); }

std::shared_ptr<const topo::SampleSource> StripGenerator::samples() const {
  gen::PlanetDemSamples::Covers covers;
  if (impl_->options.raggedness > 0.0) {
    covers = [impl = impl_](double x, double y) { return impl->covers(x, y); };
  }
  return std::make_shared<gen::PlanetDemSamples>(impl_->planet, impl_->placement, impl_->grid,
                                                 nullptr, std::move(covers));
}

void StripGenerator::write(const std::filesystem::path& path) const {
  const GridSource grid{gridInfo(), samples()};
  WriteOptions w = impl_->options.write;
  w.statistics = true;  // the height range a catalogue's bounds need
  writeStore(path, std::span(&grid, 1), w);
}

}  // namespace regolith::store
