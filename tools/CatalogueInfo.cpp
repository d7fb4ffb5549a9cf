#include "CatalogueInfo.hpp"

#include <regolith/compose/FromStore.hpp>
#include <regolith/store/Store.hpp>

#include "OutputFolder.hpp"
#include "ReportText.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <fstream>
#include <ostream>
#include <string>
#include <system_error>
#include <unordered_map>
#include <vector>

namespace regolith::tools {

namespace {

using nlohmann::ordered_json;

const char* latitudeTypeName(topo::LatitudeType t) {
  return t == topo::LatitudeType::Planetocentric ? "planetocentric" : "planetodetic";
}

/// The planetodetic latitude and longitude of the centre of a dataset's level-0 extent.
topo::Geodetic centreOf(const compose::Dataset& d) {
  const topo::TopoGrid& g = d.level(0).grid;
  const double x = 0.5 * (g.west() + g.east()), y = 0.5 * (g.south() + g.north());
  if (d.isPlanet()) return {d.body().toPlanetodetic(y, d.latitudeType()), x, 0.0};
  return d.placement()->toGeodetic(x, y, 0.0);
}

/// The datasets of a catalogue file in file order.
std::vector<std::shared_ptr<const compose::Dataset>> inFileOrder(const compose::CatalogueFile& cf) {
  const auto snapshot = cf.catalogue->snapshot();
  std::unordered_map<compose::DatasetId, std::shared_ptr<const compose::Dataset>> byId;
  for (const compose::CatalogueEntry& e : snapshot->entries()) byId.emplace(e.id, e.dataset);
  std::vector<std::shared_ptr<const compose::Dataset>> out;
  out.reserve(cf.ids.size());
  for (const compose::DatasetId id : cf.ids) out.push_back(byId.at(id));
  return out;
}

ordered_json datasetJson(std::size_t index, compose::DatasetId id, const compose::Dataset& d) {
  const topo::TopoGrid& g = d.level(0).grid;
  const compose::DatasetOptions& o = d.options();
  ordered_json j;
  j["index"] = index;
  j["id"] = id;
  j["name"] = d.name();
  j["kind"] = d.isPlanet() ? "planet" : "dem";
  j["placement"] = d.isPlanet()
                       ? ordered_json(nullptr)
                       : ordered_json(std::string(store::placementKindName(d.placement()->kind())));
  j["latitude_type"] = latitudeTypeName(d.latitudeType());
  j["role"] = compose::roleName(o.role);
  j["priority"] = o.priority;
  j["feather_m"] = o.featherMetres;
  j["mask"] = o.mask != nullptr;
  j["rows"] = g.rows();
  j["cols"] = g.cols();
  j["spacing"] = {g.spacingX(), g.spacingY()};
  j["ground_spacing_m"] = d.groundSpacing();
  j["levels"] = d.levelCount();
  j["extent"] = {
      {"west", g.west()}, {"east", g.east()}, {"north", g.north()}, {"south", g.south()}};
  const topo::Geodetic c = centreOf(d);
  j["centre"] = {{"lat", c.latDeg}, {"lon", c.lonDeg}};
  j["height_range"] = {d.heightRange()[0], d.heightRange()[1]};
  const auto& b = d.bounds();
  j["bounds"] = {{"min", {b[0].x, b[0].y, b[0].z}}, {"max", {b[1].x, b[1].y, b[1].z}}};
  return j;
}

void printDatasetText(std::size_t index, compose::DatasetId id, const compose::Dataset& d,
                      std::ostream& out) {
  const topo::TopoGrid& g = d.level(0).grid;
  const compose::DatasetOptions& o = d.options();
  const bool dem = !d.isPlanet();
  const char* unit = dem ? " m" : " deg";
  out << "\ndataset " << index << " '" << d.name() << "' (id " << id << ")\n";
  out << "  kind:           "
      << (dem ? "dem (planar grid placed on the body)" : "planet (latitude/longitude grid)")
      << "\n";
  if (dem) out << "  placement:      " << store::placementKindName(d.placement()->kind()) << "\n";
  out << "  latitude type:  " << latitudeTypeName(d.latitudeType()) << "\n";
  out << "  role:           " << compose::roleName(o.role) << ", priority " << o.priority
      << ", feather " << shortestNumber(o.featherMetres) << " m, mask " << (o.mask ? "yes" : "none")
      << "\n";
  out << "  size:           " << g.rows() << " rows x " << g.cols() << " cols, " << d.levelCount()
      << (d.levelCount() == 1 ? " level" : " levels") << "\n";
  out << "  spacing:        " << shortestNumber(g.spacingX()) << " x "
      << shortestNumber(g.spacingY()) << unit << " (ground spacing "
      << shortestNumber(d.groundSpacing()) << " m)\n";
  out << "  extent:         " << (dem ? "x " : "lon ") << shortestNumber(g.west()) << " to "
      << shortestNumber(g.east()) << ", " << (dem ? "y " : "lat ") << shortestNumber(g.south())
      << " to " << shortestNumber(g.north()) << unit << " (pixel edges)\n";
  const topo::Geodetic c = centreOf(d);
  out << "  centre:         " << shortestNumber(c.latDeg) << ", " << shortestNumber(c.lonDeg)
      << " (lat, lon deg, planetodetic)\n";
  out << "  height range:   " << shortestNumber(d.heightRange()[0]) << " to "
      << shortestNumber(d.heightRange()[1]) << " m\n";
  const auto& b = d.bounds();
  out << "  bounds:         x " << shortestNumber(b[0].x) << " to " << shortestNumber(b[1].x)
      << ", y " << shortestNumber(b[0].y) << " to " << shortestNumber(b[1].y) << ", z "
      << shortestNumber(b[0].z) << " to " << shortestNumber(b[1].z) << " m (body-fixed)\n";
}

}  // namespace

bool isCatalogueFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec) || store::Store::isHdf5(path)) return false;
  std::ifstream in(path, std::ios::binary);
  std::array<char, 4096> buf{};
  in.read(buf.data(), buf.size());
  const auto n = static_cast<std::size_t>(in.gcount());
  std::size_t i = 0;
  if (n >= 3 && buf[0] == '\xEF' && buf[1] == '\xBB' && buf[2] == '\xBF') i = 3;
  while (i < n && (buf[i] == ' ' || buf[i] == '\t' || buf[i] == '\n' || buf[i] == '\r')) ++i;
  return i < n && buf[i] == '{';
}

