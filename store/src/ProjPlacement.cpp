// store::projProjection(): any projected CRS as a topo::MapProjection through PROJ, one
// PJ_CONTEXT and one operation per thread (PROJ objects are not thread-safe).
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/ProjPlacement.hpp>

#include <proj.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace regolith::store {

namespace {

struct ContextDeleter {
  void operator()(PJ_CONTEXT* c) const noexcept { proj_context_destroy(c); }
};
struct PjDeleter {
  void operator()(PJ* p) const noexcept { proj_destroy(p); }
};
using Context = std::unique_ptr<PJ_CONTEXT, ContextDeleter>;
using Pj = std::unique_ptr<PJ, PjDeleter>;

Context newContext() {
  Context ctx(proj_context_create());
  if (!ctx) throw Error("store::projProjection(): PROJ cannot create a context");
  proj_log_level(ctx.get(), PJ_LOG_NONE);  // failures become exceptions, not stderr text
  return ctx;
}

std::string errorText(PJ_CONTEXT* ctx) {
  const char* s = proj_context_errno_string(ctx, proj_context_errno(ctx));
  return s != nullptr ? s : "unknown error";
}

/// The CRS of `text` on `ctx`; throws InvalidArgument unless it is a projected CRS.
Pj projectedCrs(PJ_CONTEXT* ctx, const std::string& text) {
  const std::string op = "store::projProjection()";
  Pj crs(proj_create(ctx, text.c_str()));
  if (!crs) {
    throw InvalidArgument(core::format({.operation = op,
                                        .field = "CRS",
                                        .value = "unreadable (PROJ: " + errorText(ctx) + ")",
                                        .expected = "WKT, PROJJSON or a PROJ string"}));
  }
  const PJ_TYPE type = proj_get_type(crs.get());
  if (type != PJ_TYPE_PROJECTED_CRS) {
    const char* name = proj_get_name(crs.get());
    throw InvalidArgument(core::format({.operation = op,
                                        .field = "CRS '" + std::string(name ? name : "") + "'",
                                        .value = "not a projected CRS",
                                        .expected = "a projected CRS"}));
  }
  return crs;
}

/// The conversion factor of a coordinate system's first axis (metres or radians per unit).
double axisFactor(PJ_CONTEXT* ctx, const PJ* crs) {
  const Pj cs(proj_crs_get_coordinate_system(ctx, crs));
  double factor = 0.0;
  if (!cs ||
      proj_cs_get_axis_info(ctx, cs.get(), 0, nullptr, nullptr, nullptr, &factor, nullptr, nullptr,
                            nullptr) == 0 ||
      !(factor > 0.0)) {
    throw InvalidArgument(
        "store::projProjection(): CRS axes have no usable unit (PROJ: " + errorText(ctx) + ")");
  }
  return factor;
}

/// Longitude, latitude (the base geographic CRS's units) to easting, northing (the CRS's
/// units), whatever the CRS's axis order.
Pj makeOperation(PJ_CONTEXT* ctx, const std::string& text) {
  const Pj crs = projectedCrs(ctx, text);
  const Pj geog(proj_crs_get_geodetic_crs(ctx, crs.get()));
  Pj op(geog ? proj_create_crs_to_crs_from_pj(ctx, geog.get(), crs.get(), nullptr, nullptr)
             : nullptr);
  Pj norm(op ? proj_normalize_for_visualization(ctx, op.get()) : nullptr);
  if (!norm) {
    throw InvalidArgument("store::projProjection(): PROJ cannot make the projection of '" +
                          std::string(proj_get_name(crs.get())) + "' (" + errorText(ctx) + ")");
  }
  return norm;
}

/// One thread's PROJ state: its context and the operations made on it, one per projection.
/// Operations go before their context (member order).
struct ThreadProj {
  struct Op {
    std::uint64_t id = 0;
    std::weak_ptr<const void> owner;
    Pj pj;
  };
  Context ctx;
  std::vector<Op> ops;
};

ThreadProj& threadProj() {
  thread_local ThreadProj t;
  return t;
}

std::atomic<std::uint64_t> nextId{1};

class ProjProjection final : public topo::MapProjection {
 public:
  explicit ProjProjection(const std::string& text) {
    const Context ctx = newContext();
    const Pj crs = projectedCrs(ctx.get(), text);
    const char* name = proj_get_name(crs.get());
    name_ = name != nullptr ? name : "unnamed CRS";
    const char* wkt = proj_as_wkt(ctx.get(), crs.get(), PJ_WKT2_2019, nullptr);
    if (wkt == nullptr) {
      throw InvalidArgument("store::projProjection(): PROJ cannot write '" + name_ + "' as WKT2 (" +
                            errorText(ctx.get()) + ")");
    }
    wkt_ = wkt;
    const Pj ellipsoid(proj_get_ellipsoid(ctx.get(), crs.get()));
    double b = 0.0, invF = 0.0;
    int computed = 0;
    if (!ellipsoid ||
        proj_ellipsoid_get_parameters(ctx.get(), ellipsoid.get(), &a_, &b, &computed, &invF) == 0 ||
        !(a_ > 0.0 && b > 0.0)) {
      throw InvalidArgument("store::projProjection(): '" + name_ + "' has no usable ellipsoid");
    }
    e2_ = 1.0 - (b / a_) * (b / a_);
    metresPerUnit_ = axisFactor(ctx.get(), crs.get());
    const Pj geog(proj_crs_get_geodetic_crs(ctx.get(), crs.get()));
    degreesPerUnit_ = axisFactor(ctx.get(), geog.get()) * 180.0 / std::numbers::pi;
    (void)makeOperation(ctx.get(), wkt_);  // fails here, not at the first query
  }

