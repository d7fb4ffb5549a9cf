#pragma once
/// \file
/// What a renderer draws for one camera: the scene graph re-rooted at the focus.

#include <regolith/scenegraph/Pose.hpp>

#include <glm/mat4x4.hpp>

#include <cstddef>
#include <vector>

namespace regolith::scenegraph {

/// One thing to draw: a drawable node, the key under which the renderer knows it, and its
/// frame relative to the focus and to the camera (item frame → focus frame, item frame →
/// camera frame; metres, double).
struct RenderItem {
  std::size_t node = 0;
  int drawable = -1;
  Pose inFocus;
  Pose inCamera;

  /// The camera's pose in this item's frame (camera → item): a renderer that draws the
  /// item in its own frame (terrain in its body-fixed or grid frame) puts its camera here.
  [[nodiscard]] Pose cameraInItem() const noexcept { return inCamera.inverse(); }
  /// The item → camera (eye) transform as a float matrix, made from the double pose only
  /// after the camera was subtracted: what the GPU gets for an object drawn in its frame.
  [[nodiscard]] glm::mat4 modelView() const noexcept;
};

/// A re-rooted view of a scene graph for one camera. The focus node sits at the origin;
/// `cameraInFocus` is the camera's pose (GL eye convention: it looks along its −z) in the
/// focus frame. Value type.
struct RenderList {
  std::size_t focus = 0;
  std::size_t camera = 0;
  Pose cameraInFocus;
  std::vector<RenderItem> items;

  /// The item for scene node `node`, or nullptr.
  [[nodiscard]] const RenderItem* find(std::size_t node) const noexcept;
  /// The item drawn under key `drawable`, or nullptr.
  [[nodiscard]] const RenderItem* findDrawable(int drawable) const noexcept;
};

}  // namespace regolith::scenegraph
