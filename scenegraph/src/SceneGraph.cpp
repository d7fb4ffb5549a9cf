#include <regolith/core/Error.hpp>
#include <regolith/scenegraph/SceneGraph.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace regolith::scenegraph {

namespace {

bool finite(const Pose& p) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(p.translation[i])) return false;
  for (int i = 0; i < 4; ++i)
    if (!std::isfinite(p.rotation[i])) return false;
  return std::abs(glm::length(p.rotation) - 1.0) < 1e-9;
}

}  // namespace

SceneGraph::SceneGraph(std::string rootName) {
  if (rootName.empty()) throw InvalidArgument("SceneGraph(): the root's name is empty");
  nodes_.push_back(Node{std::move(rootName), std::nullopt, Pose{}, NodeKind::Frame, -1});
  children_.emplace_back();
}

void SceneGraph::check(NodeId id, const char* operation) const {
  if (id >= nodes_.size())
    throw InvalidArgument(std::string(operation) + ": node " + std::to_string(id) +
                          ", expected < " + std::to_string(nodes_.size()));
}

const Node& SceneGraph::node(NodeId id) const {
  check(id, "SceneGraph::node()");
  return nodes_[id];
}

NodeId SceneGraph::add(NodeId parent, std::string name, const Pose& local, NodeKind kind,
                       int drawable) {
  check(parent, "SceneGraph::add()");
  if (name.empty()) throw InvalidArgument("SceneGraph::add(): empty node name");
  if (find(name))
    throw InvalidArgument("SceneGraph::add(): node '" + name + "' exists, expected unique names");
  if (!finite(local))
    throw InvalidArgument("SceneGraph::add(): node '" + name +
                          "' has a pose that is not finite or not a unit rotation");
  const NodeId id = nodes_.size();
  nodes_.push_back(Node{std::move(name), parent, local, kind, drawable});
  children_.emplace_back();
  children_[parent].push_back(id);
  return id;
}

void SceneGraph::setLocal(NodeId id, const Pose& local) {
  check(id, "SceneGraph::setLocal()");
  if (id == root()) throw InvalidArgument("SceneGraph::setLocal(): the root cannot move");
  if (!finite(local))
    throw InvalidArgument("SceneGraph::setLocal(): node '" + nodes_[id].name +
                          "' given a pose that is not finite or not a unit rotation");
  nodes_[id].local = local;
}

std::optional<NodeId> SceneGraph::find(std::string_view name) const {
  for (NodeId i = 0; i < nodes_.size(); ++i)
    if (nodes_[i].name == name) return i;
  return std::nullopt;
}

NodeId SceneGraph::at(std::string_view name) const {
  if (auto id = find(name)) return *id;
  throw InvalidArgument("SceneGraph::at(): no node named '" + std::string(name) + "'");
}

std::vector<NodeId> SceneGraph::pathToRoot(NodeId id) const {
  check(id, "SceneGraph::pathToRoot()");
  std::vector<NodeId> path{id};
  while (nodes_[path.back()].parent) path.push_back(*nodes_[path.back()].parent);
  return path;
}

NodeId SceneGraph::commonAncestor(NodeId a, NodeId b) const {
  const auto pa = pathToRoot(a);
  const auto pb = pathToRoot(b);
  // Walk both paths down from the root while they agree.
  auto ia = pa.rbegin();
  auto ib = pb.rbegin();
  NodeId common = root();
  while (ia != pa.rend() && ib != pb.rend() && *ia == *ib) {
    common = *ia;
    ++ia;
    ++ib;
  }
  return common;
}

Pose SceneGraph::relative(NodeId from, NodeId to) const {
  check(from, "SceneGraph::relative()");
  check(to, "SceneGraph::relative()");
  const NodeId c = commonAncestor(from, to);
  // to → c and from → c, each composed from the node upward (innermost first).
  const auto upTo = [&](NodeId n) {
    Pose p;
    for (NodeId k = n; k != c; k = *nodes_[k].parent) p = nodes_[k].local * p;
    return p;
  };
  return upTo(from).inverse() * upTo(to);
}

std::vector<Pose> SceneGraph::rerooted(NodeId focus) const {
  check(focus, "SceneGraph::rerooted()");
  std::vector<Pose> out(nodes_.size());
  std::vector<bool> seen(nodes_.size(), false);
  std::vector<NodeId> stack{focus};
  seen[focus] = true;
  out[focus] = Pose{};
  while (!stack.empty()) {
    const NodeId n = stack.back();
    stack.pop_back();
    // Down the original edges: child in focus = n in focus ∘ child in n.
    for (NodeId ch : children_[n]) {
      if (seen[ch]) continue;
      seen[ch] = true;
      out[ch] = out[n] * nodes_[ch].local;
      stack.push_back(ch);
    }
    // Up an inverted edge: parent in focus = n in focus ∘ (n in parent)⁻¹.
    if (const auto p = nodes_[n].parent; p && !seen[*p]) {
      seen[*p] = true;
      out[*p] = out[n] * nodes_[n].local.inverse();
      stack.push_back(*p);
    }
  }
  return out;
}

RenderList SceneGraph::renderList(NodeId focus, NodeId camera) const {
  check(focus, "SceneGraph::renderList()");
  check(camera, "SceneGraph::renderList()");
  if (nodes_[camera].kind != NodeKind::Camera)
    throw InvalidArgument("SceneGraph::renderList(): node '" + nodes_[camera].name +
                          "' is not a camera");
  const auto poses = rerooted(focus);
  RenderList list;
  list.focus = focus;
  list.camera = camera;
  list.cameraInFocus = poses[camera];
  const Pose focusInCamera = list.cameraInFocus.inverse();
  for (NodeId i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    if (n.drawable < 0 || (n.kind != NodeKind::Terrain && n.kind != NodeKind::Object)) continue;
    RenderItem item;
    item.node = i;
    item.drawable = n.drawable;
    item.inFocus = poses[i];
    item.inCamera = focusInCamera * poses[i];
    list.items.push_back(item);
  }
  return list;
}

}  // namespace regolith::scenegraph
