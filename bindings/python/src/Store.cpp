// Stores, grids, the patch cache, import and the procedural generators.
#include <regolith/core/Error.hpp>
#include <regolith/store/Generate.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/Pager.hpp>

#include "Common.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>

namespace regolith::python {

topo::Interpolation parseInterpolation(const std::string& name) {
  if (name == "nearest") return topo::Interpolation::Nearest;
  if (name == "bilinear") return topo::Interpolation::Bilinear;
  if (name == "bicubic") return topo::Interpolation::Bicubic;
  throw InvalidArgument("regolith: interpolation '" + name +
                        "' is unknown, expected 'nearest', 'bilinear' or 'bicubic'");
}

topo::NormalFrame parseFrame(const std::string& name) {
  if (name == "grid") return topo::NormalFrame::Grid;
  if (name == "body") return topo::NormalFrame::BodyFixed;
  throw InvalidArgument("regolith: normal frame '" + name +
                        "' is unknown, expected 'grid' or 'body'");
}

store::CachePolicy parsePolicy(const std::string& name) {
  if (name == "lru") return store::CachePolicy::Lru;
  if (name == "hitcount") return store::CachePolicy::HitCount;
  if (name == "decaying") return store::CachePolicy::DecayingHitCount;
  throw InvalidArgument("regolith: cache policy '" + name +
                        "' is unknown, expected 'lru', 'hitcount' or 'decaying'");
}

std::string policyName(store::CachePolicy p) {
  switch (p) {
    case store::CachePolicy::Lru: return "lru";
    case store::CachePolicy::HitCount: return "hitcount";
    case store::CachePolicy::DecayingHitCount: return "decaying";
  }
  return "unknown";
}

py::dict statsDict(const store::CacheStats& s) {
  py::dict d;
  d["hits"] = s.hits;
  d["misses"] = s.misses;
  d["loads"] = s.loads;
  d["evictions"] = s.evictions;
  d["bytes_loaded"] = s.bytesLoaded;
  d["resident_bytes"] = s.residentBytes;
  d["peak_resident_bytes"] = s.peakResidentBytes;
  d["resident_patches"] = s.residentPatches;
  d["capacity_bytes"] = s.capacityBytes;
  return d;
}

namespace {

py::dict reportDict(const store::ImportReport& r) {
  py::dict d;
  d["grid"] = r.info.name;
  d["rows"] = r.info.rows;
  d["cols"] = r.info.cols;
  d["levels"] = r.info.levels;
  d["driver"] = r.driver;
  d["projection"] = r.projection;
  d["radius_reference"] = r.radiusReference;
  d["offset_corrected"] = r.offsetCorrected;
  d["spacing_snapped"] = r.spacingSnapped;
  d["void_marker_assumed"] = r.voidMarkerAssumed;
  d["dropped_north_rows"] = r.droppedNorthRows;
  d["dropped_south_rows"] = r.droppedSouthRows;
  d["dropped_columns"] = r.droppedColumns;
  d["pole_shift_pixels"] = r.poleShiftPixels;
  if (r.window) {
    d["window"] = py::make_tuple(r.window->row0, r.window->col0, r.window->rows, r.window->cols);
  }
  d["missing_samples"] = r.missingSamples;
  d["implausible_samples"] = r.implausibleSamples;
  d["plausible_limit"] = r.plausibleLimit;
  d["seconds"] = r.seconds;
  return d;
}

/// ImportOptions::heightMap from import_raster()'s keywords: none without spacing and origin.
std::optional<store::HeightMapOptions> heightMapOf(const py::object& spacing,
                                                   std::optional<std::array<double, 2>> origin,
                                                   double scale, double offset, double heading) {
  if (spacing.is_none() && !origin) {
    if (scale != 1.0 || offset != 0.0 || heading != 0.0) {
      throw InvalidArgument(
          "regolith.import_raster(): height_scale, height_offset and heading place a height "
          "map, expected them with spacing= and origin=");
    }
    return std::nullopt;
  }
  if (spacing.is_none() || !origin) {
    throw InvalidArgument("regolith.import_raster(): a height map needs both spacing= and origin=");
  }
  store::HeightMapOptions h;
  if (py::isinstance<py::sequence>(spacing)) {
    const auto s = spacing.cast<std::array<double, 2>>();
    h.spacingX = s[0];
    h.spacingY = s[1];
  } else {
    h.spacingX = h.spacingY = spacing.cast<double>();
  }
  h.originLatDeg = (*origin)[0];
  h.originLonDeg = (*origin)[1];
  h.heightScale = scale;
  h.heightOffset = offset;
  h.headingDeg = heading;
  return h;
}

py::object openTerrain(std::shared_ptr<const store::Store> file,
                       std::shared_ptr<store::PatchCache> cache, const std::string& gridArg,
                       std::size_t level) {
  std::string grid = gridArg;
  if (grid.empty()) {
    const auto names = file->gridNames();
    if (names.size() != 1) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "'" : ", '") + n + "'";
      throw InvalidArgument("regolith.open(): " + file->path().string() + " has " +
                            std::to_string(names.size()) + " grids (" + list +
                            "), name one with grid=");
    }
    grid = names.front();
  }
  const store::Pager pager(file, cache);
  const auto fill = [&](Terrain& t) {
    t.store = file;
    t.cache = cache;
    t.grid = grid;
    t.level = level;
  };
  if (file->grid(grid).kind == store::GridKind::Dem) {
    auto t = std::make_shared<DemTerrain>();
    fill(*t);
    t->dem.emplace(pager.dem(grid, level));
    return py::cast(t);
  }
  auto t = std::make_shared<PlanetTerrain>();
  fill(*t);
  t->planet.emplace(pager.planet(grid, level));
  return py::cast(t);
}

}  // namespace

