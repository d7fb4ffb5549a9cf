#include <regolith/scenegraph/StorePyramid.hpp>
#include <regolith/store/GridInfo.hpp>

#include <optional>
#include <utility>
#include <vector>

namespace regolith::scenegraph {

std::shared_ptr<const clod::HeightPyramid> pyramidFromStore(const store::Pager& pager,
                                                            const std::string& grid) {
  const store::GridInfo& info = pager.store().grid(grid);
  std::vector<clod::HeightPyramid::Level> levels;
  levels.reserve(info.levels);
  for (std::size_t l = 0; l < info.levels; ++l)
    levels.push_back({store::topoGridOf(info, l), pager.source(grid, l)});
  const bool planet = info.kind == store::GridKind::Planet;
  return std::make_shared<const clod::HeightPyramid>(
      std::move(levels), planet ? clod::SurfaceKind::Planet : clod::SurfaceKind::Plane,
      planet ? std::optional<topo::Body>(store::bodyOf(info)) : std::nullopt, info.latitudeType);
}

}  // namespace regolith::scenegraph
