#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/rover/TrackPresser.hpp>

#include <array>
#include <cmath>
#include <string>

namespace regolith::rover {

TrackPresser::TrackPresser(TrackLayer& layer, TrackPressOptions options)
    : layer_(&layer), options_(options) {
  const std::string op = "rover::TrackPresser(): ";
  if (!(std::isfinite(options.spacingMetres) && options.spacingMetres >= 0.0)) {
    throw InvalidArgument(op + "spacing is " + core::number(options.spacingMetres) +
                          " m, expected finite and ≥ 0");
  }
  if (!(std::isfinite(options.wheelWidthMetres) && options.wheelWidthMetres > 0.0)) {
    throw InvalidArgument(op + "wheel width is " + core::number(options.wheelWidthMetres) +
                          " m, expected finite and > 0");
  }
  if (!(std::isfinite(options.depthMetres) && options.depthMetres >= 0.0)) {
    throw InvalidArgument(op + "rut depth is " + core::number(options.depthMetres) +
                          " m, expected finite and ≥ 0");
  }
}

bool TrackPresser::press(const StepState& s) {
  if (s.distance < next_) return false;
  std::array<WheelImprint, kWheels> imprint;
  for (std::size_t w = 0; w < kWheels; ++w) {
    imprint[w] = {{s.wheels[w].x, s.wheels[w].y}, options_.wheelWidthMetres, options_.depthMetres};
  }
  layer_->step(imprint);
  ++imprints_;
  next_ = s.distance + options_.spacingMetres;
  return true;
}

}  // namespace regolith::rover
