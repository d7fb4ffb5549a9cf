// writer::validateOptions() and writer::prepare(): what store::writeStore() checks before it
// creates a file (docs/store-format.md; the limits of "Size limits").
#include <regolith/core/Message.hpp>

#include "Mosaic.hpp"
#include "WriterParts.hpp"

#include <utility>

namespace regolith::store::writer {

[[noreturn]] void invalid(const Context& ctx, const std::string& what) {
  throw InvalidArgument(ctx.prefix + ": " + what);
}

void validateOptions(const WriteOptions& o, const Context& ctx) {
  if (o.patchRows == 0 || o.patchCols == 0) {
    invalid(ctx, "patch size " + std::to_string(o.patchRows) + "x" + std::to_string(o.patchCols) +
                     ", expected both > 0");
  }
  // HDF5 chunks are limited to 4 GiB.
  constexpr std::size_t kMaxChunkSamples = (std::size_t{1} << 32U) / sizeof(float) - 1;
  if (o.patchRows > kMaxChunkSamples / o.patchCols) {
    invalid(ctx, "patch size " + std::to_string(o.patchRows) + "x" + std::to_string(o.patchCols) +
                     " exceeds HDF5's 4 GiB chunk limit");
  }
  if (o.deflate < 0 || o.deflate > 9) {
    invalid(ctx, "deflate level " + std::to_string(o.deflate) + ", expected 0 to 9");
  }
  if (o.codec == Codec::Zfp && o.deflate != 0) {
    invalid(ctx, "deflate level " + std::to_string(o.deflate) +
                     " with the zfp codec, which has no level (expected 0)");
  }
  if (o.codec != Codec::Deflate && o.codec != Codec::Zfp) {
    invalid(ctx, "codec " + std::to_string(static_cast<int>(o.codec)) +
                     ", expected Codec::Deflate or Codec::Zfp");
  }
}

namespace {

/// Checks tile i of a tiled grid: one source, inside the mosaic, and an external grid that
/// opens, is plain and gives the tile's size.
PreparedTile prepareTile(const TileSource& ts, std::size_t i, const GridInfo& info,
                         const std::filesystem::path& storeDir, const Context& ctx) {
  const std::string towner = "grid '" + info.name + "' tile " + std::to_string(i);
  PreparedTile t;
  t.row0 = ts.row0;
  t.col0 = ts.col0;
  const bool hasExternal = !ts.externalStore.empty();
  if (static_cast<bool>(ts.samples) == hasExternal) {
    invalid(ctx, towner + " has " +
                     (hasExternal ? "both samples and externalStore"
                                  : "neither samples nor externalStore") +
                     ", expected exactly one");
  }
  if (ts.samples) {
    t.samples = ts.samples;
    t.rows = ts.samples->rows();
    t.cols = ts.samples->cols();
  } else {
    t.file = ts.externalStore.string();
    t.grid = ts.externalGrid;
    const std::filesystem::path resolved =
        ts.externalStore.is_relative() ? storeDir / ts.externalStore : ts.externalStore;
    try {
      t.external = std::make_shared<const Store>(Store::open(resolved));
    } catch (const StoreError& e) {
      invalid(ctx,
              towner + " has externalStore '" + t.file + "' that cannot be opened: " + e.what());
    }
    const std::string ext = "externalGrid '" + t.grid + "'";
    if (!t.external->hasGrid(t.grid)) {
      invalid(ctx, towner + " has " + ext + ", which " + resolved.string() + " does not have");
    }
    if (t.external->tiled(t.grid)) {
      invalid(ctx, towner + " has " + ext + " of " + resolved.string() +
                       ", which is itself tiled; expected a plain grid");
    }
    t.rows = t.external->grid(t.grid).rows;
    t.cols = t.external->grid(t.grid).cols;
  }
  if (t.rows == 0 || t.cols == 0 || t.rows > info.rows || t.row0 > info.rows - t.rows ||
      t.cols > info.cols || t.col0 > info.cols - t.cols) {
    invalid(ctx, towner + " (row0 " + std::to_string(t.row0) + ", col0 " + std::to_string(t.col0) +
                     ", " + std::to_string(t.rows) + "x" + std::to_string(t.cols) +
                     " samples) reaches outside the mosaic's " + std::to_string(info.rows) + "x" +
                     std::to_string(info.cols) + " samples (info.rows, info.cols)");
  }
  return t;
}

[[noreturn]] void overlap(const Context& ctx, const GridInfo& info, std::size_t i,
                          const PreparedTile& a, std::size_t j, const PreparedTile& b) {
  invalid(ctx, "grid '" + info.name + "' tiles " + std::to_string(i) + " (" +
                   mosaic::range(mosaic::rectOf(a)) + ") and " + std::to_string(j) + " (" +
                   mosaic::range(mosaic::rectOf(b)) + ") overlap");
}

/// Checks the tiles of a tiled grid (prepareTile) and that no two overlap.
std::vector<PreparedTile> prepareTiles(const GridSource& src, const GridInfo& info,
                                       const std::filesystem::path& storeDir, const Context& ctx) {
  std::vector<PreparedTile> out;
  for (std::size_t i = 0; i < src.tiles.size(); ++i) {
    PreparedTile t = prepareTile(src.tiles[i], i, info, storeDir, ctx);
    for (std::size_t j = 0; j < out.size(); ++j) {
      const PreparedTile& o = out[j];
      if (mosaic::overlap(mosaic::rectOf(o), mosaic::rectOf(t))) overlap(ctx, info, j, o, i, t);
    }
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace

/// Checks one grid and returns the description that will be written: levels and patch size
/// from the options, scale 1 and offset 0 (the writer stores heights in metres as float32).
Prepared prepare(const GridSource& src, const WriteOptions& o,
                 const std::filesystem::path& storeDir, const Context& ctx) {
  GridInfo info = src.info;
  const std::string owner = "grid '" + info.name + "'";
  if (info.name.empty() || info.name.find('/') != std::string::npos || info.name == "." ||
      info.name == "..") {
    invalid(ctx, owner + ": name must be non-empty and contain no '/'");
  }
  const bool tiled = !src.tiles.empty();
  if (tiled && src.samples) invalid(ctx, owner + " has both samples and tiles, expected one");
  if (!tiled && !src.samples) invalid(ctx, owner + " has no samples");
  if (tiled && o.reserveRows > 0) {
    invalid(ctx, owner + " is tiled, but options.reserveRows is " + std::to_string(o.reserveRows) +
                     ", expected 0 (only a plain grid may grow)");
  }
  if (o.reserveRows > kMaxGridSide) {
    invalid(ctx, "options.reserveRows is " + std::to_string(o.reserveRows) + ", expected at most " +
                     std::to_string(kMaxGridSide) + " (the limit of docs/store-format.md)");
  }
  if (info.rows == 0 || info.cols == 0) {
    invalid(ctx, owner + " has " + std::to_string(info.rows) + "x" + std::to_string(info.cols) +
                     " samples, expected both > 0");
  }
  for (const auto& [field, v] : {std::pair{"rows", info.rows}, std::pair{"cols", info.cols}}) {
    if (v > kMaxGridSide) {
      invalid(ctx, owner + " has " + field + " " + std::to_string(v) + ", expected at most " +
                       std::to_string(kMaxGridSide) + " (the limit of docs/store-format.md)");
    }
  }
  if (const std::size_t n = patchCount(info.rows, info.cols, o.patchRows, o.patchCols);
      n > kMaxPatchesPerGrid) {
    invalid(ctx, owner + " has " + std::to_string(info.rows) + "x" + std::to_string(info.cols) +
                     " samples in patches of " + std::to_string(o.patchRows) + "x" +
                     std::to_string(o.patchCols) + ": " + std::to_string(n) +
                     " patches, expected at most " + std::to_string(kMaxPatchesPerGrid) +
                     " (use larger patches; the limit of docs/store-format.md)");
  }
  if (!tiled && (src.samples->rows() != info.rows || src.samples->cols() != info.cols)) {
    invalid(ctx, owner + " describes " + std::to_string(info.rows) + "x" +
                     std::to_string(info.cols) + " samples but its source holds " +
                     std::to_string(src.samples->rows()) + "x" +
                     std::to_string(src.samples->cols()));
  }
  const std::string unit = info.kind == GridKind::Dem ? " m" : " deg";
  const auto checkSpacing = [&](double s) {
    if (!(std::isfinite(s) && s > 0.0)) {
      invalid(ctx, owner + " has spacing " + core::number(s) + unit + ", expected > 0");
    }
  };
  checkSpacing(info.spacingX);
  checkSpacing(info.spacingY);
  for (const auto& [name, v] : {std::pair{"x0", info.x0}, std::pair{"y0", info.y0},
                                std::pair{"scale", info.scale}, std::pair{"offset", info.offset}}) {
    if (!std::isfinite(v)) {
      invalid(ctx, owner + " has " + name + " " + core::number(v) + ", expected a finite number");
    }
  }
  if (info.nodata && std::isnan(*info.nodata)) info.nodata.reset();
  if (info.nodata && std::isinf(*info.nodata)) {
    invalid(ctx, owner + " has nodata " + core::number(static_cast<double>(*info.nodata)) +
                     ", expected a finite number or none");
  }
  try {
    (void)bodyOf(info);
    if (info.kind == GridKind::Dem) (void)placementOf(info);
  } catch (const InvalidArgument& e) {
    invalid(ctx, owner + ": " + e.what());
  }

  const std::size_t maxLevels = format::maxLevels(info.rows, info.cols);
  info.patchRows = o.patchRows;
  info.patchCols = o.patchCols;
  if (o.levels == 0) {
    info.levels = 1;
    while (info.levelRows(info.levels - 1) > o.patchRows ||
           info.levelCols(info.levels - 1) > o.patchCols) {
      ++info.levels;
    }
  } else if (o.levels > maxLevels) {
    invalid(ctx, "options.levels is " + std::to_string(o.levels) + ", but " + owner +
                     " reaches 1x1 samples at " + std::to_string(maxLevels) + " levels");
  } else {
    info.levels = o.levels;
  }
  info.scale = 1.0;
  info.offset = 0.0;
  Prepared p;
  if (tiled) p.tiles = prepareTiles(src, info, storeDir, ctx);
  p.info = std::move(info);
  return p;
}

}  // namespace regolith::store::writer
