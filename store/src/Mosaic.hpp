#pragma once
/// \file
/// The rules of a tiled grid's level 0 (docs/store-format.md, "Tiled grids"), written once
/// for the reader (Store.cpp) and the writer (WriterPrepare.cpp, WriterBlocks.cpp): where a
/// tile lies in its mosaic, when two tiles overlap, and how a window of the mosaic is put
/// together from its tiles.

#include <algorithm>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace regolith::store::mosaic {

/// Rows and columns of the mosaic (level 0 of a tiled grid) that a tile or a window covers.
struct Rect {
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
};

/// The place of a tile (anything with row0, col0, rows, cols) in its mosaic.
template <class Tile>
Rect rectOf(const Tile& t) {
  return {t.row0, t.col0, t.rows, t.cols};
}

/// The samples that both cover; rows or cols are 0 where they do not meet.
inline Rect intersect(const Rect& a, const Rect& b) {
  const std::size_t r0 = std::max(a.row0, b.row0), r1 = std::min(a.row0 + a.rows, b.row0 + b.rows);
  const std::size_t c0 = std::max(a.col0, b.col0), c1 = std::min(a.col0 + a.cols, b.col0 + b.cols);
  return {r0, c0, r1 > r0 ? r1 - r0 : 0, c1 > c0 ? c1 - c0 : 0};
}

/// True if the two share a sample: two tiles of one mosaic may not.
inline bool overlap(const Rect& a, const Rect& b) {
  const Rect i = intersect(a, b);
  return i.rows > 0 && i.cols > 0;
}

/// "rows 0-9, cols 10-19" (first and last, inclusive), for messages.
inline std::string range(const Rect& t) {
  return "rows " + std::to_string(t.row0) + "-" + std::to_string(t.row0 + t.rows - 1) + ", cols " +
         std::to_string(t.col0) + "-" + std::to_string(t.col0 + t.cols - 1);
}

/// Fills `out` (window.rows × window.cols, row-major) with the mosaic's samples in `window`:
/// `fill` where no tile lies, and for each tile the window meets, the part of it that
/// `readPart(tile, part, buffer)` reads, `part` in the tile's own rows and columns and
/// `buffer` already sized part.rows × part.cols.
template <class Tile, class ReadPart>
void assemble(std::span<const Tile> tiles, const Rect& window, float fill, float* out,
              ReadPart&& readPart) {
  std::fill(out, out + window.rows * window.cols, fill);
  std::vector<float> buffer;
  for (const Tile& t : tiles) {
    const Rect part = intersect(window, rectOf(t));
    if (part.rows == 0 || part.cols == 0) continue;
    buffer.resize(part.rows * part.cols);
    readPart(t, Rect{part.row0 - t.row0, part.col0 - t.col0, part.rows, part.cols}, buffer);
    for (std::size_t r = 0; r < part.rows; ++r) {
      std::copy_n(buffer.begin() + static_cast<std::ptrdiff_t>(r * part.cols), part.cols,
                  out + (part.row0 - window.row0 + r) * window.cols + (part.col0 - window.col0));
    }
  }
}

}  // namespace regolith::store::mosaic
