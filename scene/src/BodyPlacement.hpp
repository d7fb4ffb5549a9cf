#pragma once
/// \file
/// Where a scene's bodies are (Body::pose): the one rule the scene file's reader and Scene
/// both check (docs/scene-format.md, "Body"): a finite position, and no body's centre closer
/// to another's than the sum of their equatorial radii (relief ignored).

#include <regolith/core/Message.hpp>
#include <regolith/scene/SceneDescription.hpp>

#include <cmath>
#include <cstddef>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace regolith::scene::detail {

/// What is wrong with the bodies' places: the JSON pointer of the key and the expectation.
struct PlacementError {
  std::string pointer, what;
};

/// Checks the bodies' positions. `equatorialRadius[i]` is body i's equatorial radius in
/// metres, NaN where it is not known yet (the reader knows only the radii a file gives; Scene
/// knows every body's): pairs with an unknown radius are not checked. The first body that
/// sits inside an earlier one is named.
[[nodiscard]] inline std::optional<PlacementError> checkBodiesApart(
    const std::vector<Body>& bodies, const std::vector<double>& equatorialRadius) {
  // Messages through a stream (GCC 12 warns falsely on chains of std::string +).
  const auto pointer = [&](std::size_t i) {
    std::ostringstream p;
    p << "/bodies/" << i << (bodies[i].pose ? "/pose/position" : "/pose");
    return p.str();
  };
  const auto text = [](const std::array<double, 3>& p) {
    std::ostringstream t;
    t << '[' << core::number(p[0]) << ", " << core::number(p[1]) << ", " << core::number(p[2])
      << ']';
    return t.str();
  };
  const auto at = [&](std::size_t i) {
    return bodies[i].pose ? bodies[i].pose->position : std::array<double, 3>{0.0, 0.0, 0.0};
  };
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const std::array<double, 3> p = at(i);
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
      return PlacementError{pointer(i), text(p) + " is not finite, expected metres"};
    if (bodies[i].pose &&
        !(std::isfinite(bodies[i].pose->obliquity) && std::isfinite(bodies[i].pose->spin))) {
      std::ostringstream what;
      what << "obliquity " << core::number(bodies[i].pose->obliquity) << ", spin "
           << core::number(bodies[i].pose->spin) << ": expected finite degrees";
      std::ostringstream ptr;
      ptr << "/bodies/" << i << "/pose";
      return PlacementError{ptr.str(), what.str()};
    }
  }
  for (std::size_t i = 1; i < bodies.size(); ++i) {
    const std::array<double, 3> p = at(i);
    for (std::size_t k = 0; k < i; ++k) {
      const double need = equatorialRadius[i] + equatorialRadius[k];
      if (std::isnan(need)) continue;
      const std::array<double, 3> q = at(k);
      const double distance = std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
      if (distance >= need) continue;
      std::ostringstream what;
      what << (bodies[i].pose ? text(p) : std::string("missing (the root's origin)")) << " puts \""
           << bodies[i].name << "\" " << core::number(distance) << " m from the centre of \""
           << bodies[k].name << "\" (/bodies/" << k << "), inside it: expected at least "
           << core::number(need) << " m (the sum of their equatorial radii)";
      return PlacementError{pointer(i), what.str()};
    }
  }
  return std::nullopt;
}

}  // namespace regolith::scene::detail
