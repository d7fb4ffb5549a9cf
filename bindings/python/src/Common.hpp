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
#include <string>

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

/// C-contiguous float64 view of any array-like (copies only if it is not one already).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

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
/// Adds render() to the Dem and Planet classes.
void bindRender(py::class_<DemTerrain, std::shared_ptr<DemTerrain>>& dem,
                py::class_<PlanetTerrain, std::shared_ptr<PlanetTerrain>>& planet);
void bindRover(py::module_& m);
/// The paper's example scene: paper_scene(), render_scene(), render_flyover().
void bindScene(py::module_& m);

}  // namespace regolith::python
