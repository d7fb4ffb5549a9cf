#include <regolith/clod/FocusController.hpp>
#include <regolith/core/Error.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace regolith::clod {

FocusController::FocusController(double halfLife) : halfLife_(halfLife) {
  if (!(halfLife > 0.0) || !std::isfinite(halfLife))
    throw InvalidArgument("FocusController(): half-life " + std::to_string(halfLife) +
                          " s, expected a finite value > 0");
}

std::size_t FocusController::addCamera(const Camera& camera, double time) {
  cameras_.push_back(Entry{camera, 0.0, time, time, 0});
  return cameras_.size() - 1;
}

void FocusController::update(std::size_t i, const Camera& camera, double time, double interact) {
  Entry& e = cameras_.at(i);
  const double scale = std::max(glm::length(e.camera.target - e.camera.position), 1e-9);
  const double moved = (glm::length(camera.position - e.camera.position) +
                        glm::length(camera.target - e.camera.target)) /
                       scale;
  e.score = activity(i, time) + moved + interact;
  e.time = time;
  e.camera = camera;
  if (moved > 0.0 || interact > 0.0) e.order = ++sequence_;
}

double FocusController::activity(std::size_t i, double time) const {
  const Entry& e = cameras_.at(i);
  return e.score * std::exp2(-std::max(time - e.time, 0.0) / halfLife_);
}

std::size_t FocusController::mostActive(double time) const {
  if (cameras_.empty()) throw InvalidArgument("FocusController::mostActive(): no cameras");
  std::size_t best = 0;
  for (std::size_t i = 1; i < cameras_.size(); ++i) {
    const double a = activity(i, time), b = activity(best, time);
    if (a > b || (a == b && cameras_[i].order > cameras_[best].order)) best = i;
  }
  return best;
}

glm::dvec3 FocusController::focus(double time) const {
  if (tied_) return tied_();
  return cameras_.at(mostActive(time)).camera.target;
}

}  // namespace regolith::clod
