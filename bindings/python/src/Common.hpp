#pragma once
// Shared by the binding sources: the terrain handles Python holds, and argument parsing.

#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Query.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace regolith::gl {
struct RgbaImage;
}  // namespace regolith::gl

namespace regolith::python {

namespace py = pybind11;

/// A paged grid as Python sees it: the store and the cache it pages through stay alive as
/// long as the handle does. Exactly one of dem / planet is set.
struct Terrain {
  std::shared_ptr<const store::Store> store;
  std::shared_ptr<store::PatchCache> cache;
  std::string grid;
  std::size_t level = 0;
  std::optional<topo::TopoDem> dem;
  std::optional<topo::TopoPlanet> planet;
};
/// Distinct types for Python's Dem and Planet classes.
struct DemTerrain : Terrain {};
struct PlanetTerrain : Terrain {};

/// C-contiguous float64 view of any array-like of real numbers (copies only if it is not
/// one already). Its caster (below) refuses, with InvalidArgument (ValueError), what numpy
/// would cast with a loss: complex numbers (the imaginary part dropped), objects (None
/// becomes NaN), booleans, strings. Every call that takes arrays takes them as DoubleArray.
class DoubleArray : public py::array_t<double, py::array::c_style | py::array::forcecast> {
 public:
  using array_t::array_t;
  DoubleArray() = default;
  explicit DoubleArray(array_t&& a) : array_t(std::move(a)) {}
};

/// Throws InvalidArgument unless `a`'s dtype holds real numbers (numpy kinds i, u, f).
void requireRealDtype(const py::array& a);

/// Checks that a and b (named na, nb in the message of `op`) have one shape; returns it.
std::vector<py::ssize_t> commonShape(const char* op, const char* na, const DoubleArray& a,
                                     const char* nb, const DoubleArray& b);
/// The array's values as one span (DoubleArray is C-contiguous).
[[nodiscard]] std::span<const double> spanOf(const DoubleArray& a);
/// `out` if given (a writable, C-contiguous float64 array of `shape`: results are written
/// into it, so repeated batches allocate nothing), else a new array.
[[nodiscard]] py::array_t<double> outputArray(const char* op, const char* name,
                                              const py::object& out,
                                              const std::vector<py::ssize_t>& shape);

[[nodiscard]] topo::Interpolation parseInterpolation(const std::string& name);
[[nodiscard]] topo::NormalFrame parseFrame(const std::string& name);
[[nodiscard]] store::CachePolicy parsePolicy(const std::string& name);
[[nodiscard]] std::string policyName(store::CachePolicy p);
[[nodiscard]] py::dict statsDict(const store::CacheStats& s);
/// "(2, 3)", "(5,)": an array's shape as Python prints it, for messages.
[[nodiscard]] std::string shapeOf(const py::array& a);
/// A rendered image as a (height, width, 4) uint8 RGBA array (a copy).
[[nodiscard]] py::array_t<std::uint8_t> imageArray(const gl::RgbaImage& img);

void bindErrors(py::module_& m);
void bindStore(py::module_& m);
void bindQueries(py::module_& m);
/// Catalogue files and composed surfaces (compose/): Catalogue, read_catalogue(),
/// ComposedSurface.
void bindCompose(py::module_& m);
/// Adds render() to the Dem and Planet classes.
void bindRender(py::class_<DemTerrain, std::shared_ptr<DemTerrain>>& dem,
                py::class_<PlanetTerrain, std::shared_ptr<PlanetTerrain>>& planet);
void bindRover(py::module_& m);
/// The paper's example scene: paper_scene(), render_scene(), render_flyover().
void bindScene(py::module_& m);
/// regolith.load_scene() and SceneFile (SceneFile.cpp).
void bindSceneFile(py::module_& m);

}  // namespace regolith::python

namespace pybind11::detail {

/// Loads a DoubleArray: what numpy makes of the argument (np.asarray), refused unless its
/// dtype holds real numbers, then converted to C-contiguous float64.
template <>
struct type_caster<regolith::python::DoubleArray> {
  PYBIND11_TYPE_CASTER(regolith::python::DoubleArray, const_name("numpy.ndarray[float64]"));

  bool load(handle src, bool convert) {
    using Base = regolith::python::DoubleArray::array_t;
    if (!convert && !Base::check_(src)) return false;
    const array any = array::ensure(src);
    if (!any) return false;
    regolith::python::requireRealDtype(any);
    Base a = Base::ensure(any);
    if (!a) return false;
    value = regolith::python::DoubleArray(std::move(a));
    return true;
  }

  static handle cast(const regolith::python::DoubleArray& src, return_value_policy, handle) {
    return src.inc_ref();
  }
};

}  // namespace pybind11::detail
