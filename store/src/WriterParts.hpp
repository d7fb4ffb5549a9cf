#pragma once
/// \file
/// The parts of store::writeStore() (store/src/StoreWriter.cpp), one concern per file:
/// - WriterPrepare.cpp: the checks of the options and of each grid, and the tiles' layout;
/// - WriterAttributes.cpp: a grid's attributes and the writer's groups;
/// - WriterBlocks.cpp: one block of level 0 (a source's samples or a mosaic of tiles) and
///   of a coarser level (topo::downsample2x2());
/// - ChunkEncoding.cpp: chunks encoded on worker threads (deflate with libdeflate, ZFP) and
///   written in order;
/// - WriterMemory.cpp: the writer's memory plan (WriteOptions::memoryBudgetBytes);
/// - PyramidWriter.cpp: the pyramid built band by band, or in column tiles;
/// - StoreWriter.cpp: tiles, grids, the file, and the public entry points.
/// Private to store/src.

#include <regolith/store/Store.hpp>

#include "Hdf5.hpp"
#include "StoreFormat.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace regolith::store::writer {

using hdf5::Context;
using hdf5::fail;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

/// Throws InvalidArgument prefixed with the operation and the file.
[[noreturn]] void invalid(const Context& ctx, const std::string& what);

/// Checks the patch size, the codec and its level.
void validateOptions(const WriteOptions& o, const Context& ctx);

/// One tile as it will be written: its bounds, and its samples or its opened external store.
struct PreparedTile {
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
  std::shared_ptr<const topo::SampleSource> samples;
  std::shared_ptr<const Store> external;
  std::string file, grid;  // as recorded
};

struct Prepared {
  GridInfo info;
  std::vector<PreparedTile> tiles;
};

/// Checks one grid and returns the description that will be written: levels and patch size
/// from the options, scale 1 and offset 0 (the writer stores heights in metres as float32).
/// A tiled grid's tiles are checked too: one source each, inside the mosaic, no two
/// overlapping, and external grids that open, are plain and have the tile's size.
Prepared prepare(const GridSource& src, const WriteOptions& o,
                 const std::filesystem::path& storeDir, const Context& ctx);

/// A grid's attributes (docs/store-format.md).
void writeAttributes(hid_t g, const GridInfo& info, bool tiled, bool statistics,
                     const Context& ctx);

/// A group (no modification times: rewriting the same input changes no content).
hdf5::Group createGroup(hid_t parent, const std::string& name, const Context& ctx);

/// Reports progress by samples written, at most about once per 1/1000 of the work.
class Progress {
 public:
  Progress(const WriteOptions& o, double total) : fn_(o.progress), total_(total) {}
  void advance(double samples, std::string_view what) {
    done_ += samples;
    const double f = std::min(1.0, done_ / total_);
    if (fn_ && (f - last_ >= 1e-3 || what != lastWhat_)) {
      last_ = f;
      lastWhat_ = what;
      fn_(f, what);
    }
  }
  void finish() const {
    if (fn_) fn_(1.0, "done");
  }

 private:
  const ProgressFn& fn_;
  double total_;
  double done_ = 0.0, last_ = -1.0;
  std::string lastWhat_;
};

inline void checkCancel(const WriteOptions& o, const Context& ctx) {
  if (o.cancel != nullptr && o.cancel->load()) fail(ctx, "cancelled");
}

/// Missing-sample test in the stored domain.
struct Missing {
  std::optional<float> nodata;
  [[nodiscard]] bool operator()(float v) const noexcept {
    return std::isnan(v) || (nodata && v == *nodata);
  }
  [[nodiscard]] float stored() const noexcept { return nodata.value_or(kNan); }
};

/// One dataset of a grid, written chunk by chunk (already encoded) and read back.
class LevelWriter {
 public:
  LevelWriter(hid_t group, const GridInfo& info, std::size_t level, const WriteOptions& o,
              const Context& ctx)
      : LevelWriter(
            group, info, format::levelName(level), {info.levelRows(level), info.levelCols(level)},
            format::chunkShape(info, level), o, ctx,
            // WriteOptions::reserveRows, halved as the grid's rows are.
            std::max<std::size_t>(info.levelRows(level),
                                  (o.reserveRows + (std::size_t{1} << level) - 1) >> level)) {}

