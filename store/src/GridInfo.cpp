#include <regolith/core/Error.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/ProjPlacement.hpp>

#include "StoreFormat.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace regolith::store {

std::string_view placementKindName(PlacementInfo::Kind kind) noexcept {
  switch (kind) {
    case PlacementInfo::Kind::LocalTangentPlane: return format::kLocalTangentPlane;
    case PlacementInfo::Kind::PolarStereographic: return format::kPolarStereographic;
    case PlacementInfo::Kind::Equirectangular: return format::kEquirectangular;
    case PlacementInfo::Kind::TransverseMercator: return format::kTransverseMercator;
    case PlacementInfo::Kind::Projected: return format::kProjected;
  }
  return "unknown";
}

std::string_view placementKindName(topo::Placement::Kind kind) noexcept {
  using K = topo::Placement::Kind;
  switch (kind) {
    case K::LocalTangentPlane: return placementKindName(PlacementInfo::Kind::LocalTangentPlane);
    case K::PolarStereographic: return placementKindName(PlacementInfo::Kind::PolarStereographic);
    case K::Equirectangular: return placementKindName(PlacementInfo::Kind::Equirectangular);
    case K::TransverseMercator: return placementKindName(PlacementInfo::Kind::TransverseMercator);
    case K::Projected: return placementKindName(PlacementInfo::Kind::Projected);
  }
  return "unknown";
}

topo::Body bodyOf(const GridInfo& info) {
  if (info.equatorialRadius == info.polarRadius) {
    return topo::Body::sphere(info.bodyName, info.equatorialRadius);
  }
  return topo::Body::ellipsoid(info.bodyName, info.equatorialRadius, info.polarRadius);
}

topo::TopoGrid topoGridOf(const GridInfo& info, std::size_t level) {
  // Level k's sample (r, c) is the mean of level 0's samples 2^k·r … 2^k·r + 2^k − 1, so
  // its centre sits (2^k − 1)/2 level-0 spacings beyond sample (0, 0)'s.
  const double f = static_cast<double>(std::size_t{1} << level);
  const double shift = 0.5 * (f - 1.0);
  return {info.levelRows(level),
          info.levelCols(level),
          info.x0 + shift * info.spacingX,
          info.y0 - shift * info.spacingY,
          f * info.spacingX,
          f * info.spacingY,
          std::nullopt};
}

topo::Placement placementOf(const GridInfo& info) {
  if (info.kind != GridKind::Dem) {
    throw InvalidArgument("store::placementOf(): grid '" + info.name +
                          "' is a planet grid, expected a DEM");
  }
  const topo::Body body = bodyOf(info);
  const PlacementInfo& p = info.placement;
  switch (p.kind) {
    case PlacementInfo::Kind::LocalTangentPlane:
      return topo::Placement(topo::LocalTangentPlane(
          body, {p.originLatDeg, p.originLonDeg, p.originHeight}, p.headingDeg));
    case PlacementInfo::Kind::PolarStereographic: {
      const auto pole = p.pole >= 0 ? topo::PolarStereographic::Pole::North
                                    : topo::PolarStereographic::Pole::South;
      if (p.latTrueScaleDeg.has_value() == p.scaleFactor.has_value()) {
        throw InvalidArgument("store::placementOf(): grid '" + info.name +
                              "' polar stereographic placement needs exactly one of "
                              "lat_true_scale and scale_factor");
      }
      if (p.latTrueScaleDeg) {
        return {body, topo::PolarStereographic::withTrueScaleLatitude(
                          body, pole, *p.latTrueScaleDeg, p.lonCentreDeg, p.falseEasting,
                          p.falseNorthing)};
      }
      return {body,
              topo::PolarStereographic::withScaleFactor(body, pole, *p.scaleFactor, p.lonCentreDeg,
                                                        p.falseEasting, p.falseNorthing)};
    }
    case PlacementInfo::Kind::TransverseMercator:
      if (!p.scaleFactor) {
        throw InvalidArgument("store::placementOf(): grid '" + info.name +
                              "' transverse Mercator placement has no scale_factor");
      }
      return {body, topo::TransverseMercator(body, p.lonCentreDeg, p.latOriginDeg, *p.scaleFactor,
                                             p.falseEasting, p.falseNorthing)};
    case PlacementInfo::Kind::Equirectangular:
      return {body,
              topo::Equirectangular(p.projectionRadius, p.latTrueScaleDeg.value_or(0.0),
                                    p.lonCentreDeg, p.latOriginDeg),
              info.latitudeType};
    case PlacementInfo::Kind::Projected: return projPlacement(body, p.crs);
  }
  throw InvalidArgument("store::placementOf(): grid '" + info.name + "' has an unknown placement");
}

PlacementInfo placementInfoOf(const topo::Placement& placement) {
  PlacementInfo p;
  if (const auto* ltp = placement.localTangentPlane()) {
    p.kind = PlacementInfo::Kind::LocalTangentPlane;
    p.originLatDeg = ltp->origin().latDeg;
    p.originLonDeg = ltp->origin().lonDeg;
    p.originHeight = ltp->origin().height;
    p.headingDeg = ltp->headingDeg();
  } else if (const auto* ps = placement.polarStereographic()) {
    p.kind = PlacementInfo::Kind::PolarStereographic;
    p.pole = ps->pole() == topo::PolarStereographic::Pole::North ? 1 : -1;
    p.scaleFactor = ps->scaleFactorAtPole();
    p.lonCentreDeg = ps->lonCentreDeg();
    p.falseEasting = ps->falseEasting();
    p.falseNorthing = ps->falseNorthing();
  } else if (const auto* eq = placement.equirectangular()) {
    p.kind = PlacementInfo::Kind::Equirectangular;
    p.projectionRadius = eq->radius();
    p.latTrueScaleDeg = eq->latTrueScaleDeg();
    p.lonCentreDeg = eq->lonCentreDeg();
    p.latOriginDeg = eq->latOriginDeg();
  } else if (const auto* tm = placement.transverseMercator()) {
    p.kind = PlacementInfo::Kind::TransverseMercator;
    p.lonCentreDeg = tm->lonCentreDeg();
    p.latOriginDeg = tm->latOriginDeg();
    p.scaleFactor = tm->scaleFactor();
    p.falseEasting = tm->falseEasting();
    p.falseNorthing = tm->falseNorthing();
  } else if (const auto* mp = placement.mapProjection()) {
    p.kind = PlacementInfo::Kind::Projected;
    p.crs = mp->definition();
  }
  return p;
}

}  // namespace regolith::store
