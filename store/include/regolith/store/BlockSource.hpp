#pragma once
/// \file
/// A sample source whose samples are resident in blocks (the pager's patches), and the fast
/// paths that topo's queries take on it.

#include <regolith/store/BlockIndex.hpp>
#include <regolith/topo/Bilinear.hpp>
#include <regolith/topo/TopoGrid.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace regolith::store {

/// A resident block of samples: rows × cols samples starting at (row0, col0), row-major
/// with `stride` floats between rows. `owner` keeps the memory alive (a pager hands out its
/// patch), so a block stays valid after the source evicts it.
struct SampleBlock {
  const float* data = nullptr;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0, stride = 0;
  std::shared_ptr<const void> owner;
  [[nodiscard]] bool contains(std::size_t r, std::size_t c) const noexcept {
    return data != nullptr && r >= row0 && c >= col0 && r - row0 < rows && c - col0 < cols;
  }
};

/// A sample source whose samples come in resident blocks, loaded by block(): the pager's
/// levels (a block is a patch). TopoDem and TopoPlanet queries on it take its fast paths
/// (topo::PagedQueries, which this class implements): the calling thread keeps the block
/// it read last, so a run of queries inside one block costs no call into the source, and,
/// when the source has a block table (BlockIndex.hpp), a query entering another resident
/// block finds it there without a lock (random access). The per-thread state of those
/// paths lives here in the store (src/ThreadQueries.hpp), not in topo.
///
/// Thread-safety: every const member may be called from several threads at once.
class BlockSource : public topo::SampleSource, private topo::PagedQueries {
 public:
  /// `table`: the lock-free table of this source's resident blocks, or null (queries then
  /// enter every new block through block()). It must describe this source's grid.
  explicit BlockSource(std::shared_ptr<const BlockIndex> table = nullptr);

  /// The resident block holding sample (row, col), loading it if needed. Requires
  /// row < rows(), col < cols(). May throw (a load that fails).
  [[nodiscard]] virtual SampleBlock block(std::size_t row, std::size_t col) const = 0;
  /// The block table given at construction, or null.
  [[nodiscard]] const BlockIndex* blockIndex() const noexcept { return table_.get(); }
  /// A process-unique id, never reused, so per-thread query state can tell sources apart
  /// even when one is destroyed and another is allocated at the same address.
  [[nodiscard]] std::uint64_t id() const noexcept { return id_; }

  [[nodiscard]] const topo::PagedQueries* paged() const noexcept final { return this; }

 private:
  [[nodiscard]] double bilinearHeight(const topo::kernel::ResidentBilinear& grid, double u,
                                      double v) const noexcept override;
  [[nodiscard]] bool bilinearSurface(const topo::kernel::ResidentBilinear& grid, double u, double v,
                                     topo::kernel::CellValue& out) const noexcept override;
  void bilinearHeights(const topo::kernel::DemIndexer& m,
                       const topo::kernel::ResidentBilinear& grid,
                       const topo::kernel::HeightBatch& b,
                       topo::kernel::Fallback<topo::HeightSample> generic) const override;
  void bilinearSurfaces(const topo::kernel::DemIndexer& m,
                        const topo::kernel::ResidentBilinear& grid,
                        const topo::kernel::SurfaceBatch& b,
                        topo::kernel::Fallback<topo::SurfaceSample> generic) const override;
  void prefetchCell(std::size_t r, std::size_t c) const noexcept override;
  [[nodiscard]] const topo::kernel::BlockView& threadBlock(std::size_t r,
                                                           std::size_t c) const override;

  std::shared_ptr<const BlockIndex> table_;
  std::uint64_t id_;
};

}  // namespace regolith::store
