#pragma once
/// \file
/// HDF5 terrain stores: reading grids by hyperslab, and writing them crash-safely.

#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Executor.hpp>
#include <regolith/store/GridInfo.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace regolith::store {

/// A store file is unusable: not HDF5, truncated, corrupt, a newer major format version, a
/// missing grid, a dataset of the wrong rank or type, an attribute that lies. The message
/// names the operation, the file and the field, and carries HDF5's error stack when there
/// is one.
class StoreError : public regolith::Error {
 public:
  using Error::Error;
};

/// Format version written by this library; a store with a newer major version is refused.
/// Since 1.4 every text attribute is a fixed-length string (docs/store-format.md), so every
/// grid written is at least 1.4; older stores, with variable-length strings, still open.
inline constexpr int kFormatVersionMajor = 1;
inline constexpr int kFormatVersionMinor = 4;

/// Byte counters of one Store (for cache statistics and benchmarks). A read of a tiled level 0
/// counts one read per tile; bytes of external tiles are counted by their own Store.
/// Which file an open store reads: its device and inode, taken from the file HDF5 opened
/// (fstat(2)) when the store was opened. Two opens of one file, through any path, symlink or
/// hard link, compare equal; a file written over the path since (a new inode) compares
/// unequal. store::Pager keys the patches it shares between pagers by it.
struct FileId {
  std::uint64_t device = 0;
  std::uint64_t inode = 0;
  friend bool operator==(const FileId&, const FileId&) = default;
  /// An order for maps (device, then inode). Not a defaulted <=>: clang-tidy 14 reads its
  /// synthesised comparison with 0 as a null pointer constant (modernize-use-nullptr).
  friend bool operator<(const FileId& a, const FileId& b) noexcept {
    return a.device != b.device ? a.device < b.device : a.inode < b.inode;
  }
};

struct ReadCounters {
  std::uint64_t reads = 0;      // hyperslab reads
  std::uint64_t bytesRead = 0;  // bytes delivered by those reads (stored sample type)
};

/// An open store (read-only). Opening validates every grid's attributes and datasets, so
/// later reads fail only on I/O errors.
///
/// Thread-safety: all const members may be called concurrently. HDF5 calls are serialised
/// by one process-wide mutex (HDF5 keeps global state; Debian's build is thread-safe but
/// serialises internally anyway).
/// Tells HDF5 not to shut itself down when the process exits (H5dont_atexit). For programs
/// (the `regolith` command calls it first thing): after a metadata checksum failure, HDF5
/// 1.10.8 leaks an internal block, and its shutdown at exit then prints "HDF5: infinite loop
/// closing library" and a line of junk after Regolith's clear error. The operating system
/// frees the memory anyway; Regolith closes every file it writes before the rename that
/// commits it, so nothing is left to flush. Effective only before the first HDF5 call of the
/// process; later calls change nothing.
void skipHdf5ShutdownAtExit() noexcept;

/// The budget of one Store::open: the files it may open (the store and its external tiles,
/// however deeply nested; a file named by several tiles counts once) and their total size.
/// An open that would exceed it is refused with a StoreError naming the limit, so a store
/// whose tiles fan out (files nested 7 deep, each tile naming 10 links to the next) cannot
/// make an open take unbounded time.
struct OpenLimits {
  std::size_t maxFiles = 4096;
  std::uintmax_t maxBytes = std::uintmax_t{1} << 44;  // 16 TiB
};

class Store {
 public:
  /// Throws StoreError naming the file and the reason, or the limit of `limits` exceeded.
  static Store open(const std::filesystem::path& path, const OpenLimits& limits = {});
  /// Whether `path` is a readable file that starts with the HDF5 signature (H5Fis_hdf5):
  /// false for a missing, unreadable or non-HDF5 file. Lets a caller tell a store (or a
  /// broken one, which open() then explains) from a file of another format.
  [[nodiscard]] static bool isHdf5(const std::filesystem::path& path);

  Store(Store&&) noexcept;
  Store& operator=(Store&&) noexcept;
  ~Store();

  [[nodiscard]] const std::filesystem::path& path() const noexcept;
  /// The file's [major, minor] format version (the root group's `format_version`).
  [[nodiscard]] std::array<int, 2> formatVersion() const noexcept;
  [[nodiscard]] std::vector<std::string> gridNames() const;
  [[nodiscard]] bool hasGrid(std::string_view name) const noexcept;
  /// Throws StoreError naming the file and the grid if there is no such grid.
  [[nodiscard]] const GridInfo& grid(std::string_view name) const;
  /// Whether level 0 of a grid is a mosaic of tiles (docs/store-format.md, "Tiled grids").
  /// Throws StoreError if there is no such grid.
  [[nodiscard]] bool tiled(std::string_view name) const;

