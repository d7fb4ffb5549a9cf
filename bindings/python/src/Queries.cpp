// Batch height and normal queries: numpy arrays in and out, the GIL released in the batch.
#include <regolith/core/Error.hpp>

#include "Common.hpp"

#include <glm/vec3.hpp>

#include <span>
#include <vector>

namespace regolith::python {

std::string shapeOf(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) {
    s += std::to_string(a.shape(i)) + (a.ndim() == 1 || i + 1 < a.ndim() ? "," : "");
    if (i + 1 < a.ndim()) s += " ";
  }
  return s + ")";
}

void requireRealDtype(const py::array& a) {
  const char kind = a.dtype().kind();
  if (kind == 'i' || kind == 'u' || kind == 'f') return;
  const std::string name = py::str(a.dtype());
  const char* why = kind == 'c'   ? " (its imaginary part would be dropped)"
                    : kind == 'O' ? " (None and other objects are not numbers)"
                                  : "";
  throw InvalidArgument("regolith: an array argument has dtype " + name + why +
                        ", expected real numbers (an integer or floating-point dtype)");
}

static_assert(sizeof(glm::dvec3) == 3 * sizeof(double), "glm::dvec3 must be three packed doubles");

std::vector<py::ssize_t> commonShape(const char* op, const char* na, const DoubleArray& a,
                                     const char* nb, const DoubleArray& b) {
  std::vector<py::ssize_t> shape(a.shape(), a.shape() + a.ndim());
  const std::vector<py::ssize_t> other(b.shape(), b.shape() + b.ndim());
  if (shape != other) {
    throw InvalidArgument(std::string(op) + ": " + na + " has shape " + shapeOf(a) + " and " + nb +
                          " has shape " + shapeOf(b) + ", expected the same shape");
  }
  return shape;
}

std::span<const double> spanOf(const DoubleArray& a) {
  return {a.data(), static_cast<std::size_t>(a.size())};
}

py::array_t<double> outputArray(const char* op, const char* name, const py::object& out,
                                const std::vector<py::ssize_t>& shape) {
  if (out.is_none()) return py::array_t<double>(shape);
  const auto fail = [&](const std::string& why) {
    return InvalidArgument(std::string(op) + ": " + name + " " + why);
  };
  if (!py::isinstance<py::array_t<double>>(out)) throw fail("must be a float64 numpy array");
  auto a = py::reinterpret_borrow<py::array_t<double>>(out);
  const std::vector<py::ssize_t> got(a.shape(), a.shape() + a.ndim());
  if (got != shape) throw fail("has shape " + shapeOf(a) + ", expected the shape of the result");
  if ((a.flags() & py::array::c_style) == 0) throw fail("must be C-contiguous");
  if (!a.writeable()) throw fail("is read-only");
  return a;
}

