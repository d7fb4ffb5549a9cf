// Catalogue files and their composed surfaces (compose/, docs/composition.md): numpy arrays
// of latitudes and longitudes in, composed heights, normals, statuses and the number of
// contributing datasets out.
#include <regolith/compose/FromStore.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/store/Store.hpp>

#include "Common.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace regolith::python {

namespace {

/// A catalogue file as Python holds it: what readCatalogueFile() returned (its pagers keep
/// the stores and the cache alive), its path, and its datasets in file order.
struct PyCatalogue {
  std::filesystem::path path;
  compose::CatalogueFile file;
  std::shared_ptr<const compose::Snapshot> snapshot;
  std::vector<std::shared_ptr<const compose::Dataset>> datasets;  ///< in file order
  std::vector<compose::DatasetId> ids;                            ///< in file order
  std::unordered_map<compose::DatasetId, py::ssize_t> index;      ///< id -> index in the file

  /// The index in the file of dataset `id`; -1 if it is not one of the file's.
  [[nodiscard]] py::ssize_t indexOf(compose::DatasetId id) const {
    const auto it = index.find(id);
    return it == index.end() ? -1 : it->second;
  }
};

/// A composed surface, keeping its catalogue (stores, cache) alive.
struct PySurface {
  std::shared_ptr<PyCatalogue> catalogue;
  compose::ComposedSurface surface;
};

std::shared_ptr<PyCatalogue> readCatalogue(const std::filesystem::path& path,
                                           std::size_t cacheBytes) {
  if (cacheBytes == 0) {
    throw InvalidArgument("regolith.read_catalogue(): cache_bytes is 0, expected > 0");
  }
  auto c = std::make_shared<PyCatalogue>();
  c->path = path;
  {
    const py::gil_scoped_release release;  // opens every store of the file
    c->file = compose::readCatalogueFile(path, cacheBytes);
  }
  c->snapshot = c->file.catalogue->snapshot();
  c->ids = c->file.ids;
  std::unordered_map<compose::DatasetId, std::shared_ptr<const compose::Dataset>> byId;
  for (const compose::CatalogueEntry& e : c->snapshot->entries()) byId.emplace(e.id, e.dataset);
  for (std::size_t i = 0; i < c->ids.size(); ++i) {
    c->datasets.push_back(byId.at(c->ids[i]));
    c->index.emplace(c->ids[i], static_cast<py::ssize_t>(i));
  }
  return c;
}

/// One dataset as a dict, with the keys of `regolith info CATALOGUE --json` (docs/cli.md).
py::dict datasetDict(std::size_t index, compose::DatasetId id, const compose::Dataset& d) {
  const topo::TopoGrid& g = d.level(0).grid;
  const compose::DatasetOptions& o = d.options();
  py::dict j;
  j["index"] = index;
  j["id"] = id;
  j["name"] = d.name();
  j["kind"] = d.isPlanet() ? "planet" : "dem";
  j["placement"] =
      d.isPlanet()
          ? py::object(py::none())
          : py::object(py::str(std::string(store::placementKindName(d.placement()->kind()))));
  j["latitude_type"] =
      d.latitudeType() == topo::LatitudeType::Planetocentric ? "planetocentric" : "planetodetic";
  j["role"] = compose::roleName(o.role);
  j["priority"] = o.priority;
  j["feather_m"] = o.featherMetres;
  j["mask"] = o.mask != nullptr;
  j["rows"] = g.rows();
  j["cols"] = g.cols();
  j["spacing"] = py::make_tuple(g.spacingX(), g.spacingY());
  j["ground_spacing_m"] = d.groundSpacing();
  j["levels"] = d.levelCount();
  py::dict extent;
  extent["west"] = g.west();
  extent["east"] = g.east();
  extent["north"] = g.north();
  extent["south"] = g.south();
  j["extent"] = extent;
  j["height_range"] = py::make_tuple(d.heightRange()[0], d.heightRange()[1]);
  const auto& b = d.bounds();
  py::dict bounds;
  bounds["min"] = py::make_tuple(b[0].x, b[0].y, b[0].z);
  bounds["max"] = py::make_tuple(b[1].x, b[1].y, b[1].z);
  j["bounds"] = bounds;
  return j;
}

compose::Policy parseComposePolicy(const std::string& name) {
  if (name == "weighted") return compose::Policy::Weighted;
  if (name == "finest") return compose::Policy::FinestWins;
  throw InvalidArgument("regolith: composition policy '" + name +
                        "' is unknown, expected 'weighted' or 'finest'");
}

bool pointOk(double lat, double lon) {
  return std::isfinite(lat) && std::isfinite(lon) && std::abs(lat) <= 90.0;
}

py::array_t<std::uint8_t> statusArray(const std::vector<py::ssize_t>& shape,
                                      const std::vector<topo::QueryStatus>& v) {
  py::array_t<std::uint8_t> st(shape);
  auto* s = st.mutable_data();
  for (std::size_t i = 0; i < v.size(); ++i) s[i] = static_cast<std::uint8_t>(v[i]);
  return st;
}

py::array_t<std::uint32_t> countArray(const std::vector<py::ssize_t>& shape,
                                      const std::vector<std::uint32_t>& v) {
  py::array_t<std::uint32_t> a(shape);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

/// ComposedSurface.heights(): the library's batch (with each point's number of datasets with
/// a share of its height, if asked).
py::object heights(const PySurface& s, const DoubleArray& lat, const DoubleArray& lon,
                   bool withStatus, bool withContributors, const py::object& outArg) {
  const char* op = "ComposedSurface.heights()";
  const auto shape = commonShape(op, "lat", lat, "lon", lon);
  py::array_t<double> out = outputArray(op, "out", outArg, shape);
  const auto n = static_cast<std::size_t>(lat.size());
  std::vector<topo::QueryStatus> status(n);
  std::vector<std::uint32_t> contributors(withContributors ? n : 0);
  {
    const py::gil_scoped_release release;
    const std::span<double> h(out.mutable_data(), n);
    s.surface.heights(spanOf(lat), spanOf(lon), h, status, contributors);
  }
  if (!withStatus && !withContributors) return out;
  if (withStatus && withContributors) {
    return py::make_tuple(out, statusArray(shape, status), countArray(shape, contributors));
  }
  if (withStatus) return py::make_tuple(out, statusArray(shape, status));
  return py::make_tuple(out, countArray(shape, contributors));
}

/// ComposedSurface.surfaces(): (heights, normals), then the statuses, the normals' statuses
/// and the contributor counts that were asked for, in that order.
py::tuple surfaces(const PySurface& s, const DoubleArray& lat, const DoubleArray& lon,
                   const std::string& frameName, bool withStatus, bool withNormalStatus,
                   bool withContributors, const py::object& outArg) {
  const char* op = "ComposedSurface.surfaces()";
  const topo::NormalFrame frame = parseFrame(frameName);
  const auto shape = commonShape(op, "lat", lat, "lon", lon);
  auto nshape = shape;
  nshape.push_back(3);
  py::object outH = py::none(), outN = py::none();
  if (!outArg.is_none()) {
    if (!py::isinstance<py::tuple>(outArg) || py::len(outArg) != 2) {
      throw InvalidArgument(std::string(op) + ": out must be a (heights, normals) tuple");
    }
    const auto t = py::reinterpret_borrow<py::tuple>(outArg);
    outH = t[0];
    outN = t[1];
  }
  py::array_t<double> heightsOut = outputArray(op, "out[0]", outH, shape);
  py::array_t<double> normalsOut = outputArray(op, "out[1]", outN, nshape);
  const auto n = static_cast<std::size_t>(lat.size());
  std::vector<topo::QueryStatus> status(n), normalStatus(n);
  std::vector<std::uint32_t> contributors(n);
  {
    const py::gil_scoped_release release;
    double* h = heightsOut.mutable_data();
    double* nrm = normalsOut.mutable_data();
    const double* la = lat.data();
    const double* lo = lon.data();
    for (std::size_t i = 0; i < n; ++i) {
      // As ComposedSurface::surfaces(): a point that is not finite or beyond ±90° is
      // OutsideGrid, never a failed batch.
      compose::ComposedSample c;
      if (pointOk(la[i], lo[i])) c = s.surface.surface(la[i], lo[i], frame);
      h[i] = c.height;
      for (int k = 0; k < 3; ++k) nrm[3 * i + static_cast<std::size_t>(k)] = c.normal[k];
      status[i] = c.status;
      normalStatus[i] = c.normalStatus;
      contributors[i] = c.contributors;
    }
  }
  py::list items;
  items.append(heightsOut);
  items.append(normalsOut);
  if (withStatus) items.append(statusArray(shape, status));
  if (withNormalStatus) items.append(statusArray(shape, normalStatus));
  if (withContributors) items.append(countArray(shape, contributors));
  return py::tuple(items);
}

}  // namespace

void bindCompose(py::module_& m) {
  py::class_<PyCatalogue, std::shared_ptr<PyCatalogue>> catalogue(
      m, "Catalogue",
      "A body's datasets read from a catalogue file (JSON, docs/composition.md): store grids "
      "with their roles, priorities, feathers and masks, and the file's composition rules, "
      "every store paged through one cache. Catalogue(path) or read_catalogue(path); "
      "surface() gives the composed surface to query. A bad file raises the library's error "
      "naming the file, the dataset and the key: InvalidArgument (ValueError) for bad "
      "content, an unknown key or datasets on different bodies, IoError for a file that "
      "cannot be read, StoreError for a bad store.");
  catalogue
      .def(py::init(&readCatalogue), py::arg("path"),
           py::arg("cache_bytes") = std::size_t{256} << 20)
      .def_readonly("path", &PyCatalogue::path)
      .def_property_readonly("body",
                             [](const PyCatalogue& c) {
                               const topo::Body& b = c.file.catalogue->body();
                               py::dict d;
                               d["name"] = b.name();
                               d["equatorial_radius"] = b.equatorialRadius();
                               d["polar_radius"] = b.polarRadius();
                               return d;
                             })
      .def_property_readonly(
          "policy", [](const PyCatalogue& c) { return compose::policyName(c.file.rules.policy); },
          "The file's policy: 'weighted' or 'finest'")
      .def_property_readonly(
          "resolution_power", [](const PyCatalogue& c) { return c.file.rules.resolutionPower; },
          "The file's p of the resolution term (ground spacing^-p)")
      .def_property_readonly(
          "tier_ratio", [](const PyCatalogue& c) { return c.file.rules.tierRatio; },
          "The file's tier ratio: under 'weighted', datasets blend by weight only with those "
          "whose ground spacing is within this factor of their tier's finest")
      .def_property_readonly(
          "datasets",
          [](const PyCatalogue& c) {
            py::list l;
            for (std::size_t i = 0; i < c.datasets.size(); ++i) {
              l.append(datasetDict(i, c.ids[i], *c.datasets[i]));
            }
            return l;
          },
          "The datasets in file order, each a dict with the keys of `regolith info "
          "CATALOGUE --json`: index, id, name, kind, placement, latitude_type, role, priority, "
          "feather_m, mask, rows, cols, spacing, ground_spacing_m, levels, extent, "
          "height_range, bounds (body-fixed metres)")
      .def("__len__", [](const PyCatalogue& c) { return c.datasets.size(); })
      .def(
          "cache_stats",
          [](const PyCatalogue& c) {
            if (c.file.pagers.empty()) return py::dict();
            return statsDict(c.file.pagers.front()->cache().stats());
          },
          "Statistics of the patch cache every store of the file pages through")
      .def(
          "surface",
          [](const std::shared_ptr<PyCatalogue>& c, std::optional<std::string> policy,
             std::optional<double> resolutionPower, std::optional<double> tierRatio) {
            compose::Rules rules = c->file.rules;
            if (policy) rules.policy = parseComposePolicy(*policy);
            if (resolutionPower) rules.resolutionPower = *resolutionPower;
            if (tierRatio) rules.tierRatio = *tierRatio;
            return PySurface{c, compose::ComposedSurface(c->snapshot, rules)};
          },
          py::arg("policy") = py::none(), py::arg("resolution_power") = py::none(),
          py::arg("tier_ratio") = py::none(),
          "The composed surface of the datasets: with the file's rules, or with policy "
          "('weighted' or 'finest'), resolution_power and tier_ratio (float('inf'): one tier "
          "per priority) given here; values the rules refuse raise InvalidArgument")
      .def("__repr__", [](const PyCatalogue& c) {
        return "<regolith.Catalogue '" + c.path.string() +
               "': " + std::to_string(c.datasets.size()) + " datasets on " +
               c.file.catalogue->body().name() + ">";
      });

  m.def("read_catalogue", &readCatalogue, py::arg("path"),
        py::arg("cache_bytes") = std::size_t{256} << 20,
        "Reads a catalogue file (JSON, docs/composition.md): Catalogue(path). Relative store "
        "paths are relative to the file's folder.");

  py::class_<PySurface>(
      m, "ComposedSurface",
      "The composed surface of a catalogue's datasets (compose::ComposedSurface, "
      "Catalogue.surface()). Queries take planetodetic latitude and east longitude in "
      "degrees as numpy arrays of any one shape (real dtypes only) and give heights in metres "
      "above the body's reference surface along its normal. Unlike Dem and Planet, a point "
      "that is NaN, infinite or beyond +-90 degrees does not raise: it is STATUS_OUTSIDE with "
      "a NaN height, as a point nothing covers. Batches release the GIL; the surface is "
      "immutable and may be queried from several threads.")
      .def_property_readonly(
          "policy",
          [](const PySurface& s) { return compose::policyName(s.surface.rules().policy); })
      .def_property_readonly("resolution_power",
                             [](const PySurface& s) { return s.surface.rules().resolutionPower; })
      .def_property_readonly("tier_ratio",
                             [](const PySurface& s) { return s.surface.rules().tierRatio; })
      .def_property_readonly("catalogue", [](const PySurface& s) { return s.catalogue; })
      .def("heights", &heights, py::arg("lat"), py::arg("lon"), py::arg("status") = false,
           py::arg("contributors") = false, py::arg("out") = py::none(),
           "Composed heights at (lat, lon), NaN where no dataset has data; status=True adds a "
           "uint8 array of STATUS_* codes, contributors=True (after it) a uint32 array of the "
           "number of datasets that cover each point (coverage > 0, including those a higher "
           "tier hides). out: a float64 array of lat's shape to write into.")
      .def("surfaces", &surfaces, py::arg("lat"), py::arg("lon"), py::arg("frame") = "grid",
           py::arg("status") = false, py::arg("normal_status") = false,
           py::arg("contributors") = false, py::arg("out") = py::none(),
           "(heights, normals[..., 3]): unit normals of the composed surface in the point's "
           "east-north-up frame (frame='grid') or body-fixed (frame='body'); status=True, "
           "normal_status=True and contributors=True add, in that order, the heights' and the "
           "normals' STATUS_* codes (uint8) and the contributor counts (uint32). out: a "
           "(heights, normals) pair of float64 arrays to write into.")
      .def(
          "height",
          [](const PySurface& s, double lat, double lon) {
            return s.surface.height(lat, lon).height;
          },
          py::arg("lat"), py::arg("lon"),
          "The composed height at one point (NaN where no dataset has data); raises "
          "InvalidArgument for NaN, inf or |lat| > 90")
      .def(
          "weights",
          [](const PySurface& s, double lat, double lon) {
            py::list l;
            for (const compose::Share& sh : s.surface.weights(lat, lon)) {
              const py::ssize_t index = s.catalogue->indexOf(sh.id);
              py::dict d;
              d["dataset"] = index;
              d["id"] = sh.id;
              d["name"] = index >= 0
                              ? s.catalogue->datasets[static_cast<std::size_t>(index)]->name()
                              : std::string();
              d["height"] = sh.height;
              d["coverage"] = sh.coverage;
              d["quality"] = sh.quality;
              d["share"] = sh.weight;
              l.append(d);
            }
            return l;
          },
          py::arg("lat"), py::arg("lon"),
          "Each covering dataset's share of the composed height at one point, as a list of "
          "dicts: dataset (its index in the catalogue file), id, name, height (its own), "
          "coverage, quality and share (the shares sum to 1; a dataset a higher tier hides "
          "has share 0). Empty where nothing covers the point. Raises InvalidArgument for "
          "NaN, inf or |lat| > 90.")
      .def("__repr__", [](const PySurface& s) {
        return "<regolith.ComposedSurface of '" + s.catalogue->path.string() + "', policy " +
               compose::policyName(s.surface.rules().policy) + ">";
      });
}

}  // namespace regolith::python
