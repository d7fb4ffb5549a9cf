#pragma once
/// \file
/// What a Pager pages from: a store on disk, or grids computed on demand.

#include <regolith/store/GridInfo.hpp>

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace regolith::store {

/// A set of named grids, each with its pyramid levels, whose windows can be read at any
/// level: what a Pager serves patch by patch through its PatchCache. A Store is one (the
/// Pager wraps it; its windows are HDF5 hyperslab reads); proceduralMars() (Procedural.hpp)
/// is another, whose windows are computed. Every level's geometry follows GridInfo:
/// ⌈rows/2^k⌉ × ⌈cols/2^k⌉ samples, spacing 2^k times level 0's, sample (r, c) centred on
/// level k−1's samples (2r…2r+1, 2c…2c+1). How the samples of a level are made is the
/// source's to document (a store holds the 2×2 rule's means, topo::downsample2x2).
///
/// Thread-safety: implementations must allow every member to be called concurrently.
class PageSource {
 public:
  PageSource() = default;
  PageSource(const PageSource&) = delete;
  PageSource& operator=(const PageSource&) = delete;
  virtual ~PageSource() = default;

  /// The grids' names, in a fixed order.
  [[nodiscard]] virtual std::vector<std::string> gridNames() const = 0;
  /// One grid's description: levels and patch sizes included. Throws StoreError naming the
  /// source and the grid if there is no such grid.
  [[nodiscard]] virtual const GridInfo& grid(std::string_view name) const = 0;
  /// Samples [row0, row0 + rows) × [col0, col0 + cols) of one level, row-major into `out`
  /// (rows·cols floats), as heights in metres with NaN where missing. Throws StoreError
  /// for a window outside the level.
  virtual void readWindow(std::string_view grid, std::size_t level, std::size_t row0,
                          std::size_t col0, std::size_t rows, std::size_t cols,
                          std::span<float> out) const = 0;
  /// The mean, summed in double in column order, of the valid (non-NaN) samples of one row
  /// of a level (NaN if none): a planet grid's first and last rows give its pole heights
  /// (topo::TopoPlanet, which asks at its first query in a polar cap). This default reads the
  /// row through readWindow() in windows of at most 2^17 samples, outside any cache, so that
  /// a planet 2^17 samples wide does not page 2·512 patches through the cache to find its
  /// poles. Throws StoreError for a row outside the level, and what readWindow() throws.
  [[nodiscard]] virtual double rowMean(std::string_view grid, std::size_t level,
                                       std::size_t row) const;
  /// Where the grids come from, for messages: a store's path, or a description such as
  /// "procedural Mars (seed 1, 1048576 rows)".
  [[nodiscard]] virtual std::string name() const = 0;
};

}  // namespace regolith::store
