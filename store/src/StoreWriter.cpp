// writeStore(): writes grids and their pyramids into a temporary file, then renames it into
// place (docs/store-format.md, "Crash-safe writing").
// Its parts, one concern per file, are listed in WriterParts.hpp.
#include <regolith/core/AtomicFile.hpp>
#include <regolith/store/Store.hpp>

#include "WriterParts.hpp"

#include <algorithm>
#include <map>
#include <mutex>
#include <set>

namespace regolith::store {

namespace {

using writer::checkCancel;
using writer::Context;
using writer::createGroup;
using writer::fail;
using writer::invalid;
using writer::level0Block;
using writer::LevelWriter;
using writer::Missing;
using writer::mosaicBlock;
using writer::planMemory;
using writer::prepare;
using writer::Prepared;
using writer::PreparedTile;
using writer::Progress;
using writer::Pyramid;
using writer::validateOptions;
using writer::writeAttributes;
using writer::writeBandChunks;

/// Writes tile i of a tiled grid: its group tiles/<i> with its bounds and either its level0
/// dataset or the reference to its external grid.
void writeTile(hid_t tilesGroup, std::size_t i, const Prepared& p, const WriteOptions& o,
               Progress& progress, const Context& ctx) {
  const GridInfo& info = p.info;
  const PreparedTile& t = p.tiles[i];
  const std::string what = "grid '" + info.name + "' tile " + std::to_string(i);
  hdf5::Group tg = createGroup(tilesGroup, std::to_string(i), ctx);
  hdf5::writeUInt64(tg.get(), format::kTileRow0, t.row0, ctx);
  hdf5::writeUInt64(tg.get(), format::kTileCol0, t.col0, ctx);
  hdf5::writeUInt64(tg.get(), format::kTileRows, t.rows, ctx);
  hdf5::writeUInt64(tg.get(), format::kTileCols, t.cols, ctx);
  if (t.external) {
    hdf5::writeString(tg.get(), format::kExternalFile, t.file, ctx);
    hdf5::writeString(tg.get(), format::kExternalGrid, t.grid, ctx);
  } else {
    const std::array<hsize_t, 2> chunk = format::tileChunkShape(info, t.rows, t.cols);
    LevelWriter writer(tg.get(), info, "level0", {t.rows, t.cols}, chunk, o, ctx);
    for (std::size_t r0 = 0; r0 < t.rows; r0 += info.patchRows) {
      const std::size_t nr = std::min(info.patchRows, t.rows - r0);
      checkCancel(o, ctx);
      writeBandChunks(
          writer, chunk, r0, nr, t.cols, Missing{info.nodata}.stored(), o,
          [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
            level0Block(*t.samples, info, r0, c0, nr, nc, out, ctx);
          },
          progress, what, ctx);
    }
    writer.close();
  }
  const hdf5::Lock lock;
  hdf5::check(H5Gclose(tg.release()), ctx, "cannot close the group of " + what);
}

/// Writes the tiles of a tiled grid: tile_count and a group tiles/<i> per tile.
void writeTiles(hid_t group, const Prepared& p, const WriteOptions& o, Progress& progress,
                const Context& ctx) {
  hdf5::writeUInt64(group, format::kTileCount, p.tiles.size(), ctx);
  hdf5::Group tilesGroup = createGroup(group, format::kTiles, ctx);
  for (std::size_t i = 0; i < p.tiles.size(); ++i) {
    writeTile(tilesGroup.get(), i, p, o, progress, ctx);
  }
  const hdf5::Lock lock;
  hdf5::check(H5Gclose(tilesGroup.release()), ctx,
              "cannot close group '/grids/" + p.info.name + "/tiles'");
}

void writeGrid(hid_t grids, const GridSource& src, const Prepared& p, const WriteOptions& o,
               Progress& progress, const Context& ctx) {
  const GridInfo& info = p.info;
  // The threads the memory budget allows (all of them unless it forces column tiles).
  const WriterMemoryPlan plan = planMemory(info, info.levels, o);
  WriteOptions oPlanned = o;
  oPlanned.threads = static_cast<unsigned>(plan.threads);
  const bool tiled = !p.tiles.empty();
  hdf5::Group group = createGroup(grids, info.name, ctx);
  writeAttributes(group.get(), info, tiled, o.statistics, ctx);
  if (tiled) writeTiles(group.get(), p, o, progress, ctx);
  // Level 0's statistics, per block keyed by its position and summed in that order (band by
  // band, then along the band), so that they do not depend on the threads.
  std::mutex statsMutex;
  std::map<std::pair<std::size_t, std::size_t>, BlockStatistics> blockStats;
  BlockStatistics all;
  const auto sumBand = [&] {
    for (const auto& [key, b] : blockStats) {
      if (o.blockStatistics) o.blockStatistics(info.name, b);
      all.min = std::min(all.min, b.min);
      all.max = std::max(all.max, b.max);
      all.sum += b.sum;
      all.count += b.count;
    }
    blockStats.clear();
  };
  const Missing missing{info.nodata};
  const auto collect = [&](std::size_t br0, std::size_t c0, const std::vector<float>& out) {
    if (!o.statistics) return;
    BlockStatistics b;
    b.row0 = br0;
    b.col0 = c0;
    for (const float v : out) {
      if (missing(v)) continue;
      const auto d = static_cast<double>(v);
      b.min = std::min(b.min, d);
      b.max = std::max(b.max, d);
      b.sum += d;
      ++b.count;
    }
    const std::lock_guard lock(statsMutex);
    blockStats[{br0, c0}] = b;
  };
  {
    Pyramid pyramid(group.get(), p, oPlanned, plan.tileChunks, progress, ctx);
    // Level 0 band by band; each band flows up the pyramid as soon as its pair is complete.
    // The source and the progress callback run without the HDF5 lock: the source may itself
    // be a pager reading another store.
    for (std::size_t r0 = 0; r0 < info.rows; r0 += info.patchRows) {
      const std::size_t nr = std::min(info.patchRows, info.rows - r0);
      pyramid.level0Band(r0, nr,
                         [&](std::size_t br0, std::size_t c0, std::size_t bnr, std::size_t nc,
                             std::vector<float>& out) {
                           if (tiled) {
                             out.resize(bnr * nc);
                             mosaicBlock(p, br0, c0, bnr, nc, out.data(), ctx);
                           } else {
                             level0Block(*src.samples, info, br0, c0, bnr, nc, out, ctx);
                           }
                           collect(br0, c0, out);
                         });
      sumBand();
    }
    pyramid.close();
  }
  if (o.statistics) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const bool none = all.count == 0;
    hdf5::writeDouble(group.get(), format::kHeightMin, none ? nan : all.min, ctx);
    hdf5::writeDouble(group.get(), format::kHeightMax, none ? nan : all.max, ctx);
    hdf5::writeDouble(group.get(), format::kHeightMean,
                      none ? nan : all.sum / static_cast<double>(all.count), ctx);
    hdf5::writeUInt64(group.get(), format::kValidSamples, all.count, ctx);
  }
  const hdf5::Lock lock;
  hdf5::check(H5Gclose(group.release()), ctx, "cannot close group '/grids/" + info.name + "'");
}

}  // namespace

