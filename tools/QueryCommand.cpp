// `regolith query STORE [points...]`: heights and normals at points, as CSV (docs/cli.md).
#include <regolith/core/Error.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Store.hpp>

#include "CatalogueInfo.hpp"
#include "CatalogueQuery.hpp"
#include "Commands.hpp"
#include "OutputFolder.hpp"
#include "PointsCsv.hpp"
#include "StoreGrid.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace regolith::tools {

namespace {

struct Result {
  std::vector<double> height;
  std::vector<glm::dvec3> normal;
  std::vector<topo::QueryStatus> status;        // the height's
  std::vector<topo::QueryStatus> normalStatus;  // the normal's
  explicit Result(std::size_t n)
      : height(n, std::nan("")),
        normal(n, glm::dvec3(std::nan(""))),
        status(n, topo::QueryStatus::OutsideGrid),
        normalStatus(n, topo::QueryStatus::OutsideGrid) {}
};

/// Heights and normals of the points `index` names, written into res at those indices.
template <class Query>
void querySubset(std::span<const std::size_t> index, Result& res, Query&& query) {
  const std::size_t m = index.size();
  std::vector<double> h(m);
  std::vector<glm::dvec3> nrm(m);
  std::vector<topo::QueryStatus> st(m), nst(m);
  query(std::span<double>(h), std::span<glm::dvec3>(nrm), std::span<topo::QueryStatus>(st),
        std::span<topo::QueryStatus>(nst));
  for (std::size_t k = 0; k < m; ++k) {
    res.height[index[k]] = h[k];
    res.normal[index[k]] = nrm[k];
    res.status[index[k]] = st[k];
    res.normalStatus[index[k]] = nst[k];
  }
}

/// Ellipsoid height at which the vertical through (lat, lon) meets the grid's zero surface
/// (h = 0): the seed of the terrain iteration, taken from the point itself. For map
/// projections it is 0 (their h is the ellipsoid height); for a tangent plane the plane's
/// own height there. Throws DomainError if the placement cannot map the point.
double seedHeight(const topo::Placement& placement, double lat, double lon) {
  const double z0 = placement.fromGeodetic({lat, lon, 0.0}).z;
  const double z1 = placement.fromGeodetic({lat, lon, 1.0}).z;
  return -z0 / (z1 - z0);
}

void queryDem(const topo::TopoDem& dem, Coords coords, std::span<const Point> pts,
              topo::Interpolation interp, topo::NormalFrame frame, Result& res) {
  const std::size_t n = pts.size();
  std::vector<double> xs, ys;
  std::vector<std::size_t> index;  // the points the placement maps (others: Unmappable)
  xs.reserve(n);
  ys.reserve(n);
  index.reserve(n);
  const topo::TopoGrid& grid = dem.grid();
  if (coords != Coords::LonLat) {
    for (std::size_t i = 0; i < n; ++i) {
      const glm::dvec2 p = coords == Coords::Grid ? grid.sampleCentre(pts[i].a, pts[i].b)
                                                  : glm::dvec2(pts[i].a, pts[i].b);
      xs.push_back(p.x);
      ys.push_back(p.y);
      index.push_back(i);
    }
  } else {
    // The point where the vertical through (lat, lon) meets the terrain: project at an
    // ellipsoid height, read the terrain there, and repeat with the terrain's ellipsoid
    // height (the plane's normal and the ellipsoid's differ away from its origin). A point
    // the projection cannot map (the pole opposite a polar stereographic centre, 90° or more
    // from a transverse Mercator meridian) is Unmappable, and the others go on.
    const topo::Placement& placement = dem.placement();
    const double xNear = 0.5 * (grid.west() + grid.east());
    std::vector<double> he, h;
    for (std::size_t i = 0; i < n; ++i) {
      try {
        const double lat = pts[i].b, lon = pts[i].a;
        const double seed = seedHeight(placement, lat, lon);
        const glm::dvec3 g = placement.fromGeodeticNear({lat, lon, seed}, xNear);
        xs.push_back(g.x);
        ys.push_back(g.y);
        he.push_back(seed);
        index.push_back(i);
      } catch (const DomainError&) {
        res.status[i] = res.normalStatus[i] = topo::QueryStatus::Unmappable;
      }
    }
    const std::size_t m = index.size();
    h.resize(m);
    std::vector<topo::QueryStatus> st(m);
    for (int iter = 0; iter < 4; ++iter) {
      dem.heights(xs, ys, h, st, interp);
      for (std::size_t k = 0; k < m; ++k) {
        if (st[k] != topo::QueryStatus::Ok) continue;
        const std::size_t i = index[k];
        try {
          he[k] = placement.toGeodetic(xs[k], ys[k], h[k]).height;
          const glm::dvec3 g = placement.fromGeodeticNear({pts[i].b, pts[i].a, he[k]}, xNear);
          xs[k] = g.x;
          ys[k] = g.y;
        } catch (const DomainError&) {
          // Keeps the previous position: the terrain moved the point no further.
        }
      }
    }
  }
  querySubset(index, res, [&](auto h, auto nrm, auto st, auto nst) {
    dem.surfaces(xs, ys, h, nrm, st, interp, frame, nst);
  });
}

void queryPlanet(const topo::TopoPlanet& planet, Coords coords, std::span<const Point> pts,
                 topo::Interpolation interp, topo::NormalFrame frame, Result& res) {
  const std::size_t n = pts.size();
  std::vector<double> lats, lons;
  std::vector<std::size_t> index;  // points inside −90…90 (others stay OutsideGrid)
  lats.reserve(n);
  lons.reserve(n);
  index.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    double lon = pts[i].a, lat = pts[i].b;
    if (coords == Coords::Grid) {
      const glm::dvec2 p = planet.grid().sampleCentre(pts[i].a, pts[i].b);
      lon = p.x;
      lat = p.y;
    }
    if (std::abs(lat) > 90.0) continue;
    lats.push_back(lat);
    lons.push_back(lon);
    index.push_back(i);
  }
  querySubset(index, res, [&](auto h, auto nrm, auto st, auto nst) {
    planet.surfaces(lats, lons, h, nrm, st, interp, frame, nst);
  });
}

