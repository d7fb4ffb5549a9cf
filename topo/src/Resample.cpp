#include <regolith/core/Error.hpp>
#include <regolith/topo/Resample.hpp>

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace regolith::topo {
namespace {
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kTolerance = 1e-6;  // metres
constexpr int kMaxIterations = 20;

bool sameBody(const Body& a, const Body& b) {
  return a.equatorialRadius() == b.equatorialRadius() && a.polarRadius() == b.polarRadius();
}
}  // namespace

TopoDem resamplePlanetToDem(const TopoPlanet& planet, const LocalTangentPlane& plane,
                            const TopoGrid& demGrid, Interpolation interp) {
  const Body& body = planet.body();
  if (!sameBody(body, plane.body())) {
    throw InvalidArgument("resamplePlanetToDem(): the plane is on body '" + plane.body().name() +
                          "', expected the planet's body '" + body.name() + "' (same radii)");
  }
  std::vector<float> out(demGrid.rows() * demGrid.cols());
  for (std::size_t r = 0; r < demGrid.rows(); ++r) {
    for (std::size_t c = 0; c < demGrid.cols(); ++c) {
      const glm::dvec2 xy = demGrid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      double z = 0.0, result = kNan;
      for (int it = 0; it < kMaxIterations; ++it) {
        const glm::dvec3 p = plane.toBodyFixed({xy.x, xy.y, z});
        const Geodetic g = body.toGeodetic(p);
        const HeightSample t = planet.height(
            {body.fromPlanetodetic(g.latDeg, planet.latitudeType()), g.lonDeg}, interp);
        if (!t.valid()) break;
        // p is g.height − t above the terrain along the body normal; move along the plane
        // normal by the matching amount.
        const double above = g.height - t.height;
        const double cosAngle = glm::dot(plane.zAxis(), body.enuFrame(g.latDeg, g.lonDeg)[2]);
        z -= above / cosAngle;
        if (std::abs(above) < kTolerance) {
          result = z;
          break;
        }
      }
      out[r * demGrid.cols() + c] = static_cast<float>(result);
    }
  }
  TopoGrid grid(demGrid.rows(), demGrid.cols(), demGrid.x0(), demGrid.y0(), demGrid.spacingX(),
                demGrid.spacingY());
  return {grid, Placement(plane),
          std::make_shared<InMemorySamples>(demGrid.rows(), demGrid.cols(), std::move(out))};
}

TopoPlanet resampleDemToPlanet(const TopoDem& dem, const TopoGrid& latLonGrid,
                               LatitudeType latitudeType, Interpolation interp) {
  const Body& body = dem.body();
  const Placement& pl = dem.placement();
  std::vector<float> out(latLonGrid.rows() * latLonGrid.cols());
  for (std::size_t r = 0; r < latLonGrid.rows(); ++r) {
    for (std::size_t c = 0; c < latLonGrid.cols(); ++c) {
      const glm::dvec2 ll = latLonGrid.sampleCentre(static_cast<double>(r), static_cast<double>(c));
      const double latD = body.toPlanetodetic(ll.y, latitudeType);
      const glm::dvec3 up = body.enuFrame(latD, ll.x)[2];
      double h = 0.0, result = kNan;
      for (int it = 0; it < kMaxIterations; ++it) {
        const glm::dvec3 p = body.toBodyFixed({latD, ll.x, h});
        const glm::dvec3 q = pl.fromBodyFixed(p);
        const HeightSample t = dem.height(q.x, q.y, interp);
        if (!t.valid()) break;
        const double above = q.z - t.height;  // along the DEM's height direction
        const glm::dvec3 demUp = pl.jacobian(q.x, q.y, q.z)[2];
        h -= above / glm::dot(up, glm::normalize(demUp));
        if (std::abs(above) < kTolerance) {
          result = h;
          break;
        }
      }
      out[r * latLonGrid.cols() + c] = static_cast<float>(result);
    }
  }
  TopoGrid grid(latLonGrid.rows(), latLonGrid.cols(), latLonGrid.x0(), latLonGrid.y0(),
                latLonGrid.spacingX(), latLonGrid.spacingY());
  return {grid, body, latitudeType,
          std::make_shared<InMemorySamples>(latLonGrid.rows(), latLonGrid.cols(), std::move(out))};
}

}  // namespace regolith::topo
