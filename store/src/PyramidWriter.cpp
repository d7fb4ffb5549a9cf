// writer::Pyramid: a grid's pyramid built band by band (docs/store-format.md, "Pyramid levels").
#include <regolith/topo/Pyramid.hpp>

#include "WriterParts.hpp"

#include <algorithm>
#include <utility>

namespace regolith::store::writer {

Pyramid::Pyramid(hid_t group, const Prepared& p, const WriteOptions& o, std::size_t tileChunks,
                 Progress& progress, const Context& ctx)
    : p_(p),
      info_(p.info),
      o_(o),
      tileChunks_(tileChunks),
      progress_(progress),
      ctx_(ctx),
      tiled_(!p.tiles.empty()),
      pending_(p.info.levels) {
  writers_.reserve(info_.levels);
  for (std::size_t level = 0; level < info_.levels; ++level) {
    if (level == 0 && tiled_) {
      writers_.emplace_back(std::nullopt);
    } else {
      writers_.emplace_back(std::in_place, group, info_, level, o, ctx);
    }
  }
}

void Pyramid::level0Band(std::size_t r0, std::size_t nr, const Level0Block& block) {
  checkCancel(o_, ctx_);
  if (!writers_[0] && info_.levels == 1) return;  // tiled, no pyramid: nothing to build
  const std::size_t cols = info_.cols;
  if (tileChunks_ > 0) {
    level0Tiled(r0, nr, block);
    return;
  }
  Band band{r0, nr, std::vector<float>(nr * cols)};
  const auto fill = [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
    block(r0, c0, nr, nc, out);
    for (std::size_t r = 0; r < nr; ++r) {
      std::copy_n(out.begin() + static_cast<std::ptrdiff_t>(r * nc), nc,
                  band.data.begin() + static_cast<std::ptrdiff_t>(r * cols + c0));
    }
  };
  if (writers_[0]) {
    writeBandChunks(*writers_[0], format::chunkShape(info_, 0), r0, nr, cols,
                    Missing{info_.nodata}.stored(), o_, fill, progress_,
                    "grid '" + info_.name + "' level 0", ctx_);
  } else {
    // Tiled: level 0 lives in the tiles; the mosaic's band is only read for level 1.
    const std::size_t cc = info_.patchCols;
    parallelFor((cols + cc - 1) / cc, o_, [&](std::size_t k) {
      std::vector<float> b;
      fill(k * cc, std::min(cc, cols - k * cc), b);
    });
  }
  push(1, std::move(band));
}

void Pyramid::close() {
  for (auto& w : writers_) {
    if (w) w->close();
  }
}

void Pyramid::level0Tiled(std::size_t r0, std::size_t nr, const Level0Block& block) {
  const std::size_t cols = info_.cols;
  const auto fill = [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
    block(r0, c0, nr, nc, out);
  };
  if (writers_[0]) {
    writeBandChunks(*writers_[0], format::chunkShape(info_, 0), r0, nr, cols,
                    Missing{info_.nodata}.stored(), o_, fill, progress_,
                    "grid '" + info_.name + "' level 0", ctx_, tileChunks_);
  } else {
    // Tiled grid: the blocks only feed the statistics (and check the samples).
    const std::size_t cc = info_.patchCols;
    parallelFor((cols + cc - 1) / cc, o_, [&](std::size_t k) {
      std::vector<float> b;
      fill(k * cc, std::min(cc, cols - k * cc), b);
    });
  }
  push(1, Band{r0, nr, {}});
}

void Pyramid::push(std::size_t level, Band fine) {
  if (level >= info_.levels) return;
  std::optional<Band>& held = pending_[level];
  const bool last = fine.row0 + fine.rows == info_.levelRows(level - 1);
  const bool evenBand = (fine.row0 / info_.patchRows) % 2 == 0;
  if (evenBand && !last) {
    held = std::move(fine);
    return;
  }
  Band pair;
  if (held) {
    pair = std::move(*held);
    held.reset();
    pair.rows += fine.rows;
    pair.data.insert(pair.data.end(), fine.data.begin(), fine.data.end());
  } else {
    pair = std::move(fine);
  }
  coarseBand(level, pair);
}

void Pyramid::coarseBand(std::size_t level, const Band& fine) {
  checkCancel(o_, ctx_);
  const std::size_t fineCols = info_.levelCols(level - 1);
  const std::size_t cols = info_.levelCols(level);
  const std::size_t r0 = fine.row0 / 2, nr = (fine.rows + 1) / 2;
  const bool keep = tileChunks_ == 0;
  Band band{r0, nr, keep ? std::vector<float>(nr * cols) : std::vector<float>{}};
  // Column tiles: fine columns [tileCol0, tileCol0 + tileCols) of the band, read back.
  std::vector<float> tile;
  std::size_t tileCol0 = 0, tileCols = 0;
  const auto readTile = [&](std::size_t c0, std::size_t nc) {
    tileCol0 = 2 * c0;
    tileCols = std::min(2 * nc, fineCols - tileCol0);
    tile.resize(fine.rows * tileCols);
    if (writers_[level - 1]) {
      writers_[level - 1]->read(fine.row0, tileCol0, fine.rows, tileCols, tile.data());
    } else {
      mosaicBlock(p_, fine.row0, tileCol0, fine.rows, tileCols, tile.data(), ctx_);
    }
  };
  const FineReader reader = [&](std::size_t fr0, std::size_t fc0, std::size_t fnr, std::size_t fnc,
                                float* data) {
    const float* from = keep ? fine.data.data() : tile.data();
    const std::size_t stride = keep ? fineCols : tileCols, col0 = keep ? 0 : tileCol0;
    for (std::size_t r = 0; r < fnr; ++r) {
      std::copy_n(from + (fr0 - fine.row0 + r) * stride + (fc0 - col0), fnc, data + r * fnc);
    }
  };
  const auto fill = [&](std::size_t c0, std::size_t nc, std::vector<float>& out) {
    std::vector<float> scratch;
    coarseBlock(reader, info_, level, r0, c0, nr, nc, scratch, out);
    if (!keep) return;
    for (std::size_t r = 0; r < nr; ++r) {
      std::copy_n(out.begin() + static_cast<std::ptrdiff_t>(r * nc), nc,
                  band.data.begin() + static_cast<std::ptrdiff_t>(r * cols + c0));
    }
  };
  writeBandChunks(*writers_[level], format::chunkShape(info_, level), r0, nr, cols,
                  Missing{info_.nodata}.stored(), o_, fill, progress_,
                  "grid '" + info_.name + "' level " + std::to_string(level), ctx_, tileChunks_,
                  keep ? std::function<void(std::size_t, std::size_t)>{} : readTile);
  std::vector<float>().swap(tile);
  push(level + 1, std::move(band));
}

}  // namespace regolith::store::writer