void printCatalogueInfo(const std::filesystem::path& path, bool json, std::ostream& out) {
  const compose::CatalogueFile cf = compose::readCatalogueFile(path);
  // `regolith info moon.json >> mola.h5` would append to a store it reads (the command
  // checks the catalogue file itself).
  for (const auto& pager : cf.pagers) refuseStdoutOverInput("info", pager->store().path());
  const topo::Body& body = cf.catalogue->body();
  const auto datasets = inFileOrder(cf);
  if (json) {
    ordered_json j;
    j["path"] = path.string();
    j["body"] = {{"name", body.name()},
                 {"equatorial_radius", body.equatorialRadius()},
                 {"polar_radius", body.polarRadius()}};
    j["policy"] = compose::policyName(cf.rules.policy);
    j["resolution_power"] = cf.rules.resolutionPower;
    j["tier_ratio"] = cf.rules.tierRatio;
    ordered_json list = ordered_json::array();
    for (std::size_t i = 0; i < datasets.size(); ++i) {
      list.push_back(datasetJson(i, cf.ids[i], *datasets[i]));
    }
    j["datasets"] = list;
    out << j.dump(2, ' ', false, ordered_json::error_handler_t::replace) << '\n';
    return;
  }
  out << "catalogue:      " << path.string() << "\n";
  out << "body:           " << body.name() << ", equatorial radius "
      << shortestNumber(body.equatorialRadius()) << " m, polar radius "
      << shortestNumber(body.polarRadius()) << " m\n";
  out << "rules:          policy " << compose::policyName(cf.rules.policy) << ", resolution power "
      << shortestNumber(cf.rules.resolutionPower) << ", tier ratio "
      << shortestNumber(cf.rules.tierRatio) << "\n";
  out << "datasets:       " << datasets.size() << "\n";
  for (std::size_t i = 0; i < datasets.size(); ++i) {
    printDatasetText(i, cf.ids[i], *datasets[i], out);
  }
}

}  // namespace regolith::tools
