#pragma once
/// \file
/// Transforms between representations, as SimScape offers them: a planet region resampled
/// into a local tangent-plane DEM, and a DEM resampled back onto a lat/lon grid.

#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

namespace regolith::topo {

/// Resamples `planet` into a DEM on `plane` with the sample geometry `demGrid` (plane
/// metres). Each DEM height is measured along the plane's normal and solved so that the
/// DEM sample lies on the planet's interpolated surface (Newton iteration to 1e-6 m), so
/// curvature is kept, not flattened away. Samples over planet nodata or outside the planet
/// grid are NaN. The plane's body must equal the planet's (else InvalidArgument).
[[nodiscard]] TopoDem resamplePlanetToDem(const TopoPlanet& planet, const LocalTangentPlane& plane,
                                          const TopoGrid& demGrid,
                                          Interpolation interp = Interpolation::Bicubic);

/// Resamples `dem` onto the lat/lon grid `latLonGrid` (degrees, latitudes of `latitudeType`)
/// on the DEM's body. Each height is along the body normal, solved so that the point lies
/// on the DEM's interpolated surface. Samples outside the DEM or over nodata are NaN.
[[nodiscard]] TopoPlanet resampleDemToPlanet(const TopoDem& dem, const TopoGrid& latLonGrid,
                                             LatitudeType latitudeType,
                                             Interpolation interp = Interpolation::Bicubic);

}  // namespace regolith::topo