namespace {

/// Heights (and statuses) for a Dem or a Planet: fn(xs, ys, out, status).
template <class Fn>
py::object batchHeights(const char* op, const char* na, const DoubleArray& a, const char* nb,
                        const DoubleArray& b, bool withStatus, const py::object& outArg, Fn&& fn) {
  const auto shape = commonShape(op, na, a, nb, b);
  py::array_t<double> out = outputArray(op, "out", outArg, shape);
  const auto n = static_cast<std::size_t>(a.size());
  std::vector<topo::QueryStatus> status(withStatus ? n : 0);
  {
    const py::gil_scoped_release release;
    fn(spanOf(a), spanOf(b), std::span<double>(out.mutable_data(), n), std::span(status));
  }
  if (!withStatus) return out;
  py::array_t<std::uint8_t> st(shape);
  auto* s = st.mutable_data();
  for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<std::uint8_t>(status[i]);
  return py::make_tuple(out, st);
}

/// Heights and normals: fn(xs, ys, heights, normals, status, normalStatus). Returns
/// (heights, normals), then the heights' statuses if withStatus, then the normals' if
/// withNormalStatus.
template <class Fn>
py::tuple batchSurfaces(const char* op, const char* na, const DoubleArray& a, const char* nb,
                        const DoubleArray& b, bool withStatus, bool withNormalStatus,
                        const py::object& outArg, Fn&& fn) {
  const auto shape = commonShape(op, na, a, nb, b);
  auto nshape = shape;
  nshape.push_back(3);
  py::object outH = py::none(), outN = py::none();
  if (!outArg.is_none()) {
    const auto t = py::reinterpret_borrow<py::tuple>(outArg);
    if (!py::isinstance<py::tuple>(outArg) || t.size() != 2) {
      throw InvalidArgument(std::string(op) + ": out must be a (heights, normals) tuple");
    }
    outH = t[0];
    outN = t[1];
  }
  py::array_t<double> heights = outputArray(op, "out[0]", outH, shape);
  py::array_t<double> normals = outputArray(op, "out[1]", outN, nshape);
  const auto n = static_cast<std::size_t>(a.size());
  std::vector<topo::QueryStatus> status(withStatus ? n : 0);
  std::vector<topo::QueryStatus> normalStatus(withNormalStatus ? n : 0);
  {
    const py::gil_scoped_release release;
    fn(spanOf(a), spanOf(b), std::span<double>(heights.mutable_data(), n),
       std::span<glm::dvec3>(reinterpret_cast<glm::dvec3*>(normals.mutable_data()), n),
       std::span(status), std::span(normalStatus));
  }
  const auto codes = [&](const std::vector<topo::QueryStatus>& v) {
    py::array_t<std::uint8_t> st(shape);
    auto* s = st.mutable_data();
    for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<std::uint8_t>(v[i]);
    return st;
  };
  if (withStatus && withNormalStatus) {
    return py::make_tuple(heights, normals, codes(status), codes(normalStatus));
  }
  if (withStatus) return py::make_tuple(heights, normals, codes(status));
  if (withNormalStatus) return py::make_tuple(heights, normals, codes(normalStatus));
  return py::make_tuple(heights, normals);
}

const topo::TopoDem& demOf(const Terrain& t) { return *t.dem; }
const topo::TopoPlanet& planetOf(const Terrain& t) { return *t.planet; }

template <class T>
void commonMembers(py::class_<T, std::shared_ptr<T>>& c) {
  c.def_property_readonly("grid_info", [](const T& t) { return t.store->grid(t.grid); })
      .def_readonly("name", &Terrain::grid)
      .def_readonly("level", &Terrain::level)
      .def_readonly("cache", &Terrain::cache, "The Cache this grid pages through")
      .def_property_readonly(
          "store", [](const T& t) { return std::const_pointer_cast<store::Store>(t.store); })
      .def_property_readonly(
          "rows", [](const T& t) { return t.dem ? t.dem->grid().rows() : t.planet->grid().rows(); })
      .def_property_readonly(
          "cols", [](const T& t) { return t.dem ? t.dem->grid().cols() : t.planet->grid().cols(); })
      .def_property_readonly(
          "extent",
          [](const T& t) {
            const topo::TopoGrid& g = t.dem ? t.dem->grid() : t.planet->grid();
            return py::make_tuple(g.west(), g.east(), g.south(), g.north());
          },
          "(west, east, south, north) pixel extent of this level");
}

}  // namespace

