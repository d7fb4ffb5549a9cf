// `regolith info FILE [--json]`: what a store holds, or what an import would make of a raster.
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>
#include <regolith/store/ProjPlacement.hpp>
#include <regolith/store/Store.hpp>

#include "CatalogueInfo.hpp"
#include "Commands.hpp"
#include "OutputFolder.hpp"
#include "ReportText.hpp"
#include "SceneFiles.hpp"

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
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
  return std::string(store::placementKindName(k));
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
    case PlacementInfo::Kind::TransverseMercator:
      j["lon_centre_deg"] = p.lonCentreDeg;
      j["lat_origin_deg"] = p.latOriginDeg;
      j["scale_factor"] = p.scaleFactor ? ordered_json(*p.scaleFactor) : nullptr;
      j["false_easting"] = p.falseEasting;
      j["false_northing"] = p.falseNorthing;
      break;
    case PlacementInfo::Kind::Projected:
      j["crs_name"] = store::projProjection(p.crs)->name();
      j["proj_string"] = store::projString(p.crs);
      j["crs_wkt"] = p.crs;
      break;
  }
  return j;
}

/// Planetodetic position of the reference surface at fractional sample (row, col).
topo::Geodetic geodeticAt(const GridInfo& g, double row, double col) {
  const double x = g.x0 + col * g.spacingX, y = g.y0 - row * g.spacingY;
  if (g.kind == GridKind::Dem) return store::placementOf(g).toGeodetic(x, y, 0.0);
  return {store::bodyOf(g).toPlanetodetic(y, g.latitudeType), x, 0.0};
}

/// Where a grid lies: its corner and centre samples (planetodetic degrees), and its ground
/// size in metres along the centre row and the centre column, pixel edge to edge, measured
/// on the reference surface as a polyline of 256 segments in body-fixed coordinates.
struct Footprint {
  std::array<topo::Geodetic, 4> corners;  // NW, NE, SW, SE sample centres
  topo::Geodetic centre;
  double widthM = 0.0, heightM = 0.0;
};

Footprint footprintOf(const GridInfo& g) {
  Footprint f;
  const double r1 = static_cast<double>(g.rows) - 1.0, c1 = static_cast<double>(g.cols) - 1.0;
  f.corners = {geodeticAt(g, 0.0, 0.0), geodeticAt(g, 0.0, c1), geodeticAt(g, r1, 0.0),
               geodeticAt(g, r1, c1)};
  f.centre = geodeticAt(g, 0.5 * r1, 0.5 * c1);
  const topo::Body body = store::bodyOf(g);
  const auto length = [&](double ra, double ca, double rb, double cb) {
    constexpr int kSegments = 256;
    double sum = 0.0;
    glm::dvec3 prev = body.toBodyFixed(geodeticAt(g, ra, ca));
    for (int k = 1; k <= kSegments; ++k) {
      const double t = static_cast<double>(k) / kSegments;
      const glm::dvec3 p = body.toBodyFixed(geodeticAt(g, ra + t * (rb - ra), ca + t * (cb - ca)));
      sum += glm::length(p - prev);
      prev = p;
    }
    return sum;
  };
  f.widthM = length(0.5 * r1, -0.5, 0.5 * r1, c1 + 0.5);
  f.heightM = length(-0.5, 0.5 * c1, r1 + 0.5, 0.5 * c1);
  return f;
}

ordered_json geodeticJson(const topo::Geodetic& p) {
  return {{"lat", p.latDeg}, {"lon", p.lonDeg}};
}

/// A grid's provenance attribute as JSON: null if not recorded, the text itself (a string)
/// if it is not JSON (a damaged store: printing what parse() returns then, a "discarded"
/// value, made `info --json` print `<discarded>`, found by tests/fuzz/fuzz_info_json).
ordered_json provenanceJson(const std::string& text) {
  if (text.empty()) return nullptr;
  ordered_json p = ordered_json::parse(text, nullptr, false);
  return p.is_discarded() ? ordered_json(text) : p;
}