void bindStore(py::module_& m) {
  py::class_<store::GridInfo>(m, "GridInfo",
                              "One grid of a store: size, georeferencing, body, pyramid, patch "
                              "size (docs/store-format.md). Read-only.")
      .def_readonly("name", &store::GridInfo::name)
      .def_property_readonly("kind",
                             [](const store::GridInfo& g) {
                               return g.kind == store::GridKind::Dem ? "dem" : "planet";
                             })
      .def_readonly("rows", &store::GridInfo::rows)
      .def_readonly("cols", &store::GridInfo::cols)
      .def_readonly("x0", &store::GridInfo::x0, "x (or longitude, deg) of sample (0, 0)")
      .def_readonly("y0", &store::GridInfo::y0, "y (or latitude, deg) of sample (0, 0)")
      .def_readonly("spacing_x", &store::GridInfo::spacingX)
      .def_readonly("spacing_y", &store::GridInfo::spacingY)
      .def_readonly("levels", &store::GridInfo::levels)
      .def_readonly("patch_rows", &store::GridInfo::patchRows)
      .def_readonly("patch_cols", &store::GridInfo::patchCols)
      .def_readonly("units", &store::GridInfo::units)
      .def_readonly("body", &store::GridInfo::bodyName)
      .def_readonly("equatorial_radius", &store::GridInfo::equatorialRadius)
      .def_readonly("polar_radius", &store::GridInfo::polarRadius)
      .def_property_readonly("nodata",
                             [](const store::GridInfo& g) -> py::object {
                               if (g.nodata) return py::float_(static_cast<double>(*g.nodata));
                               return py::none();
                             })
      .def_property_readonly(
          "placement",
          [](const store::GridInfo& g) -> py::object {
            if (g.kind != store::GridKind::Dem) return py::none();
            return py::str(std::string(store::placementKindName(g.placement.kind)));
          },
          "A DEM's placement: 'local_tangent_plane', 'polar_stereographic', "
          "'equirectangular', 'transverse_mercator' or 'projected' (any "
          "other CRS, through PROJ); None for a planet")
      .def_property_readonly(
          "crs",
          [](const store::GridInfo& g) -> py::object {
            if (g.placement.crs.empty()) return py::none();
            return py::str(g.placement.crs);
          },
          "A 'projected' DEM's CRS as WKT2; None otherwise")
      .def_property_readonly(
          "extent",
          [](const store::GridInfo& g) {
            const topo::TopoGrid t = store::topoGridOf(g);
            return py::make_tuple(t.west(), t.east(), t.south(), t.north());
          },
          "(west, east, south, north) of the pixel extent (metres, or degrees for a planet)")
      .def("__repr__", [](const store::GridInfo& g) {
        return "<regolith.GridInfo '" + g.name + "' " +
               (g.kind == store::GridKind::Dem ? "dem " : "planet ") + std::to_string(g.rows) +
               "x" + std::to_string(g.cols) + ", " + std::to_string(g.levels) + " levels>";
      });

  py::class_<store::Store, std::shared_ptr<store::Store>>(
      m, "Store", "An open HDF5 terrain store (read-only). Store(path) raises StoreError.")
      .def(py::init([](const std::filesystem::path& p) {
             return std::make_shared<store::Store>(store::Store::open(p));
           }),
           py::arg("path"))
      .def_property_readonly("path", &store::Store::path)
      .def_property_readonly("format_version", &store::Store::formatVersion)
      .def("grid_names", &store::Store::gridNames)
      .def("grid", &store::Store::grid, py::arg("name"), py::return_value_policy::copy)
      .def_property_readonly("grids",
                             [](const store::Store& s) {
                               py::dict d;
                               for (const auto& n : s.gridNames()) d[py::str(n)] = s.grid(n);
                               return d;
                             })
      .def("tiled", &store::Store::tiled, py::arg("name"))
      .def("counters",
           [](const store::Store& s) {
             const auto c = s.counters();
             py::dict d;
             d["reads"] = c.reads;
             d["bytes_read"] = c.bytesRead;
             return d;
           })
      .def("__repr__",
           [](const store::Store& s) { return "<regolith.Store '" + s.path().string() + "'>"; });

  py::class_<store::PatchCache, std::shared_ptr<store::PatchCache>>(
      m, "Cache", "A byte-budgeted patch cache, shared by any number of grids (thread-safe).")
      .def(py::init([](std::size_t capacity, const std::string& policy) {
             if (capacity == 0) {
               throw InvalidArgument("regolith.Cache(): capacity_bytes is 0, expected > 0");
             }
             return std::make_shared<store::PatchCache>(capacity, parsePolicy(policy));
           }),
           py::arg("capacity_bytes"), py::arg("policy") = "lru")
      .def_property("capacity_bytes", &store::PatchCache::capacityBytes,
                    &store::PatchCache::setCapacityBytes)
      .def_property_readonly("policy",
                             [](const store::PatchCache& c) { return policyName(c.policy()); })
      .def("stats", [](const store::PatchCache& c) { return statsDict(c.stats()); })
      .def("reset_stats", &store::PatchCache::resetStats)
      .def("clear", &store::PatchCache::clear);

  m.def(
      "open",
      [](const std::filesystem::path& path, const std::string& grid, std::size_t level,
         std::size_t cacheBytes, std::shared_ptr<store::PatchCache> cache) {
        if (!cache) {
          if (cacheBytes == 0) {
            throw InvalidArgument("regolith.open(): cache_bytes is 0, expected > 0");
          }
          cache = std::make_shared<store::PatchCache>(cacheBytes);
        }
        auto file = std::make_shared<const store::Store>(store::Store::open(path));
        return openTerrain(std::move(file), std::move(cache), grid, level);
      },
      py::arg("path"), py::arg("grid") = "", py::arg("level") = 0,
      py::arg("cache_bytes") = std::size_t{256} << 20, py::arg("cache") = nullptr,
      "Opens one grid of a store, paged through `cache` (or a new Cache of cache_bytes): a Dem "
      "or a Planet. `grid` may be omitted when the store holds one grid.");

  m.def(
      "import_raster",
      [](const std::filesystem::path& raster, const std::filesystem::path& out,
         const std::string& grid, std::size_t levels, std::size_t patch, int deflate,
         std::optional<double> nodata, const std::string& compression,
         std::optional<std::array<std::size_t, 4>> window,
         std::optional<std::array<double, 4>> bbox, const std::string& body, bool strict,
         const py::object& spacing, std::optional<std::array<double, 2>> origin, double heightScale,
         double heightOffset, double heading) {
        store::ImportOptions o;
        o.heightMap = heightMapOf(spacing, origin, heightScale, heightOffset, heading);
        o.gridName = grid;
        o.body = body;
        o.strict = strict;
        if (window) {
          o.window = store::SampleWindow{(*window)[0], (*window)[1], (*window)[2], (*window)[3]};
        }
        o.bbox = bbox;
        o.levels = levels;
        o.patchRows = o.patchCols = patch;
        o.deflate = deflate;
        o.codec = store::codecNamed(compression);
        o.nodata = nodata;
        store::ImportReport r;
        {
          const py::gil_scoped_release release;
          r = store::importRaster(raster, out, o);
        }
        return reportDict(r);
      },
      py::arg("raster"), py::arg("store"), py::arg("grid") = "", py::arg("levels") = 0,
      py::arg("patch_size") = 256, py::arg("deflate") = 0, py::arg("nodata") = py::none(),
      py::arg("compression") = "deflate", py::arg("window") = py::none(),
      py::arg("bbox") = py::none(), py::arg("body") = "", py::arg("strict") = false,
      py::arg("spacing") = py::none(), py::arg("origin") = py::none(),
      py::arg("height_scale") = 1.0, py::arg("height_offset") = 0.0, py::arg("heading") = 0.0,
      "Imports a single-band raster GDAL reads (GeoTIFF, PDS3, PDS4, ISIS3...) as one grid of a "
      "new store, written crash-safely. compression: 'deflate' (shuffle + deflate at `deflate`) "
      "or 'zfp' (ZFP reversible, lossless and smaller; readers need HDF5's ZFP filter plugin, "
      "and deflate must be 0). window: (row0, col0, rows, cols) of the grid `regolith info RASTER` "
      "shows; bbox: (west, south, east, north) degrees, the samples whose centres lie inside "
      "(at most one of the two); body: the body's name where the CRS lacks it. Heights beyond "
      "+-(equatorial radius / 10) are counted in the report's implausible_samples, or refused "
      "(RasterImportError) with strict=True. A height map without georeferencing (PNG, "
      "GeoTIFF without a CRS) needs spacing (metres, dx or (dx, dy)), origin ((lat, lon) of "
      "its centre sample) and body ('Mars', 'Moon', 'Earth'); heights are height_offset + "
      "height_scale * value, its y axis at azimuth heading. The store may not be one of the "
      "raster's files (ValueError). Returns the import report as a dict. Raises "
      "RasterImportError, "
      "StoreError or ValueError (a bad option).");

  m.def(
      "generate_victoria",
      [](const std::filesystem::path& out, std::size_t size, double spacing, std::uint64_t seed,
         const std::string& grid, double originHeight, std::size_t patch) {
        store::VictoriaOptions o;
        o.size = size;
        o.spacing = spacing;
        o.seed = seed;
        o.gridName = grid;
        o.originHeight = originHeight;
        o.write.patchRows = o.write.patchCols = patch;
        const store::VictoriaGenerator gen(o);
        {
          const py::gil_scoped_release release;
          gen.write(out);
        }
        return gen.gridInfo();
      },
      py::arg("path"), py::arg("size") = 1201, py::arg("spacing") = 1.0, py::arg("seed") = 1,
      py::arg("grid") = "victoria", py::arg("origin_height") = -1400.0, py::arg("patch_size") = 256,
      "Writes a Victoria-crater-like DEM (store::VictoriaGenerator) placed on Mars at 2.05 S, "
      "5.5 W. Returns its GridInfo (levels as requested, before the write fixes them).");

  m.def(
      "generate_mars",
      [](const std::filesystem::path& out, std::size_t rows, std::uint64_t seed, bool ellipsoid,
         const std::string& grid, double craterDensity, std::size_t patch) {
        store::MarsPlanetOptions o;
        o.rows = rows;
        o.seed = seed;
        o.ellipsoid = ellipsoid;
        o.gridName = grid;
        o.craterDensity = craterDensity;
        o.write.patchRows = o.write.patchCols = patch;
        const store::MarsPlanetGenerator gen(o);
        {
          const py::gil_scoped_release release;
          gen.write(out);
        }
        return gen.gridInfo();
      },
      py::arg("path"), py::arg("rows") = 720, py::arg("seed") = 1, py::arg("ellipsoid") = false,
      py::arg("grid") = "mars", py::arg("crater_density") = 1.0, py::arg("patch_size") = 256,
      "Writes a global Mars-like planet (store::MarsPlanetGenerator): rows latitude samples, "
      "2*rows longitude samples.");
}

}  // namespace regolith::python
