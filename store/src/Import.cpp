// GDAL import (docs/import.md): describeRaster(), importRaster(), importTiles().
#include <regolith/core/FileIdentity.hpp>
#include <regolith/store/Import.hpp>

#include "GdalRaster.hpp"
#include "ImportChecks.hpp"

#include <cpl_json.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

namespace regolith::store {

namespace {

/// The store's options of an import: its own, with level 0's statistics (min, max, mean and
/// count of valid heights, computed once for `info`).
WriteOptions writeOptionsOf(const ImportOptions& o) {
  WriteOptions w = static_cast<const WriteOptions&>(o);
  w.statistics = true;
  return w;
}

std::string number(double v) {
  std::ostringstream o;
  o.precision(12);
  o << v;
  return o.str();
}

ImportReport reportOf(const gdal::Raster& r) {
  ImportReport rep;
  const gdal::Layout& l = r.layout();
  rep.info = l.info;
  rep.driver = l.driver;
  rep.projection = l.projection;
  rep.radiusReference = l.radiusReference;
  rep.offsetCorrected = l.offsetCorrected;
  rep.spacingSnapped = l.spacingSnapped;
  rep.voidMarkerAssumed = l.voidMarker;
  rep.droppedNorthRows = l.droppedNorthRows;
  rep.droppedSouthRows = l.droppedSouthRows;
  rep.droppedColumns = l.droppedColumns;
  rep.poleShiftPixels = l.poleShiftPixels;
  rep.window = l.window;
  return rep;
}

/// The grid as written: what the store reports back (levels, patch size).
GridInfo writtenInfo(const std::filesystem::path& store, const std::string& name) {
  return Store::open(store).grid(name);
}

/// The process's peak resident set size in bytes (Linux: ru_maxrss is in KiB); 0 if unknown.
std::size_t peakRssBytes() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0 || u.ru_maxrss < 0) return 0;
  return static_cast<std::size_t>(u.ru_maxrss) * 1024U;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Whether two grid descriptions agree on everything but their extent.
std::string mismatch(const GridInfo& a, const GridInfo& b) {
  const auto differ = [](double x, double y) {
    return std::abs(x - y) > 1e-9 * std::max(std::abs(x), std::abs(y));
  };
  if (a.kind != b.kind) return "grid kind (planet vs DEM)";
  if (differ(a.spacingX, b.spacingX) || differ(a.spacingY, b.spacingY)) {
    return "spacing " + number(b.spacingX) + " x " + number(b.spacingY) +
           " (first tile: " + number(a.spacingX) + " x " + number(a.spacingY) + ")";
  }
  if (differ(a.equatorialRadius, b.equatorialRadius) || differ(a.polarRadius, b.polarRadius)) {
    return "body radii " + number(b.equatorialRadius) + " / " + number(b.polarRadius) +
           " m (first tile: " + number(a.equatorialRadius) + " / " + number(a.polarRadius) + ")";
  }
  if (a.latitudeType != b.latitudeType) return "latitude type";
  if (a.kind == GridKind::Dem) {
    const PlacementInfo &p = a.placement, &q = b.placement;
    if (p.kind != q.kind || p.pole != q.pole || p.latTrueScaleDeg != q.latTrueScaleDeg ||
        p.scaleFactor != q.scaleFactor || p.lonCentreDeg != q.lonCentreDeg ||
        p.falseEasting != q.falseEasting || p.falseNorthing != q.falseNorthing ||
        p.projectionRadius != q.projectionRadius || p.latOriginDeg != q.latOriginDeg ||
        p.crs != q.crs) {
      return "projection parameters";
    }
  }
  return {};
}

/// The rasters' heights as the writer reads them: checked (ImportChecks.hpp), and counted.
struct Checked {
  std::vector<std::shared_ptr<const gdal::CheckedHeights>> sources;