/// JSON text of `j`, indented by 2. A store's strings (names, body, units, provenance) are
/// bytes from the file: any that are not UTF-8 are printed as U+FFFD rather than making
/// dump() throw type_error (tests/tools/InfoCommandTest.cpp).
std::string jsonText(const ordered_json& j) {
  return j.dump(2, ' ', false, ordered_json::error_handler_t::replace);
}

/// The grid's keys. `tiled` is set for a grid of a store (whether level 0 is tiled), and adds
/// levels, patch shape and tiling; unset for the grid a raster would become.
ordered_json gridJson(const GridInfo& g, std::optional<bool> tiled) {
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
  const Footprint f = footprintOf(g);
  j["geodetic"] = {{"north_west", geodeticJson(f.corners[0])},
                   {"north_east", geodeticJson(f.corners[1])},
                   {"south_west", geodeticJson(f.corners[2])},
                   {"south_east", geodeticJson(f.corners[3])},
                   {"centre", geodeticJson(f.centre)}};
  j["ground_size_m"] = {f.widthM, f.heightM};
  if (tiled) {
    j["levels"] = g.levels;
    ordered_json shapes = ordered_json::array();
    for (std::size_t k = 0; k < g.levels; ++k) {
      shapes.push_back({g.levelRows(k), g.levelCols(k)});
    }
    j["level_shapes"] = shapes;
    j["patch_shape"] = {g.patchRows, g.patchCols};
  }
  j["nodata"] = g.nodata ? ordered_json(static_cast<double>(*g.nodata)) : nullptr;
  j["scale"] = g.scale;
  j["offset"] = g.offset;
  if (tiled) {
    j["tiled"] = *tiled;
    // Stored at import (format 1.3); null for stores written without them: no scan at open.
    if (g.statistics) {
      const store::HeightStatistics& s = *g.statistics;
      j["statistics"] = {
          {"min", s.min}, {"max", s.max}, {"mean", s.mean}, {"valid_samples", s.validSamples}};
    } else {
      j["statistics"] = nullptr;
    }
    // Recorded at import (format 1.3): sources, GDAL, label fields; null if not recorded.
    j["provenance"] = provenanceJson(g.provenance);
  }
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
  for (const std::string& name : sortedGrids(s)) {
    grids.push_back(gridJson(s.grid(name), s.tiled(name)));
  }
  j["grids"] = grids;
  out << jsonText(j) << '\n';
}

void printPlacement(const GridInfo& g, std::ostream& out) {
  const PlacementInfo& p = g.placement;
  out << "  placement:      " << placementName(p.kind);
  switch (p.kind) {
    case PlacementInfo::Kind::LocalTangentPlane:
      out << ", origin lat " << shortestNumber(p.originLatDeg) << " deg, lon "
          << shortestNumber(p.originLonDeg) << " deg, height " << shortestNumber(p.originHeight)
          << " m, heading " << shortestNumber(p.headingDeg) << " deg\n";
      break;
    case PlacementInfo::Kind::PolarStereographic:
      out << ", " << (p.pole >= 0 ? "north" : "south") << " pole";
      if (p.latTrueScaleDeg)
        out << ", true scale at " << shortestNumber(*p.latTrueScaleDeg) << " deg";
      if (p.scaleFactor) out << ", scale factor " << shortestNumber(*p.scaleFactor);
      out << ", centre lon " << shortestNumber(p.lonCentreDeg) << " deg, false easting "
          << shortestNumber(p.falseEasting) << " m, false northing "
          << shortestNumber(p.falseNorthing) << " m\n";
      break;
    case PlacementInfo::Kind::Equirectangular:
      out << ", radius " << shortestNumber(p.projectionRadius) << " m, true scale at "
          << shortestNumber(p.latTrueScaleDeg.value_or(0.0)) << " deg, centre lon "
          << shortestNumber(p.lonCentreDeg) << " deg, origin lat " << shortestNumber(p.latOriginDeg)
          << " deg\n";
      break;
    case PlacementInfo::Kind::TransverseMercator:
      out << ", central meridian " << shortestNumber(p.lonCentreDeg) << " deg, origin lat "
          << shortestNumber(p.latOriginDeg) << " deg, scale factor "
          << shortestNumber(p.scaleFactor.value_or(std::numeric_limits<double>::quiet_NaN()))
          << ", false easting " << shortestNumber(p.falseEasting) << " m, false northing "
          << shortestNumber(p.falseNorthing) << " m\n";
      break;
    case PlacementInfo::Kind::Projected:
      out << " through PROJ, CRS '" << store::projProjection(p.crs)->name() << "'\n"
          << "  proj string:    " << store::projString(p.crs) << "\n";
      break;
  }
}

