// `regolith info STORE [--json]`: what a store holds.
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Store.hpp>

#include "Commands.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>

namespace regolith::tools {

namespace {

using nlohmann::ordered_json;
using store::GridInfo;
using store::GridKind;
using store::PlacementInfo;

std::string kindName(GridKind k) { return k == GridKind::Dem ? "dem" : "planet"; }

std::string latitudeTypeName(topo::LatitudeType t) {
  return t == topo::LatitudeType::Planetocentric ? "planetocentric" : "planetodetic";
}

std::string placementName(PlacementInfo::Kind k) {
  switch (k) {
    case PlacementInfo::Kind::LocalTangentPlane: return "local_tangent_plane";
    case PlacementInfo::Kind::PolarStereographic: return "polar_stereographic";
    case PlacementInfo::Kind::Equirectangular: return "equirectangular";
  }
  return "unknown";
}

/// Shortest text that reads back as the same double.
std::string num(double v) {
  if (std::isnan(v)) return "nan";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {buf, r.ptr};
}

ordered_json placementJson(const GridInfo& g) {
  if (g.kind != GridKind::Dem) return nullptr;
  const PlacementInfo& p = g.placement;
  ordered_json j;
  j["kind"] = placementName(p.kind);
  switch (p.kind) {
    case PlacementInfo::Kind::LocalTangentPlane:
      j["origin_lat_deg"] = p.originLatDeg;
      j["origin_lon_deg"] = p.originLonDeg;
      j["origin_height"] = p.originHeight;
      j["heading_deg"] = p.headingDeg;
      break;
    case PlacementInfo::Kind::PolarStereographic:
      j["pole"] = p.pole >= 0 ? 1 : -1;
      j["lat_true_scale_deg"] = p.latTrueScaleDeg ? ordered_json(*p.latTrueScaleDeg) : nullptr;
      j["scale_factor"] = p.scaleFactor ? ordered_json(*p.scaleFactor) : nullptr;
      j["lon_centre_deg"] = p.lonCentreDeg;
      j["false_easting"] = p.falseEasting;
      j["false_northing"] = p.falseNorthing;
      break;
    case PlacementInfo::Kind::Equirectangular:
      j["projection_radius"] = p.projectionRadius;
      j["lat_true_scale_deg"] = p.latTrueScaleDeg ? ordered_json(*p.latTrueScaleDeg) : nullptr;
      j["lon_centre_deg"] = p.lonCentreDeg;
      j["lat_origin_deg"] = p.latOriginDeg;
      break;
  }
  return j;
}

ordered_json gridJson(const store::Store& s, const std::string& name) {
  const GridInfo& g = s.grid(name);
  const topo::TopoGrid tg = store::topoGridOf(g);
  ordered_json j;
  j["name"] = g.name;
  j["kind"] = kindName(g.kind);
  j["rows"] = g.rows;
  j["cols"] = g.cols;
  j["x0"] = g.x0;
  j["y0"] = g.y0;
  j["spacing"] = {g.spacingX, g.spacingY};
  j["extent"] = {
      {"west", tg.west()}, {"east", tg.east()}, {"north", tg.north()}, {"south", tg.south()}};
  j["units"] = g.units;
  j["body"] = {{"name", g.bodyName},
               {"equatorial_radius", g.equatorialRadius},
               {"polar_radius", g.polarRadius}};
  j["latitude_type"] = latitudeTypeName(g.latitudeType);
  j["placement"] = placementJson(g);
  j["levels"] = g.levels;
  ordered_json shapes = ordered_json::array();
  for (std::size_t k = 0; k < g.levels; ++k) shapes.push_back({g.levelRows(k), g.levelCols(k)});
  j["level_shapes"] = shapes;
  j["patch_shape"] = {g.patchRows, g.patchCols};
  j["nodata"] = g.nodata ? ordered_json(static_cast<double>(*g.nodata)) : nullptr;
  j["scale"] = g.scale;
  j["offset"] = g.offset;
  j["tiled"] = s.tiled(name);
  return j;
}

std::vector<std::string> sortedGrids(const store::Store& s) {
  std::vector<std::string> names = s.gridNames();
  std::sort(names.begin(), names.end());
  return names;
}

void printJson(const store::Store& s, std::ostream& out) {
  ordered_json j;
  j["path"] = s.path().string();
  j["format_version"] = {s.formatVersion()[0], s.formatVersion()[1]};
  ordered_json grids = ordered_json::array();
  for (const std::string& name : sortedGrids(s)) grids.push_back(gridJson(s, name));
  j["grids"] = grids;
  out << j.dump(2) << '\n';
}

void printPlacement(const GridInfo& g, std::ostream& out) {
  const PlacementInfo& p = g.placement;
  out << "  placement:      " << placementName(p.kind);
  switch (p.kind) {
    case PlacementInfo::Kind::LocalTangentPlane:
      out << ", origin lat " << num(p.originLatDeg) << " deg, lon " << num(p.originLonDeg)
          << " deg, height " << num(p.originHeight) << " m, heading " << num(p.headingDeg)
          << " deg\n";
      break;
    case PlacementInfo::Kind::PolarStereographic:
      out << ", " << (p.pole >= 0 ? "north" : "south") << " pole";
      if (p.latTrueScaleDeg) out << ", true scale at " << num(*p.latTrueScaleDeg) << " deg";
      if (p.scaleFactor) out << ", scale factor " << num(*p.scaleFactor);
      out << ", centre lon " << num(p.lonCentreDeg) << " deg, false easting " << num(p.falseEasting)
          << " m, false northing " << num(p.falseNorthing) << " m\n";
      break;
    case PlacementInfo::Kind::Equirectangular:
      out << ", radius " << num(p.projectionRadius) << " m, true scale at "
          << num(p.latTrueScaleDeg.value_or(0.0)) << " deg, centre lon " << num(p.lonCentreDeg)
          << " deg, origin lat " << num(p.latOriginDeg) << " deg\n";
      break;
  }
}

void printText(const store::Store& s, std::ostream& out) {
  out << "store:          " << s.path().string() << "\n";
  out << "format version: " << s.formatVersion()[0] << "." << s.formatVersion()[1] << "\n";
  const std::vector<std::string> names = sortedGrids(s);
  out << "grids:          " << names.size() << "\n";
  for (const std::string& name : names) {
    const GridInfo& g = s.grid(name);
    const topo::TopoGrid tg = store::topoGridOf(g);
    const bool dem = g.kind == GridKind::Dem;
    const char* unit = dem ? " m" : " deg";
    out << "\ngrid '" << name << "'\n";
    out << "  kind:           "
        << (dem ? "dem (planar grid placed on the body)" : "planet (latitude/longitude grid)")
        << "\n";
    out << "  size:           " << g.rows << " rows x " << g.cols << " cols\n";
    out << "  spacing:        " << num(g.spacingX) << " x " << num(g.spacingY) << unit << "\n";
    out << "  sample (0, 0):  " << (dem ? "x " : "lon ") << num(g.x0) << ", "
        << (dem ? "y " : "lat ") << num(g.y0) << unit << "\n";
    out << "  extent:         " << (dem ? "x " : "lon ") << num(tg.west()) << " to "
        << num(tg.east()) << ", " << (dem ? "y " : "lat ") << num(tg.south()) << " to "
        << num(tg.north()) << unit << " (pixel edges)\n";
    out << "  body:           " << g.bodyName << ", equatorial radius " << num(g.equatorialRadius)
        << " m, polar radius " << num(g.polarRadius) << " m\n";
    out << "  latitude type:  " << latitudeTypeName(g.latitudeType) << "\n";
    if (dem) printPlacement(g, out);
    out << "  levels:         " << g.levels << " (";
    for (std::size_t k = 0; k < g.levels; ++k) {
      out << (k > 0 ? ", " : "") << g.levelRows(k) << "x" << g.levelCols(k);
    }
    out << ")\n";
    out << "  patch:          " << g.patchRows << " x " << g.patchCols << " samples\n";
    out << "  nodata:         "
        << (g.nodata ? num(static_cast<double>(*g.nodata)) : std::string("none (NaN only)"))
        << "\n";
    out << "  height:         " << num(g.offset) << " + " << num(g.scale) << " x stored value, in "
        << g.units << "\n";
    out << "  tiled:          " << (s.tiled(name) ? "yes" : "no") << "\n";
  }
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  struct Args {
    std::string store;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "info",
      "Describe a store: its grids with kind, size, spacing, extent, body, latitude type, "
      "placement, pyramid levels, patch size, nodata, scale/offset and tiling");
  cmd->add_option("store", a->store, "Store file (HDF5)")->required();
  cmd->add_flag("--json", a->json, "Print JSON (keys documented in docs/cli.md)");
  cmd->footer(
      "Examples:\n"
      "  regolith info victoria.h5\n"
      "  regolith info mars.h5 --json | python3 -c 'import json,sys; "
      "print(json.load(sys.stdin)[\"grids\"][0][\"rows\"])'");
  cmd->callback([a] {
    const store::Store s = store::Store::open(a->store);
    if (a->json) {
      printJson(s, std::cout);
    } else {
      printText(s, std::cout);
    }
  });
}

}  // namespace regolith::tools
