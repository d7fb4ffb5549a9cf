#pragma once
/// \file
/// The dataset catalogue of one body and its spatial index (White's dataset hierarchy, as a
/// bounding-volume hierarchy over body-fixed boxes that include each dataset's heights).

#include <regolith/compose/Dataset.hpp>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace regolith::compose {

/// A dataset's handle in its catalogue: never reused.
using DatasetId = std::uint64_t;

/// One registered dataset.
struct CatalogueEntry {
  DatasetId id = 0;
  std::shared_ptr<const Dataset> dataset;
};

/// The composition's tier order of entries `ia` and `ib` (indices into `entries`): higher
/// priority first, then finer ground spacing, then the lower index.
[[nodiscard]] bool tierBefore(std::span<const CatalogueEntry> entries, std::uint32_t ia,
                              std::uint32_t ib) noexcept;

/// An immutable state of a catalogue: its datasets and a BVH over their bounds. Queries
/// are O(log N + k) for N datasets of which k answer (a BVH whose boxes overlap little:
/// datasets far apart on the body). Thread-safe (immutable).
class Snapshot {
 public:
  Snapshot(topo::Body body, std::vector<CatalogueEntry> entries, std::uint64_t version);
  ~Snapshot();
  Snapshot(const Snapshot&) = delete;
  Snapshot& operator=(const Snapshot&) = delete;
  Snapshot(Snapshot&&) = delete;
  Snapshot& operator=(Snapshot&&) = delete;

  [[nodiscard]] const topo::Body& body() const noexcept { return body_; }
  [[nodiscard]] std::span<const CatalogueEntry> entries() const noexcept { return entries_; }
  [[nodiscard]] std::size_t size() const noexcept { return entries_.size(); }
  /// Counts changes of the catalogue: a snapshot with a higher version is newer.
  [[nodiscard]] std::uint64_t version() const noexcept { return version_; }
  /// Lowest and highest height of every dataset, metres (0, 0 when empty).
  [[nodiscard]] double lowestHeight() const noexcept { return hLow_; }
  [[nodiscard]] double highestHeight() const noexcept { return hHigh_; }

  /// Appends to `out` the indices (into entries()) of the datasets of role `role` whose
  /// bounds the body's normal line at a planetodetic latitude/longitude crosses between
  /// the lowest and the highest height above the ellipsoid that any dataset reaches
  /// (Dataset::ellipsoidHeightRange()): every dataset that can cover the point, and a few
  /// whose boxes merely reach it (Dataset::evaluate() decides). Returns the number of BVH
  /// nodes visited (the index's cost, for tests and benchmarks).
  std::size_t covering(double latDeg, double lonDeg, std::vector<std::uint32_t>& out,
                       Role role = Role::Height) const;
  /// The indices of the datasets of role `role` whose bounds reach the shell of that band of
  /// heights over the whole 1° × 1° latitude/longitude cell that holds
  /// the point: every dataset covering() can return anywhere in that cell, and a few more
  /// (Dataset::evaluate() decides). A query costs a table look-up instead of the index walk
  /// and its trigonometry, for composed point queries (ComposedSurface). Each cell's list is
  /// built on its first query and kept for the snapshot's life (lock-free; any thread).
  [[nodiscard]] std::span<const std::uint32_t> cellCandidates(double latDeg, double lonDeg,
                                                              Role role = Role::Height) const {
    return cell(latDeg, lonDeg, role).candidates;
  }
  /// One 1° cell of cellCandidates()'s table.
  struct Cell {
    std::vector<std::uint32_t> candidates;  ///< indices into entries(), ascending
    /// The first candidate in tier order (tierBefore()) and its index into entries(); null
    /// when there is none. A composed query's common case, a cell of one candidate, reaches
    /// its dataset here without the list and the entry (fewer dependent loads).
    const Dataset* top = nullptr;
    std::uint32_t topEntry = 0;
  };
  /// cellCandidates() with the cell's first dataset. The reference lives as long as the
  /// snapshot. An empty catalogue or a non-finite point gives an empty cell.
  [[nodiscard]] const Cell& cell(double latDeg, double lonDeg, Role role = Role::Height) const {
    return cell(cellTable(role), latDeg, lonDeg);
  }
  /// One role's table of cells (opaque), made on first use and kept for the snapshot's life.
  struct CellTable;
  [[nodiscard]] const CellTable& cellTable(Role role) const;
  /// cell() in a table taken once: a caller that looks up cells at a high rate (a composed
  /// query) keeps the table and saves a dependent load per look-up.
  [[nodiscard]] const Cell& cell(const CellTable& table, double latDeg, double lonDeg) const;
  /// Appends the indices of the datasets whose bounds are not wholly outside one of the
  /// `planes` (a, b, c, d: a·x + b·y + c·z + d ≥ 0 inside, body-fixed metres): "which
  /// datasets can this view see", for a view frustum's six planes. Returns the number of
  /// BVH nodes visited.
  std::size_t visible(std::span<const glm::dvec4> planes, std::vector<std::uint32_t>& out) const;

