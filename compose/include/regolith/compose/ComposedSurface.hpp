#pragma once
/// \file
/// One surface from many datasets: the composition rule that CPU queries (the rover, Python,
/// `regolith query`) and the renderers (clipmap levels) both evaluate (docs/composition.md).

#include <regolith/compose/Catalogue.hpp>

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace regolith::compose {

/// How covering datasets combine (docs/composition.md). Datasets fall into tiers: by
/// priority first, then by resolution class (the datasets whose ground spacing is within
/// Rules::tierRatio of the finest in the class). Tiers composite "over" each other, higher
/// priority and finer classes on top, each with its coverage as alpha.
/// - Weighted: within a tier, H = Σ wᵢhᵢ / Σ wᵢ with wᵢ = coverage × projection quality ×
///   (ground spacing)^−p. With tierRatio = ∞ every dataset of a priority blends this way.
/// - FinestWins: every distinct spacing is its own class (tierRatio 1): the limit p → ∞ of
///   Weighted, and the old cut-out's behaviour with a feather-wide blend at each border
///   instead of a crack.
enum class Policy : std::uint8_t { Weighted, FinestWins };

/// Lower-case name ("weighted", "finest").
[[nodiscard]] const char* policyName(Policy policy) noexcept;

/// The rule's parameters.
struct Rules {
  Policy policy = Policy::Weighted;
  /// p of the resolution term (spacing^−p), ≥ 0. 2: a 1 m DEM outweighs a 463 m planet
  /// grid 2·10^5 to 1 where both have full coverage and quality.
  double resolutionPower = 2.0;
  /// Weighted: datasets blend by weight only with others whose spacing is within this
  /// factor of their tier's finest; a much finer dataset composites over coarser ones with
  /// its coverage as alpha, so its feather blends it in (a weight ratio of (463/1)² would
  /// squeeze a 1 m DEM's feather against the planet to a cliff). ≥ 1; infinity for one
  /// tier per priority.
  double tierRatio = 4.0;
  /// The spacing ratio within which datasets of one priority share a tier: tierRatio, or
  /// equal spacings only (to 1e-9) under FinestWins.
  [[nodiscard]] double spacingRatio() const noexcept {
    return policy == Policy::FinestWins ? 1.0 + 1e-9 : tierRatio;
  }
};

/// A composed height and normal at one point, with the number of datasets that contributed.
struct ComposedSample {
  double height = std::numeric_limits<double>::quiet_NaN();
  glm::dvec3 normal{std::numeric_limits<double>::quiet_NaN()};
  topo::QueryStatus status = topo::QueryStatus::OutsideGrid;
  topo::QueryStatus normalStatus = topo::QueryStatus::OutsideGrid;
  std::uint32_t contributors = 0;  ///< datasets with a non-zero share of the height
  [[nodiscard]] bool valid() const noexcept { return status == topo::QueryStatus::Ok; }
};

/// One dataset's share of a composed height (ComposedSurface::weights()).
struct Share {
  DatasetId id = 0;
  double height = 0.0;    ///< the dataset's own height there
  double coverage = 0.0;  ///< border feather × mask
  double quality = 0.0;   ///< projection quality
  double weight = 0.0;    ///< its share of the composed height: Σ shares = 1
};

/// The composed surface of one catalogue snapshot. Queries take a planetodetic latitude and
/// a longitude in degrees (any longitude; it wraps) and answer heights above the body's
/// reference surface along its normal. Normals are those of the composed surface: the
/// gradient of H from each dataset's own gradient and the gradients of the weights, so they
/// are continuous across a border wherever the weights are (feathered borders).
///
/// Thread-safety: immutable; queries may run on any number of threads at once.
class ComposedSurface {
 public:
  /// Throws InvalidArgument for a null snapshot or a negative or non-finite p.
  explicit ComposedSurface(std::shared_ptr<const Snapshot> snapshot, Rules rules = {});

  [[nodiscard]] const Snapshot& snapshot() const noexcept { return *snapshot_; }
  [[nodiscard]] const topo::Body& body() const noexcept { return snapshot_->body(); }
  [[nodiscard]] const Rules& rules() const noexcept { return rules_; }

  /// Composed height. Throws InvalidArgument for NaN/inf or |lat| > 90.
  [[nodiscard]] topo::HeightSample height(double latDeg, double lonDeg) const;
  /// Composed height and unit normal, in the east-north-up frame of the point (Grid) or
  /// body-fixed.
  [[nodiscard]] ComposedSample surface(double latDeg, double lonDeg,
                                       topo::NormalFrame frame = topo::NormalFrame::Grid) const;
  /// The composed height at a ground resolution of `metres`: each dataset reads the pyramid
  /// level that serves it (Dataset::levelFor()), with level-0 weights. What a renderer's
  /// clipmap level of that spacing shows; metres ≤ 0 is level 0 (height()).
  [[nodiscard]] topo::HeightSample heightAt(double latDeg, double lonDeg, double metres) const;

  /// Batch heights: spans of one length (status and contributors may be empty). Each point
  /// has its own status: a NaN or out-of-range coordinate gives OutsideGrid for that point,
  /// never a failed batch. Throws InvalidArgument only for spans of different lengths.
  void heights(std::span<const double> latsDeg, std::span<const double> lonsDeg,
               std::span<double> out, std::span<topo::QueryStatus> status,
               std::span<std::uint32_t> contributors = {}) const;
  /// Batch heights and normals (normalStatus and contributors may be empty).
  void surfaces(std::span<const double> latsDeg, std::span<const double> lonsDeg,
                std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                std::span<topo::QueryStatus> status,
                topo::NormalFrame frame = topo::NormalFrame::Grid,
                std::span<topo::QueryStatus> normalStatus = {},
                std::span<std::uint32_t> contributors = {}) const;

  /// Each contributing dataset's share of the height at a point (empty where nothing
  /// covers it): the rule written out, for tests, `regolith query --explain` and Python.
  [[nodiscard]] std::vector<Share> weights(double latDeg, double lonDeg) const;

 private:
  /// The general path for a normal or the shares (composeGeneral() at the point's cell).
  ComposedSample compose(double latDeg, double lonDeg, bool wantNormal,
                         std::vector<Share>* shares) const;
  /// A height, its status and its contributor count: 16 bytes, returned in registers.
  struct CountedHeight {
    double height;
    topo::QueryStatus status;
    std::uint32_t contributors;
  };
  /// fastHeight()'s "the general path answers" (a real answer has a contributor).
  static constexpr CountedHeight kNoFastHeight{std::numeric_limits<double>::quiet_NaN(),
                                               topo::QueryStatus::OutsideGrid, 0};
  /// height(), heightAt() and heights() past their checks: fastHeight(), else the general
  /// path.
  [[nodiscard]] CountedHeight heightOf(double latDeg, double lonDeg, double metres) const;
  /// A height without composeGeneral()'s large frame, or contributors 0 where the general
  /// path must answer (a real answer has at least one; in registers, as an optional's 24
  /// bytes would not be): the cell's sole candidate (Dataset::soleHeightOrNan()), else
  /// topTierHeight().
  [[nodiscard]] CountedHeight fastHeight(const Snapshot::Cell& cell, double latDeg, double lonDeg,
                                         double metres) const;
  /// One pass over several candidates for their first tier. Its one member alone, covering
  /// the point fully (nested data; featheredTopHeight() if it has a feather or a mask), or
  /// two to four planet grids without feather or mask that all answer, with nothing finer
  /// below (blendHeight()): composeGeneral()'s height and contributors there, to the bit.
  /// Else contributors 0.
  [[nodiscard]] CountedHeight topTierHeight(const Snapshot::Cell& cell, double latDeg,
                                            double lonDeg, double metres) const;
  /// The cell's top, alone in its tier, with a feather or a mask: its height where its
  /// coverage is 1, and in its band its composite over the one other candidate if that one
  /// has neither and answers; else contributors 0.
  [[nodiscard]] CountedHeight featheredTopHeight(const Snapshot::Cell& cell, double latDeg,
                                                 double lonDeg, double metres) const;
  /// The weighted mean of a blend's members `tier` (entries, in tier order, the first the
  /// finest), as composeGeneral() forms it; contributors 0 where one does not answer.
  [[nodiscard]] CountedHeight blendHeight(std::span<const std::uint32_t> tier, double latDeg,
                                          double lonDeg, double metres) const;
  /// compose() past its shortcuts, given the point's cell candidates.
  ComposedSample composeGeneral(std::span<const std::uint32_t> cell, double latDeg, double lonDeg,
                                double metres, bool wantNormal, std::vector<Share>* shares) const;

  std::shared_ptr<const Snapshot> snapshot_;
  /// The snapshot's table of height cells, taken once (Snapshot::cell(table, ...)).
  const Snapshot::CellTable* heightCells_ = nullptr;
  Rules rules_;
};

}  // namespace regolith::compose
