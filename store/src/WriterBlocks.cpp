// writer::level0Block(), coarseBlock() and mosaicBlock(): the samples of one block of a
// level, as stored.
#include <regolith/core/Message.hpp>
#include <regolith/topo/Pyramid.hpp>

#include "Mosaic.hpp"
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
  mosaic::assemble(
      std::span<const PreparedTile>(p.tiles), {r0, c0, nr, nc}, missing.stored(), out,
      [&](const PreparedTile& t, const mosaic::Rect& part, std::vector<float>& buffer) {
        if (t.samples) {
          level0Block(*t.samples, p.info, part.row0, part.col0, part.rows, part.cols, buffer, ctx);
          return;
        }
        t.external->readWindow(t.grid, 0, part.row0, part.col0, part.rows, part.cols, buffer);
        for (float& v : buffer) {
          if (std::isnan(v)) v = missing.stored();
        }
      });
}

}  // namespace regolith::store::writer