 private:
  struct Node {
    glm::dvec3 lo, hi;
    std::uint32_t first = 0, count = 0;  // leaf: entries order_[first, first + count)
    std::uint32_t left = 0, right = 0;   // inner (count == 0): children
  };
  std::uint32_t build(std::uint32_t first, std::uint32_t count);
  [[nodiscard]] std::vector<std::uint32_t> cellList(int latCell, int lonCell, Role role) const;
  /// cell() where the cell (or the role's table) is not built yet.
  [[nodiscard]] const Cell& buildCell(const CellTable& table, int latCell, int lonCell) const;

  /// cellCandidates()'s tables, one per role, each 180 × 360 cells (null until built).
  static constexpr std::size_t kRoles = 3;
  mutable std::array<std::atomic<CellTable*>, kRoles> cells_{};

  topo::Body body_;
  std::vector<CatalogueEntry> entries_;
  std::uint64_t version_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
  double hLow_ = 0.0, hHigh_ = 0.0;
  /// The band of heights above the ellipsoid that covering() and cellCandidates() search:
  /// every dataset's Dataset::ellipsoidHeightRange().
  double bandLow_ = 0.0, bandHigh_ = 0.0;
};

/// The datasets of one body. add() and remove() may be called from any thread while other
/// threads query and render (White's F03 and N03): each change publishes a new Snapshot,
/// and readers keep the one they took for as long as they hold it (copy on write; a change
/// costs O(N log N) to rebuild the index, a query nothing extra).
class Catalogue {
 public:
  /// An empty catalogue of `body`.
  explicit Catalogue(topo::Body body);

  [[nodiscard]] const topo::Body& body() const noexcept { return body_; }
  /// Registers a dataset. Throws InvalidArgument for a null dataset or one on another body
  /// (radii differ by more than 1 mm).
  DatasetId add(std::shared_ptr<const Dataset> dataset);
  /// Registers several datasets with one index rebuild (adding N one by one costs
  /// O(N² log N)). All are checked before any is added. Returns their ids in order.
  std::vector<DatasetId> add(std::span<const std::shared_ptr<const Dataset>> datasets);
  /// Unregisters a dataset; false if the id is not registered. Snapshots taken earlier keep
  /// it alive.
  bool remove(DatasetId id);
  /// The current state.
  [[nodiscard]] std::shared_ptr<const Snapshot> snapshot() const;

 private:
  topo::Body body_;
  std::mutex writers_;
  std::vector<CatalogueEntry> entries_;  // guarded by writers_
  DatasetId nextId_ = 1;                 // guarded by writers_
  std::uint64_t version_ = 0;            // guarded by writers_
  std::atomic<std::shared_ptr<const Snapshot>> current_;
};

}  // namespace regolith::compose