const char* codecName(Codec c) noexcept {
  return c == Codec::Zfp ? "zfp" : c == Codec::Deflate ? "deflate" : "unknown";
}

Codec codecNamed(std::string_view name) {
  if (name == "deflate") return Codec::Deflate;
  if (name == "zfp") return Codec::Zfp;
  throw InvalidArgument("store::codecNamed(): codec '" + std::string(name) +
                        "', expected deflate or zfp");
}

void writeStore(const std::filesystem::path& path, std::span<const GridSource> grids,
                const WriteOptions& options) {
  const Context ctx("store::writeStore()", path);
  validateOptions(options, ctx);
  if (const std::size_t least = writerMemoryMinimum(options);
      options.memoryBudgetBytes != 0 && options.memoryBudgetBytes != kDefaultMemoryBudget &&
      options.memoryBudgetBytes < least) {
    invalid(ctx, "options.memoryBudgetBytes is " + std::to_string(options.memoryBudgetBytes) +
                     " bytes, below the minimum of " + std::to_string(least) +
                     " bytes for patches of " + std::to_string(options.patchRows) + "x" +
                     std::to_string(options.patchCols) +
                     " (one column tile of one chunk, and one thread's scratch); expected at "
                     "least that, or 0 for no bound");
  }
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  std::vector<Prepared> prepared;
  std::set<std::string, std::less<>> names;
  double totalSamples = 0.0;
  int rootMinor = kFormatVersionMinor;
  for (const GridSource& src : grids) {
    prepared.push_back(prepare(src, options, dir, ctx));
    const GridInfo& info = prepared.back().info;
    rootMinor = std::max(rootMinor, format::gridFormatMinor(info, !prepared.back().tiles.empty(),
                                                            options.statistics));
    for (const PreparedTile& t : prepared.back().tiles) {
      if (t.samples) totalSamples += static_cast<double>(t.rows * t.cols);
    }
    if (!names.insert(info.name).second) {
      invalid(ctx, "grid '" + info.name + "' appears twice");
    }
    for (std::size_t k = prepared.back().tiles.empty() ? 0 : 1; k < info.levels; ++k) {
      totalSamples += static_cast<double>(info.levelRows(k) * info.levelCols(k));
    }
  }
  if (options.codec == Codec::Deflate && options.deflate > 0) {
    const hdf5::Lock lock;
    if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) {
      fail(ctx, "deflate level " + std::to_string(options.deflate) +
                    " requested, but this HDF5 library has no deflate filter");
    }
  }
  if (options.codec == Codec::Zfp) {
    const hdf5::Lock lock;
    if (H5Zfilter_avail(kZfpFilterId) <= 0) {
      (void)hdf5::takeErrorStack();  // the failed plugin search; the message says what matters
      fail(ctx,
           "the zfp codec needs HDF5's ZFP filter (id 32013), which this HDF5 library "
           "cannot load: " +
               hdf5::missingFilterHint(kZfpFilterId));
    }
  }
  checkCancel(options, ctx);

  Progress progress(options, std::max(totalSamples, 1.0));
  const auto write = [&](const std::filesystem::path& tmp) {
    hdf5::File file;
    hdf5::Group gridsGroup;
    {
      const hdf5::Lock lock;
      const std::string what = "cannot create the temporary file " + tmp.string();
      // The HDF5 1.8 file format: checksummed metadata (corruption is reported, not
      // misread), readable by any HDF5 since 1.8.
      const hdf5::PropertyList fapl(hdf5::check(H5Pcreate(H5P_FILE_ACCESS), ctx, what));
      hdf5::check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), ctx, what);
      file = hdf5::File(
          hdf5::check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), ctx, what));
      const hdf5::Group root(
          hdf5::check(H5Gopen2(file.get(), "/", H5P_DEFAULT), ctx, "cannot open '/'"));
      hdf5::writeString(root.get(), format::kMarker, format::kMarkerValue, ctx);
      hdf5::writeInt32s(root.get(), format::kFormatVersion, {kFormatVersionMajor, rootMinor}, ctx);
      gridsGroup = createGroup(file.get(), format::kGrids, ctx);
    }
    for (std::size_t i = 0; i < grids.size(); ++i) {
      writeGrid(gridsGroup.get(), grids[i], prepared[i], options, progress, ctx);
    }
    checkCancel(options, ctx);
    {
      const hdf5::Lock lock;
      hdf5::check(H5Gclose(gridsGroup.release()), ctx, "cannot close group '/grids'");
      hdf5::check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), ctx, "cannot flush " + tmp.string());
      hdf5::check(H5Fclose(file.release()), ctx, "cannot close " + tmp.string());
    }
    checkCancel(options, ctx);
  };
  // core::writeFileAtomically: a unique temporary beside the target, synced, renamed into
  // place, then the folder synced (durable before visible; a scratch file only renamed).
  try {
    core::writeFileAtomically(path, write, "store::writeStore()", options.durability);
  } catch (const IoError& e) {
    throw StoreError(e.what());
  }
  progress.finish();
}

}  // namespace regolith::store