/// Field `key` of a JSON object as text: a string as it is, anything else as JSON, "" if
/// `o` is no object or has no such field. The provenance is read from the file, so none of
/// its fields may be trusted to have the type the importer wrote (a wrong one made
/// nlohmann::json throw type_error out of `info`; tests/tools/InfoCommandTest.cpp).
std::string fieldText(const ordered_json& o, const char* key) {
  if (!o.is_object() || !o.contains(key)) return {};
  const ordered_json& v = o[key];
  return v.is_string() ? v.get<std::string>()
                       : v.dump(-1, ' ', false, ordered_json::error_handler_t::replace);
}

/// The provenance lines of `info`: sources, GDAL, the label's fields.
void printProvenance(const ordered_json& p, std::ostream& out) {
  const char* label = "  sources:        ";
  if (p.contains("sources") && p["sources"].is_array()) {
    for (const auto& s : p["sources"]) {
      // The digest is absent where the import was told not to take it (digestSources).
      const std::string sha = fieldText(s, "sha256");
      out << label << fieldText(s, "file") << ", " << fieldText(s, "bytes") << " bytes, "
          << (sha.empty() ? std::string("no digest recorded") : "sha256 " + sha) << "\n";
      label = "                  ";
    }
  }
  out << "  made with:      GDAL " << fieldText(p, "gdal_version") << ", driver "
      << fieldText(p, "gdal_driver") << "\n";
  if (p.contains("label") && p["label"].is_object()) {
    std::string fields;
    for (const auto& [key, value] : p["label"].items()) {
      // GDAL's "_type" and the like, and PDS3's end marker.
      if ((!key.empty() && key.front() == '_') || key == "END_OBJECT") continue;
      const auto json = [](const ordered_json& x) {
        return x.dump(-1, ' ', false, ordered_json::error_handler_t::replace);
      };
      std::string v = value.is_object() && value.contains("value") ? json(value["value"])
                      : value.is_string()                          ? value.get<std::string>()
                                                                   : json(value);
      if (value.is_object() && value.contains("value") && value.contains("unit")) {
        v += " <" + fieldText(value, "unit") + ">";
      }
      if (!fields.empty()) fields += "; ";
      fields.append(key).append(" = ").append(v);
    }
    out << "  label:          " << fields << "\n";
  }
}

