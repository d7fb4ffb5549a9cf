#include <regolith/compose/FromStore.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>

namespace regolith::compose {

std::shared_ptr<const Dataset> datasetFromStore(const store::Pager& pager, std::string_view grid,
                                                DatasetOptions options,
                                                std::shared_ptr<core::Executor> loader) {
  const store::GridInfo& info = pager.grid(grid);
  if (options.name.empty()) options.name = info.name;
  if (!options.heightRange && info.statistics && info.statistics->validSamples > 0) {
    options.heightRange = std::array<double, 2>{info.statistics->min, info.statistics->max};
  }
  const topo::GridPyramid pyramid = pager.pyramid(grid, std::move(loader));
  if (info.kind == store::GridKind::Planet) return Dataset::planet(pyramid, std::move(options));
  return Dataset::dem(pyramid, store::placementOf(info), std::move(options));
}

namespace {

[[noreturn]] void badFile(const std::filesystem::path& path, const std::string& field,
                          const std::string& value, const std::string& expected) {
  throw InvalidArgument(core::format({.operation = "compose::readCatalogueFile()",
                                      .file = path.string(),
                                      .field = field,
                                      .value = value,
                                      .expected = expected}));
}

std::string shown(const nlohmann::json& j) {
  std::string s = j.dump();
  if (s.size() > 80) s = s.substr(0, 77) + "...";
  return s;
}

double number(const std::filesystem::path& path, const nlohmann::json& j, const std::string& field,
              double lo, double hi) {
  if (!j.is_number()) badFile(path, field, shown(j), "a number");
  const double v = j.get<double>();
  if (!(v >= lo && v <= hi)) {
    badFile(path, field, core::number(v), "within " + core::number(lo) + " .. " + core::number(hi));
  }
  return v;
}

std::string text(const std::filesystem::path& path, const nlohmann::json& j,
                 const std::string& field) {
  if (!j.is_string() || j.get<std::string>().empty())
    badFile(path, field, shown(j), "a non-empty string");
  return j.get<std::string>();
}

}  // namespace

CatalogueFile readCatalogueFile(const std::filesystem::path& path, std::size_t cacheBytes,
                                const std::shared_ptr<core::Executor>& loader) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw IoError(core::format({.operation = "compose::readCatalogueFile()",
                                .file = path.string(),
                                .field = "the file cannot be opened",
                                .expected = "a readable catalogue file (JSON)"}));
  }
  std::ostringstream buf;
  buf << in.rdbuf();
  if (buf.str().size() > (std::size_t{16} << 20)) {
    badFile(path, "size", std::to_string(buf.str().size()) + " bytes", "at most 16 MiB");
  }
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(buf.str());
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range 406 for a number beyond double (1e999): found by
    // fuzz_info_json (stop 31), which reached here through `regolith info` on such a file.
    badFile(path, "JSON", e.what(), "valid JSON");
  }
  if (!root.is_object()) badFile(path, "top level", shown(root), "an object");
  static const std::set<std::string> kTop{"policy", "resolution_power", "tier_ratio", "datasets"};
  for (const auto& [key, value] : root.items()) {
    if (!kTop.count(key))
      badFile(path, "key '" + key + "'", shown(value),
              "one of policy, resolution_power, tier_ratio, datasets");
  }
  CatalogueFile out;
  if (root.contains("policy")) {
    const std::string p = text(path, root["policy"], "policy");
    if (p == "weighted") {
      out.rules.policy = Policy::Weighted;
    } else if (p == "finest") {
      out.rules.policy = Policy::FinestWins;
    } else {
      badFile(path, "policy", "'" + p + "'", "weighted or finest");
    }
  }
  if (root.contains("resolution_power")) {
    out.rules.resolutionPower =
        number(path, root["resolution_power"], "resolution_power", 0.0, 64.0);
  }
  if (root.contains("tier_ratio")) {
    out.rules.tierRatio =
        number(path, root["tier_ratio"], "tier_ratio", 1.0, std::numeric_limits<double>::max());
  }
  if (!root.contains("datasets") || !root["datasets"].is_array() || root["datasets"].empty()) {
    badFile(path, "datasets", root.contains("datasets") ? shown(root["datasets"]) : "missing",
            "a non-empty array of datasets");
  }
  auto cache = std::make_shared<store::PatchCache>(cacheBytes);
  std::map<std::filesystem::path, std::shared_ptr<const store::Pager>> pagers;
  std::vector<std::shared_ptr<const Dataset>> datasets;
  static const std::set<std::string> kKeys{"store",
                                           "grid",
                                           "role",
                                           "priority",
                                           "feather_m",
                                           "mask_grid",
                                           "feather_nodata_samples",
                                           "name",
                                           "height_offset_m"};
  std::size_t index = 0;
  for (const auto& d : root["datasets"]) {
    const std::string where = "datasets[" + std::to_string(index++) + "]";
    if (!d.is_object()) badFile(path, where, shown(d), "an object");
    for (const auto& [key, value] : d.items()) {
      if (!kKeys.count(key)) {
        std::string field = where;
        field += " key '";
        field += key;
        field += "'";
        badFile(path, field, shown(value),
                "one of store, grid, name, role, priority, feather_m, height_offset_m, "
                "mask_grid, feather_nodata_samples");
      }
    }
    if (!d.contains("store")) badFile(path, where + ".store", "missing", "a store path");
    if (!d.contains("grid")) badFile(path, where + ".grid", "missing", "a grid name");
    std::filesystem::path storePath = text(path, d["store"], where + ".store");
    if (storePath.is_relative()) storePath = path.parent_path() / storePath;
    auto& pager = pagers[storePath];
    if (!pager) {
      pager = std::make_shared<store::Pager>(
          std::make_shared<const store::Store>(store::Store::open(storePath)), cache);
    }
    const std::string grid = text(path, d["grid"], where + ".grid");
    DatasetOptions o;
    if (d.contains("name")) o.name = text(path, d["name"], where + ".name");
    if (d.contains("role")) {
      const std::string r = text(path, d["role"], where + ".role");
      if (r == "height") {
        o.role = Role::Height;
      } else if (r == "albedo") {
        o.role = Role::Albedo;
      } else if (r == "overlay") {
        o.role = Role::Overlay;
      } else {
        badFile(path, where + ".role", "'" + r + "'", "height, albedo or overlay");
      }
    }
    if (d.contains("priority")) {
      o.priority = static_cast<int>(number(path, d["priority"], where + ".priority", -1e6, 1e6));
    }
    if (d.contains("height_offset_m")) {
      o.heightOffset = number(path, d["height_offset_m"], where + ".height_offset_m", -1e6, 1e6);
    }
    if (d.contains("feather_m"))
      o.featherMetres = number(path, d["feather_m"], where + ".feather_m", 0.0, 1e8);
    if (d.contains("mask_grid") && d.contains("feather_nodata_samples")) {
      badFile(path, where + ".mask_grid", shown(d["mask_grid"]),
              "either mask_grid or feather_nodata_samples, not both");
    }
    if (d.contains("mask_grid")) {
      o.mask = pager->source(text(path, d["mask_grid"], where + ".mask_grid"), 0);
    }
    if (d.contains("feather_nodata_samples")) {
      const double w =
          number(path, d["feather_nodata_samples"], where + ".feather_nodata_samples", 1e-3, 1e6);
      const auto& info = pager->grid(grid);
      o.mask = featherMask(store::topoGridOf(info, 0), *pager->source(grid, 0), w, false);
    }
    datasets.push_back(datasetFromStore(*pager, grid, std::move(o), loader));
  }
  out.catalogue = std::make_shared<Catalogue>(datasets.front()->body());
  const topo::Body& body = datasets.front()->body();
  for (std::size_t i = 1; i < datasets.size(); ++i) {
    const topo::Body& b = datasets[i]->body();
    if (std::abs(b.equatorialRadius() - body.equatorialRadius()) > 1e-3 ||
        std::abs(b.polarRadius() - body.polarRadius()) > 1e-3) {
      badFile(path, "datasets[" + std::to_string(i) + "] body",
              b.name() + " (" + core::number(b.equatorialRadius()) + " / " +
                  core::number(b.polarRadius()) + " m)",
              "datasets[0]'s body " + body.name() + " (" + core::number(body.equatorialRadius()) +
                  " / " + core::number(body.polarRadius()) + " m): one catalogue is one body");
    }
  }
  out.ids = out.catalogue->add(datasets);
  for (auto& [p, pager] : pagers) out.pagers.push_back(pager);
  return out;
}

}  // namespace regolith::compose