  /// maxRows: the dataset's maximum rows (0: its rows).
  LevelWriter(hid_t group, const GridInfo& info, std::string name,
              const std::array<hsize_t, 2>& shape, const std::array<hsize_t, 2>& chunk,
              const WriteOptions& o, const Context& ctx, std::size_t maxRows = 0)
      : info_(info), ctx_(ctx), name_(std::move(name)) {
    const hdf5::Lock lock;
    const std::string what = "cannot create grid '" + info.name + "' dataset '" + name_ + "'";
    const std::array<hsize_t, 2> maxShape{std::max<hsize_t>(shape[0], maxRows), shape[1]};
    const hdf5::Dataspace space(
        hdf5::check(H5Screate_simple(2, shape.data(), maxShape.data()), ctx, what));
    const hdf5::PropertyList dcpl(hdf5::check(H5Pcreate(H5P_DATASET_CREATE), ctx, what));
    hdf5::check(H5Pset_chunk(dcpl.get(), 2, chunk.data()), ctx, what);
    // No modification times in object headers: rewriting the same input changes no content.
    hdf5::check(H5Pset_obj_track_times(dcpl.get(), 0), ctx, what);
    const float fill = Missing{info.nodata}.stored();
    hdf5::check(H5Pset_fill_value(dcpl.get(), H5T_NATIVE_FLOAT, &fill), ctx, what);
    if (o.codec == Codec::Zfp) {
      // H5Z-ZFP's generic interface: mode 5 is reversible. At H5Dcreate the plugin turns
      // these values into its stored form (its version and ZFP's header for this chunk
      // shape), which is what decodes the chunks encodeChunk() writes.
      const std::array<unsigned, 6> zfpReversible{5, 0, 0, 0, 0, 0};
      hdf5::check(H5Pset_filter(dcpl.get(), kZfpFilterId, H5Z_FLAG_MANDATORY, zfpReversible.size(),
                                zfpReversible.data()),
                  ctx, what);
    } else if (o.deflate > 0) {
      hdf5::check(H5Pset_shuffle(dcpl.get()), ctx, what);
      hdf5::check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(o.deflate)), ctx, what);
    }
    // Every write covers whole chunks (clipped at the level's edge), so no chunk cache is
    // needed here either.
    const hdf5::PropertyList dapl(hdf5::check(H5Pcreate(H5P_DATASET_ACCESS), ctx, what));
    hdf5::check(H5Pset_chunk_cache(dapl.get(), 0, 0, 1.0), ctx, what);
    ds_ = hdf5::Dataset(hdf5::check(H5Dcreate2(group, name_.c_str(), H5T_IEEE_F32LE, space.get(),
                                               H5P_DEFAULT, dcpl.get(), dapl.get()),
                                    ctx, what));
  }

  [[nodiscard]] hid_t id() const noexcept { return ds_.get(); }

  /// Writes one chunk, already encoded (encodeChunk()), at element offset (row0, col0).
  void writeChunk(std::size_t row0, std::size_t col0,
                  const std::vector<unsigned char>& bytes) const {
    const hdf5::Lock lock;
    const std::array<hsize_t, 2> offset{row0, col0};
    hdf5::check(
        H5Dwrite_chunk(ds_.get(), H5P_DEFAULT, 0, offset.data(), bytes.size(), bytes.data()), ctx_,
        "cannot write grid '" + info_.name + "' dataset '" + name_ + "'");
  }

  /// Reads rows [row0, row0 + nr) × columns [col0, col0 + nc), already written, into `out`
  /// (row-major, as stored: missing samples are the stored nodata value).
  void read(std::size_t row0, std::size_t col0, std::size_t nr, std::size_t nc, float* out) const {
    const hdf5::Lock lock;
    const std::string what = "cannot read back grid '" + info_.name + "' dataset '" + name_ + "'";
    const std::array<hsize_t, 2> start{row0, col0}, count{nr, nc};
    const hdf5::Dataspace fileSpace(hdf5::check(H5Dget_space(ds_.get()), ctx_, what));
    hdf5::check(H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start.data(), nullptr,
                                    count.data(), nullptr),
                ctx_, what);
    const hdf5::Dataspace memSpace(
        hdf5::check(H5Screate_simple(2, count.data(), nullptr), ctx_, what));
    hdf5::check(
        H5Dread(ds_.get(), H5T_NATIVE_FLOAT, memSpace.get(), fileSpace.get(), H5P_DEFAULT, out),
        ctx_, what);
  }

  void close() {
    const hdf5::Lock lock;
    hdf5::check(H5Dclose(ds_.release()), ctx_,
                "cannot close grid '" + info_.name + "' dataset '" + name_ + "'");
  }

 private:
  const GridInfo& info_;
  const Context& ctx_;
  std::string name_;
  hdf5::Dataset ds_;
};

/// Level 0 of one chunk: the source's heights, missing samples as the stored nodata value.
/// Infinite heights are refused (they are neither data nor a declared nodata).
void level0Block(const topo::SampleSource& src, const GridInfo& info, std::size_t r0,
                 std::size_t c0, std::size_t nr, std::size_t nc, std::vector<float>& out,
                 const Context& ctx);

/// Level k ≥ 1 of one chunk: topo::downsample2x2() of level k−1 (read back from the file),
/// the one definition of the format's pyramid rule.
using FineReader = std::function<void(std::size_t, std::size_t, std::size_t, std::size_t, float*)>;

