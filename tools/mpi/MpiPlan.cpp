// regolith-mpi: the split of an import into parts (MpiPlan.hpp).
#include "MpiPlan.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>

namespace regolith::tools::mpi {

std::size_t levelCount(std::size_t rows, std::size_t cols, std::size_t patchRows,
                       std::size_t patchCols, std::size_t levels) {
  if (levels != 0) return levels;
  std::size_t n = 1;
  const auto side = [](std::size_t s, std::size_t k) { return ((s - 1) >> k) + 1; };
  while (side(rows, n - 1) > patchRows || side(cols, n - 1) > patchCols) ++n;
  return n;
}

SplitPlan splitRows(std::size_t rows, std::size_t patchRows, std::size_t levels, std::size_t ranks,
                    const std::vector<std::size_t>* allowedCuts) {
  SplitPlan best;
  best.parts = {PartRows{0, rows}};
  std::size_t bestLargest = rows;
  for (std::size_t top = 0; top < std::max<std::size_t>(levels, 1); ++top) {
    if (top >= 40) break;
    const std::size_t unit = patchRows << top;
    if (unit == 0 || unit > rows) break;
    // The cuts this level allows: multiples of unit, leaving at least unit rows on each side.
    std::vector<std::size_t> cuts;
    if (allowedCuts == nullptr) {
      for (std::size_t c = unit; c + unit <= rows; c += unit) cuts.push_back(c);
    } else {
      for (const std::size_t c : *allowedCuts) {
        if (c % unit == 0 && c >= unit && c + unit <= rows) cuts.push_back(c);
      }
      std::sort(cuts.begin(), cuts.end());
      cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    }
    // For each of the ranks − 1 ideal cuts, the nearest allowed cut after the one before.
    std::vector<PartRows> parts;
    std::size_t start = 0, next = 0;
    for (std::size_t j = 1; j < ranks && next < cuts.size(); ++j) {
      const double ideal =
          static_cast<double>(rows) * static_cast<double>(j) / static_cast<double>(ranks);
      std::size_t pick = next;
      double bestGap = std::numeric_limits<double>::infinity();
      for (std::size_t i = next; i < cuts.size(); ++i) {
        const double gap = std::abs(static_cast<double>(cuts[i]) - ideal);
        if (gap < bestGap) {
          bestGap = gap;
          pick = i;
        }
      }
      parts.push_back(PartRows{start, cuts[pick]});
      start = cuts[pick];
      next = pick + 1;
    }
    parts.push_back(PartRows{start, rows});
    std::size_t largest = 0;
    for (const PartRows& p : parts) largest = std::max(largest, p.row1 - p.row0);
    if (largest <= bestLargest) {  // ties: the higher top, fewer levels left to assemble
      bestLargest = largest;
      best.parts = parts;
      best.partTop = top;
    }
  }
  if (best.parts.size() == 1) best.partTop = 0;
  return best;
}

}  // namespace regolith::tools::mpi