/// One grid as text; `tiled` as in gridJson().
void printGrid(const GridInfo& g, std::optional<bool> tiled, std::ostream& out) {
  const topo::TopoGrid tg = store::topoGridOf(g);
  const bool dem = g.kind == GridKind::Dem;
  const char* unit = dem ? " m" : " deg";
  out << "\ngrid '" << g.name << "'\n";
  out << "  kind:           "
      << (dem ? "dem (planar grid placed on the body)" : "planet (latitude/longitude grid)")
      << "\n";
  out << "  size:           " << g.rows << " rows x " << g.cols << " cols\n";
  out << "  spacing:        " << shortestNumber(g.spacingX) << " x " << shortestNumber(g.spacingY)
      << unit << "\n";
  out << "  sample (0, 0):  " << (dem ? "x " : "lon ") << shortestNumber(g.x0) << ", "
      << (dem ? "y " : "lat ") << shortestNumber(g.y0) << unit << "\n";
  out << "  extent:         " << (dem ? "x " : "lon ") << shortestNumber(tg.west()) << " to "
      << shortestNumber(tg.east()) << ", " << (dem ? "y " : "lat ") << shortestNumber(tg.south())
      << " to " << shortestNumber(tg.north()) << unit << " (pixel edges)\n";
  out << "  body:           " << g.bodyName << ", equatorial radius "
      << shortestNumber(g.equatorialRadius) << " m, polar radius " << shortestNumber(g.polarRadius)
      << " m\n";
  out << "  latitude type:  " << latitudeTypeName(g.latitudeType) << "\n";
  if (dem) printPlacement(g, out);
  const Footprint f = footprintOf(g);
  const auto at = [](const topo::Geodetic& p) {
    return shortestNumber(p.latDeg) + ", " + shortestNumber(p.lonDeg);
  };
  out << "  corners:        NW " << at(f.corners[0]) << "; NE " << at(f.corners[1]) << "; SW "
      << at(f.corners[2]) << "; SE " << at(f.corners[3])
      << " (lat, lon deg, planetodetic, sample centres)\n";
  out << "  centre:         " << at(f.centre) << " (lat, lon deg)\n";
  out << "  ground size:    " << shortestNumber(std::round(f.widthM)) << " x "
      << shortestNumber(std::round(f.heightM))
      << " m (centre row x centre column, pixel edge to edge)\n";
  if (tiled) {
    out << "  levels:         " << g.levels << " (";
    for (std::size_t k = 0; k < g.levels; ++k) {
      out << (k > 0 ? ", " : "") << g.levelRows(k) << "x" << g.levelCols(k);
    }
    out << ")\n";
    out << "  patch:          " << g.patchRows << " x " << g.patchCols << " samples\n";
  }
  out << "  nodata:         "
      << (g.nodata ? shortestNumber(static_cast<double>(*g.nodata))
                   : std::string("none (NaN only)"))
      << "\n";
  out << "  height:         " << shortestNumber(g.offset) << " + " << shortestNumber(g.scale)
      << " x stored value, in " << g.units << "\n";
  if (tiled) {
    out << "  tiled:          " << (*tiled ? "yes" : "no") << "\n";
    if (g.statistics) {
      const store::HeightStatistics& s = *g.statistics;
      const double total = static_cast<double>(g.rows) * static_cast<double>(g.cols);
      out << "  heights:        min " << shortestNumber(s.min) << ", max " << shortestNumber(s.max)
          << ", mean " << shortestNumber(s.mean) << " m; " << s.validSamples << " valid samples ("
          << shortestNumber(std::round(1000.0 * static_cast<double>(s.validSamples) / total) / 10.0)
          << "%)\n";
    } else {
      out << "  heights:        no statistics stored (written before format 1.3)\n";
    }
    const ordered_json p = provenanceJson(g.provenance);
    if (p.is_object()) {
      printProvenance(p, out);
    } else if (p.is_string()) {
      out << "  provenance:     recorded, but not JSON (a damaged store?)\n";
    } else {
      out << "  provenance:     not recorded\n";
    }
  }
}

void printText(const store::Store& s, std::ostream& out) {
  out << "store:          " << s.path().string() << "\n";
  out << "format version: " << s.formatVersion()[0] << "." << s.formatVersion()[1] << "\n";
  const std::vector<std::string> names = sortedGrids(s);
  out << "grids:          " << names.size() << "\n";
  for (const std::string& name : names) printGrid(s.grid(name), s.tiled(name), out);
}

