// gdal::placeHeightMap(): a raster without georeferencing (8- or 16-bit PNG, a GeoTIFF without
// a CRS) placed as the caller says (ImportOptions::heightMap), or refused naming the options.
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include "GdalRaster.hpp"

#include <cctype>
#include <cmath>

namespace regolith::store::gdal {

namespace {

/// What the refusal of a raster without georeferencing suggests.
constexpr const char* kHeightMapHint =
    "; a height map imports with its spacing and placement: --spacing, --origin and --body, "
    "optionally --height-scale, --height-offset and --heading (regolith import), or spacing=, "
    "origin=, body=, height_scale=, height_offset=, heading= (regolith.import_raster())";

/// A body by its name (any case): the radii a height map's placement needs.
std::optional<topo::Body> bodyNamed(std::string name) {
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (name == "mars") return topo::Body::marsEllipsoid();
  if (name == "moon") return topo::Body::moon();
  if (name == "earth") return topo::Body::earthWgs84();
  return std::nullopt;
}

void require(bool ok, const std::string& prefix, const std::string& field, double value,
             const char* expected) {
  if (!ok) {
    throw ImportError(core::format({.file = prefix,
                                    .field = "height map " + field,
                                    .value = core::number(value),
                                    .expected = expected}));
  }
}

}  // namespace

void placeHeightMap(GDALDatasetH ds, const ImportOptions& options, Layout& l,
                    const std::string& prefix) {
  if (OGRSpatialReferenceH srs = GDALGetSpatialRef(ds)) {
    const char* name = OSRGetName(srs);
    throw ImportError(prefix + ": is georeferenced (CRS '" + (name != nullptr ? name : "") +
                      "'); expected the height-map options (spacing, origin) only for a raster "
                      "without a coordinate reference system");
  }
  if (!options.heightMap) {
    throw ImportError(prefix +
                      ": has no georeferencing (no coordinate reference system), expected a "
                      "georeferenced raster" +
                      kHeightMapHint);
  }
  const HeightMapOptions& h = *options.heightMap;
  require(std::isfinite(h.spacingX) && h.spacingX > 0.0, prefix, "spacing x", h.spacingX,
          "finite and > 0 (metres)");
  require(std::isfinite(h.spacingY) && h.spacingY > 0.0, prefix, "spacing y", h.spacingY,
          "finite and > 0 (metres)");
  require(std::isfinite(h.heightScale) && h.heightScale != 0.0, prefix, "height scale",
          h.heightScale, "finite and non-zero");
  require(std::isfinite(h.heightOffset), prefix, "height offset", h.heightOffset, "finite");
  require(std::abs(h.originLatDeg) <= 90.0, prefix, "origin latitude", h.originLatDeg,
          "within -90 to 90 deg");
  require(std::isfinite(h.originLonDeg), prefix, "origin longitude", h.originLonDeg, "finite");
  require(std::isfinite(h.headingDeg), prefix, "heading", h.headingDeg, "finite");
  const std::optional<topo::Body> body = bodyNamed(options.body);
  if (!body) {
    throw ImportError(core::format({.file = prefix,
                                    .field = "height map body",
                                    .value = "'" + options.body + "'",
                                    .expected = "Mars, Moon or Earth (--body; Python body=)"}));
  }
  GridInfo& info = l.info;
  info.kind = GridKind::Dem;
  info.bodyName = body->name();
  info.equatorialRadius = body->equatorialRadius();
  info.polarRadius = body->polarRadius();
  info.latitudeType = topo::LatitudeType::Planetodetic;
  info.placement = {};
  info.placement.kind = PlacementInfo::Kind::LocalTangentPlane;
  info.placement.originLatDeg = h.originLatDeg;
  info.placement.originLonDeg = h.originLonDeg;
  info.placement.headingDeg = h.headingDeg;
  info.spacingX = h.spacingX;
  info.spacingY = h.spacingY;
  // The centre sample at the plane's origin.
  info.x0 = -0.5 * static_cast<double>(info.cols - 1) * h.spacingX;
  info.y0 = 0.5 * static_cast<double>(info.rows - 1) * h.spacingY;
  l.offset = h.heightOffset + h.heightScale * l.offset;
  l.scale = h.heightScale * l.scale;
  l.projection = "none: height map on the local tangent plane at lat " +
                 core::number(h.originLatDeg) + ", lon " + core::number(h.originLonDeg) +
                 " deg, heading " + core::number(h.headingDeg) + " deg";
}

}  // namespace regolith::store::gdal
