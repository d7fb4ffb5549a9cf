#include <regolith/core/Error.hpp>
#include <regolith/scenegraph/Jitter.hpp>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

namespace regolith::scenegraph {

namespace {

// Pixel position of an eye-space point (x right, y down, centres at +0.5), or nullopt if it
// is not in front of the camera or not finite.
template <typename T>
std::optional<glm::dvec2> project(const glm::vec<3, T>& eye, T focal, T width, T height) {
  const T d = -eye.z;
  if (!(d > T(0))) return std::nullopt;
  const T x = T(0.5) * width + focal * eye.x / d;
  const T y = T(0.5) * height - focal * eye.y / d;
  if (!std::isfinite(x) || !std::isfinite(y)) return std::nullopt;
  return glm::dvec2(static_cast<double>(x), static_cast<double>(y));
}

glm::dmat4 toMatrix(const Pose& p) {
  glm::dmat4 m(p.matrix());
  m[3] = glm::dvec4(p.translation, 1.0);
  return m;
}

}  // namespace

JitterResult measureJitter(SceneGraph& graph, NodeId camera, NodeId focus, NodeId world,
                           Pipeline pipeline, const std::vector<TrackedPoint>& points,
                           std::size_t frames,
                           const std::function<void(SceneGraph&, std::size_t)>& step,
                           const JitterCamera& intrinsics, double anchorCell) {
  if (!(intrinsics.fovYDegrees > 0.0 && intrinsics.fovYDegrees < 180.0) || intrinsics.width < 1 ||
      intrinsics.height < 1)
    throw InvalidArgument("measureJitter(): camera intrinsics out of range");
  if (!(anchorCell > 0.0))
    throw InvalidArgument("measureJitter(): anchor cell " + std::to_string(anchorCell) +
                          " m, expected > 0");
  const double focal =
      0.5 * intrinsics.height / std::tan(0.5 * intrinsics.fovYDegrees * std::numbers::pi / 180.0);
  const auto w = static_cast<double>(intrinsics.width);
  const auto h = static_cast<double>(intrinsics.height);
  const auto focalF = static_cast<float>(focal);
  const auto wF = static_cast<float>(w);
  const auto hF = static_cast<float>(h);

  JitterResult result;
  result.name = pipeline == Pipeline::Rerooted
                    ? "re-rooted at '" + graph.node(focus).name + "'"
                    : "naive, float world = '" + graph.node(world).name + "'";
  std::vector<std::optional<glm::dvec2>> previous(points.size());
  for (std::size_t i = 0; i < frames; ++i) {
    step(graph, i);
    const RenderList list = graph.renderList(focus, camera);
    const std::vector<Pose> inFocus = graph.rerooted(focus);
    const glm::mat4 viewF = glm::mat4(toMatrix(graph.relative(camera, world)));
    for (std::size_t k = 0; k < points.size(); ++k) {
      const TrackedPoint& tp = points[k];
      const glm::dvec3 exactEye = graph.relative(camera, tp.node).apply(tp.local);
      const auto exact = project(exactEye, focal, w, h);
      if (!exact) {
        previous[k].reset();
        continue;
      }
      std::optional<glm::dvec2> approx;
      if (pipeline == Pipeline::NaiveWorld) {
        const glm::vec3 worldF(graph.relative(world, tp.node).apply(tp.local));
        const glm::vec4 eye = viewF * glm::vec4(worldF, 1.0F);
        approx = project(glm::vec3(eye), focalF, wF, hF);
      } else {
        // The item's frame: the tracked node's. Camera in the item frame, through the focus.
        const Pose cameraInItem = inFocus[tp.node].inverse() * list.cameraInFocus;
        const glm::dvec3 anchor = glm::round(tp.local / anchorCell) * anchorCell;
        const glm::vec3 offsetF(tp.local - anchor);                     // texel / vertex
        const glm::vec3 anchorRelF(anchor - cameraInItem.translation);  // uniform
        const glm::mat3 rotF(glm::transpose(cameraInItem.matrix()));    // item → eye
        approx = project(rotF * (offsetF + anchorRelF), focalF, wF, hF);
      }
      if (!approx) {
        ++result.lost;
        previous[k].reset();
        continue;
      }
      const glm::dvec2 err = *approx - *exact;
      result.errorPx = std::max(result.errorPx, glm::length(err));
      if (previous[k]) result.jitterPx = std::max(result.jitterPx, glm::length(err - *previous[k]));
      previous[k] = err;
    }
  }
  return result;
}

}  // namespace regolith::scenegraph
