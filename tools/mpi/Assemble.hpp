#pragma once
// regolith-mpi: the assembling rank joins the ranks' part stores into one store, copying their
// encoded chunks as they are (HDF5 direct chunk I/O), and computes the levels above them.

#include <regolith/store/Store.hpp>

#include "MpiPlan.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace regolith::tools::mpi {

/// What the assembly joins.
struct Assembly {
  std::filesystem::path out;      // the target store (written through a temporary, then renamed)
  std::filesystem::path scratch;  // a folder for the coarse levels' store
  std::string grid;
  std::vector<std::filesystem::path> parts;  // one store per SplitPlan part
  SplitPlan plan;
  std::size_t rows = 0, cols = 0, levels = 0, patchRows = 0, patchCols = 0;
  /// Tiled grids: for each part, the global index of each of its tiles, in order.
  std::vector<std::vector<std::size_t>> partTiles;
  std::size_t tileCount = 0;
  /// Every block's statistics, row-major over the whole grid.
  std::vector<store::BlockStatistics> blocks;
  /// The grid's provenance (tiled grids); empty: the first part's.
  std::string provenance;
  /// If set: called once every chunk is copied, and its result is the grid's provenance
  /// (a single raster: another rank takes the source's digests meanwhile). May throw; the
  /// store is then not written.
  std::function<std::string()> lateProvenance;
  /// An untiled grid whose first part was written with room for the whole grid
  /// (store::WriteOptions::reserveRows = rows): that part becomes the store, moved to the
  /// target's temporary and extended in place, and only the other parts' chunks are copied
  /// (docs/scale.md, "Stop 45"). Once moved, the first part is the target's temporary, which
  /// a failing join removes (core::writeFileAtomically); the caller removes the other parts.
  bool growFirst = false;
  /// Threads for the coarse levels (0: all).
  unsigned threads = 0;
};

/// Where the join's time went, in seconds (the summary's `joining:` line).
struct JoinSeconds {
  double coarse = 0.0;  // the levels above the parts'
  double copies = 0.0;  // the parts' chunks copied (and the first part grown)
  double sync = 0.0;    // with lateProvenance: the chunks synced while it is awaited
  double wait = 0.0;    // lateProvenance, after that sync
  double finish = 0.0;  // the provenance written, the last sync (all of it without
                        // lateProvenance: a mosaic), the rename
};

/// Writes the store (core::writeFileAtomically). Throws regolith::Error naming the file.
JoinSeconds assemble(const Assembly& a);

}  // namespace regolith::tools::mpi
