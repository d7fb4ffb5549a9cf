#include <regolith/core/Assert.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>
#include <regolith/store/BlockSource.hpp>
#include <regolith/store/BlockTable.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/Prefetcher.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace regolith::store {
namespace {

// Grid ids are unique across pagers, so pagers of different stores can share one cache.
std::uint32_t nextGridId() {
  static std::atomic<std::uint32_t> next{1};  // ids only; no state is shared through it
  return next.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace

namespace detail {

/// The patches of one store file that are alive anywhere in the process, by key, and the
/// file's grid ids: what every pager of the file shares (Pager.hpp, "One store file, many
/// pagers"). Pagers find it by the file's identity in a process-wide registry of weak
/// references, so it lives while a pager or a source of the file does: while the file is
/// open, so its inode cannot be reused by another file.
///
/// A patch is held here by a weak reference only: it stays alive while a cache or a reader
/// holds it, and a request for it meanwhile gets the same object instead of a new read.
/// Concurrent requests for a key that is not alive share one read, as in PatchCache.
///
/// Thread-safety: every member may be called concurrently.
class FilePatches {
 public:
  struct Grid {
    std::uint32_t id;
    std::size_t rows, cols, levels, patchRows, patchCols;
    GridKind kind;
    friend bool operator==(const Grid&, const Grid&) = default;
  };

  /// New ids for the grids of `store`. `registered` says whether the registry names it.
  FilePatches(const Store& store, bool registered) : id_(store.fileId()), registered_(registered) {
    for (const std::string& name : store.gridNames()) {
      grids_.emplace(name, shapeOf(store.grid(name), nextGridId()));
    }
  }
  ~FilePatches();
  FilePatches(const FilePatches&) = delete;
  FilePatches& operator=(const FilePatches&) = delete;
  FilePatches(FilePatches&&) = delete;
  FilePatches& operator=(FilePatches&&) = delete;

  /// The pagers' shared state of the file `store` has open: the live one if there is one
  /// and its grids are those of `store`, else a new one.
  static std::shared_ptr<FilePatches> of(const Store& store);

  /// The id of a grid of the file (it must be one of its grids).
  [[nodiscard]] std::uint32_t gridId(const std::string& name) const { return grids_.at(name).id; }

  /// The patch `key`: the live one if any holder has it, else `read()`'s (whose exception
  /// propagates, to concurrent requests for the key too).
  template <class Read>
  std::shared_ptr<const Patch> get(const PatchKey& key, const Read& read) {
    std::shared_ptr<Pending> pending;
    {
      std::unique_lock lock(mutex_);
      Slot& slot = slots_[key];
      if (auto alive = slot.patch.lock()) return alive;
      if (slot.pending) {
        const std::shared_ptr<Pending> other = slot.pending;
        other->done.wait(lock, [&other] { return other->finished; });
        if (other->error) std::rethrow_exception(other->error);
        return other->patch;
      }
      pending = std::make_shared<Pending>();
      slot.pending = pending;
    }
    std::shared_ptr<const Patch> patch;
    std::exception_ptr error;
    try {
      patch = read();
    } catch (...) {
      error = std::current_exception();
    }
    {
      const std::lock_guard lock(mutex_);
      const auto it = slots_.find(key);  // there: a slot with a read pending is never swept
      it->second.pending.reset();
      it->second.patch = patch;
      pending->finished = true;
      pending->patch = patch;
      pending->error = error;
      sweep();
    }
    pending->done.notify_all();
    if (error) std::rethrow_exception(error);
    return patch;
  }

 private:
  struct Pending {
    std::condition_variable done;
    bool finished = false;  // these three are guarded by mutex_
    std::shared_ptr<const Patch> patch;
    std::exception_ptr error;
  };
  struct Slot {
    std::weak_ptr<const Patch> patch;
    std::shared_ptr<Pending> pending;  // a read in flight
  };

  static Grid shapeOf(const GridInfo& g, std::uint32_t id) {
    return {id, g.rows, g.cols, g.levels, g.patchRows, g.patchCols, g.kind};
  }
  /// Whether `store`'s grids are this file's (false only if the file changed in place).
  [[nodiscard]] bool describes(const Store& store) const {
    const std::vector<std::string> names = store.gridNames();
    if (names.size() != grids_.size()) return false;
    return std::all_of(names.begin(), names.end(), [&](const std::string& name) {
      const auto it = grids_.find(name);
      return it != grids_.end() && it->second == shapeOf(store.grid(name), it->second.id);
    });
  }
  /// Drops the slots of patches no longer alive, once the table has doubled since the last
  /// sweep: amortised O(1) per read, and at most twice the live slots plus 64 kept.
  void sweep() {
    if (slots_.size() < sweepAt_) return;
    std::erase_if(slots_,
                  [](const auto& kv) { return !kv.second.pending && kv.second.patch.expired(); });
    sweepAt_ = 2 * slots_.size() + 64;
  }

  struct Registry {
    std::mutex mutex;
    std::map<FileId, std::weak_ptr<FilePatches>> files;
  };
  static Registry& registry() {
    static Registry r;  // made before any FilePatches, so destroyed after the last one
    return r;
  }

  const FileId id_;
  const bool registered_;
  std::map<std::string, Grid, std::less<>> grids_;  // fixed after construction
  std::mutex mutex_;
  std::unordered_map<PatchKey, Slot, PatchKeyHash> slots_;  // guarded by mutex_
  std::size_t sweepAt_ = 64;                                // guarded by mutex_
};

FilePatches::~FilePatches() {
  if (!registered_) return;
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  // The entry is this one's unless a new pager of the file replaced it after this one's
  // last reference went; that one is alive.
  if (const auto it = r.files.find(id_); it != r.files.end() && it->second.expired()) {
    r.files.erase(it);
  }
}

std::shared_ptr<FilePatches> FilePatches::of(const Store& store) {
  Registry& r = registry();
  std::shared_ptr<FilePatches> live;  // released after the lock: its destructor takes it
  {
    const std::lock_guard lock(r.mutex);
    std::weak_ptr<FilePatches>& slot = r.files[store.fileId()];
    live = slot.lock();
    if (!live) {
      auto made = std::make_shared<FilePatches>(store, true);
      slot = made;
      return made;
    }
    if (live->describes(store)) return live;
  }
  // The file changed in place since the live one was made: share nothing with it.
  return std::make_shared<FilePatches>(store, false);
}

}  // namespace detail

namespace {

// A Store as a PageSource: its windows are hyperslab reads.
class StorePages final : public PageSource {
 public:
  explicit StorePages(std::shared_ptr<const Store> store) : store_(std::move(store)) {}
  std::vector<std::string> gridNames() const override { return store_->gridNames(); }
  const GridInfo& grid(std::string_view name) const override { return store_->grid(name); }
  void readWindow(std::string_view grid, std::size_t level, std::size_t row0, std::size_t col0,
                  std::size_t rows, std::size_t cols, std::span<float> out) const override {
    store_->readWindow(grid, level, row0, col0, rows, cols, out);
  }
  std::string name() const override { return store_->path().string(); }

 private:
  std::shared_ptr<const Store> store_;
};

// Checks what Store::open checks of a grid, for sources that are not stores: patch keys
// must fit their 32-bit fields, and the block tables their reservation.
void checkGrid(const PageSource& pages, const GridInfo& info) {
  const auto bad = [&](const std::string& field, const std::string& value,
                       std::string_view expected) {
    const std::string file = pages.name();
    throw InvalidArgument(core::format({"store::Pager()", file, field, value, expected}));
  };
  const std::string g = "grid '" + info.name + "' ";
  if (info.rows == 0 || info.cols == 0 || info.rows > kMaxGridSide || info.cols > kMaxGridSide) {
    bad(g + "size", core::number(info.rows) + "x" + core::number(info.cols),
        "1 to 2^31 samples a side");
  }
  if (info.patchRows == 0 || info.patchCols == 0 ||
      patchCount(info.rows, info.cols, info.patchRows, info.patchCols) > kMaxPatchesPerGrid) {
    bad(g + "patch size", core::number(info.patchRows) + "x" + core::number(info.patchCols),
        "> 0, with at most 2^35 patches in level 0");
  }
  if (info.levels == 0 || info.levels > 32 ||
      (info.levels > 1 && info.levelRows(info.levels - 2) == 1 &&
       info.levelCols(info.levels - 2) == 1)) {
    bad(g + "levels", core::number(info.levels), "1 to the level of 1x1 samples");
  }
}

// Reads the patch `key` of `info` with one window read (one hyperslab read from a store).
std::shared_ptr<const Patch> loadPatch(const PageSource& pages, const GridInfo& info,
                                       const PatchKey& key) {
  const std::size_t level = key.level;
  const std::size_t row0 = std::size_t{key.row} * info.patchRows;
  const std::size_t col0 = std::size_t{key.col} * info.patchCols;
  auto p = std::make_shared<Patch>();
  p->key = key;
  p->rows = std::min(info.patchRows, info.levelRows(level) - row0);
  p->cols = std::min(info.patchCols, info.levelCols(level) - col0);
  p->samples.resize(p->rows * p->cols);
  pages.readWindow(info.name, level, row0, col0, p->rows, p->cols, p->samples);
  return p;
}

// The patch `key`: through the file's shared patches when paging a store (`file`), so that
// a patch alive anywhere in the process is not read again; else read.
std::shared_ptr<const Patch> loadShared(detail::FilePatches* file, const PageSource& pages,
                                        const GridInfo& info, const PatchKey& key) {
  if (file == nullptr) return loadPatch(pages, info, key);
  return file->get(key, [&] { return loadPatch(pages, info, key); });
}

static_assert(kMaxPatchesPerGrid <= BlockTable::kMaxBlocks,
              "every grid a store may hold has a block table");

// The background loader of one exported pyramid (Pager::pyramid()), shared by its levels: a
// Prefetcher made at the first hint, so that a pyramid nobody hints starts no work. It loads
// on the executor the pyramid was given, else on a thread of its own. It holds a copy of the
// pager (which holds no source), not the levels: no cycle.
class AheadLoader {
 public:
  AheadLoader(Pager pager, std::shared_ptr<core::Executor> executor)
      : pager_(std::make_shared<const Pager>(std::move(pager))), executor_(std::move(executor)) {}
  Prefetcher& get() {
    const std::lock_guard lock(mutex_);
    // One load at a time: a hint must not take the cores the renderer draws on.
    if (!prefetcher_) {
      prefetcher_ = executor_ ? std::make_unique<Prefetcher>(pager_, executor_, 1)
                              : std::make_unique<Prefetcher>(pager_, 1);
    }
    return *prefetcher_;
  }

 private:
  std::shared_ptr<const Pager> pager_;
  std::shared_ptr<core::Executor> executor_;
  std::mutex mutex_;
  std::unique_ptr<Prefetcher> prefetcher_;
};

// One level of one grid, paged through the cache. Holds the source and the cache, so it
// stays usable after the Pager that made it is gone.
class PagedSource final : public BlockSource {
 public:
  PagedSource(const GridInfo& info, std::uint32_t gridId, std::size_t level,
              std::shared_ptr<const PageSource> pages, std::shared_ptr<PatchCache> cache,
              std::shared_ptr<detail::FilePatches> file,
              std::shared_ptr<AheadLoader> ahead = nullptr)
      // The table of the patches resident in the cache: lock-free hits on them.
      : BlockSource(cache->blockTable(gridId, static_cast<std::uint32_t>(level),
                                      info.levelRows(level), info.levelCols(level), info.patchRows,
                                      info.patchCols)),
        info_(info),
        rows_(info.levelRows(level)),
        cols_(info.levelCols(level)),
        pr_(info.patchRows),
        pc_(info.patchCols),
        gridId_(gridId),
        level_(static_cast<std::uint32_t>(level)),
        pages_(std::move(pages)),
        cache_(std::move(cache)),
        file_(std::move(file)),
        loader_([this](const PatchKey& k) { return loadShared(file_.get(), *pages_, info_, k); }),
        ahead_(std::move(ahead)) {}

  std::size_t rows() const noexcept override { return rows_; }
  std::size_t cols() const noexcept override { return cols_; }

  float sample(std::size_t row, std::size_t col) const override {
    const auto p = patchAt(row, col);
    return p->samples[(row - p->key.row * pr_) * p->cols + (col - p->key.col * pc_)];
  }

  void readWindow(std::size_t row0, std::size_t col0, std::size_t nrows, std::size_t ncols,
                  std::span<float> out) const override {
    // Patch by patch, copying each patch's overlap with the window.
    for (std::size_t pr = row0 / pr_; pr * pr_ < row0 + nrows; ++pr) {
      for (std::size_t pc = col0 / pc_; pc * pc_ < col0 + ncols; ++pc) {
        const auto p = patchAt(pr * pr_, pc * pc_);
        const std::size_t r0 = std::max(row0, pr * pr_),
                          r1 = std::min(row0 + nrows, pr * pr_ + p->rows);
        const std::size_t c0 = std::max(col0, pc * pc_),
                          c1 = std::min(col0 + ncols, pc * pc_ + p->cols);
        for (std::size_t r = r0; r < r1; ++r) {
          const float* src = p->samples.data() + (r - pr * pr_) * p->cols + (c0 - pc * pc_);
          std::copy(src, src + (c1 - c0),
                    out.begin() + static_cast<std::ptrdiff_t>((r - row0) * ncols + (c0 - col0)));
        }
      }
    }
  }

  // The pyramid's Prefetcher loads the windows; this level's previous hint is cancelled. A
  // source made by Pager::source() has no loader and ignores hints.
  void prefetch(std::span<const Window> windows) const noexcept override {
    if (!ahead_) return;
    try {
      const std::vector<LevelWindow> w = levelWindows(windows);
      Prefetcher& pf = ahead_->get();
      const std::lock_guard lock(aheadMutex_);
      if (aheadTicket_ != 0) pf.cancel(aheadTicket_);
      aheadTicket_ = pf.request(info_.name, w);
    } catch (...) {  // NOLINT(bugprone-empty-catch): a hint; the read that needs it reports
    }
  }

  void load(std::span<const Window> windows) const noexcept override {
    if (!ahead_) return;
    try {
      // Windows whose patches would fill more than half the cache are read as they go:
      // loaded whole first, their first patches could be evicted before they are read.
      std::size_t patches = 0;
      for (const Window& w : windows) {
        if (w.rows == 0 || w.cols == 0) continue;
        patches += ((w.row0 + w.rows - 1) / pr_ - w.row0 / pr_ + 1) *
                   ((w.col0 + w.cols - 1) / pc_ - w.col0 / pc_ + 1);
      }
      if (patches * pr_ * pc_ * sizeof(float) > cache_->capacityBytes() / 2) return;
      ahead_->get().load(info_.name, levelWindows(windows));
    } catch (...) {  // NOLINT(bugprone-empty-catch): the read that follows reports it
    }
  }

  SampleBlock block(std::size_t row, std::size_t col) const override {
    auto p = patchAt(row, col);
    SampleBlock out{p->samples.data(), p->key.row * pr_, p->key.col * pc_, p->rows,
                    p->cols,           p->cols,          nullptr};
    out.owner = std::move(p);
    return out;
  }

 private:
  std::vector<LevelWindow> levelWindows(std::span<const Window> windows) const {
    std::vector<LevelWindow> w;
    w.reserve(windows.size());
    for (const Window& x : windows) w.push_back({level_, x.row0, x.col0, x.rows, x.cols});
    return w;
  }
  std::shared_ptr<const Patch> patchAt(std::size_t row, std::size_t col) const {
    const PatchKey key{gridId_, level_, static_cast<std::uint32_t>(row / pr_),
                       static_cast<std::uint32_t>(col / pc_)};
    return cache_->get(key, loader_);
  }

  const GridInfo& info_;  // owned by pages_
  std::size_t rows_, cols_, pr_, pc_;
  std::uint32_t gridId_, level_;
  std::shared_ptr<const PageSource> pages_;
  std::shared_ptr<PatchCache> cache_;
  std::shared_ptr<detail::FilePatches> file_;  // null unless paging a Store
  PatchCache::Loader loader_;  // made once: a std::function per lookup costs more than a hit
  std::shared_ptr<AheadLoader> ahead_;  // null unless a level of an exported pyramid
  mutable std::mutex aheadMutex_;
  mutable Prefetcher::Ticket aheadTicket_ = 0;  // this level's last hint
};

}  // namespace

double PageSource::rowMean(std::string_view grid, std::size_t level, std::size_t row) const {
  const GridInfo& info = this->grid(grid);
  if (level >= info.levels || row >= info.levelRows(level)) {
    throw StoreError(core::format(
        {"store::PageSource::rowMean()", name(), "row of grid '" + std::string(grid) + "'",
         "level " + core::number(level) + " row " + core::number(row), "a row of a stored level"}));
  }
  // Windows of at most 2^17 samples (0.5 MiB; 3.5 MiB of working memory in the procedural
  // generator), and at least cols/16, so that a row near a pole of the procedural planet,
  // whose windows each search about half the longitude cells of every crater band, takes
  // few windows. The sum topo::TopoPlanet makes of a row: every valid sample, in column
  // order, in double.
  constexpr std::size_t kWindowMax = std::size_t{1} << 17, kWindows = 16;
  const std::size_t cols = info.levelCols(level);
  const std::size_t window = std::clamp(cols / kWindows, std::size_t{4096}, kWindowMax);
  std::vector<float> buf(std::min(window, cols));
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t c0 = 0; c0 < cols; c0 += window) {
    const std::size_t nc = std::min(window, cols - c0);
    readWindow(grid, level, row, c0, 1, nc, std::span(buf.data(), nc));
    for (std::size_t c = 0; c < nc; ++c) {
      if (!std::isnan(buf[c])) {
        sum += static_cast<double>(buf[c]);
        ++n;
      }
    }
  }
  return n == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(n);
}

Pager::Pager(std::shared_ptr<const Store> store, std::shared_ptr<PatchCache> cache)
    : store_(std::move(store)), cache_(std::move(cache)) {
  if (!store_ || !cache_) {
    throw InvalidArgument("store::Pager(): store and cache must not be null");
  }
  pages_ = std::make_shared<StorePages>(store_);
  file_ = detail::FilePatches::of(*store_);
  for (const std::string& name : store_->gridNames()) {
    const GridInfo& info = store_->grid(name);
    const std::uint32_t id = file_->gridId(name);
    grids_.emplace(name, GridEntry{&info, id});
    byId_.emplace(id, &info);
  }
}

Pager::Pager(std::shared_ptr<const PageSource> source, std::shared_ptr<PatchCache> cache)
    : pages_(std::move(source)), cache_(std::move(cache)) {
  if (!pages_ || !cache_) {
    throw InvalidArgument("store::Pager(): source and cache must not be null");
  }
  for (const std::string& name : pages_->gridNames()) {
    const GridInfo& info = pages_->grid(name);
    checkGrid(*pages_, info);
    const std::uint32_t id = nextGridId();
    grids_.emplace(name, GridEntry{&info, id});
    byId_.emplace(id, &info);
  }
}

const Store& Pager::store() const noexcept {
  REGOLITH_ASSERT(store_ != nullptr, "store::Pager::store(): this pager pages no Store");
  return *store_;
}

const Pager::GridEntry& Pager::entry(std::string_view grid, std::size_t level,
                                     const char* op) const {
  const auto it = grids_.find(std::string(grid));
  if (it == grids_.end()) {
    throw StoreError(std::string(op) + ": " + pages_->name() + ": no grid '" + std::string(grid) +
                     "'");
  }
  if (level >= it->second.info->levels) {
    throw StoreError(std::string(op) + ": " + pages_->name() + ": grid '" + std::string(grid) +
                     "' has " + std::to_string(it->second.info->levels) + " levels, level " +
                     std::to_string(level) + " requested");
  }
  return it->second;
}

std::shared_ptr<const topo::SampleSource> Pager::source(std::string_view grid,
                                                        std::size_t level) const {
  const GridEntry& e = entry(grid, level, "store::Pager::source()");
  return std::make_shared<PagedSource>(*e.info, e.id, level, pages_, cache_, file_);
}

topo::TopoDem Pager::dem(std::string_view grid, std::size_t level) const {
  const GridEntry& e = entry(grid, level, "store::Pager::dem()");
  if (e.info->kind != GridKind::Dem) {
    throw StoreError("store::Pager::dem(): " + pages_->name() + ": grid '" + std::string(grid) +
                     "' is a planet grid, expected a DEM");
  }
  return {topoGridOf(*e.info, level), placementOf(*e.info), source(grid, level)};
}

topo::TopoPlanet Pager::planet(std::string_view grid, std::size_t level) const {
  const GridEntry& e = entry(grid, level, "store::Pager::planet()");
  if (e.info->kind != GridKind::Planet) {
    throw StoreError("store::Pager::planet(): " + pages_->name() + ": grid '" + std::string(grid) +
                     "' is a DEM, expected a planet grid");
  }
  // The pole heights are the means of the first and last rows, read outside the cache when a
  // query first reaches a cap: opening reads nothing (a 131072-sample row is 512 patches).
  return {topoGridOf(*e.info, level), bodyOf(*e.info), e.info->latitudeType, source(grid, level),
          [pages = pages_, name = std::string(grid), level](std::size_t row) {
            return pages->rowMean(name, level, row);
          }};
}

topo::GridPyramid Pager::pyramid(std::string_view grid,
                                 std::shared_ptr<core::Executor> loader) const {
  const GridEntry& e = entry(grid, 0, "store::Pager::pyramid()");
  topo::GridPyramid p;
  p.levels.reserve(e.info->levels);
  const auto ahead = std::make_shared<AheadLoader>(*this, std::move(loader));
  for (std::size_t l = 0; l < e.info->levels; ++l) {
    p.levels.push_back(
        {topoGridOf(*e.info, l),
         std::make_shared<PagedSource>(*e.info, e.id, l, pages_, cache_, file_, ahead)});
  }
  if (e.info->kind == GridKind::Planet) p.planetBody = bodyOf(*e.info);
  p.latitudeType = e.info->latitudeType;
  return p;
}

PatchKey Pager::keyOf(std::string_view grid, std::size_t level, std::size_t row,
                      std::size_t col) const {
  const GridEntry& e = entry(grid, level, "store::Pager::keyOf()");
  return {e.id, static_cast<std::uint32_t>(level),
          static_cast<std::uint32_t>(row / e.info->patchRows),
          static_cast<std::uint32_t>(col / e.info->patchCols)};
}

std::shared_ptr<const Patch> Pager::patch(const PatchKey& key) const {
  const auto it = byId_.find(key.grid);
  if (it == byId_.end()) {
    throw InvalidArgument("store::Pager::patch(): patch key names grid id " +
                          std::to_string(key.grid) + ", which is not a grid of " + pages_->name());
  }
  const GridInfo& info = *it->second;
  if (key.level >= info.levels ||
      std::size_t{key.row} * info.patchRows >= info.levelRows(key.level) ||
      std::size_t{key.col} * info.patchCols >= info.levelCols(key.level)) {
    throw InvalidArgument("store::Pager::patch(): patch (level " + std::to_string(key.level) +
                          ", row " + std::to_string(key.row) + ", col " + std::to_string(key.col) +
                          ") is outside grid '" + info.name + "'");
  }
  return cache_->get(key,
                     [&](const PatchKey& k) { return loadShared(file_.get(), *pages_, info, k); });
}

}  // namespace regolith::store
