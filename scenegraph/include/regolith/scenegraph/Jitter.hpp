#pragma once
/// \file
/// Screen-space jitter of float32 vertex pipelines, measured against double precision.

#include <regolith/scenegraph/SceneGraph.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace regolith::scenegraph {

/// A point to follow: a position in the frame of a scene node (metres).
struct TrackedPoint {
  NodeId node = 0;
  glm::dvec3 local{0.0};
};

/// How the GPU would be fed, emulated exactly in IEEE float32 on the CPU.
/// - NaiveWorld: positions in the frame of `world` (the Sun-rooted root, or a body) are
///   stored as float; the view matrix (world → eye, with its translation) is made in double
///   and cast to float; eye = V_f · (p_f, 1) in float. What a renderer without re-rooting
///   does.
/// - Rerooted: what regolith's renderer does. The camera is expressed in each item's frame
///   in double (SceneGraph::renderList through the focus); a vertex is stored as a float
///   offset from an anchor of its item (the anchor: the point rounded to `anchorCell`
///   metres, as a clipmap level keeps its texels relative to a level anchor), the anchor's
///   offset from the camera is made in double and cast to float, and eye = R_f · (offset_f
///   + anchorRel_f) in float.
enum class Pipeline { NaiveWorld, Rerooted };

/// One pipeline's result over a run of frames.
struct JitterResult {
  std::string name;
  /// Largest frame-to-frame screen motion not explained by the exact motion, pixels:
  /// max over points and frames of |(s_f(i) − s(i)) − (s_f(i−1) − s(i−1))|, s the double
  /// projection, s_f the float pipeline's.
  double jitterPx = 0.0;
  /// Largest |s_f(i) − s(i)|, pixels.
  double errorPx = 0.0;
  /// Point-frames the float pipeline lost (not finite, or behind the camera) while the
  /// double projection had them in front.
  std::size_t lost = 0;
};

/// Camera intrinsics for the projection (the clod::Camera convention: pixel centres at +0.5,
/// focal length in pixels from the vertical field of view).
struct JitterCamera {
  double fovYDegrees = 60.0;
  int width = 1280, height = 720;
};

/// Projects `points` for every frame through the double pipeline and through `pipeline`,
/// where frame i is set up by calling `step(graph, i)` (it moves nodes, e.g. the rover by
/// 1 mm). The camera is node `camera` (GL eye convention), `focus` the render focus,
/// `world` the frame of the naive pipeline. Points behind the camera in double are skipped.
JitterResult measureJitter(SceneGraph& graph, NodeId camera, NodeId focus, NodeId world,
                           Pipeline pipeline, const std::vector<TrackedPoint>& points,
                           std::size_t frames,
                           const std::function<void(SceneGraph&, std::size_t)>& step,
                           const JitterCamera& intrinsics = {}, double anchorCell = 64.0);

}  // namespace regolith::scenegraph
