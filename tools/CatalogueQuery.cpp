#include "CatalogueQuery.hpp"

#include <regolith/compose/FromStore.hpp>
#include <regolith/store/Store.hpp>

#include "OutputFolder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace regolith::tools {

namespace {

/// A CSV field: as it is, or in double quotes (inner quotes doubled) if it holds a comma, a
/// quote or a line break (RFC 4180); dataset names come from files.
void appendCsvText(std::string& out, std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) {
    out += s;
    return;
  }
  out += '"';
  for (const char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
}

/// Writes `out` to stdout once it holds about 1 MiB (and at the end), so a million points
/// need no more memory than a batch.
void flushIfLarge(std::string& out, bool force = false) {
  if (!force && out.size() < (std::size_t{1} << 20U)) return;
  std::fwrite(out.data(), 1, out.size(), stdout);
  out.clear();
}

void appendSurfaceRow(std::string& out, const Point& p, const compose::ComposedSample& s) {
  const bool valid = s.status == topo::QueryStatus::Ok;
  const bool normalValid = valid && s.normalStatus == topo::QueryStatus::Ok;
  const double nan = std::nan("");
  appendCsvNumber(out, p.a);
  out += ',';
  appendCsvNumber(out, p.b);
  out += ',';
  appendCsvNumber(out, valid ? s.height : nan);
  for (int k = 0; k < 3; ++k) {
    out += ',';
    appendCsvNumber(out, normalValid ? s.normal[k] : nan);
  }
  out += valid ? ",1," : ",0,";
  out += normalValid ? "1," : "0,";
  out += topo::statusName(valid ? s.normalStatus : s.status);
  out += ',';
  out += std::to_string(s.contributors);
  out += '\n';
}

}  // namespace

void runCatalogueQuery(const CatalogueQueryOptions& options, std::span<const Point> points) {
  const compose::CatalogueFile cf =
      compose::readCatalogueFile(options.file, options.cacheMb << 20U);
  for (const auto& pager : cf.pagers) refuseStdoutOverInput("query", pager->store().path());
  const auto snapshot = cf.catalogue->snapshot();
  const compose::ComposedSurface surface(snapshot, cf.rules);

  // Each dataset's index in the file and its name, for --explain.
  std::unordered_map<compose::DatasetId, std::pair<std::size_t, std::string>> datasets;
  for (std::size_t i = 0; i < cf.ids.size(); ++i) datasets.emplace(cf.ids[i], std::pair{i, ""});
  for (const compose::CatalogueEntry& e : snapshot->entries()) {
    const auto it = datasets.find(e.id);
    if (it != datasets.end()) it->second.second = e.dataset->name();
  }

  std::string out;
  if (!options.explain) {
    out = "lon,lat,height,nx,ny,nz,valid,normal_valid,reason,contributors\n";
    for (const Point& p : points) {
      appendSurfaceRow(out, p, surface.surface(p.b, p.a, options.frame));
      flushIfLarge(out);
    }
  } else {
    out =
        "lon,lat,point,height,valid,reason,contributors,dataset,name,dataset_height,coverage,"
        "quality,share\n";
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Point& p = points[i];
      const topo::HeightSample h = surface.height(p.b, p.a);
      const std::vector<compose::Share> shares = surface.weights(p.b, p.a);
      const bool valid = h.status == topo::QueryStatus::Ok;
      // The columns every row of this point repeats.
      std::string head;
      appendCsvNumber(head, p.a);
      head += ',';
      appendCsvNumber(head, p.b);
      head += ',';
      head += std::to_string(i + 1);
      head += ',';
      appendCsvNumber(head, valid ? h.height : std::nan(""));
      head += valid ? ",1," : ",0,";
      head += topo::statusName(h.status);
      head += ',';
      // Contributors: the datasets with a non-zero share (ComposedSample::contributors).
      head += std::to_string(std::count_if(
          shares.begin(), shares.end(), [](const compose::Share& sh) { return sh.weight > 0.0; }));
      head += ',';
      if (shares.empty()) {
        // A point nothing covers still gets its row.
        out += head;
        out += ",,nan,nan,nan,nan\n";
      }
      for (const compose::Share& s : shares) {
        const auto& [index, name] = datasets.at(s.id);
        out += head;
        out += std::to_string(index);
        out += ',';
        appendCsvText(out, name);
        for (const double v : {s.height, s.coverage, s.quality, s.weight}) {
          out += ',';
          appendCsvNumber(out, v);
        }
        out += '\n';
      }
      flushIfLarge(out);
    }
  }
  flushIfLarge(out, true);
  std::fflush(stdout);
}

}  // namespace regolith::tools