/// The raster section (what importRaster() would report) as JSON.
ordered_json rasterJson(const store::ImportReport& r) {
  ordered_json j;
  j["driver"] = r.driver;
  j["projection"] = r.projection;
  j["radius_reference"] = r.radiusReference;
  j["offset_corrected"] = r.offsetCorrected;
  j["spacing_snapped"] = r.spacingSnapped;
  j["void_marker_assumed"] = r.voidMarkerAssumed;
  j["dropped_north_rows"] = r.droppedNorthRows;
  j["dropped_south_rows"] = r.droppedSouthRows;
  j["dropped_columns"] = r.droppedColumns;
  j["pole_shift_pixels"] = r.poleShiftPixels;
  j["corrections"] = appliedCorrections(r);
  return j;
}

/// `info` on a file that is not HDF5: GDAL's view of it, and the grid an import would write.
void printRaster(const std::filesystem::path& path, bool json, std::ostream& out) {
  store::ImportReport r;
  try {
    r = store::inspectRaster(path);
  } catch (const store::ImportError& e) {
    throw store::ImportError(
        "info: " + path.string() +
        " is not an HDF5 file (not a Regolith store), and as a raster: " + e.what());
  }
  if (json) {
    ordered_json j;
    j["path"] = path.string();
    j["raster"] = rasterJson(r);
    j["grid"] = gridJson(r.info, std::nullopt);
    out << jsonText(j) << '\n';
    return;
  }
  out << "raster:         " << path.string() << " (not a store; what `regolith import` would "
      << "write)\n";
  out << "driver:         " << r.driver << "\n";
  out << "projection:     " << r.projection << "\n";
  const std::vector<std::string> corrections = appliedCorrections(r);
  out << "corrections:    " << (corrections.empty() ? "none" : corrections.front()) << "\n";
  for (std::size_t i = 1; i < corrections.size(); ++i) {
    out << "                " << corrections[i] << "\n";
  }
  printGrid(r.info, std::nullopt, out);
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
      "placement, pyramid levels, patch size, nodata, scale/offset and tiling. Given a "
      "raster that is not HDF5, describe what an import would make of it: GDAL driver, "
      "projection, corrections and the grid, without writing anything. Given a catalogue file "
      "(a JSON object, docs/composition.md), list its body, rules and datasets: name, kind, "
      "placement, size, spacing, role, priority, feather, mask, height range and bounds");
  cmd->add_option("file", a->store,
                  "Store file (HDF5), or a raster GDAL reads (GeoTIFF, PDS3, PDS4, ISIS3, "
                  ".hgt, ...): then what `regolith import` would make of it, or a catalogue "
                  "file (JSON)")
      ->required();
  cmd->add_flag("--json", a->json, "Print JSON (keys documented in docs/cli.md)");
  cmd->footer(
      "Examples:\n"
      "  regolith info victoria.h5\n"
      "  regolith info dtm.cub --json\n"
      "  regolith info moon.json\n"
      "  regolith info mars.h5 --json | python3 -c 'import json,sys; "
      "print(json.load(sys.stdin)[\"grids\"][0][\"rows\"])'");
  cmd->callback([a] {
    refuseStdoutOverInput("info", a->store);
    printInfo(a->store, a->json, std::cout);
  });
}

void printInfo(const std::string& file, bool json, std::ostream& out) {
  std::error_code ec;
  // GDAL's virtual paths (/vsizip/, /vsicurl/, ...) are rasters: `import` accepts them.
  const bool virtualPath = file.rfind("/vsi", 0) == 0;
  if (!virtualPath && isSceneFile(file)) {
    printSceneInfo(file, json, out);
    return;
  }
  if (!virtualPath && isCatalogueFile(file)) {
    printCatalogueInfo(file, json, out);
    return;
  }
  if (virtualPath || (std::filesystem::is_regular_file(file, ec) && !store::Store::isHdf5(file))) {
    printRaster(file, json, out);
    return;
  }
  const store::Store s = store::Store::open(file);
  if (json) {
    printJson(s, out);
  } else {
    printText(s, out);
  }
}

}  // namespace regolith::tools
