#include <regolith/scenegraph/RenderList.hpp>

namespace regolith::scenegraph {

glm::mat4 RenderItem::modelView() const noexcept {
  glm::dmat4 m(inCamera.matrix());
  m[3] = glm::dvec4(inCamera.translation, 1.0);
  return glm::mat4(m);
}

const RenderItem* RenderList::find(std::size_t node) const noexcept {
  for (const auto& item : items)
    if (item.node == node) return &item;
  return nullptr;
}

const RenderItem* RenderList::findDrawable(int drawable) const noexcept {
  for (const auto& item : items)
    if (item.drawable == drawable) return &item;
  return nullptr;
}

}  // namespace regolith::scenegraph
