#include "ImportChecks.hpp"

#include <regolith/core/Message.hpp>
#include <regolith/store/Import.hpp>

#include <cmath>
#include <limits>
#include <numbers>

namespace regolith::store::gdal {

namespace {

using core::number;

[[noreturn]] void refuse(const std::string& prefix, const std::string& field,
                         const std::string& value, const std::string& expected) {
  throw ImportError(core::format({prefix, {}, field, value, expected}));
}

/// A pixel size: finite, > 0 and at most `most` (the whole body).
void checkPixel(const std::string& prefix, const char* field, double v, double most,
                const char* unit) {
  if (!(std::isfinite(v) && v > 0.0)) refuse(prefix, field, number(v) + unit, "finite and > 0");
  if (v > most) {
    refuse(prefix, field, number(v) + unit,
           "at most " + number(most) + unit + " (one pixel cannot be larger than the body)");
  }
}

void checkPlanet(const GridInfo& g, const std::string& prefix) {
  checkPixel(prefix, "pixel width", g.spacingX, 360.0, " deg");
  checkPixel(prefix, "pixel height", g.spacingY, 180.0, " deg");
  const double west = g.x0 - 0.5 * g.spacingX;
  if (!(std::abs(west) <= 360.0)) {
    refuse(prefix, "west edge longitude", number(west) + " deg", "within -360 to 360 deg");
  }
  if (!std::isfinite(g.y0)) {
    refuse(prefix, "north edge latitude", number(g.y0 + 0.5 * g.spacingY) + " deg",
           "finite, within -90 to 90 deg");
  }
}

void checkDem(const GridInfo& g, const std::string& prefix) {
  // A grid on no body (no radius: a height map without georeferencing) has no bound.
  const double circumference = g.equatorialRadius > 0.0
                                   ? 2.0 * std::numbers::pi * g.equatorialRadius
                                   : std::numeric_limits<double>::max();
  checkPixel(prefix, "pixel width", g.spacingX, circumference, " m");
  checkPixel(prefix, "pixel height", g.spacingY, circumference, " m");
  if (!std::isfinite(g.x0) || !std::isfinite(g.y0)) {
    refuse(prefix, "origin (first sample's centre)", number(g.x0) + ", " + number(g.y0) + " m",
           "finite");
  }
  // Equirectangular metres are degrees of longitude (x = R cos(lat_ts) lon): more than 360
  // degrees, by over a pixel (rounded pixel sizes of global maps), is more than the body.
  const PlacementInfo& p = g.placement;
  if (p.kind != PlacementInfo::Kind::Equirectangular) return;
  const double metresPerDegree =
      p.projectionRadius * std::cos(p.latTrueScaleDeg.value_or(0.0) * std::numbers::pi / 180.0) *
      std::numbers::pi / 180.0;
  const double degrees = static_cast<double>(g.cols) * g.spacingX / metresPerDegree;
  const double pixel = g.spacingX / metresPerDegree;
  if (degrees > 360.0 + pixel) {
    refuse(prefix,
           "grid width (" + std::to_string(g.cols) + " columns of " + number(g.spacingX) + " m)",
           number(std::round(degrees * 1e6) / 1e6) + " deg of longitude",
           "at most 360 deg (one pixel more for a rounded pixel size)");
  }
}

}  // namespace

void checkGeoreferencing(const GridInfo& info, const std::string& prefix) {
  if (info.kind == GridKind::Planet) {
    checkPlanet(info, prefix);
  } else {
    checkDem(info, prefix);
  }
}

double plausibleHeightLimit(const GridInfo& info) noexcept {
  return info.equatorialRadius > 0.0 ? 0.1 * info.equatorialRadius
                                     : std::numeric_limits<double>::infinity();
}

CheckedHeights::CheckedHeights(std::shared_ptr<const topo::SampleSource> source,
                               const GridInfo& info, std::string prefix, bool strict)
    : source_(std::move(source)),
      prefix_(std::move(prefix)),
      limit_(plausibleHeightLimit(info)),
      strict_(strict) {}

float CheckedHeights::sample(std::size_t row, std::size_t col) const {
  float v = 0.0F;
  readWindow(row, col, 1, 1, {&v, 1});
  return v;
}

void CheckedHeights::readWindow(std::size_t row0, std::size_t col0, std::size_t nrows,
                                std::size_t ncols, std::span<float> out) const {
  source_->readWindow(row0, col0, nrows, ncols, out);
  std::size_t beyond = 0;
  for (std::size_t k = 0; k < out.size(); ++k) {
    const float h = out[k];  // printed as the float it is: 1e+30, not 1.0000000150474662e+30
    if (!(std::isinf(h) || std::abs(static_cast<double>(h)) > limit_)) continue;  // NaN: missing
    const std::string field = "sample at row " + std::to_string(row0 + k / ncols) + ", col " +
                              std::to_string(col0 + k % ncols);
    if (std::isinf(h)) {
      refuse(prefix_, field, number(h) + " m",
             "finite (a source value beyond float's range after scale and offset)");
    }
    if (strict_) {
      refuse(prefix_, field, number(h) + " m",
             "within +-" + number(limit_) +
                 " m (a tenth of the body's radius; --strict / strict=True refuses heights "
                 "beyond it)");
    }
    ++beyond;
  }
  implausible_ += beyond;
}

}  // namespace regolith::store::gdal
