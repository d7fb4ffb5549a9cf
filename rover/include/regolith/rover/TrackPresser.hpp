#pragma once
/// \file
/// Presses a traverse's wheels into a TrackLayer as the rover drives (CPU only, no GL).

#include <regolith/rover/TrackLayer.hpp>
#include <regolith/rover/Traverse.hpp>

#include <cstddef>

namespace regolith::rover {

/// How a TrackPresser presses: one imprint of all wheels every `spacingMetres` of travel,
/// each rut `wheelWidthMetres` wide and `depthMetres` deep at its centre. The defaults are
/// the project's rover (RoverRuts). Value type.
struct TrackPressOptions {
  double spacingMetres = RoverRuts::kSpacingMetres;
  double wheelWidthMetres = RoverRuts::kWheelWidthMetres;
  double depthMetres = RoverRuts::kDepthMetres;
};

/// Turns traverse steps into wheel imprints: call press() from a traverse's StepCallback.
/// It presses the six wheels of a step (TrackLayer::step(), so each wheel's rut runs on
/// from its previous imprint) at the first step, and then at the first step that has
/// driven at least `spacingMetres` beyond the previous imprint.
///
/// Holds a reference to the layer, which must outlive it. Not thread-safe (one traverse
/// drives it); the layer itself may be read by another thread meanwhile.
class TrackPresser {
 public:
  /// Throws regolith::InvalidArgument for a spacing < 0 or not finite, and for a width or
  /// depth that TrackLayer::step() would reject (width ≤ 0, depth < 0, or not finite).
  explicit TrackPresser(TrackLayer& layer, TrackPressOptions options = {});

  /// Presses the wheels of `s` if it is time to (see above); returns whether it did.
  bool press(const StepState& s);

  /// Imprints pressed so far (each of all six wheels).
  [[nodiscard]] std::size_t imprints() const noexcept { return imprints_; }
  [[nodiscard]] const TrackPressOptions& options() const noexcept { return options_; }

 private:
  TrackLayer* layer_;
  TrackPressOptions options_;
  double next_ = 0.0;  // distance of the next imprint, m
  std::size_t imprints_ = 0;
};

}  // namespace regolith::rover
