// `regolith import SOURCE... --out STORE`: GDAL rasters into a store (store/Import.hpp,
// docs/import.md).
#include <regolith/core/Error.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/store/Import.hpp>

#include "CancelOnSignal.hpp"
#include "Commands.hpp"
#include "OutputFolder.hpp"
#include "ReportText.hpp"
#include "TerminalProgress.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace regolith::tools {

namespace {

struct Args {
  std::vector<std::string> sources;
  std::string out;
  std::string grid;
  std::size_t patch = 256;
  std::size_t levels = 0;
  int deflate = 0;
  std::string compression = "deflate";
  unsigned threads = 0;
  std::size_t memoryMb = 1024;
  double nodata = 0.0;
  std::string body;
  std::vector<std::size_t> window;
  std::vector<double> bbox;
  bool strict = false;
  // A height map without georeferencing (store::HeightMapOptions).
  std::vector<double> spacing, origin;
  double heightScale = 1.0, heightOffset = 0.0, heading = 0.0;
};

/// The height-map flags, which place a raster without georeferencing.
void addHeightMapOptions(CLI::App& cmd, Args& a) {
  auto* spacing = cmd.add_option("--spacing", a.spacing,
                                 "Height map without georeferencing (PNG, GeoTIFF without a CRS): "
                                 "metres between samples, DX or DX,DY")
                      ->delimiter(',')
                      ->expected(1, 2);
  auto* origin = cmd.add_option("--origin", a.origin,
                                "Height map: LAT,LON (planetodetic degrees) of its centre sample; "
                                "with --body (Mars, Moon or Earth)")
                     ->delimiter(',')
                     ->expected(2);
  spacing->needs(origin);
  origin->needs(spacing);
  cmd.add_option("--height-scale", a.heightScale,
                 "Height map: metres per raster value (heights = offset + scale * value)")
      ->needs(spacing)
      ->capture_default_str();
  cmd.add_option("--height-offset", a.heightOffset, "Height map: metres added to every height")
      ->needs(spacing)
      ->capture_default_str();
  cmd.add_option("--heading", a.heading,
                 "Height map: azimuth of the grid's y axis (up the rows), degrees clockwise "
                 "from north")
      ->needs(spacing)
      ->capture_default_str();
}

std::optional<store::HeightMapOptions> heightMapOf(const Args& a) {
  if (a.spacing.empty()) return std::nullopt;
  store::HeightMapOptions h;
  h.spacingX = a.spacing.front();
  h.spacingY = a.spacing.back();
  h.heightScale = a.heightScale;
  h.heightOffset = a.heightOffset;
  h.originLatDeg = a.origin.at(0);
  h.originLonDeg = a.origin.at(1);
  h.headingDeg = a.heading;
  return h;
}

std::string mebibytes(std::size_t bytes) {
  return shortestNumber(std::round(static_cast<double>(bytes) / 1048576.0 * 10.0) / 10.0) + " MiB";
}

/// The budget in bytes of --memory-mb; refuses one below the writer's minimum.
std::size_t memoryBudgetOf(const Args& a, const store::ImportOptions& o) {
  constexpr std::size_t kMiB = std::size_t{1} << 20U;
  if (a.memoryMb == 0) return 0;
  if (a.memoryMb > std::numeric_limits<std::size_t>::max() / kMiB) {
    throw InvalidArgument("import: --memory-mb " + std::to_string(a.memoryMb) +
                          " is beyond this machine's address space");
  }
  // The default grows to the minimum (patches above 4096), as the library's does.
  if (a.memoryMb * kMiB == store::kDefaultMemoryBudget) return store::kDefaultMemoryBudget;
  const std::size_t least = store::writerMemoryMinimum(o);
  if (a.memoryMb * kMiB < least) {
    const std::size_t leastMb = (least + kMiB - 1) / kMiB;
    throw InvalidArgument("import: --memory-mb " + std::to_string(a.memoryMb) +
                          " is below the minimum of " + std::to_string(leastMb) +
                          " MiB for --patch " + std::to_string(o.patchRows) +
                          " (one column tile of one patch, and one thread's scratch); "
                          "expected at least " +
                          std::to_string(leastMb) + ", or 0 for no bound");
  }
  return a.memoryMb * kMiB;
}

void printSummary(const std::string& out, const store::ImportReport& r, std::size_t budgetBytes,
                  std::ostream& os) {
  const store::GridInfo& g = r.info;
  const bool dem = g.kind == store::GridKind::Dem;
  os << "Wrote " << out << " from " << r.tiles << (r.tiles == 1 ? " file" : " files") << "\n";
  os << "  grid:           '" << g.name << "', "
     << (dem ? "dem (planar grid placed on the body)" : "planet (latitude/longitude grid)")
     << (r.tiles > 1 ? ", tiled" : "") << "\n";
  os << "  size:           " << g.rows << " rows x " << g.cols << " cols";
  if (r.window) {
    os << " (window from row " << r.window->row0 << ", col " << r.window->col0 << ")";
  }
  os << "\n";
  os << "  spacing:        " << shortestNumber(g.spacingX) << " x " << shortestNumber(g.spacingY)
     << (dem ? " m" : " deg") << "\n";
  os << "  body:           " << g.bodyName << ", equatorial radius "
     << shortestNumber(g.equatorialRadius) << " m, polar radius " << shortestNumber(g.polarRadius)
     << " m\n";
  os << "  latitude type:  "
     << (g.latitudeType == topo::LatitudeType::Planetocentric ? "planetocentric" : "planetodetic")
     << "\n";
  os << "  driver:         " << r.driver << "\n";
  os << "  projection:     " << r.projection << "\n";
  const std::vector<std::string> corrections = appliedCorrections(r);
  os << "  corrections:    " << (corrections.empty() ? "none" : corrections.front()) << "\n";
  for (std::size_t i = 1; i < corrections.size(); ++i) {
    os << "                  " << corrections[i] << "\n";
  }
  const double total = static_cast<double>(g.rows) * static_cast<double>(g.cols);
  os << "  missing:        " << r.missingSamples << " samples ("
     << shortestNumber(std::round(1000.0 * static_cast<double>(r.missingSamples) / total) / 10.0)
     << "%" << (r.tiles > 1 ? ", gaps between tiles included" : "") << ")\n";
  if (r.implausibleSamples > 0) {
    os << "  warning:        " << r.implausibleSamples << " samples beyond +-"
       << shortestNumber(r.plausibleLimit)
       << " m (a tenth of the body's radius): a spike, or a wrong scale or unit? --strict "
          "refuses them\n";
  }
  os << "  levels:         " << g.levels << ", patch " << g.patchRows << " x " << g.patchCols
     << "\n";
  os << "  tiles:          " << r.tiles << "\n";
  os << "  seconds:        " << shortestNumber(std::round(r.seconds * 100.0) / 100.0) << "\n";
  os << "  peak RSS:       " << (r.peakRssBytes > 0 ? mebibytes(r.peakRssBytes) : "unknown")
     << " (the whole process, GDAL's and HDF5's caches included)\n";
  os << "  memory budget:  " << (budgetBytes == 0 ? std::string("none") : mebibytes(budgetBytes))
     << " (--memory-mb): "
     << (r.memory.tileChunks == 0 ? std::string("whole-width bands")
                                  : "column tiles of " + std::to_string(r.memory.tileChunks) +
                                        " patches on " + std::to_string(r.memory.threads) +
                                        (r.memory.threads == 1 ? " thread" : " threads"))
     << ", writer's buffers about " << mebibytes(r.memory.plannedBytes) << "\n";
}

}  // namespace

