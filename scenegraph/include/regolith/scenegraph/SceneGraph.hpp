#pragma once
/// \file
/// A tree of frames with double-precision edges, re-rooted at the object of interest to
/// produce render lists (JPL Dspace/SimScape paper, section IV.B, figures 10–12).

#include <regolith/scenegraph/Pose.hpp>
#include <regolith/scenegraph/RenderList.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace regolith::scenegraph {

/// Index of a node in its SceneGraph.
using NodeId = std::size_t;

/// What a node stands for. Frames only place their children; the other kinds appear in
/// render lists (terrain, objects) or view them (cameras).
enum class NodeKind { Frame, Terrain, Object, Camera };

/// One node: its name, parent, pose in the parent's frame (child → parent) and, for
/// drawable nodes, the key under which the renderer knows what to draw (-1: nothing).
struct Node {
  std::string name;
  std::optional<NodeId> parent;
  Pose local;
  NodeKind kind = NodeKind::Frame;
  int drawable = -1;
};

/// A tree of frames. Every edge is a rigid transform in double (metres); nothing here knows
/// about GL. Positions far from each other (the Sun and a rover on Mars) are never added
/// together: every relative pose is composed along the tree path between its two nodes,
/// through their lowest common ancestor, so the pose of a rover in its DEM's frame or of a
/// camera beside it is exact to double rounding of small numbers.
///
/// renderList(focus, camera) is the paper's re-rooting (figure 12): the tree is walked out
/// from the focus (edges towards the old root are inverted), every drawable node gets its
/// pose relative to the focus, and the camera gets its pose relative to the focus, so a
/// renderer that works relative to the camera never sees a coordinate of planetary
/// magnitude. The focus can be any node and can change from one frame to the next; the
/// render list it gives describes the same scene (only the frame of reference moves).
///
/// Not thread-safe for writes; const members may be called concurrently.
class SceneGraph {
 public:
  /// A graph holding only its root frame.
  explicit SceneGraph(std::string rootName = "root");

  [[nodiscard]] NodeId root() const noexcept { return 0; }
  [[nodiscard]] std::size_t size() const noexcept { return nodes_.size(); }
  /// Throws InvalidArgument for an unknown id.
  [[nodiscard]] const Node& node(NodeId id) const;

  /// Adds a child of `parent` at `local` (child → parent). Names must be unique and not
  /// empty. Throws InvalidArgument for an unknown parent, a duplicate or empty name, or a
  /// pose that is not finite.
  NodeId add(NodeId parent, std::string name, const Pose& local, NodeKind kind = NodeKind::Frame,
             int drawable = -1);
  /// Moves a node relative to its parent. Throws as add() for a bad id or pose; the root
  /// stays at the identity (InvalidArgument).
  void setLocal(NodeId id, const Pose& local);
  /// The node with that name, if any.
  [[nodiscard]] std::optional<NodeId> find(std::string_view name) const;
  /// find(), or InvalidArgument naming the missing node.
  [[nodiscard]] NodeId at(std::string_view name) const;

  /// The nodes from `id` up to the root, both included.
  [[nodiscard]] std::vector<NodeId> pathToRoot(NodeId id) const;
  /// The lowest common ancestor of a and b.
  [[nodiscard]] NodeId commonAncestor(NodeId a, NodeId b) const;
  /// The pose of node `to` in the frame of node `from` (to → from), composed through their
  /// common ancestor only.
  [[nodiscard]] Pose relative(NodeId from, NodeId to) const;
  /// The pose of `id` in the root's frame (relative(root, id)). For naive pipelines and
  /// tests; a renderer should use renderList().
  [[nodiscard]] Pose inRoot(NodeId id) const { return relative(root(), id); }

  /// Every node's pose relative to `focus`, by walking the re-rooted tree out from it.
  [[nodiscard]] std::vector<Pose> rerooted(NodeId focus) const;
  /// The render list for `camera` with `focus` as the origin: every drawable node (kind
  /// Terrain or Object with a key ≥ 0), in node order, with its pose relative to the
  /// focus and to the camera. Throws InvalidArgument unless `camera` is a Camera node.
  [[nodiscard]] RenderList renderList(NodeId focus, NodeId camera) const;

 private:
  void check(NodeId id, const char* operation) const;
  std::vector<Node> nodes_;
  std::vector<std::vector<NodeId>> children_;
};

}  // namespace regolith::scenegraph
