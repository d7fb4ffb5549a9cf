#pragma once
// regolith-mpi: how the ranks split an import (docs/scale.md, "Beyond one machine: MPI").
// Pure arithmetic, no MPI and no I/O, so that every rank computes the same plan.

#include <cstddef>
#include <vector>

namespace regolith::tools::mpi {

/// Level-0 rows [row0, row1) of the mosaic that one rank imports as its part store.
struct PartRows {
  std::size_t row0 = 0, row1 = 0;
};

/// How an import is split: the parts, and the highest level every part builds itself
/// (levels 0 … partTop); the levels above are computed by the assembling rank.
struct SplitPlan {
  std::vector<PartRows> parts;
  std::size_t partTop = 0;
};

/// The pyramid's level count for a rows × cols grid: `levels`, or (0) until a level fits in one
/// patch, as the store writer counts them.
[[nodiscard]] std::size_t levelCount(std::size_t rows, std::size_t cols, std::size_t patchRows,
                                     std::size_t patchCols, std::size_t levels);

/// Splits `rows` level-0 rows into at most `ranks` parts. A cut must be a multiple of
/// patchRows · 2^partTop (so that levels 0 … partTop of a part are whole chunks of the same
/// levels of the grid), one of `*allowedCuts` if given (tile borders), and leave
/// every part at least patchRows · 2^partTop rows (its chunks keep the grid's chunk shape);
/// allowedCuts null: any row may be cut.
/// Chooses the split whose largest part is smallest, then the highest partTop
/// (partTop ≤ levels − 1). One part: no split was possible.
[[nodiscard]] SplitPlan splitRows(std::size_t rows, std::size_t patchRows, std::size_t levels,
                                  std::size_t ranks, const std::vector<std::size_t>* allowedCuts);

}  // namespace regolith::tools::mpi
