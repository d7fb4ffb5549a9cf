#pragma once
/// \file
/// Placements through PROJ: any projected CRS PROJ knows (sinusoidal, Lambert conformal conic,
/// orthographic, Mollweide, ...) as a topo::MapProjection. The import chooses topo's analytic
/// projections where they apply (equirectangular on a sphere, polar stereographic, transverse
/// Mercator) and this one for the rest; stores record its CRS as WKT2 (docs/store-format.md).

#include <regolith/topo/MapProjection.hpp>
#include <regolith/topo/Placement.hpp>

#include <memory>
#include <string>

namespace regolith::store {

/// The projection of a projected CRS given as text PROJ reads (WKT1 or WKT2, PROJJSON, a PROJ
/// string with +type=crs): map metres (x east, y north, false easting/northing included;
/// other linear units converted) from and to planetodetic degrees on the CRS's own ellipsoid.
/// Thread-safe: every thread that calls it gets its own PJ_CONTEXT and PROJ operation (PROJ's
/// objects are not thread-safe), made on its first call and freed when the thread ends or, on
/// its next call after this projection is gone, at once. definition() is the CRS as WKT2_2019.
/// Throws InvalidArgument if PROJ cannot read the text or it is not a projected CRS.
[[nodiscard]] std::shared_ptr<const topo::MapProjection> projProjection(const std::string& crs);

/// The placement of a DEM in `crs` on `body` (projProjection() on it). Throws InvalidArgument
/// as projProjection() does, and if the CRS's ellipsoid is not the body's.
[[nodiscard]] topo::Placement projPlacement(const topo::Body& body, const std::string& crs);

/// The PROJ string of a CRS (for people: `regolith info`), e.g. "+proj=sinu +lon_0=137
/// +x_0=0 +y_0=0 +R=3396190 +units=m +no_defs +type=crs"; empty if PROJ cannot write one.
[[nodiscard]] std::string projString(const std::string& crs);

}  // namespace regolith::store
