#include <regolith/topo/Pyramid.hpp>

namespace regolith::topo {

TopoGrid coarserGrid(const TopoGrid& fine) {
  return TopoGrid((fine.rows() + 1) / 2, (fine.cols() + 1) / 2, fine.x0() + 0.5 * fine.spacingX(),
                  fine.y0() - 0.5 * fine.spacingY(), 2.0 * fine.spacingX(), 2.0 * fine.spacingY(),
                  fine.nodata());
}

}  // namespace regolith::topo
