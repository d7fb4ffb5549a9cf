#pragma once
/// \file
/// A store's grid as the renderer's height pyramid.

#include <regolith/clod/HeightPyramid.hpp>
#include <regolith/store/Pager.hpp>

#include <memory>
#include <string>

namespace regolith::scenegraph {

/// One grid of a store as clod's height pyramid: one level per stored pyramid level, each
/// read through `pager` (rendering pages patches into the pager's cache, so memory stays
/// within its budget). A DEM is a plane pyramid in its grid frame (x east, y north, z up); a
/// planet grid is drawn on its body in body-fixed metres, with the grid's latitude type.
/// The pager must outlive nothing: the pyramid's sources keep the store and cache alive.
/// Throws StoreError for an unknown grid.
[[nodiscard]] std::shared_ptr<const clod::HeightPyramid> pyramidFromStore(const store::Pager& pager,
                                                                          const std::string& grid);

}  // namespace regolith::scenegraph
