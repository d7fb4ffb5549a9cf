#include <regolith/core/Error.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/topo/BlockTable.hpp>

#include <algorithm>
#include <atomic>
#include <string>

namespace regolith::store {
namespace {

// Grid ids are unique across pagers, so pagers of different stores can share one cache.
std::uint32_t nextGridId() {
  static std::atomic<std::uint32_t> next{1};  // ids only; no state is shared through it
  return next.fetch_add(1, std::memory_order_relaxed);
}

// Reads the patch `key` of `info` with one hyperslab read.
std::shared_ptr<const Patch> loadPatch(const Store& store, const GridInfo& info,
                                       const PatchKey& key) {
  const std::size_t level = key.level;
  const std::size_t row0 = std::size_t{key.row} * info.patchRows;
  const std::size_t col0 = std::size_t{key.col} * info.patchCols;
  auto p = std::make_shared<Patch>();
  p->key = key;
  p->rows = std::min(info.patchRows, info.levelRows(level) - row0);
  p->cols = std::min(info.patchCols, info.levelCols(level) - col0);
  p->samples.resize(p->rows * p->cols);
  store.readWindow(info.name, level, row0, col0, p->rows, p->cols, p->samples);
  return p;
}

static_assert(kMaxPatchesPerGrid <= topo::BlockTable::kMaxBlocks,
              "every grid a store may hold has a block table");

// One level of one grid, paged through the cache. Holds the store and the cache, so it
// stays usable after the Pager that made it is gone.
class PagedSource final : public topo::SampleSource {
 public:
  PagedSource(const GridInfo& info, std::uint32_t gridId, std::size_t level,
              std::shared_ptr<const Store> store, std::shared_ptr<PatchCache> cache)
      : info_(info),
        rows_(info.levelRows(level)),
        cols_(info.levelCols(level)),
        pr_(info.patchRows),
        pc_(info.patchCols),
        gridId_(gridId),
        level_(static_cast<std::uint32_t>(level)),
        store_(std::move(store)),
        cache_(std::move(cache)),
        table_(cache_->blockTable(gridId, level_, rows_, cols_, pr_, pc_)),
        loader_([this](const PatchKey& k) { return loadPatch(*store_, info_, k); }) {}

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

  const topo::BlockTable* blockTable() const noexcept override { return table_.get(); }

  bool block(std::size_t row, std::size_t col, topo::SampleBlock& out) const override {
    auto p = patchAt(row, col);
    out.data = p->samples.data();
    out.row0 = p->key.row * pr_;
    out.col0 = p->key.col * pc_;
    out.rows = p->rows;
    out.cols = p->cols;
    out.stride = p->cols;
    out.owner = std::move(p);
    return true;
  }

 private:
  std::shared_ptr<const Patch> patchAt(std::size_t row, std::size_t col) const {
    const PatchKey key{gridId_, level_, static_cast<std::uint32_t>(row / pr_),
                       static_cast<std::uint32_t>(col / pc_)};
    return cache_->get(key, loader_);
  }

  const GridInfo& info_;  // owned by store_
  std::size_t rows_, cols_, pr_, pc_;
  std::uint32_t gridId_, level_;
  std::shared_ptr<const Store> store_;
  std::shared_ptr<PatchCache> cache_;
  std::shared_ptr<const topo::BlockTable> table_;  // lock-free hits on resident patches
  PatchCache::Loader loader_;  // made once: a std::function per lookup costs more than a hit
};

}  // namespace

Pager::Pager(std::shared_ptr<const Store> store, std::shared_ptr<PatchCache> cache)
    : store_(std::move(store)), cache_(std::move(cache)) {
  if (!store_ || !cache_) {
    throw InvalidArgument("store::Pager(): store and cache must not be null");
  }
  for (const std::string& name : store_->gridNames()) {
    const GridInfo& info = store_->grid(name);
    const std::uint32_t id = nextGridId();
    grids_.emplace(name, GridEntry{&info, id});
    byId_.emplace(id, &info);
  }
}

const Pager::GridEntry& Pager::entry(std::string_view grid, std::size_t level,
                                     const char* op) const {
  const auto it = grids_.find(std::string(grid));
  if (it == grids_.end()) {
    throw StoreError(std::string(op) + ": " + store_->path().string() + ": no grid '" +
                     std::string(grid) + "'");
  }
  if (level >= it->second.info->levels) {
    throw StoreError(std::string(op) + ": " + store_->path().string() + ": grid '" +
                     std::string(grid) + "' has " + std::to_string(it->second.info->levels) +
                     " levels, level " + std::to_string(level) + " requested");
  }
  return it->second;
}

std::shared_ptr<const topo::SampleSource> Pager::source(std::string_view grid,
                                                        std::size_t level) const {
  const GridEntry& e = entry(grid, level, "store::Pager::source()");
  return std::make_shared<PagedSource>(*e.info, e.id, level, store_, cache_);
}

topo::TopoDem Pager::dem(std::string_view grid, std::size_t level) const {
  const GridEntry& e = entry(grid, level, "store::Pager::dem()");
  if (e.info->kind != GridKind::Dem) {
    throw StoreError("store::Pager::dem(): " + store_->path().string() + ": grid '" +
                     std::string(grid) + "' is a planet grid, expected a DEM");
  }
  return {topoGridOf(*e.info, level), placementOf(*e.info), source(grid, level)};
}

topo::TopoPlanet Pager::planet(std::string_view grid, std::size_t level) const {
  const GridEntry& e = entry(grid, level, "store::Pager::planet()");
  if (e.info->kind != GridKind::Planet) {
    throw StoreError("store::Pager::planet(): " + store_->path().string() + ": grid '" +
                     std::string(grid) + "' is a DEM, expected a planet grid");
  }
  return {topoGridOf(*e.info, level), bodyOf(*e.info), e.info->latitudeType, source(grid, level)};
}

topo::GridPyramid Pager::pyramid(std::string_view grid) const {
  const GridEntry& e = entry(grid, 0, "store::Pager::pyramid()");
  topo::GridPyramid p;
  p.levels.reserve(e.info->levels);
  for (std::size_t l = 0; l < e.info->levels; ++l) {
    p.levels.push_back({topoGridOf(*e.info, l), source(grid, l)});
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
                          std::to_string(key.grid) + ", which is not a grid of " +
                          store_->path().string());
  }
  const GridInfo& info = *it->second;
  if (key.level >= info.levels ||
      std::size_t{key.row} * info.patchRows >= info.levelRows(key.level) ||
      std::size_t{key.col} * info.patchCols >= info.levelCols(key.level)) {
    throw InvalidArgument("store::Pager::patch(): patch (level " + std::to_string(key.level) +
                          ", row " + std::to_string(key.row) + ", col " + std::to_string(key.col) +
                          ") is outside grid '" + info.name + "'");
  }
  return cache_->get(key, [&](const PatchKey& k) { return loadPatch(*store_, info, k); });
}

}  // namespace regolith::store
