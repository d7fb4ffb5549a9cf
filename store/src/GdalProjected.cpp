// gdal::placeThroughProj(): a GDAL raster in a projected CRS that topo has no analytic
// projection for becomes a DEM placed through PROJ (store/ProjPlacement.hpp).
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include "GdalRaster.hpp"

#include <cpl_conv.h>

namespace regolith::store::gdal {

void placeThroughProj(OGRSpatialReferenceH srs, const std::array<double, 6>& gt,
                      double metresPerUnit, GridInfo& info, const std::string& prefix,
                      const std::string& projection) {
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  const bool exported = OSRExportToWktEx(srs, &wkt, options) == OGRERR_NONE && wkt != nullptr;
  const std::string crs = exported ? wkt : "";
  CPLFree(wkt);
  if (!exported) {
    throw ImportError(prefix + ": projection " + projection + " cannot be written as WKT2");
  }
  const double dx = gt[1] * metresPerUnit, dy = -gt[5] * metresPerUnit;
  info.kind = GridKind::Dem;
  info.placement = {};
  info.placement.kind = PlacementInfo::Kind::Projected;
  info.placement.crs = crs;
  info.spacingX = dx;
  info.spacingY = dy;
  info.x0 = gt[0] * metresPerUnit + 0.5 * dx;
  info.y0 = gt[3] * metresPerUnit - 0.5 * dy;
  // The latitudes PROJ gives are planetodetic on the CRS's ellipsoid.
  info.latitudeType = topo::LatitudeType::Planetodetic;
  const double cx = info.x0 + 0.5 * static_cast<double>(info.cols - 1) * dx;
  const double cy = info.y0 - 0.5 * static_cast<double>(info.rows - 1) * dy;
  std::optional<topo::Placement> placement;
  try {
    placement.emplace(placementOf(info));
  } catch (const Error& e) {
    throw ImportError(prefix + ": projection " + projection + " cannot be used through PROJ (" +
                      e.what() + ")");
  }
  try {
    (void)placement->toGeodetic(cx, cy, 0.0);
  } catch (const Error&) {
    throw ImportError(core::format(
        {.file = prefix,
         .field = "the grid's centre (x " + core::number(cx) + ", y " + core::number(cy) + " m)",
         .value = "off the map of " + projection,
         .expected = "a grid on the projection's map"}));
  }
}

}  // namespace regolith::store::gdal