struct Args {
  std::string store;
  std::string grid;
  std::string interp = "bilinear";
  std::string coords = "lonlat";
  std::string frame = "grid";
  std::vector<std::string> points;
  std::size_t cacheMb = 256;
  std::size_t level = 0;
  bool explain = false;
  /// The options that choose a store's grid and how to read it, which a catalogue file
  /// (whose datasets compose by its own rules) refuses when given.
  std::vector<const CLI::Option*> storeOnly;
};

/// A catalogue file composes its datasets at lon,lat points: refuses the options that only a
/// store's grid has (naming the first one given).
void refuseStoreOnlyOptions(const Args& a) {
  for (const CLI::Option* o : a.storeOnly) {
    if (o->count() == 0) continue;
    if (o->get_name() == "--coords" && a.coords == "lonlat") continue;
    throw InvalidArgument("query: " + o->get_name() + " applies to a store's grid, but " + a.store +
                          " is a catalogue file: its datasets are composed at lon,lat points "
                          "(planetodetic latitude), each read at its finest level");
  }
}

void runQuery(const Args& a) {
  static const std::map<std::string, Coords> kCoords{
      {"lonlat", Coords::LonLat}, {"grid", Coords::Grid}, {"xy", Coords::Xy}};
  static const std::map<std::string, topo::Interpolation> kInterp{
      {"nearest", topo::Interpolation::Nearest},
      {"bilinear", topo::Interpolation::Bilinear},
      {"bicubic", topo::Interpolation::Bicubic}};
  const Coords coords = kCoords.at(a.coords);
  const topo::Interpolation interp = kInterp.at(a.interp);
  const topo::NormalFrame frame =
      a.frame == "body" ? topo::NormalFrame::BodyFixed : topo::NormalFrame::Grid;

  // A catalogue file or a store: options that do not apply are refused before stdin is read.
  const bool catalogue = isCatalogueFile(a.store);
  if (catalogue) {
    refuseStoreOnlyOptions(a);
  } else if (a.explain) {
    throw InvalidArgument(
        "query: --explain shows how a catalogue file's datasets share a "
        "composed height, but " +
        a.store + " is a store (one grid, nothing to compose)");
  }

  // All input is read and checked before anything is printed: a bad line gives an error
  // and no partial output.
  std::vector<Point> points;
  if (a.points.empty()) {
    points = readPoints(std::cin, "stdin", coords);
  } else {
    for (std::size_t i = 0; i < a.points.size(); ++i) {
      points.push_back(parsePoint(a.points[i], "point " + std::to_string(i + 1), coords));
    }
  }

  if (catalogue) {
    runCatalogueQuery({a.store, frame, a.explain, a.cacheMb}, points);
    return;
  }

  std::error_code ec;
  if (std::filesystem::is_regular_file(a.store, ec) && !store::Store::isHdf5(a.store)) {
    throw InvalidArgument("query: " + a.store +
                          " is neither a store (no HDF5 signature) nor a catalogue file (its "
                          "text does not start with '{', a JSON object)");
  }
  auto store = std::make_shared<const store::Store>(store::Store::open(a.store));
  const std::string gridName = chooseGrid(*store, a.grid, "query");
  const store::GridInfo& info = store->grid(gridName);
  if (a.level >= info.levels) {
    throw InvalidArgument("query: grid '" + gridName + "' has " + std::to_string(info.levels) +
                          " levels (0 to " + std::to_string(info.levels - 1) + "), not level " +
                          std::to_string(a.level));
  }
  auto cache = std::make_shared<store::PatchCache>(a.cacheMb << 20U);
  const store::Pager pager(store, cache);
  std::optional<topo::TopoDem> dem;
  std::optional<topo::TopoPlanet> planet;
  if (info.kind == store::GridKind::Dem) {
    dem.emplace(pager.dem(gridName, a.level));
  } else {
    planet.emplace(pager.planet(gridName, a.level));
  }

  const auto [nameA, nameB] = coordNames(coords);
  std::string out =
      std::string(nameA) + "," + nameB + ",height,nx,ny,nz,valid,normal_valid,reason\n";
  constexpr std::size_t kBatch = 1U << 16U;
  for (std::size_t first = 0; first < points.size() || first == 0; first += kBatch) {
    const std::size_t n = std::min(kBatch, points.size() - first);
    const std::span<const Point> batch(points.data() + first, n);
    Result res(n);
    if (dem) {
      queryDem(*dem, coords, batch, interp, frame, res);
    } else {
      queryPlanet(*planet, coords, batch, interp, frame, res);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const bool valid = res.status[i] == topo::QueryStatus::Ok;
      const bool normalValid = valid && res.normalStatus[i] == topo::QueryStatus::Ok;
      const double nan = std::nan("");
      appendCsvNumber(out, batch[i].a);
      out += ',';
      appendCsvNumber(out, batch[i].b);
      out += ',';
      appendCsvNumber(out, valid ? res.height[i] : nan);
      for (int k = 0; k < 3; ++k) {
        out += ',';
        appendCsvNumber(out, normalValid ? res.normal[i][k] : nan);
      }
      out += valid ? ",1," : ",0,";
      out += normalValid ? "1," : "0,";
      // Why the height, else the normal, is invalid: outside, nodata or unmappable.
      out += topo::statusName(valid ? res.normalStatus[i] : res.status[i]);
      out += '\n';
    }
    std::fwrite(out.data(), 1, out.size(), stdout);
    out.clear();
    if (n == 0) break;
  }
  std::fflush(stdout);
}

}  // namespace

