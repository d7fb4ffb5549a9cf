// writer::level0Block(), coarseBlock() and mosaicBlock(): the samples of one block of a
// level, as stored.
#include <regolith/core/Message.hpp>
#include <regolith/topo/Pyramid.hpp>

#include "WriterParts.hpp"

#include <algorithm>

namespace regolith::store::writer {

/// Level 0 of one chunk: the source's heights, missing samples as the stored nodata value.
/// Infinite heights are refused (they are neither data nor a declared nodata).
void level0Block(const topo::SampleSource& src, const GridInfo& info, std::size_t r0,
                 std::size_t c0, std::size_t nr, std::size_t nc, std::vector<float>& out,
                 const Context& ctx) {
  out.resize(nr * nc);
  src.readWindow(r0, c0, nr, nc, out);
  const Missing missing{info.nodata};
  for (std::size_t i = 0; i < out.size(); ++i) {
    float& v = out[i];
    if (missing(v)) {
      v = missing.stored();
    } else if (std::isinf(v)) {
      invalid(ctx, "grid '" + info.name + "' sample (" + std::to_string(r0 + i / nc) + ", " +
                       std::to_string(c0 + i % nc) + ") is " +
                       core::number(static_cast<double>(v)) + ", expected a finite height or NaN");
    }
  }
}

/// Level k ≥ 1 of one chunk: topo::downsample2x2() of level k−1 (read back from the file),
/// the one definition of the format's pyramid rule.
void coarseBlock(const FineReader& below, const GridInfo& info, std::size_t level, std::size_t r0,
                 std::size_t c0, std::size_t nr, std::size_t nc, std::vector<float>& fine,
                 std::vector<float>& out) {
  const std::size_t fineRows = info.levelRows(level - 1), fineCols = info.levelCols(level - 1);
  const std::size_t fr0 = 2 * r0, fc0 = 2 * c0;
  const std::size_t fnr = std::min(2 * nr, fineRows - fr0);
  const std::size_t fnc = std::min(2 * nc, fineCols - fc0);
  fine.resize(fnr * fnc);
  below(fr0, fc0, fnr, fnc, fine.data());
  const Missing missing{info.nodata};
  out.resize(nr * nc);
  topo::downsample2x2(fine.data(), fnr, fnc, out.data(), nr, nc, missing, missing.stored());
}

/// Level 0 of a tiled grid's block as stored: each tile's samples (missing as the stored
/// nodata value), the stored nodata value where no tile lies.
void mosaicBlock(const Prepared& p, std::size_t r0, std::size_t c0, std::size_t nr, std::size_t nc,
                 float* out, const Context& ctx) {
  const Missing missing{p.info.nodata};
  std::fill(out, out + nr * nc, missing.stored());
  std::vector<float> buffer;
  for (const PreparedTile& t : p.tiles) {
    const std::size_t a0 = std::max(r0, t.row0), a1 = std::min(r0 + nr, t.row0 + t.rows);
    const std::size_t b0 = std::max(c0, t.col0), b1 = std::min(c0 + nc, t.col0 + t.cols);
    if (a0 >= a1 || b0 >= b1) continue;
    const std::size_t tr = a1 - a0, tc = b1 - b0;
    if (t.samples) {
      level0Block(*t.samples, p.info, a0 - t.row0, b0 - t.col0, tr, tc, buffer, ctx);
    } else {
      buffer.resize(tr * tc);
      t.external->readWindow(t.grid, 0, a0 - t.row0, b0 - t.col0, tr, tc, buffer);
      for (float& v : buffer) {
        if (std::isnan(v)) v = missing.stored();
      }
    }
    for (std::size_t r = 0; r < tr; ++r) {
      std::copy_n(buffer.begin() + static_cast<std::ptrdiff_t>(r * tc), tc,
                  out + (a0 - r0 + r) * nc + (b0 - c0));
    }
  }
}

}  // namespace regolith::store::writer
