#pragma once
/// \file
/// Grids computed patch by patch on demand, paged like a store: the generated Mars at any
/// resolution, up to 2^31 rows, with no file and no memory that grows with the grid.

#include <regolith/store/Generate.hpp>
#include <regolith/store/PageSource.hpp>
#include <regolith/store/Pager.hpp>
#include <regolith/store/PatchCache.hpp>

#include <cstddef>
#include <memory>

namespace regolith::store {

struct ProceduralMarsOptions {
  /// The planet: rows (2·rows columns), seed, body, crater density and grid name, as for
  /// MarsPlanetGenerator. `threads` and `write` are not used: a patch is computed on the
  /// thread that asks for it (a query, or a Prefetcher's task on its executor).
  MarsPlanetOptions planet{};
  /// Pyramid levels, level 0 included. 0: as the store writer chooses them (until a level
  /// fits one patch), but no more than the rows allow (below).
  std::size_t levels = 0;
  /// Patch (cache entry) size; 256 × 256 as a store's chunks by default.
  std::size_t patchRows = 256, patchCols = 256;
};

/// The generated Mars of `options.planet` as a PageSource, computed patch by patch when the
/// pager asks: a 2^20-row planet (2^20 × 2^21 samples, 2.2·10^12) pages like a store with
/// nothing on disk, and opening it costs the same few kilobytes at any size.
///
/// Level 0 is bit for bit what MarsPlanetGenerator (and so `regolith generate planet`)
/// writes at options.planet.rows: each sample is the generator's height at the sample
/// centre, cast to float. Level k is the generated planet at rows/2^k rows, the same seed,
/// body and crater density: bit for bit level 0 of a store generated at that size, whose
/// sample centres are exactly level k's (GridInfo's level geometry). It is computed at every
/// level, not by the 2×2 rule (a coarse patch by that rule would need 4^k fine patches):
/// a coarse sample is the planet sampled at that resolution (the fBm octaves and crater
/// bands the resolution resolves), not the mean of the four samples below it. The two agree
/// to the detail the coarser level leaves out (docs/scale.md measures how closely). Every
/// level must halve the rows exactly, so 2^(levels − 1) must divide rows and leave ≥ 2.
///
/// Its pole heights (PageSource::rowMean()) are computed in row windows outside the cache
/// when a query first reaches a polar cap: for a 2^20-row planet that takes seconds, once per
/// TopoPlanet.
///
/// Throws InvalidArgument for bad planet options (as MarsPlanetGenerator), zero patch
/// sizes, or levels the rows do not allow. Thread-safety: immutable; every member may be
/// called concurrently.
[[nodiscard]] std::shared_ptr<const PageSource> proceduralMars(
    const ProceduralMarsOptions& options);

/// A Pager over proceduralMars(options), paging into `cache` (which may be shared with
/// pagers of stores). Throws as proceduralMars() and Pager().
[[nodiscard]] Pager proceduralPager(const ProceduralMarsOptions& options,
                                    std::shared_ptr<PatchCache> cache);

}  // namespace regolith::store