  [[nodiscard]] glm::dvec2 forward(const topo::LatLon& ll) const override {
    const glm::dvec2 xy =
        transform(PJ_FWD, ll.lonDeg / degreesPerUnit_, ll.latDeg / degreesPerUnit_,
                  "latitude/longitude", ll.latDeg, ll.lonDeg);
    return xy * metresPerUnit_;
  }

  [[nodiscard]] topo::LatLon inverse(const glm::dvec2& xy) const override {
    const glm::dvec2 ll = transform(PJ_INV, xy.x / metresPerUnit_, xy.y / metresPerUnit_,
                                    "map point x/y", xy.x, xy.y);
    // PROJ inverts some points off the map too (a sinusoidal map's x beyond its outline
    // wraps in longitude): a point is on the map if it comes back through the forward
    // projection, to 1e-7 of the radius (PROJ's iterative inverses are far closer).
    const glm::dvec2 back = transform(PJ_FWD, ll.x, ll.y, "latitude/longitude", ll.y, ll.x);
    const double miss = std::hypot(back.x - xy.x / metresPerUnit_, back.y - xy.y / metresPerUnit_);
    if (std::abs(ll.y * degreesPerUnit_) > 90.0 || !(miss * metresPerUnit_ <= 1e-7 * a_)) {
      throw DomainError(core::format({.operation = "MapProjection::inverse()",
                                      .field = "map point x/y through '" + name_ + "'",
                                      .value = core::number(xy.x) + ", " + core::number(xy.y),
                                      .expected = "a point on the projection's map"}));
    }
    return {ll.y * degreesPerUnit_, ll.x * degreesPerUnit_};
  }

  [[nodiscard]] const std::string& definition() const noexcept override { return wkt_; }
  [[nodiscard]] const std::string& name() const noexcept override { return name_; }
  [[nodiscard]] double equatorialRadius() const noexcept override { return a_; }
  [[nodiscard]] double eccentricitySquared() const noexcept override { return e2_; }

 private:
  std::string wkt_, name_;
  double a_ = 0.0, e2_ = 0.0, metresPerUnit_ = 1.0, degreesPerUnit_ = 1.0;
  std::uint64_t id_ = nextId.fetch_add(1);
  std::shared_ptr<const int> alive_ = std::make_shared<const int>(0);

  /// This thread's operation, made on its first use.
  [[nodiscard]] PJ* operation() const {
    ThreadProj& t = threadProj();
    for (const ThreadProj::Op& op : t.ops) {
      if (op.id == id_) return op.pj.get();
    }
    // Operations of projections that are gone are freed here, on the thread that made them.
    std::erase_if(t.ops, [](const ThreadProj::Op& op) { return op.owner.expired(); });
    if (!t.ctx) t.ctx = newContext();
    t.ops.push_back({id_, alive_, makeOperation(t.ctx.get(), wkt_)});
    return t.ops.back().pj.get();
  }

  [[nodiscard]] glm::dvec2 transform(PJ_DIRECTION dir, double u, double v, const char* what,
                                     double a, double b) const {
    PJ* op = operation();
    proj_errno_reset(op);
    const PJ_COORD out = proj_trans(op, dir, proj_coord(u, v, 0.0, 0.0));
    if (proj_errno(op) != 0 || !std::isfinite(out.xy.x) || !std::isfinite(out.xy.y) ||
        out.xy.x == HUGE_VAL) {
      throw DomainError(core::format(
          {.operation = dir == PJ_FWD ? "MapProjection::forward()" : "MapProjection::inverse()",
           .field = std::string(what) + " through '" + name_ + "'",
           .value = core::number(a) + ", " + core::number(b),
           .expected = "a point the projection maps"}));
    }
    return {out.xy.x, out.xy.y};
  }
};

}  // namespace

std::shared_ptr<const topo::MapProjection> projProjection(const std::string& crs) {
  return std::make_shared<const ProjProjection>(crs);
}

topo::Placement projPlacement(const topo::Body& body, const std::string& crs) {
  return {body, projProjection(crs)};
}

std::string projString(const std::string& crs) {
  const Context ctx = newContext();
  const Pj pj(proj_create(ctx.get(), crs.c_str()));
  const char* s = pj ? proj_as_proj_string(ctx.get(), pj.get(), PJ_PROJ_5, nullptr) : nullptr;
  return s != nullptr ? s : "";
}

}  // namespace regolith::store
