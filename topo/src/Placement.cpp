#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/topo/Placement.hpp>

#include <glm/geometric.hpp>

#include <cmath>
#include <string>

namespace regolith::topo {

Placement::Placement(LocalTangentPlane plane)
    : body_(plane.body()), latType_(LatitudeType::Planetodetic), proj_(std::move(plane)) {}

Placement::Placement(const Body& body, PolarStereographic projection)
    : body_(body), latType_(LatitudeType::Planetodetic), proj_(projection) {}

Placement::Placement(const Body& body, Equirectangular projection, LatitudeType latitudeType)
    : body_(body), latType_(latitudeType), proj_(projection) {}

namespace {

/// Throws InvalidArgument unless a projection's ellipsoid (its latitudes are planetodetic on
/// it) is the body's: another body would put every sample somewhere else.
void requireBodysEllipsoid(const Body& body, double a, double e2, const char* what) {
  const double ba = body.equatorialRadius(), be2 = body.eccentricitySquared();
  if (std::abs(a - ba) > 1e-9 * ba || std::abs(e2 - be2) > 1e-12) {
    throw InvalidArgument(std::string("Placement(): the ") + what +
                          " projection is on an ellipsoid of a = " + core::number(a) +
                          " m, e^2 = " + core::number(e2) + ", expected the body's (" +
                          body.name() + ": a = " + core::number(ba) +
                          " m, e^2 = " + core::number(be2) + ")");
  }
}

}  // namespace

Placement::Placement(const Body& body, TransverseMercator projection)
    : body_(body), latType_(LatitudeType::Planetodetic), proj_(projection) {
  requireBodysEllipsoid(body, projection.equatorialRadius(), projection.eccentricitySquared(),
                        "transverse Mercator");
}

Placement::Placement(const Body& body, std::shared_ptr<const MapProjection> projection)
    : body_(body), latType_(LatitudeType::Planetodetic), proj_(projection) {
  if (!projection) throw InvalidArgument("Placement(): the map projection is null");
  requireBodysEllipsoid(body, projection->equatorialRadius(), projection->eccentricitySquared(),
                        ("'" + projection->name() + "'").c_str());
}

Placement::Kind Placement::kind() const noexcept {
  switch (proj_.index()) {
    case 0: return Kind::LocalTangentPlane;
    case 1: return Kind::PolarStereographic;
    case 2: return Kind::Equirectangular;
    case 3: return Kind::TransverseMercator;
    default: return Kind::Projected;
  }
}

const LocalTangentPlane* Placement::localTangentPlane() const noexcept {
  return std::get_if<LocalTangentPlane>(&proj_);
}
const PolarStereographic* Placement::polarStereographic() const noexcept {
  return std::get_if<PolarStereographic>(&proj_);
}
const Equirectangular* Placement::equirectangular() const noexcept {
  return std::get_if<Equirectangular>(&proj_);
}
const TransverseMercator* Placement::transverseMercator() const noexcept {
  return std::get_if<TransverseMercator>(&proj_);
}
const MapProjection* Placement::mapProjection() const noexcept {
  const auto* p = std::get_if<std::shared_ptr<const MapProjection>>(&proj_);
  return p != nullptr ? p->get() : nullptr;
}

Geodetic Placement::toGeodetic(double x, double y, double h) const {
  if (const auto* ltp = localTangentPlane()) return ltp->inverse({x, y, h});
  LatLon ll;
  if (const auto* ps = polarStereographic()) {
    ll = ps->inverse({x, y});
  } else if (const auto* tm = transverseMercator()) {
    ll = tm->inverse({x, y});
  } else if (const auto* mp = mapProjection()) {
    ll = mp->inverse({x, y});
  } else {
    ll = equirectangular()->inverse({x, y});
    ll.latDeg = body_.toPlanetodetic(ll.latDeg, latType_);
  }
  return {ll.latDeg, ll.lonDeg, h};
}

glm::dvec3 Placement::toBodyFixed(double x, double y, double h) const {
  if (const auto* ltp = localTangentPlane()) {
    requireFinite(x, "Placement::toBodyFixed()", "x");
    requireFinite(y, "Placement::toBodyFixed()", "y");
    requireFinite(h, "Placement::toBodyFixed()", "height");
    return ltp->toBodyFixed({x, y, h});
  }
  return body_.toBodyFixed(toGeodetic(x, y, h));
}

glm::dvec3 Placement::fromGeodetic(const Geodetic& g) const {
  if (const auto* ltp = localTangentPlane()) return ltp->forward(g);
  glm::dvec2 xy;
  if (const auto* ps = polarStereographic()) {
    xy = ps->forward({g.latDeg, g.lonDeg});
  } else if (const auto* tm = transverseMercator()) {
    xy = tm->forward({g.latDeg, g.lonDeg});
  } else if (const auto* mp = mapProjection()) {
    xy = mp->forward({g.latDeg, g.lonDeg});
  } else {
    xy = equirectangular()->forward({body_.fromPlanetodetic(g.latDeg, latType_), g.lonDeg});
  }
  return {xy.x, xy.y, g.height};
}

glm::dvec3 Placement::fromGeodeticNear(const Geodetic& g, double xNear) const {
  if (const auto* eqc = equirectangular()) {
    const glm::dvec2 xy =
        eqc->forwardNear({body_.fromPlanetodetic(g.latDeg, latType_), g.lonDeg}, xNear);
    return {xy.x, xy.y, g.height};
  }
  return fromGeodetic(g);
}

glm::dvec3 Placement::fromBodyFixed(const glm::dvec3& p) const {
  if (const auto* ltp = localTangentPlane()) return ltp->fromBodyFixed(p);
  return fromGeodetic(body_.toGeodetic(p));
}

glm::dmat3 Placement::jacobian(double x, double y, double h) const {
  if (const auto* ltp = localTangentPlane()) {
    return glm::dmat3(ltp->xAxis(), ltp->yAxis(), ltp->zAxis());
  }
  // Central differences: the projections are smooth at the metre scale, so the truncation
  // error (~(δ/R)²) and the rounding error (~1e-16·R/δ) are both ~1e-10 relative or less.
  // Within δ of the edge of the projection's domain (a pole an equirectangular map reaches)
  // the step beyond it has no image: the derivative is then one-sided, of second order too,
  // (−3P(0) + 4P(δ) − P(2δ)) / 2δ towards the domain. A point that is itself outside the
  // domain throws DomainError.
  constexpr double d = 0.5;
  const auto partial = [&](double ex, double ey) {
    try {
      return (toBodyFixed(x + d * ex, y + d * ey, h) - toBodyFixed(x - d * ex, y - d * ey, h)) /
             (2.0 * d);
    } catch (const DomainError&) {
      const glm::dvec3 p0 = toBodyFixed(x, y, h);
      for (const double sign : {1.0, -1.0}) {
        try {
          const glm::dvec3 p1 = toBodyFixed(x + sign * d * ex, y + sign * d * ey, h);
          const glm::dvec3 p2 = toBodyFixed(x + 2.0 * sign * d * ex, y + 2.0 * sign * d * ey, h);
          return sign * (-3.0 * p0 + 4.0 * p1 - p2) / (2.0 * d);
        } catch (const DomainError&) {  // NOLINT(bugprone-empty-catch): try the other side
        }
      }
      throw;
    }
  };
  const glm::dvec3 px = partial(1.0, 0.0);
  const glm::dvec3 py = partial(0.0, 1.0);
  const Geodetic g = toGeodetic(x, y, h);
  const glm::dvec3 up = body_.enuFrame(g.latDeg, g.lonDeg)[2];
  return glm::dmat3(px, py, up);
}

glm::dvec3 Placement::normalToBodyFixed(const glm::dvec3& n, double x, double y, double h) const {
  const glm::dmat3 j = jacobian(x, y, h);
  if (localTangentPlane() != nullptr) return glm::normalize(j * n);
  // The surface is S(x, y) = P(x, y, h(x, y)); the grid normal (−hx, −hy, 1)·s encodes the
  // slopes. Tangents S_x = P_x + P_h·hx and S_y = P_y + P_h·hy; the normal is their cross.
  const double hx = -n.x / n.z, hy = -n.y / n.z;
  const glm::dvec3 sx = j[0] + j[2] * hx;
  const glm::dvec3 sy = j[1] + j[2] * hy;
  return glm::normalize(glm::cross(sx, sy));
}

}  // namespace regolith::topo