  Checked(const std::vector<std::shared_ptr<gdal::Raster>>& rasters, const ImportOptions& o) {
    for (const auto& r : rasters) {
      sources.push_back(
          std::make_shared<const gdal::CheckedHeights>(r, r->layout().info, r->prefix(), o.strict));
    }
  }
  void report(ImportReport& rep) const {
    rep.plausibleLimit = gdal::plausibleHeightLimit(rep.info);
    for (const auto& s : sources) rep.implausibleSamples += s->implausible();
  }
};

/// No import may write over one of the files it reads (core::refuseOverwritingInput()).
void refuseOverwritingSources(const std::vector<std::shared_ptr<gdal::Raster>>& rasters,
                              const std::filesystem::path& store, const std::string& op) {
  std::vector<std::filesystem::path> inputs;
  for (const auto& r : rasters) {
    const std::vector<std::filesystem::path> files = r->files();
    inputs.insert(inputs.end(), files.begin(), files.end());
  }
  core::refuseOverwritingInput(store, inputs, op);
}

/// Tiles in a geographic CRS (a tile that is a planet grid: tiles leave equirectangular
/// sources to the mosaic's globalToPlanet()): the mosaic's rows snap to 180°/rows when they span
/// 180° within half a pixel, placed by their pixel offsets from the equator, as one
/// geographic file's rows do (GdalRaster.cpp). Returns whether it snapped.
bool snapGeographicRows(GridInfo& g) {
  const double rows = static_cast<double>(g.rows), span = rows * g.spacingY;
  if (g.kind != GridKind::Planet || span == 180.0 || std::abs(span - 180.0) > 0.5 * g.spacingY) {
    return false;
  }
  const double dy = 180.0 / rows;
  g.y0 = g.y0 / g.spacingY * dy;
  g.spacingY = dy;
  return true;
}

}  // namespace

GridInfo describeRaster(const std::filesystem::path& raster, const ImportOptions& options) {
  const gdal::Raster r(raster, options, "store::describeRaster()");
  return r.layout().info;
}

std::string rasterProvenance(const std::filesystem::path& raster, const ImportOptions& options) {
  const gdal::Raster r(raster, options, "store::rasterProvenance()");
  return r.provenance(options.digestSources);
}

ImportReport inspectRaster(const std::filesystem::path& raster, const ImportOptions& options) {
  const gdal::Raster r(raster, options, "store::inspectRaster()");
  return reportOf(r);
}

ImportReport importRaster(const std::filesystem::path& raster, const std::filesystem::path& store,
                          const ImportOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string op = "store::importRaster()";
  auto r = std::make_shared<gdal::Raster>(raster, options, op);
  refuseOverwritingSources({r}, store, op);
  ImportReport rep = reportOf(*r);
  rep.info.provenance = r->provenance(options.digestSources);
  const Checked checked({r}, options);
  const std::vector<GridSource> grids{GridSource{rep.info, checked.sources.front(), {}}};
  writeStore(store, grids, writeOptionsOf(options));
  checked.report(rep);
  rep.missingSamples = r->missingRead();
  rep.voidMarkerAssumed = r->voidsRead() > 0;  // the note only where such voids exist
  rep.info = writtenInfo(store, rep.info.name);
  rep.memory = writerMemoryPlan(rep.info.rows, rep.info.cols, options);
  rep.peakRssBytes = peakRssBytes();
  rep.seconds = secondsSince(t0);
  return rep;
}