void addQueryCommand(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "query",
      "Heights and unit normals at points, as CSV on stdout: a header line, then one row per "
      "input point in input order with its two coordinates, height, nx, ny, nz, valid (1, or 0 "
      "with a nan height), normal_valid (1, or 0 with a nan normal: its stencil reaches a hole "
      "the height's does not) and reason (ok, or why the height, else the normal, is invalid: "
      "outside, nodata, or unmappable where the DEM's projection cannot map a lon,lat; one "
      "such point never fails the others). Points come as arguments "
      "'a,b' (if one starts with '-.', put -- before the first point) or, with none given, as CSV "
      "lines on stdin (an optional header line naming the columns; blank lines and lines "
      "starting with # are skipped). Given a catalogue file (a JSON object, "
      "docs/composition.md) instead of a store, the composed surface of its datasets: points "
      "are lon,lat with planetodetic latitude, and a last column, contributors, counts the "
      "datasets that cover the point (with --explain: one row per point and dataset with "
      "its own height, coverage, quality and share)");
  addStoreGridOptions(*cmd, a->store, a->grid, a->cacheMb, "query");
  cmd->get_option("store")->description(
      "Store file (HDF5), or a catalogue file (JSON: datasets of store grids composed by one "
      "rule)");
  cmd->add_option("points", a->points, "Points 'a,b' in the --coords order");
  const CLI::Option* interp = cmd->add_option("--interp", a->interp, "Interpolation kernel")
                                  ->check(CLI::IsMember({"nearest", "bilinear", "bicubic"}))
                                  ->capture_default_str();
  const CLI::Option* coords =
      cmd->add_option(
             "--coords", a->coords,
             "Input coordinates: lonlat = 'lon,lat' in degrees (east longitude; "
             "latitude as the grid declares it, planetodetic for DEMs); grid = "
             "'row,col' fractional sample indices (row 0 north, integers at sample "
             "centres); xy = 'x,y' grid coordinates (metres for a DEM, lon/lat degrees "
             "for a planet). A catalogue file takes lonlat only, with planetodetic latitude")
          ->check(CLI::IsMember({"lonlat", "grid", "xy"}))
          ->capture_default_str();
  cmd->add_option("--frame", a->frame,
                  "Frame of the normal: grid (a DEM's x, y, up axes; a planet's, and a "
                  "catalogue's, local east, north, up) or body (body-fixed Cartesian)")
      ->check(CLI::IsMember({"grid", "body"}))
      ->capture_default_str();
  const CLI::Option* level =
      cmd->add_option("--level", a->level,
                      "Pyramid level to query (grid coordinates then index it); stores only")
          ->capture_default_str();
  cmd->add_flag("--explain", a->explain,
                "Catalogue files: instead of heights and normals, print each point's shares "
                "of the composed height, one row per point and contributing dataset: lon, lat, "
                "point (1-based input order), height (composed), valid, reason, "
                "contributors, dataset (its index in the file), name, dataset_height, "
                "coverage, quality, share (the shares of a point sum to 1); a point nothing "
                "covers has one row with an empty dataset");
  a->storeOnly = {cmd->get_option("--grid"), level, interp, coords};
  cmd->footer(
      "Examples:\n"
      "  regolith query mars.h5 137.4,-4.6 -5.5,-2.05\n"
      "  regolith query mars.h5 -- -.5,10 20,30\n"
      "  regolith query victoria.h5 --coords xy --interp bicubic 0,0 120.5,-40\n"
      "  printf 'lon,lat\\n-5.5,-2.05\\n' | regolith query victoria.h5 --frame body\n"
      "  regolith query moon.json 20,10 -45.5,-89.2\n"
      "  regolith query moon.json --explain 20,10\n"
      "Exit status: 0 on success; non-zero, with 'regolith: error: ...' on stderr and nothing "
      "on stdout, for malformed input (the message names the argument or stdin line) and for "
      "a bad catalogue file (the message names the file, the dataset and the key).");
  cmd->callback([a] {
    refuseStdoutOverInput("query", a->store);
    runQuery(*a);
  });
}

}  // namespace regolith::tools
