// writer::writeAttributes() and writer::createGroup(): a grid's attributes and the groups
// of a store (docs/store-format.md).
#include "WriterParts.hpp"

#include <algorithm>

namespace regolith::store::writer {

void writeAttributes(hid_t g, const GridInfo& info, bool tiled, bool statistics,
                     const Context& ctx) {
  using namespace hdf5;
  writeInt32s(g, format::kFormatVersion,
              {kFormatVersionMajor,
               std::max(kFormatVersionMinor, format::gridFormatMinor(info, tiled, statistics))},
              ctx);
  writeString(g, format::kKind,
              std::string(info.kind == GridKind::Dem ? format::kDem : format::kPlanet), ctx);
  writeUInt64(g, format::kRows, info.rows, ctx);
  writeUInt64(g, format::kCols, info.cols, ctx);
  writeDouble(g, format::kX0, info.x0, ctx);
  writeDouble(g, format::kY0, info.y0, ctx);
  writeDoubles(g, format::kSpacing, {info.spacingX, info.spacingY}, ctx);
  writeString(g, format::kUnits, info.units, ctx);
  writeString(g, format::kSampleType, std::string(format::toString(format::SampleType::Float32)),
              ctx);
  writeDouble(g, format::kScale, info.scale, ctx);
  writeDouble(g, format::kOffset, info.offset, ctx);
  // Always present: NaN says "no nodata value; missing samples are stored as NaN".
  writeFloat(g, format::kNodata, info.nodata.value_or(kNan), ctx);
  writeString(g, format::kBody, info.bodyName, ctx);
  writeDouble(g, format::kEquatorialRadius, info.equatorialRadius, ctx);
  writeDouble(g, format::kPolarRadius, info.polarRadius, ctx);
  writeString(
      g, format::kLatitudeType,
      std::string(info.latitudeType == topo::LatitudeType::Planetocentric ? format::kPlanetocentric
                                                                          : format::kPlanetodetic),
      ctx);
  writeUInt64(g, format::kLevels, info.levels, ctx);
  writeUInt64s(g, format::kPatchShape, {info.patchRows, info.patchCols}, ctx);
  if (!info.provenance.empty()) writeString(g, format::kProvenance, info.provenance, ctx);
  if (info.kind != GridKind::Dem) return;
  const PlacementInfo& p = info.placement;
  writeString(g, format::kPlacement, std::string(placementKindName(p.kind)), ctx);
  switch (p.kind) {
    case PlacementInfo::Kind::LocalTangentPlane:
      writeDouble(g, format::kOriginLat, p.originLatDeg, ctx);
      writeDouble(g, format::kOriginLon, p.originLonDeg, ctx);
      writeDouble(g, format::kOriginHeight, p.originHeight, ctx);
      writeDouble(g, format::kHeading, p.headingDeg, ctx);
      break;
    case PlacementInfo::Kind::PolarStereographic:
      writeInt32(g, format::kPole, p.pole >= 0 ? 1 : -1, ctx);
      if (p.latTrueScaleDeg) writeDouble(g, format::kLatTrueScale, *p.latTrueScaleDeg, ctx);
      if (p.scaleFactor) writeDouble(g, format::kScaleFactor, *p.scaleFactor, ctx);
      writeDouble(g, format::kLonCentre, p.lonCentreDeg, ctx);
      writeDouble(g, format::kFalseEasting, p.falseEasting, ctx);
      writeDouble(g, format::kFalseNorthing, p.falseNorthing, ctx);
      break;
    case PlacementInfo::Kind::Equirectangular:
      writeDouble(g, format::kProjectionRadius, p.projectionRadius, ctx);
      if (p.latTrueScaleDeg) writeDouble(g, format::kLatTrueScale, *p.latTrueScaleDeg, ctx);
      writeDouble(g, format::kLonCentre, p.lonCentreDeg, ctx);
      writeDouble(g, format::kLatOrigin, p.latOriginDeg, ctx);
      break;
    case PlacementInfo::Kind::TransverseMercator:
      writeDouble(g, format::kLonCentre, p.lonCentreDeg, ctx);
      writeDouble(g, format::kLatOrigin, p.latOriginDeg, ctx);
      writeDouble(g, format::kScaleFactor,
                  p.scaleFactor.value_or(std::numeric_limits<double>::quiet_NaN()), ctx);
      writeDouble(g, format::kFalseEasting, p.falseEasting, ctx);
      writeDouble(g, format::kFalseNorthing, p.falseNorthing, ctx);
      break;
    case PlacementInfo::Kind::Projected: writeString(g, format::kCrsWkt, p.crs, ctx); break;
  }
}

/// A group (no modification times: rewriting the same input changes no content).
hdf5::Group createGroup(hid_t parent, const std::string& name, const Context& ctx) {
  const hdf5::Lock lock;
  const std::string what = "cannot create group '" + name + "'";
  const hdf5::PropertyList gcpl(hdf5::check(H5Pcreate(H5P_GROUP_CREATE), ctx, what));
  hdf5::check(H5Pset_obj_track_times(gcpl.get(), 0), ctx, what);
  return hdf5::Group(hdf5::check(
      H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), ctx, what));
}

}  // namespace regolith::store::writer