ImportReport importTiles(std::span<const std::filesystem::path> tiles,
                         const std::filesystem::path& store, const ImportOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string op = "store::importTiles()";
  if (tiles.empty()) throw ImportError(op + ": " + store.string() + ": no tiles given");
  if (options.window || options.bbox) {
    throw ImportError(op + ": " + store.string() +
                      ": a window or bounding box is for one raster; expected none with tiles");
  }
  std::vector<std::shared_ptr<gdal::Raster>> rasters;
  for (const auto& t : tiles) {
    rasters.push_back(std::make_shared<gdal::Raster>(t, options, op, true));
  }
  refuseOverwritingSources(rasters, store, op);
  const Checked checked(rasters, options);
  const GridInfo& first = rasters.front()->layout().info;
  const gdal::Layout& firstLayout = rasters.front()->layout();
  // The mosaic's extent, in samples of the first tile's lattice.
  double west = first.x0, north = first.y0;
  std::vector<std::pair<long long, long long>> offsets;  // (row, col) from the first tile
  for (const auto& r : rasters) {
    const GridInfo& g = r->layout().info;
    const std::string why = mismatch(first, g);
    if (!why.empty()) {
      throw ImportError(r->prefix() + ": tile does not fit " + tiles.front().string() +
                        ": different " + why);
    }
    if (OSRIsSame(firstLayout.srs, r->layout().srs) == 0) {
      throw ImportError(r->prefix() + ": tile does not fit " + tiles.front().string() +
                        ": different CRS (" + r->layout().projection + " vs " +
                        firstLayout.projection + ")");
    }
    if (r->layout().radiusReference != firstLayout.radiusReference) {
      throw ImportError(r->prefix() + ": tile does not fit " + tiles.front().string() +
                        ": it holds " + (r->layout().radiusReference > 0 ? "radii" : "heights") +
                        ", the first tile " +
                        (firstLayout.radiusReference > 0 ? "radii" : "heights"));
    }
    const double dc = (g.x0 - first.x0) / first.spacingX;
    const double dr = (first.y0 - g.y0) / first.spacingY;
    if (std::abs(dc - std::round(dc)) > 1e-6 || std::abs(dr - std::round(dr)) > 1e-6) {
      throw ImportError(r->prefix() + ": tile does not fit " + tiles.front().string() +
                        ": its samples are offset by " + number(dr) + " rows, " + number(dc) +
                        " columns, expected whole samples");
    }
    offsets.emplace_back(std::llround(dr), std::llround(dc));
    west = std::min(west, g.x0);
    north = std::max(north, g.y0);
  }
  const long long minRow = std::llround((first.y0 - north) / first.spacingY);
  const long long minCol = std::llround((west - first.x0) / first.spacingX);
  GridSource src;
  src.info = first;
  src.info.x0 = first.x0 + static_cast<double>(minCol) * first.spacingX;
  src.info.y0 = first.y0 - static_cast<double>(minRow) * first.spacingY;
  std::size_t rows = 0, cols = 0;
  for (std::size_t i = 0; i < rasters.size(); ++i) {
    TileSource t;
    t.row0 = static_cast<std::size_t>(offsets[i].first - minRow);
    t.col0 = static_cast<std::size_t>(offsets[i].second - minCol);
    t.samples = checked.sources[i];
    rows = std::max(rows, t.row0 + rasters[i]->rows());
    cols = std::max(cols, t.col0 + rasters[i]->cols());
    for (std::size_t j = 0; j < src.tiles.size(); ++j) {
      const TileSource& o = src.tiles[j];
      if (t.row0 < o.row0 + rasters[j]->rows() && o.row0 < t.row0 + rasters[i]->rows() &&
          t.col0 < o.col0 + rasters[j]->cols() && o.col0 < t.col0 + rasters[i]->cols()) {
        throw ImportError(rasters[i]->prefix() + ": tile overlaps " + tiles[j].string());
      }
    }
    src.tiles.push_back(std::move(t));
  }
  src.info.rows = rows;
  src.info.cols = cols;
  ImportReport rep = reportOf(*rasters.front());
  // Tiles of a global equirectangular grid: the mosaic is a planet grid.
  rep.spacingSnapped =
      gdal::globalToPlanet(src.info, firstLayout.labelPixelsPerDegree) || rep.spacingSnapped;
  if (first.kind == GridKind::Planet)
    rep.spacingSnapped = snapGeographicRows(src.info) || rep.spacingSnapped;
  // The beyond-a-pole rule and the snap onto the poles apply to the mosaic's extent.
  rep.poleShiftPixels = gdal::shiftOntoPoles(src.info);
  gdal::requireWithinPoles(src.info, op + ": " + tiles.front().string() + " and " +
                                         std::to_string(tiles.size() - 1) + " more tile(s)");
  // Provenance: the first tile's, with every tile's files.
  CPLJSONDocument doc;
  if (!doc.LoadMemory(rasters.front()->provenance(options.digestSources))) {
    throw ImportError(op + ": " + store.string() + ": cannot record the tiles' provenance");
  }
  CPLJSONArray files = doc.GetRoot().GetArray("sources");
  for (std::size_t i = 1; i < rasters.size(); ++i) {
    CPLJSONDocument t;
    if (!t.LoadMemory(rasters[i]->provenance(options.digestSources))) continue;
    const CPLJSONArray more = t.GetRoot().GetArray("sources");
    for (int k = 0; k < more.Size(); ++k) files.Add(more[k]);
  }
  src.info.provenance = doc.GetRoot().Format(CPLJSONObject::PrettyFormat::Plain);
  rep.info = src.info;
  rep.tiles = rasters.size();
  const std::vector<GridSource> grids{src};
  writeStore(store, grids, writeOptionsOf(options));
  checked.report(rep);
  // Missing: what the tiles held as missing, plus the gaps no tile covers.
  std::size_t covered = 0, voids = 0;
  for (const auto& r : rasters) {
    rep.missingSamples += r->missingRead();
    voids += r->voidsRead();
    covered += r->rows() * r->cols();
  }
  rep.missingSamples += rows * cols - covered;
  rep.voidMarkerAssumed = voids > 0;
  rep.info = writtenInfo(store, src.info.name);
  rep.memory = writerMemoryPlan(rep.info.rows, rep.info.cols, options);
  rep.peakRssBytes = peakRssBytes();
  rep.seconds = secondsSince(t0);
  return rep;
}

}  // namespace regolith::store
