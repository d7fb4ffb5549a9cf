#pragma once
/// \file
/// Lazy paging of store grids into a shared patch cache.

#include <regolith/core/Executor.hpp>
#include <regolith/store/PageSource.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/store/Store.hpp>
#include <regolith/topo/Pyramid.hpp>
#include <regolith/topo/TopoDem.hpp>
#include <regolith/topo/TopoPlanet.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace regolith::store {

namespace detail {
class FilePatches;  // Pager.cpp: the patches of one store file alive in the process
}  // namespace detail

/// Serves the grids of one Store (or of any PageSource, such as a procedural planet) patch by
/// patch (the JPL paper, section III.A): reading a
/// point loads only the aligned patch (one HDF5 chunk, patchRows × patchCols samples of
/// one level) that holds it, with one hyperslab read, into a PatchCache shared by every
/// grid and level. TopoDem and TopoPlanet built here answer exactly the queries of
/// in-memory ones.
///
/// Hit counting: a query asks the cache for a patch only when the calling thread moves
/// into a patch it does not hold already (topo keeps each thread's last patch), so a hit is
/// "a run of queries entered this patch" rather than "one sample was read".
///
/// One store file, many pagers: every pager of one file (the same Store::fileId(): device
/// and inode, whatever path, symlink or hard link opened it) shares that file's grid ids and
/// the patches alive anywhere in the process. A patch is read from the file only when no
/// pager, cache or reader of that file holds it, and is then one object wherever it is held.
/// Through one cache, two pagers of a file use the same keys, so the cache holds each patch
/// once and its budget bounds them both. Through two caches, each cache keeps its own budget
/// and counts every patch it holds against it; a patch both hold is counted by both but takes
/// its memory once. A file written over the path since (a new inode) is another file: pagers
/// of it share nothing with pagers of the old one. Pagers of other PageSources share nothing.
///
/// Thread-safety: all members may be called concurrently; sources and grids made here may
/// be queried from any number of threads.
class Pager {
 public:
  /// Throws InvalidArgument if store or cache is null.
  Pager(std::shared_ptr<const Store> store, std::shared_ptr<PatchCache> cache);
  /// Pages grids computed on demand (Procedural.hpp) or held elsewhere, through the same
  /// cache and sources as a store. Throws InvalidArgument if source or cache is null, or a
  /// grid's levels or patch sizes are out of the store format's range.
  Pager(std::shared_ptr<const PageSource> source, std::shared_ptr<PatchCache> cache);

  /// Whether the grids come from a Store (false for other PageSources).
  [[nodiscard]] bool hasStore() const noexcept { return store_ != nullptr; }
  /// The store paged; requires hasStore() (an assertion).
  [[nodiscard]] const Store& store() const noexcept;
  /// What the pager reads from: the store, or the PageSource it was given.
  [[nodiscard]] const PageSource& pages() const noexcept { return *pages_; }
  [[nodiscard]] PatchCache& cache() const noexcept { return *cache_; }
  /// The grids' names, and one grid's description (StoreError for an unknown grid), whatever
  /// the source: what consumers should ask instead of store().grid().
  [[nodiscard]] std::vector<std::string> gridNames() const { return pages_->gridNames(); }
  [[nodiscard]] const GridInfo& grid(std::string_view name) const { return pages_->grid(name); }

  /// The samples of one level of a grid, paged. Throws StoreError for an unknown grid or a
  /// level the grid does not have.
  [[nodiscard]] std::shared_ptr<const topo::SampleSource> source(std::string_view grid,
                                                                 std::size_t level = 0) const;
  /// A paged TopoDem of one level. Throws StoreError if the grid is a planet grid.
  [[nodiscard]] topo::TopoDem dem(std::string_view grid, std::size_t level = 0) const;
  /// A paged TopoPlanet of one level. Throws StoreError if the grid is a DEM. Opening it
  /// reads no sample, at any width: its pole heights (the means of the first and last rows)
  /// come from PageSource::rowMean(), outside the cache, when a query first reaches a polar
  /// cap.
  [[nodiscard]] topo::TopoPlanet planet(std::string_view grid, std::size_t level = 0) const;
  /// Every stored level of a grid, paged, in topo terms: what a renderer takes to draw a
  /// store (clod::HeightPyramid) without knowing the store. A DEM's levels are planar (x
  /// east, y north, metres; no body); a planet grid's are longitude/latitude on its body.
  /// Rendering pages patches into this pager's cache, so memory stays within its budget;
  /// the sources keep the store and the cache alive. The levels share one loader, a
  /// store::Prefetcher: the windows a renderer needs now (topo::SampleSource::load()) on
  /// the renderer's thread; those it hints (prefetch(), one patch at a time, coarser levels
  /// first) in the background, on `loader` if given (the renderer's own executor,
  /// say), else on a thread the pyramid makes at its first hint. Throws StoreError for an
  /// unknown grid.
  [[nodiscard]] topo::GridPyramid pyramid(std::string_view grid,
                                          std::shared_ptr<core::Executor> loader = nullptr) const;

  /// The cache key of the patch holding sample (row, col) of a level. Pagers of one store
  /// file give the same keys.
  [[nodiscard]] PatchKey keyOf(std::string_view grid, std::size_t level, std::size_t row,
                               std::size_t col) const;
  /// The patch for `key`, through the cache (loading it on a miss); for prefetching.
  [[nodiscard]] std::shared_ptr<const Patch> patch(const PatchKey& key) const;

 private:
  struct GridEntry {
    const GridInfo* info;
    std::uint32_t id;
  };
  [[nodiscard]] const GridEntry& entry(std::string_view grid, std::size_t level,
                                       const char* op) const;

  std::shared_ptr<const Store> store_;       // null unless paging a Store
  std::shared_ptr<const PageSource> pages_;  // the store's adapter, or the source given
  std::shared_ptr<PatchCache> cache_;
  std::shared_ptr<detail::FilePatches> file_;  // null unless paging a Store
  std::unordered_map<std::string, GridEntry> grids_;
  std::unordered_map<std::uint32_t, const GridInfo*> byId_;
};

}  // namespace regolith::store
