#pragma once
/// \file
/// Chooses the clipmap focus among several cameras, or from an object it is tied to.

#include <regolith/clod/Camera.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

namespace regolith::clod {

/// Several cameras look at one terrain; the most active one controls the focus.
///
/// **Activity.** Each camera carries a score that decays exponentially with half-life
/// `halfLife` seconds. Every update adds how far the camera moved since its last update,
/// measured as what the viewer sees change: the distance its position moved plus the
/// distance its look-at point moved, divided by the camera's distance to its look-at point
/// (a pan across the whole view adds about 1, a zoom by 10 % adds 0.1), plus `interact` for
/// explicit input (a click or a key, 1 by convention). The most active camera has the
/// highest score; ties go to the camera updated most recently. A camera never moved has
/// score 0; with every score 0 the first camera is the most active.
///
/// **Focus.** The active camera's look-at point, unless the focus is tied to an object
/// (tieTo): then the object's position, so a rover is never drawn under or above a coarser
/// level than the one around it.
///
/// Times are seconds on any monotonic clock the caller passes in (deterministic in tests).
/// Not thread-safe.
class FocusController {
 public:
  explicit FocusController(double halfLife = 2.0);

  /// Adds a camera; returns its index.
  std::size_t addCamera(const Camera& camera, double time);
  /// Records camera i's new pose at `time` and adds its motion to its activity.
  void update(std::size_t i, const Camera& camera, double time, double interact = 0.0);
  /// Activity of camera i at `time` (decayed).
  [[nodiscard]] double activity(std::size_t i, double time) const;
  /// Index of the most active camera at `time`.
  [[nodiscard]] std::size_t mostActive(double time) const;

  /// Ties the focus to an object whose position (scene frame) `position` returns.
  void tieTo(std::function<glm::dvec3()> position) { tied_ = std::move(position); }
  void untie() { tied_ = nullptr; }
  [[nodiscard]] bool tied() const noexcept { return static_cast<bool>(tied_); }
  /// The focus at `time`: the tied object's position, else the most active camera's target.
  [[nodiscard]] glm::dvec3 focus(double time) const;
  [[nodiscard]] const Camera& camera(std::size_t i) const { return cameras_.at(i).camera; }
  [[nodiscard]] std::size_t cameraCount() const noexcept { return cameras_.size(); }

 private:
  struct Entry {
    Camera camera;
    double score = 0.0, time = 0.0, lastUpdate = 0.0;
    std::size_t order = 0;  // update sequence number, for ties
  };
  double halfLife_;
  std::vector<Entry> cameras_;
  std::size_t sequence_ = 0;
  std::function<glm::dvec3()> tied_;
};

}  // namespace regolith::clod