void addImportCommand(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "import",
      "Import GDAL rasters (GeoTIFF, PDS3, PDS4, ISIS3 cubes, SRTM .hgt, ...) as one grid of a "
      "new store: one file becomes a grid, several files that tile one grid become a tiled "
      "grid. Rules, corrections and errors: docs/import.md");
  cmd->add_option("source", a->sources,
                  "Raster file(s), single band; several: tiles of one grid (same CRS, spacing "
                  "and sample lattice, no overlaps)")
      ->required();
  cmd->add_option("-o,--out", a->out, "Store file to write (replaced atomically if it exists)")
      ->required();
  cmd->add_option("--grid", a->grid, "Name of the grid (default: the first source's file stem)");
  cmd->add_option("--patch", a->patch, "Patch (HDF5 chunk) size in samples, square")
      ->check(CLI::Range(std::size_t{8}, std::size_t{8192}))
      ->capture_default_str();
  cmd->add_option("--levels", a->levels,
                  "Pyramid levels including level 0 (0: until a level fits in one patch)")
      ->check(CLI::Range(0, 40))
      ->capture_default_str();
  cmd->add_option("--deflate", a->deflate, "Deflate level 0-9 (0: uncompressed)")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  cmd->add_option("--compression", a->compression, kCompressionHelp)
      ->check(CLI::IsMember({"deflate", "zfp"}))
      ->capture_default_str();
  cmd->add_option("--threads", a->threads,
                  "Threads building the pyramid (0: the cores this process may run on)")
      ->capture_default_str();
  cmd->add_option("--memory-mb", a->memoryMb,
                  "MiB the writer may hold to build the pyramid; past it, levels are built in "
                  "column tiles read back from the file (same levels, slower). Not counted: "
                  "GDAL's cache (GDAL_CACHEMAX) and HDF5's. 0: no bound; the default grows to "
                  "the minimum of patches above 4096")
      ->capture_default_str();
  cmd->add_option("--nodata", a->nodata,
                  "A further source value (before scale/offset) that means missing, beside "
                  "the ones the file declares");
  cmd->add_option("--body", a->body,
                  "Name of the body, where the CRS does not say it or says it wrongly (the "
                  "radii stay the CRS's)");
  auto* window = cmd->add_option("--window", a->window,
                                 "Import only these samples: row0,col0,rows,cols of the grid "
                                 "`regolith info SOURCE` shows")
                     ->delimiter(',')
                     ->expected(4);
  cmd->add_option("--bbox", a->bbox,
                  "Import only the samples whose centres lie in lon0,lat0,lon1,lat1 (degrees: "
                  "west, south, east, north)")
      ->delimiter(',')
      ->expected(4)
      ->excludes(window);
  cmd->add_flag("--strict", a->strict,
                "Refuse heights beyond +-(equatorial radius / 10) instead of importing them "
                "with a warning and a count");
  addHeightMapOptions(*cmd, *a);
  cmd->footer(
      "Examples:\n"
      "  regolith import dtm.cub --out dtm.h5 --deflate 4\n"
      "  regolith import dtm.cub --out dtm.h5 --compression zfp   (smaller, needs the ZFP plugin)\n"
      "  regolith import N00E010.hgt N00E011.hgt N01E010.hgt --out tiles.h5 --grid srtm\n"
      "  regolith import mola.lbl --out crater.h5 --bbox 137.2,-5.6,137.6,-5.2\n"
      "  regolith import height.png --out h.h5 --spacing 2 --height-scale 0.1 --origin -4.6,137.4 "
      "--body Mars\n"
      "  regolith info dtm.cub      (what an import would make of a raster)\n"
      "A summary goes to stdout. A progress bar is drawn on stderr when it is a terminal; "
      "Ctrl-C cancels cleanly (no partial file).");
  cmd->callback([a, cmd] {
    requireOutputFolder("import", a->out);
    for (const std::string& source : a->sources) refuseStdoutOverInput("import", source);
    store::ImportOptions o;
    o.gridName = a->grid;
    o.patchRows = o.patchCols = a->patch;
    o.levels = a->levels;
    o.deflate = a->deflate;
    o.codec = store::codecNamed(a->compression);
    o.threads = a->threads;
    o.memoryBudgetBytes = memoryBudgetOf(*a, o);
    if (cmd->count("--nodata") > 0) o.nodata = a->nodata;
    o.body = a->body;
    o.strict = a->strict;
    if (a->window.size() == 4) {
      o.window = store::SampleWindow{a->window[0], a->window[1], a->window[2], a->window[3]};
    }
    if (a->bbox.size() == 4) o.bbox = {a->bbox[0], a->bbox[1], a->bbox[2], a->bbox[3]};
    o.heightMap = heightMapOf(*a);
    TerminalProgress progress = TerminalProgress::forStderr();
    o.progress = progress.callback();
    o.cancel = CancelOnSignal::flag();
    const CancelOnSignal cancel;
    store::ImportReport report;
    if (a->sources.size() == 1) {
      report = store::importRaster(a->sources.front(), a->out, o);
    } else {
      const std::vector<std::filesystem::path> tiles(a->sources.begin(), a->sources.end());
      report = store::importTiles(tiles, a->out, o);
    }
    printSummary(a->out, report, o.memoryBudgetBytes, std::cout);
  });
}

}  // namespace regolith::tools