void coarseBlock(const FineReader& below, const GridInfo& info, std::size_t level, std::size_t r0,
                 std::size_t c0, std::size_t nr, std::size_t nc, std::vector<float>& fine,
                 std::vector<float>& out);

/// Level 0 of a tiled grid's block as stored: each tile's samples (missing as the stored
/// nodata value), the stored nodata value where no tile lies.
void mosaicBlock(const Prepared& p, std::size_t r0, std::size_t c0, std::size_t nr, std::size_t nc,
                 float* out, const Context& ctx);

/// The threads a write runs on: WriteOptions::threads, or the executor's plus the caller.
unsigned threadCount(const WriteOptions& o);

/// Runs f(0) … f(n − 1) on up to threadCount(o) threads, the caller's included: on the
/// options' executor, or on a pool made for the call; rethrows the first exception once all
/// have stopped.
void parallelFor(std::size_t n, const WriteOptions& o, const std::function<void(std::size_t)>& f);

/// One chunk as HDF5 stores it: the block padded to the full chunk shape with `fill`, then
/// ZFP-encoded (Codec::Zfp) or, with deflate, byte-shuffled (H5Z_FILTER_SHUFFLE) and
/// zlib-compressed (H5Z_FILTER_DEFLATE).
std::vector<unsigned char> encodeChunk(const float* block, std::size_t nr, std::size_t nc,
                                       const std::array<hsize_t, 2>& chunk, float fill,
                                       const WriteOptions& o);

/// Writes rows [r0, r0 + nr) of a dataset whose chunks are `chunk`, chunk column by chunk
/// column: block(c0, nc, out) fills the nr×nc block at column c0 (on a worker thread), the
/// encoded chunks are then written in order. With groupChunks > 0 the band goes in column
/// tiles of that many chunks, each computed, encoded and written before the next, and
/// beforeGroup(c0, nc) (if set) runs first for the tile's columns [c0, c0 + nc) on the calling
/// thread. The file does not depend on the grouping.
void writeBandChunks(
    const LevelWriter& writer, const std::array<hsize_t, 2>& chunk, std::size_t r0, std::size_t nr,
    std::size_t cols, float fill, const WriteOptions& o,
    const std::function<void(std::size_t, std::size_t, std::vector<float>&)>& block,
    Progress& progress, const std::string& what, const Context& ctx, std::size_t groupChunks = 0,
    const std::function<void(std::size_t, std::size_t)>& beforeGroup = {});

/// The levels a grid of `info`'s size gets with options `o` (WriteOptions::levels, or down to
/// one patch).
std::size_t levelCount(const GridInfo& info, const WriteOptions& o);

/// The memory plan of a grid with `levels` levels (docs/import.md, "Memory").
WriterMemoryPlan planMemory(const GridInfo& info, std::size_t levels, const WriteOptions& o);

/// Builds the pyramid band by band: a band of level k (up to patchRows rows, full width) is
/// written, then kept until the band after it arrives, and the two make one band of level
/// k + 1. Each level holds at most two bands in memory. With tileChunks > 0 (the memory
/// budget is smaller than that) no band is kept: each is built in column tiles of that many
/// chunks, and a band of level k + 1 reads the two bands below back from the file (level 1 of
/// a tiled grid: from its tiles), tile by tile. Both ways give the same file.
class Pyramid {
 public:
  Pyramid(hid_t group, const Prepared& p, const WriteOptions& o, std::size_t tileChunks,
          Progress& progress, const Context& ctx);

  using Level0Block =
      std::function<void(std::size_t, std::size_t, std::size_t, std::size_t, std::vector<float>&)>;
  /// Level-0 rows [r0, r0 + nr), produced by block(r0, c0, nr, nc, out) per chunk column.
  void level0Band(std::size_t r0, std::size_t nr, const Level0Block& block);

  void close();

 private:
  struct Band {
    std::size_t row0 = 0, rows = 0;
    std::vector<float> data;  // rows × levelCols, row-major
  };

  /// level0Band() in column tiles, keeping nothing: level 1 reads the band back.
  void level0Tiled(std::size_t r0, std::size_t nr, const Level0Block& block);
  /// A band of level `level − 1` arrives for level `level`.
  void push(std::size_t level, Band fine);
  /// Level `level`'s band made of fine rows [fine.row0, fine.row0 + fine.rows): from
  /// fine.data, or (column tiles) read back tile by tile.
  void coarseBand(std::size_t level, const Band& fine);

  const Prepared& p_;
  const GridInfo& info_;
  const WriteOptions& o_;
  std::size_t tileChunks_;
  Progress& progress_;
  const Context& ctx_;
  bool tiled_;
  std::vector<std::optional<LevelWriter>> writers_;
  std::vector<std::optional<Band>> pending_;
};

}  // namespace regolith::store::writer