  /// Reads samples [row0, row0 + rows·stride) × [col0, col0 + cols·stride) of one level,
  /// every `stride`-th sample, with one H5Sselect_hyperslab read, into `out` (row-major,
  /// rows·cols floats) as heights in metres: offset + scale · stored, and NaN where the
  /// stored value is missing. Throws StoreError for a window outside the level.
  /// On a tiled grid, level 0 is assembled from one read per tile the window meets (samples
  /// no tile covers read NaN), and only stride 1 is supported there (StoreError otherwise).
  void readWindow(std::string_view grid, std::size_t level, std::size_t row0, std::size_t col0,
                  std::size_t rows, std::size_t cols, std::span<float> out,
                  std::size_t stride = 1) const;

  [[nodiscard]] ReadCounters counters() const noexcept;
  /// The device and inode of the file this store has open (FileId).
  [[nodiscard]] FileId fileId() const noexcept;

 private:
  struct Impl;
  explicit Store(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Progress of a long write: fraction done in [0, 1] and a short label.
using ProgressFn = std::function<void(double fraction, std::string_view what)>;

/// How a store's chunks are compressed (docs/store-format.md, "Compression").
enum class Codec : std::uint8_t {
  /// HDF5's shuffle then deflate filters at WriteOptions::deflate (0: uncompressed). Every
  /// HDF5 reader decodes them.
  Deflate,
  /// ZFP in reversible (lossless, bit for bit, NaN included) mode: HDF5 filter 32013
  /// (H5Z-ZFP). About 14 % smaller than shuffle + deflate on terrain, but several times
  /// slower to decode. Readers need the H5Z-ZFP plugin (Debian:
  /// hdf5-filter-plugin-zfp-serial), which HDF5 loads from its default plugin directory.
  Zfp,
};

/// "deflate" or "zfp".
[[nodiscard]] const char* codecName(Codec c) noexcept;
/// The codec named `name` ("deflate", "zfp"); throws InvalidArgument naming the choices.
[[nodiscard]] Codec codecNamed(std::string_view name);

/// HDF5's registered id of the H5Z-ZFP filter.
inline constexpr int kZfpFilterId = 32013;

/// WriteOptions::memoryBudgetBytes by default: 1 GiB.
inline constexpr std::size_t kDefaultMemoryBudget = std::size_t{1} << 30U;

/// Level 0's valid heights in one block (one chunk) of a grid being written: what the
/// grid's height statistics are summed from (WriteOptions::blockStatistics).
struct BlockStatistics {
  std::size_t row0 = 0, col0 = 0;  ///< the block's first level-0 sample
  /// Smallest and largest valid height (+∞ and −∞ when the block has none), their sum and
  /// count.
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  double sum = 0.0;
  std::uint64_t count = 0;
};
/// Receives one grid's level-0 blocks (WriteOptions::blockStatistics).
using BlockStatisticsFn = std::function<void(std::string_view grid, const BlockStatistics&)>;

struct WriteOptions {
  /// HDF5 chunk (= pager patch) size; 256×256 by default.
  std::size_t patchRows = 256, patchCols = 256;
  /// Pyramid levels to write, level 0 included; 0 means "until a level fits one patch".
  std::size_t levels = 0;
  /// How chunks are compressed.
  Codec codec = Codec::Deflate;
  /// Deflate level 0–9 (0: uncompressed); with deflate, HDF5's shuffle filter runs first.
  /// Codec::Zfp has no level: it must stay 0.
  int deflate = 0;
  /// Threads that compute and compress pyramid chunks, the caller's included (0: the
  /// executor's concurrency + 1, or hardware concurrency without one). The file's content
  /// does not depend on it.
  unsigned threads = 0;
  /// Where the chunk work runs besides the calling thread (not owned; must outlive the
  /// write). Null: a thread pool made for the write.
  core::Executor* executor = nullptr;
  /// Called now and then during the write (may be empty).
  ProgressFn progress;
  /// If set and becomes true, the write stops, removes its temporary file and throws
  /// StoreError("... cancelled").
  const std::atomic<bool>* cancel = nullptr;
  /// Compute level 0's height statistics while writing and store them with each grid
  /// (format 1.3, docs/store-format.md); the import does.
  bool statistics = false;
  /// With statistics: given each level-0 block's statistics as the writer sums them, block
  /// row by block row and along each (row-major), serially, on the calling thread (may be
  /// empty). A tiled grid written with one level computes none. regolith-mpi gathers its
  /// parts' blocks this way, without reading its parts back.
  BlockStatisticsFn blockStatistics;
  /// Bytes the writer may hold to build one grid's pyramid: its bands, the chunks being
  /// computed and encoded, the per-thread scratch (docs/import.md, "Memory"). Where two
  /// full-width bands per level would exceed it, each level is built in column tiles, the
  /// level below read back from the file, on as many of the threads as it allows; the file's
  /// content does not depend on it. Below writerMemoryMinimum() it is refused
  /// (InvalidArgument), except kDefaultMemoryBudget, which grows to the minimum (patches
  /// above 4096²). 0: no bound. Not counted: the source's own caches (GDAL_CACHEMAX), HDF5's
  /// metadata cache, the code and libraries.
  std::size_t memoryBudgetBytes = kDefaultMemoryBudget;
  /// Durable: the file is synced before it is renamed into place, and its folder after.
  /// Scratch: a file that its job deletes before it ends (regolith-mpi's part stores),
  /// renamed into place unsynced; a crash may leave it incomplete (core::Durability).
  core::Durability durability = core::Durability::Durable;
  /// Level-0 rows an untiled grid's level datasets may later grow to (their HDF5 maximum
  /// dimensions; each level's the same halving of it as its rows). 0, or no more than the
  /// grid's rows: fixed at the grid's size. regolith-mpi's rank 0 writes its band, the grid's
  /// first rows, so; the join extends it in place to the whole grid (H5Dset_extent) rather
  /// than copying its chunks into a new file. Only the maximum dimensions differ until then.
  std::size_t reserveRows = 0;
};

/// How writeStore() builds one grid's pyramid within WriteOptions::memoryBudgetBytes
/// (estimates of the writer's own buffers, in bytes).
struct WriterMemoryPlan {
  /// Holding two full-width bands per level (the fastest way).
  std::size_t untiledBytes = 0;
  /// The least any grid needs: a column tile one chunk wide, and one thread's scratch.
  std::size_t minimumBytes = 0;
  /// The threads that build the grid: all of WriteOptions::threads, or as many as the budget
  /// allows beside one tile chunk when it forces column tiles.
  std::size_t threads = 0;
  /// 0: whole-width bands; otherwise the chunk columns per column tile.
  std::size_t tileChunks = 0;
  /// The estimate for the way chosen.
  std::size_t plannedBytes = 0;
};

/// The writer's memory plan for a grid of rows × cols level-0 samples under `options`
/// (levels, patch size, threads, budget); a budget below minimumBytes is not checked here.
[[nodiscard]] WriterMemoryPlan writerMemoryPlan(std::size_t rows, std::size_t cols,
                                                const WriteOptions& options);

/// The smallest WriteOptions::memoryBudgetBytes writeStore() accepts with these options
/// (their patch size): WriterMemoryPlan::minimumBytes.
[[nodiscard]] std::size_t writerMemoryMinimum(const WriteOptions& options);

/// One grid to write: its description (levels, patch size and sample type are set by the
/// writer) and its level-0 heights in metres. Samples that are NaN (or equal info.nodata)
/// are stored as the nodata value.
///
/// A tiled grid (docs/store-format.md, "Tiled grids") leaves `samples` null and lists its
/// level-0 tiles instead; info.rows × info.cols is then the size of the whole mosaic.
struct TileSource {
  /// Level-0 sample of the mosaic at which the tile's sample (0, 0) sits.
  std::size_t row0 = 0, col0 = 0;
  /// Exactly one of the two: the tile's heights (written into this store) ...
  std::shared_ptr<const topo::SampleSource> samples;
  /// ... or a plain (untiled) grid of another store, referenced, not copied. A relative path
  /// is recorded as given and resolved against the directory of the store being written.
  std::filesystem::path externalStore;
  std::string externalGrid;
};

struct GridSource {
  GridInfo info;
  std::shared_ptr<const topo::SampleSource> samples;
  /// Non-empty for a tiled grid (then `samples` must be null).
  std::vector<TileSource> tiles{};
};

/// Writes a store crash-safely (core::writeFileAtomically): into `<path>.tmp-<pid>-<n>`
/// beside the target, synced, then renamed over `path` only once complete. Pyramid levels are 2×2
/// means of the level below, ignoring missing samples (a coarse sample is missing only if all four
/// are). Throws StoreError (or regolith::InvalidArgument for a bad GridInfo) and leaves no file.
void writeStore(const std::filesystem::path& path, std::span<const GridSource> grids,
                const WriteOptions& options = {});

}  // namespace regolith::store