void bindQueries(py::module_& m) {
  m.attr("STATUS_OK") = static_cast<int>(topo::QueryStatus::Ok);
  m.attr("STATUS_NODATA") = static_cast<int>(topo::QueryStatus::Nodata);
  m.attr("STATUS_OUTSIDE") = static_cast<int>(topo::QueryStatus::OutsideGrid);
  m.attr("STATUS_UNMAPPABLE") = static_cast<int>(topo::QueryStatus::Unmappable);

  py::class_<DemTerrain, std::shared_ptr<DemTerrain>> dem(
      m, "Dem",
      "A paged DEM (regolith.open()). Queries take grid coordinates x (east), y (north) in "
      "metres as numpy arrays of any one shape; heights are metres, NaN where the point is "
      "outside the grid or over nodata; NaN/inf coordinates raise InvalidArgument. Batches "
      "release the GIL.");
  commonMembers(dem);
  dem.def(
         "heights",
         [](const DemTerrain& t, const DoubleArray& x, const DoubleArray& y,
            const std::string& interp, bool status, const py::object& out) {
           const auto k = parseInterpolation(interp);
           return batchHeights(
               "Dem.heights()", "x", x, "y", y, status, out,
               [&](auto xs, auto ys, auto hs, auto st) { demOf(t).heights(xs, ys, hs, st, k); });
         },
         py::arg("x"), py::arg("y"), py::arg("interp") = "bilinear", py::arg("status") = false,
         py::arg("out") = py::none(),
         "Heights at (x, y); with status=True also a uint8 array of STATUS_* codes. out: a "
         "float64 array of x's shape to write into (no allocation).")
      .def(
          "surfaces",
          [](const DemTerrain& t, const DoubleArray& x, const DoubleArray& y,
             const std::string& interp, const std::string& frame, bool status,
             const py::object& out, bool normalStatus) {
            const auto k = parseInterpolation(interp);
            const auto f = parseFrame(frame);
            return batchSurfaces("Dem.surfaces()", "x", x, "y", y, status, normalStatus, out,
                                 [&](auto xs, auto ys, auto h, auto n, auto st, auto nst) {
                                   demOf(t).surfaces(xs, ys, h, n, st, k, f, nst);
                                 });
          },
          py::arg("x"), py::arg("y"), py::arg("interp") = "bilinear", py::arg("frame") = "grid",
          py::arg("status") = false, py::arg("out") = py::none(), py::arg("normal_status") = false,
          "(heights, normals[..., 3]) at (x, y); unit normals in the grid frame (x, y, h) or "
          "frame='body' (body-fixed); with status=True also the heights' STATUS_* codes, with "
          "normal_status=True (after them) the normals': a height next to a hole is valid while "
          "its normal may not be, and a normal the placement cannot map is STATUS_UNMAPPABLE. "
          "out: a (heights, normals) pair of float64 arrays to write into (no allocation).")
      .def(
          "height",
          [](const DemTerrain& t, double x, double y, const std::string& interp) {
            return demOf(t).height(x, y, parseInterpolation(interp)).height;
          },
          py::arg("x"), py::arg("y"), py::arg("interp") = "bilinear")
      .def(
          "to_body_fixed",
          [](const DemTerrain& t, const DoubleArray& x, const DoubleArray& y,
             const DoubleArray& h) {
            auto shape = commonShape("Dem.to_body_fixed()", "x", x, "y", y);
            commonShape("Dem.to_body_fixed()", "x", x, "h", h);
            shape.push_back(3);
            py::array_t<double> out(shape);
            double* o = out.mutable_data();
            for (py::ssize_t i = 0; i < x.size(); ++i) {
              const glm::dvec3 p = demOf(t).toBodyFixed(x.data()[i], y.data()[i], h.data()[i]);
              o[3 * i] = p.x, o[3 * i + 1] = p.y, o[3 * i + 2] = p.z;
            }
            return out;
          },
          py::arg("x"), py::arg("y"), py::arg("h"),
          "Body-fixed positions (metres, [..., 3]) of grid points at heights h.")
      .def("__repr__", [](const DemTerrain& t) {
        return "<regolith.Dem '" + t.grid + "' level " + std::to_string(t.level) + " of '" +
               t.store->path().string() + "'>";
      });

  py::class_<PlanetTerrain, std::shared_ptr<PlanetTerrain>> planet(
      m, "Planet",
      "A paged latitude/longitude grid (regolith.open()). Queries take latitude and east "
      "longitude in degrees as numpy arrays; normals are in the local east-north-up frame "
      "(frame='grid') or body-fixed (frame='body'). Batches release the GIL.");
  commonMembers(planet);
  planet
      .def(
          "heights",
          [](const PlanetTerrain& t, const DoubleArray& lat, const DoubleArray& lon,
             const std::string& interp, bool status, const py::object& out) {
            const auto k = parseInterpolation(interp);
            return batchHeights("Planet.heights()", "lat", lat, "lon", lon, status, out,
                                [&](auto la, auto lo, auto hs, auto st) {
                                  planetOf(t).heights(la, lo, hs, st, k);
                                });
          },
          py::arg("lat"), py::arg("lon"), py::arg("interp") = "bilinear", py::arg("status") = false,
          py::arg("out") = py::none())
      .def(
          "surfaces",
          [](const PlanetTerrain& t, const DoubleArray& lat, const DoubleArray& lon,
             const std::string& interp, const std::string& frame, bool status,
             const py::object& out, bool normalStatus) {
            const auto k = parseInterpolation(interp);
            const auto f = parseFrame(frame);
            return batchSurfaces("Planet.surfaces()", "lat", lat, "lon", lon, status, normalStatus,
                                 out, [&](auto la, auto lo, auto h, auto n, auto st, auto nst) {
                                   planetOf(t).surfaces(la, lo, h, n, st, k, f, nst);
                                 });
          },
          py::arg("lat"), py::arg("lon"), py::arg("interp") = "bilinear", py::arg("frame") = "grid",
          py::arg("status") = false, py::arg("out") = py::none(), py::arg("normal_status") = false,
          "(heights, normals[..., 3]); status=True and normal_status=True add the heights' and "
          "the normals' STATUS_* codes, as Dem.surfaces().")
      .def("__repr__", [](const PlanetTerrain& t) {
        return "<regolith.Planet '" + t.grid + "' level " + std::to_string(t.level) + " of '" +
               t.store->path().string() + "'>";
      });
  bindRender(dem, planet);
}

}  // namespace regolith::python
