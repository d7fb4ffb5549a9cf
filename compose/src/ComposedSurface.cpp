#include <regolith/compose/ComposedSurface.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <string>
#include <utility>

namespace regolith::compose {

namespace {

using topo::QueryStatus;

struct Member {
  // A user-provided constructor: a value-initialised Member (emplace_back()) is zero-filled
  // first, by a `rep stos` that cost a tenth of a two-dataset composition.
  explicit Member(std::uint32_t e) noexcept : entry(e) {}
  std::uint32_t entry = 0;
  Contribution c;
  double resolution = 1.0;  // (finest spacing / spacing)^p
  double spacing = 0.0;
  int priority = 0;
  int tier = 0;
  bool qualityPending = false;        // c.quality not evaluated yet (see evaluateAll)
  glm::dvec2 gradC{0.0}, gradQ{0.0};  // ∂/∂east, ∂/∂north of coverage and quality
};

/// The most candidates of a point's 1° cell that a composition reads from the cell; beyond
/// it, the exact catalogue query (fewer evaluations). So also the most a blend may hold.
constexpr std::size_t kCellCandidatesAtMost = 4;

/// Per-thread scratch, so a query allocates nothing once warm.
struct Scratch {
  std::vector<std::uint32_t> candidates;
  std::vector<std::uint32_t> ranked;  // the candidates in tier order (evaluateAll)
  std::vector<Member> members;        // in evaluation (tier) order, each built in place
  std::vector<std::pair<std::size_t, std::size_t>> tiers;  // [begin, end) of members, bottom-up
  std::vector<double> alphas;                              // each tier's α
};
/// One Scratch per nesting depth: a dataset's samples may themselves be a composed surface
/// (a ComposedSamples pyramid in another catalogue), whose query runs inside this one's.
struct ScratchStack {
  std::deque<Scratch> scratches;
  std::size_t depth = 0;
};
thread_local ScratchStack tlScratch;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

/// Takes this thread's next Scratch for the length of one composition.
class ScratchLease {
 public:
  ScratchLease() {
    ScratchStack& st = tlScratch;
    if (st.depth == st.scratches.size()) st.scratches.emplace_back();
    scratch_ = &st.scratches[st.depth++];
  }
  ScratchLease(const ScratchLease&) = delete;
  ScratchLease& operator=(const ScratchLease&) = delete;
  ~ScratchLease() { --tlScratch.depth; }
  [[nodiscard]] Scratch& get() const noexcept { return *scratch_; }

 private:
  Scratch* scratch_ = nullptr;
};

bool pointOk(double latDeg, double lonDeg) noexcept {
  return std::abs(latDeg) <= 90.0 && std::isfinite(lonDeg);  // false for a NaN latitude
}

[[noreturn]] void throwBadPoint(double latDeg, double lonDeg, const char* op) {
  topo::requireFinite(latDeg, op, "latitude");
  topo::requireFinite(lonDeg, op, "longitude");
  // Both finite, so pointOk() failed on the latitude's range.
  throw InvalidArgument(core::format({.operation = op,
                                      .field = "latitude",
                                      .value = core::number(latDeg) + " deg",
                                      .expected = "within -90 .. 90"}));
}

/// One test on a query's path, the messages out of line.
inline void checkPoint(double latDeg, double lonDeg, const char* op) {
  if (!pointOk(latDeg, lonDeg)) [[unlikely]]
    throwBadPoint(latDeg, lonDeg, op);
}

}  // namespace

const char* policyName(Policy policy) noexcept {
  switch (policy) {
    case Policy::Weighted: return "weighted";
    case Policy::FinestWins: return "finest";
  }
  return "unknown";
}

ComposedSurface::ComposedSurface(std::shared_ptr<const Snapshot> snapshot, Rules rules)
    : snapshot_(std::move(snapshot)), rules_(rules) {
  if (!snapshot_) {
    throw InvalidArgument(core::format({.operation = "compose::ComposedSurface()",
                                        .field = "snapshot",
                                        .value = "null",
                                        .expected = "a catalogue snapshot"}));
  }
  heightCells_ = &snapshot_->cellTable(Role::Height);
  if (!(rules_.tierRatio >= 1.0)) {  // +inf allowed: one tier per priority
    throw InvalidArgument(core::format({.operation = "compose::ComposedSurface()",
                                        .field = "rules.tierRatio",
                                        .value = core::number(rules_.tierRatio),
                                        .expected = ">= 1 (infinity: one tier per priority)"}));
  }
  if (!(std::isfinite(rules_.resolutionPower) && rules_.resolutionPower >= 0.0)) {
    throw InvalidArgument(core::format({.operation = "compose::ComposedSurface()",
                                        .field = "rules.resolutionPower",
                                        .value = core::number(rules_.resolutionPower),
                                        .expected = "finite, >= 0"}));
  }
}

// A height where the point's cell has one candidate that answers: it is the surface, a tier
// of one whose height composeGeneral() keeps exactly (the common case away from dataset
// borders). Several candidates: topTierHeight().
ComposedSurface::CountedHeight ComposedSurface::fastHeight(const Snapshot::Cell& cell,
                                                           double latDeg, double lonDeg,
                                                           double metres) const {
  if (cell.candidates.size() != 1) return topTierHeight(cell, latDeg, lonDeg, metres);
  const Dataset* d = cell.top;
  if (const double h = d->soleHeightOrNan(latDeg, lonDeg, metres > 0.0 ? d->levelFor(metres) : 0);
      !std::isnan(h)) {
    return CountedHeight{h, QueryStatus::Ok, 1};
  }
  return kNoFastHeight;
}

// One pass over the cell's candidates finds the first tier (the candidates of the top's
// priority within the spacing ratio of its spacing, the tier's finest) in tier order.
//
// Nested data: the top alone in its tier and covering the point fully. composeGeneral()
// would read it and find its tier complete and full: its α is 1, so the composite keeps its
// height exactly, whatever it reads below (nothing, unless a lower-priority dataset is
// finer), and no member below has a share (one contributor). Without the general path's
// scratch, sort, members and tiers, a HiRISE-class DEM inside a CTX-class one over a global
// grid costs about its own query. Only a top whose coverage is 1 wherever it answers: in a
// feather's band the general path would read it again (inside a 10° grid with a 2° feather,
// 27 % slower).
//
// Blended data: two to four planet grids, each without feather or mask, and no finer
// candidate below: blendHeight(). A DEM's quality comes from its located point in the general
// path, and a finer dataset below changes the resolution weights (relative to the finest
// member read), so those stay the general path's; so do cells of more than four candidates,
// where it asks the exact catalogue query.
//
// The cell's candidates hold every dataset the exact catalogue query returns (a superset),
// so the same holds where the general path would ask that query.
ComposedSurface::CountedHeight ComposedSurface::topTierHeight(const Snapshot::Cell& cell,
                                                              double latDeg, double lonDeg,
                                                              double metres) const {
  if (cell.top == nullptr) return kNoFastHeight;
  const auto entries = snapshot_->entries();
  const Dataset& top = *cell.top;
  const double ratio = rules_.spacingRatio();
  const int priority = top.options().priority;
  const double finest = top.groundSpacing();  // the first in tier order: the tier's finest
  std::array<std::uint32_t, kCellCandidatesAtMost> tier{};
  std::size_t k = 0;
  bool blendable = cell.candidates.size() <= kCellCandidatesAtMost;
  for (const std::uint32_t e : cell.candidates) {
    const Dataset& d = *entries[e].dataset;
    if (d.options().priority == priority && d.groundSpacing() <= finest * ratio) {
      blendable = blendable && d.isPlanet() && d.unfeathered();
      if (k < kCellCandidatesAtMost) {  // insertion in tier order (a handful of entries)
        std::size_t at = k;
        for (; at > 0 && tierBefore(entries, e, tier[at - 1]); --at) tier[at] = tier[at - 1];
        tier[at] = e;
      }
      ++k;
    } else {
      blendable = blendable && !(d.groundSpacing() < finest);
    }
  }
  if (k == 1) {
    if (top.unfeathered()) {
      if (const double h =
              top.soleHeightOrNan(latDeg, lonDeg, metres > 0.0 ? top.levelFor(metres) : 0, true);
          !std::isnan(h)) {
        return CountedHeight{h, QueryStatus::Ok, 1};
      }
      return kNoFastHeight;
    }
    return featheredTopHeight(cell, latDeg, lonDeg, metres);
  }
  if (!blendable) return kNoFastHeight;
  return blendHeight(std::span(tier).first(k), latDeg, lonDeg, metres);
}

// A top alone in its tier with a feather or a mask (a HiRISE-class DEM feathered into the
// planet). Where it covers the point fully, it is the surface, as for nested data above.
// In its band (0 < c < 1) over one plain dataset below (no feather or mask, so coverage 1
// where it answers), composeGeneral() reads both, each a tier of one that keeps its height
// exactly, and composites the top over the bottom with α = 1 − (1 − c) (its product of
// 1 − coverage over the tier): α·h_top + (1 − α)·h_below, two contributors. That is formed
// here in its order, so the bits are its own. Anything else (more candidates, a feathered
// dataset below, a member that does not answer) takes the general path.
ComposedSurface::CountedHeight ComposedSurface::featheredTopHeight(const Snapshot::Cell& cell,
                                                                   double latDeg, double lonDeg,
                                                                   double metres) const {
  const Dataset& top = *cell.top;
  const Dataset::CoveredHeight c =
      top.coveredHeight(latDeg, lonDeg, metres > 0.0 ? top.levelFor(metres) : 0);
  if (!(c.coverage > 0.0)) return kNoFastHeight;
  if (c.coverage == 1.0) return CountedHeight{c.height, QueryStatus::Ok, 1};
  if (cell.candidates.size() != 2) return kNoFastHeight;
  const auto entries = snapshot_->entries();
  const std::uint32_t other =
      cell.candidates[0] == cell.topEntry ? cell.candidates[1] : cell.candidates[0];
  const Dataset& below = *entries[other].dataset;
  if (!below.unfeathered()) return kNoFastHeight;
  const double hb =
      below.soleHeightOrNan(latDeg, lonDeg, metres > 0.0 ? below.levelFor(metres) : 0, true);
  if (std::isnan(hb)) return kNoFastHeight;
  const double alpha = 1.0 - (1.0 - c.coverage);
  if (!(alpha > 0.0 && alpha < 1.0)) return kNoFastHeight;
  return CountedHeight{alpha * c.height + (1.0 - alpha) * hb, QueryStatus::Ok, 2};
}

// A blend of planet grids without feather or mask that all answer (coverage 1):
// composeGeneral() would read the tier, find it complete and full, and read nothing below.
// The height is the tier's weighted mean Σ w·h / Σ w, w = coverage (1) × quality ×
// resolution, the quality left out where the members share it, as composeGeneral() leaves
// it out, and the sums formed in its (tier) order, so the bits are its own. Without its
// scratch, sort, members and tiers, each blended grid costs about its own query
// (docs/composition.md, "Stop 42" and "Stop 43").
ComposedSurface::CountedHeight ComposedSurface::blendHeight(std::span<const std::uint32_t> tier,
                                                            double latDeg, double lonDeg,
                                                            double metres) const {
  const auto entries = snapshot_->entries();
  const std::size_t k = tier.size();
  const double finest = entries[tier[0]].dataset->groundSpacing();
  std::array<double, kCellCandidatesAtMost> h{};
  for (std::size_t i = 0; i < k; ++i) {
    const Dataset& d = *entries[tier[i]].dataset;
    h[i] = d.soleHeightOrNan(latDeg, lonDeg, metres > 0.0 ? d.levelFor(metres) : 0, true);
    if (std::isnan(h[i])) return kNoFastHeight;
  }
  // Members of one planet quality (one body and pixel shape: overlapping products of one
  // kind) have it as a common factor that composeGeneral() leaves out of the height's
  // weights: it is not evaluated. Otherwise each distinct one is, and shared as there.
  const Dataset& lead = *entries[tier[0]].dataset;
  bool oneQuality = true, oneSpacing = true;
  for (std::size_t i = 1; i < k; ++i) {
    const Dataset& d = *entries[tier[i]].dataset;
    oneQuality = oneQuality && d.samePlanetQuality(lead);
    oneSpacing = oneSpacing && d.groundSpacing() == lead.groundSpacing();
  }
  if (oneQuality && oneSpacing) {  // twins: equal weights, the plain mean
    double sumH = 0.0;
    for (std::size_t i = 0; i < k; ++i) sumH += h[i];
    return CountedHeight{sumH / static_cast<double>(k), QueryStatus::Ok,
                         static_cast<std::uint32_t>(k)};
  }
  std::array<double, kCellCandidatesAtMost> q{};
  q.fill(1.0);
  if (!oneQuality) {
    const Dataset* last = nullptr;
    for (std::size_t i = 0; i < k; ++i) {
      const Dataset& d = *entries[tier[i]].dataset;
      if (last != nullptr && d.samePlanetQuality(*last)) {
        q[i] = q[i - 1];
      } else {
        q[i] = d.qualityInside(latDeg, lonDeg);  // it answered: quality()'s value
        last = &d;
      }
    }
    oneQuality = true;  // equal values cancel as a shared function does
    for (std::size_t i = 1; i < k; ++i) oneQuality = oneQuality && q[i] == q[0];
    if (oneQuality) q.fill(1.0);
  }
  double sumW = 0.0, sumWH = 0.0, sumH = 0.0, w0 = 0.0;
  bool equal = true;
  std::uint32_t contributors = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const Dataset& d = *entries[tier[i]].dataset;
    const double relative = finest / d.groundSpacing();
    const double resolution = rules_.resolutionPower == 2.0
                                  ? relative * relative
                                  : std::pow(relative, rules_.resolutionPower);
    const double w = 1.0 * q[i] * resolution;  // coverage × (quality) × resolution
    if (i == 0) w0 = w;
    equal = equal && w == w0;
    sumW += w;
    sumWH += w * h[i];
    sumH += h[i];
    contributors += w > 0.0 ? 1U : 0U;
  }
  const double height = equal && w0 > 0.0 ? sumH / static_cast<double>(k) : sumWH / sumW;
  return CountedHeight{height, QueryStatus::Ok, contributors};
}

ComposedSurface::CountedHeight ComposedSurface::heightOf(double latDeg, double lonDeg,
                                                         double metres) const {
  const Snapshot::Cell& cell = snapshot_->cell(*heightCells_, latDeg, lonDeg);
  if (const CountedHeight h = fastHeight(cell, latDeg, lonDeg, metres); h.contributors != 0) {
    return h;
  }
  const ComposedSample c = composeGeneral(cell.candidates, latDeg, lonDeg, metres, false, nullptr);
  return {c.height, c.status, c.contributors};
}

ComposedSample ComposedSurface::compose(double latDeg, double lonDeg, bool wantNormal,
                                        std::vector<Share>* shares) const {
  const Snapshot::Cell& cell = snapshot_->cell(*heightCells_, latDeg, lonDeg);
  return composeGeneral(cell.candidates, latDeg, lonDeg, 0.0, wantNormal, shares);
}

ComposedSample ComposedSurface::composeGeneral(std::span<const std::uint32_t> cell, double latDeg,
                                               double lonDeg, double metres, bool wantNormal,
                                               std::vector<Share>* shares) const {
  const auto entries = snapshot_->entries();
  const ScratchLease lease;
  Scratch& s = lease.get();
  s.members.clear();
  ComposedSample out;
  bool sawNodata = false, sawUnmappable = false, sawOutside = false;
  double finest = std::numeric_limits<double>::infinity();
  // Several candidates will most likely give several members, whose weights may need each
  // one's quality: evaluate() then finds it from the point it located (quality() locates
  // again, through the placement's projection for a DEM). A planet grid's quality needs no
  // location (only the latitude) and costs a cosine and two logarithms, so for a height it
  // waits until the tiers show whether the member shares a tier (below).
  const bool eagerPlanetQuality = wantNormal || shares != nullptr;
  // Candidates are evaluated in tier order (priority, then spacing, then entry), so the
  // members come out in it and need no sorting. For a height, a complete tier with a member of full
  // coverage has α = 1 and hides every tier below exactly (acc = its height, see below), so
  // the candidates after it are not read, provided none is finer than the finest member so
  // far (the resolution weights are relative to the finest member).
  const double ratio = rules_.spacingRatio();
  const bool heightOnly = !wantNormal && shares == nullptr;
  const auto evaluateAll = [&](std::span<const std::uint32_t> candidates) {
    s.ranked.assign(candidates.begin(), candidates.end());
    std::sort(s.ranked.begin(), s.ranked.end(), [&entries](std::uint32_t ia, std::uint32_t ib) {
      return tierBefore(entries, ia, ib);
    });
    // The first candidate's memory miss overlaps those of the others, fetched meanwhile:
    // for a height, those of the first one's tier only (if the first covers the point fully,
    // the ones below are not read, and a prefetch of theirs costs a locate and evicts).
    const Dataset* first = s.ranked.empty() ? nullptr : entries[s.ranked.front()].dataset.get();
    for (std::size_t i = 1; i < s.ranked.size(); ++i) {
      const Dataset& d = *entries[s.ranked[i]].dataset;
      if (heightOnly && (d.options().priority != first->options().priority ||
                         d.groundSpacing() > first->groundSpacing() * ratio))
        break;
      d.prefetch(latDeg, lonDeg, metres > 0.0 ? d.levelFor(metres) : 0);
    }
    // The current tier: its first member's priority and spacing, and whether a member of it
    // covers the point fully.
    bool inTier = false, tierFull = false;
    int tierPriority = 0;
    double tierFinest = 0.0;
    for (std::size_t i = 0; i < s.ranked.size(); ++i) {
      const std::uint32_t e = s.ranked[i];
      const Dataset& d = *entries[e].dataset;
      if (inTier &&
          (d.options().priority != tierPriority || d.groundSpacing() > tierFinest * ratio)) {
        // The tier is complete (the candidates are in tier order).
        if (heightOnly && tierFull) {
          bool finer = false;
          for (std::size_t j = i; j < s.ranked.size(); ++j)
            finer |= entries[s.ranked[j]].dataset->groundSpacing() < finest;
          if (!finer) return;
        }
        inTier = tierFull = false;
      }
      const bool quality = candidates.size() > 1 && (eagerPlanetQuality || !d.isPlanet());
      const std::size_t level = metres > 0.0 ? d.levelFor(metres) : 0;
      // Written in place, field by field: a Member built on the stack and copied in was read
      // back in wider pieces than it was written, a store-forwarding stall per piece (a
      // third of a two-dataset composition's time).
      Member& m = s.members.emplace_back(e);
      const Contribution& c = m.c;
      d.evaluateInto(latDeg, lonDeg, level, wantNormal, quality, m.c);
      if (c.status != QueryStatus::Ok || !(c.coverage > 0.0)) {
        sawNodata |= c.status == QueryStatus::Nodata;
        sawUnmappable |= c.status == QueryStatus::Unmappable;
        sawOutside |= c.status == QueryStatus::OutsideGrid;
        s.members.pop_back();
        continue;
      }
      m.qualityPending = !quality;
      m.spacing = d.groundSpacing();
      m.priority = d.options().priority;
      finest = std::min(finest, m.spacing);
      if (!inTier) {
        inTier = true;
        tierPriority = m.priority;
        tierFinest = m.spacing;
      }
      tierFull |= c.coverage == 1.0;
    }
  };
  const auto exactCandidates = [&]() -> std::span<const std::uint32_t> {
    s.candidates.clear();
    snapshot_->covering(latDeg, lonDeg, s.candidates);
    return s.candidates;
  };
  // The candidates of the point's 1° cell (a table look-up) while they are few
  // (kCellCandidatesAtMost): a dataset among them that does not reach the point answers
  // OutsideGrid and is skipped, so the composition is the same as from the exact catalogue
  // query, which takes a walk of the index and a sine and cosine per angle. Many
  // candidates: the exact query, fewer evaluations.
  const bool fromCell = cell.size() <= kCellCandidatesAtMost;
  evaluateAll(fromCell ? cell : exactCandidates());
  if (s.members.empty() && fromCell && !cell.empty()) {
    // Nothing covers the point: its status (nodata, unmappable or outside) is that of the
    // exact candidates, which the cell's extra ones must not change.
    sawNodata = sawUnmappable = sawOutside = false;
    evaluateAll(exactCandidates());
  }
  if (s.members.empty()) {
    out.status = sawNodata                        ? QueryStatus::Nodata
                 : (sawUnmappable && !sawOutside) ? QueryStatus::Unmappable
                                                  : QueryStatus::OutsideGrid;
    out.normalStatus = out.status;
    return out;
  }
  // Weights matter only between several contributors (or to report shares): one alone is
  // the surface, and its quality costs as much as its height.
  const bool weighted = s.members.size() > 1 || shares != nullptr;
  if (weighted) {
    for (Member& m : s.members) {
      const double relative = finest / m.spacing;
      m.resolution = rules_.resolutionPower == 2.0 ? relative * relative
                                                   : std::pow(relative, rules_.resolutionPower);
    }
  } else {
    s.members.front().c.quality = 1.0;  // any positive weight: it is the only one
    s.members.front().qualityPending = false;
  }
  // Tiers: higher priority first, then finer resolution classes first. A class holds the
  // datasets whose spacing is within rules_.tierRatio of its finest (FinestWins: equal
  // spacings only), so similar data blend by weight and much finer data composite over
  // coarser with their coverage as alpha (docs/composition.md "Tiers").
  // The members are in tier order already: evaluateAll() read the candidates in it and
  // appended each member as it came (priority, then spacing, then entry: one order, in one
  // place).
  const auto member = [&s](std::size_t i) -> Member& { return s.members[i]; };
  if (s.members.size() > 1) {
    int tier = 0;
    double tierFinest = member(0).spacing;
    for (std::size_t i = 1; i < s.members.size(); ++i) {
      Member& m = member(i);
      if (m.priority != member(i - 1).priority || m.spacing > tierFinest * ratio) {
        ++tier;
        tierFinest = m.spacing;
      }
      m.tier = tier;
    }
  }
  auto sameTier = [](const Member& a, const Member& b) { return a.tier == b.tier; };
  if (weighted) {
    // The qualities not evaluated yet. A member alone in its tier is the tier's height
    // exactly, whatever its weight (its w·h/w is never formed), so for a height any positive
    // quality gives the same bits; its normal (w·slope/w) and the shares use the quality.
    // Planet grids of one body and pixel shape have one quality at a latitude (overlapping
    // products of one kind): computed once.
    const Dataset* last = nullptr;
    double lastQuality = 0.0;
    for (std::size_t i = 0; i < s.members.size(); ++i) {
      Member& m = member(i);
      if (!m.qualityPending) continue;
      const bool alone = (i == 0 || !sameTier(member(i - 1), m)) &&
                         (i + 1 == s.members.size() || !sameTier(member(i + 1), m));
      const Dataset& d = *entries[m.entry].dataset;
      if (alone && !wantNormal && shares == nullptr) {
        m.c.quality = 1.0;
      } else if (last != nullptr && d.samePlanetQuality(*last)) {
        m.c.quality = lastQuality;
      } else {
        m.c.quality = d.quality(latDeg, lonDeg);
        last = &d;
        lastQuality = m.c.quality;
      }
      m.qualityPending = false;
    }
  }

  const bool several = s.members.size() > 1;
  if (wantNormal && several) {
    // Gradients of each member's coverage and quality, by central differences along the
    // point's east and north directions (body-fixed, so the poles need no special case),
    // over a thousandth of the smaller of its ground spacing and its feather width: both
    // terms change on those scales. The step is far above the rounding of the positions
    // (1e-9 m), and keeps the error small where a term has a kink (the feather's start, a
    // mask's or the quality lattice's cell edge), where it grows with the step.
    const glm::dmat3 enu = body().enuFrame(latDeg, lonDeg);
    const glm::dvec3 p = body().toBodyFixed({latDeg, lonDeg, 0.0});
    for (Member& m : s.members) {
      const Dataset& d = *entries[m.entry].dataset;
      const double feather = d.options().featherMetres;
      const double delta =
          1e-3 * (feather > 0.0 ? std::min(d.groundSpacing(), feather) : d.groundSpacing());
      for (int axis = 0; axis < 2; ++axis) {
        const topo::Geodetic gp = body().toGeodetic(p + delta * enu[axis]);
        const topo::Geodetic gm = body().toGeodetic(p - delta * enu[axis]);
        const auto tp = d.coverageQuality(gp.latDeg, gp.lonDeg);
        const auto tm = d.coverageQuality(gm.latDeg, gm.lonDeg);
        m.gradC[axis] = (tp[0] - tm[0]) / (2.0 * delta);
        m.gradQ[axis] = (tp[1] - tm[1]) / (2.0 * delta);
      }
    }
  }

  // Composite tiers bottom-up: acc = α_t·H_t + (1 − α_t)·acc, the lowest tier as it is.
  double acc = 0.0;
  glm::dvec2 accGrad(0.0);
  bool normalOk = true;
  QueryStatus badNormal = QueryStatus::Ok;
  std::size_t end = s.members.size();
  bool bottom = true;
  auto& tiers = s.tiers;
  auto& alphas = s.alphas;
  tiers.clear();
  alphas.clear();
  while (end > 0) {
    std::size_t begin = end - 1;
    while (begin > 0 && sameTier(member(begin - 1), member(end - 1))) --begin;
    const Member& first = member(begin);
    // A quality the tier's members share (planet grids of one body and pixel shape) is a
    // common factor of the weights and cancels from the mean: the height's weights leave it
    // out, so blendHeight() forms them without evaluating it. Equal weights then give the
    // plain mean (twin grids).
    bool oneQuality = true;
    for (std::size_t i = begin + 1; i < end; ++i)
      oneQuality = oneQuality && member(i).c.quality == first.c.quality;
    const auto heightWeight = [oneQuality](const Member& m) {
      return m.c.coverage * (oneQuality ? 1.0 : m.c.quality) * m.resolution;
    };
    double sumW = 0.0, sumWH = 0.0, sumH = 0.0, keep = 1.0;
    const double w0 = heightWeight(first);
    bool equal = w0 > 0.0;
    for (std::size_t i = begin; i < end; ++i) {
      const Member& m = member(i);
      const double w = heightWeight(m);
      sumW += w;
      sumWH += w * m.c.height;
      sumH += m.c.height;
      equal = equal && w == w0;
      keep *= 1.0 - m.c.coverage;
    }
    // A tier of one keeps its member's height exactly (w·h/w may round).
    const double ht = end - begin == 1 ? first.c.height
                      : equal          ? sumH / static_cast<double>(end - begin)
                                       : sumWH / sumW;
    const double alpha = bottom ? 1.0 : 1.0 - keep;
    glm::dvec2 gradHt(0.0), gradAlpha(0.0);
    if (wantNormal) {
      for (std::size_t i = begin; i < end; ++i) {
        const Member& m = member(i);
        if (m.c.normalStatus != QueryStatus::Ok) {
          if (normalOk) badNormal = m.c.normalStatus;
          normalOk = false;
          continue;
        }
        const double w = m.c.coverage * m.c.quality * m.resolution;
        gradHt += w * m.c.slope;
        if (several) {
          const glm::dvec2 gradW = m.resolution * (m.c.quality * m.gradC + m.c.coverage * m.gradQ);
          gradHt += (m.c.height - ht) * gradW;
          if (!bottom) {
            double others = 1.0;
            for (std::size_t j = begin; j < end; ++j) {
              if (j != i) others *= 1.0 - member(j).c.coverage;
            }
            gradAlpha += others * m.gradC;
          }
        }
      }
      gradHt /= oneQuality ? first.c.quality * sumW : sumW;  // Σ w with the quality
    }
    if (bottom) {
      acc = ht;
      accGrad = gradHt;
    } else {
      accGrad = alpha * gradHt + (1.0 - alpha) * accGrad + (ht - acc) * gradAlpha;
      // A tier of full coverage hides the ones below exactly (1·ht + 0·acc would turn a
      // height of -0 into +0 below a positive one), as when evaluateAll() leaves them unread.
      acc = alpha == 1.0 ? ht : alpha * ht + (1.0 - alpha) * acc;
    }
    tiers.emplace_back(begin, end);
    alphas.push_back(alpha);
    bottom = false;
    end = begin;
  }
  out.height = acc;
  out.status = QueryStatus::Ok;
  // Contributors: members with a non-zero share (a tier under one of full coverage has none).
  {
    std::uint32_t n = 0;
    double above = 1.0;
    for (std::size_t t = tiers.size(); t-- > 0;) {
      if (above > 0.0) {
        for (std::size_t i = tiers[t].first; i < tiers[t].second; ++i) {
          const Member& m = member(i);
          n += m.c.coverage * m.c.quality * m.resolution > 0.0 && alphas[t] > 0.0 ? 1U : 0U;
        }
      }
      above *= 1.0 - alphas[t];
    }
    out.contributors = n;
  }
  if (wantNormal) {
    if (normalOk) {
      // In the point's east-north-up frame; surface() turns it body-fixed if asked.
      out.normal = glm::normalize(glm::dvec3(-accGrad.x, -accGrad.y, 1.0));
      out.normalStatus = std::isfinite(out.normal.x) ? QueryStatus::Ok : QueryStatus::Nodata;
    } else {
      out.normalStatus = badNormal;
    }
  }
  if (shares != nullptr) {
    // tiers[] runs bottom-up; a tier's members share α_t times what the tiers above leave.
    double above = 1.0;
    for (std::size_t t = tiers.size(); t-- > 0;) {
      const auto [begin, tierEnd] = tiers[t];
      double sumW = 0.0;
      for (std::size_t i = begin; i < tierEnd; ++i) {
        const Member& m = member(i);
        sumW += m.c.coverage * m.c.quality * m.resolution;
      }
      for (std::size_t i = begin; i < tierEnd; ++i) {
        const Member& m = member(i);
        const double w = m.c.coverage * m.c.quality * m.resolution;
        shares->push_back({entries[m.entry].id, m.c.height, m.c.coverage, m.c.quality,
                           above * alphas[t] * w / sumW});
      }
      above *= 1.0 - alphas[t];
    }
  }
  return out;
}

topo::HeightSample ComposedSurface::height(double latDeg, double lonDeg) const {
  checkPoint(latDeg, lonDeg, "compose::ComposedSurface::height()");
  const CountedHeight h = heightOf(latDeg, lonDeg, 0.0);
  return {h.height, h.status};
}

topo::HeightSample ComposedSurface::heightAt(double latDeg, double lonDeg, double metres) const {
  checkPoint(latDeg, lonDeg, "compose::ComposedSurface::heightAt()");
  const CountedHeight h = heightOf(latDeg, lonDeg, metres);
  return {h.height, h.status};
}

ComposedSample ComposedSurface::surface(double latDeg, double lonDeg,
                                        topo::NormalFrame frame) const {
  checkPoint(latDeg, lonDeg, "compose::ComposedSurface::surface()");
  ComposedSample c = compose(latDeg, lonDeg, true, nullptr);
  if (frame == topo::NormalFrame::BodyFixed && c.normalStatus == QueryStatus::Ok) {
    c.normal = body().enuFrame(latDeg, lonDeg) * c.normal;
  }
  return c;
}

std::vector<Share> ComposedSurface::weights(double latDeg, double lonDeg) const {
  checkPoint(latDeg, lonDeg, "compose::ComposedSurface::weights()");
  std::vector<Share> shares;
  (void)compose(latDeg, lonDeg, false, &shares);
  return shares;
}

void ComposedSurface::heights(std::span<const double> latsDeg, std::span<const double> lonsDeg,
                              std::span<double> out, std::span<topo::QueryStatus> status,
                              std::span<std::uint32_t> contributors) const {
  const std::size_t n = latsDeg.size();
  if (lonsDeg.size() != n || out.size() != n || (!status.empty() && status.size() != n) ||
      (!contributors.empty() && contributors.size() != n)) {
    throw InvalidArgument(
        core::format({.operation = "compose::ComposedSurface::heights()",
                      .field = "array lengths",
                      .value = std::to_string(n) + " latitudes, " + std::to_string(lonsDeg.size()) +
                               " longitudes, " + std::to_string(out.size()) + " outputs",
                      .expected = "equal (status empty or equal too)"}));
  }
  for (std::size_t i = 0; i < n; ++i) {
    CountedHeight h{std::numeric_limits<double>::quiet_NaN(), QueryStatus::OutsideGrid, 0};
    if (pointOk(latsDeg[i], lonsDeg[i])) h = heightOf(latsDeg[i], lonsDeg[i], 0.0);
    out[i] = h.height;
    if (!status.empty()) status[i] = h.status;
    if (!contributors.empty()) contributors[i] = h.contributors;
  }
}

void ComposedSurface::surfaces(std::span<const double> latsDeg, std::span<const double> lonsDeg,
                               std::span<double> outHeights, std::span<glm::dvec3> outNormals,
                               std::span<topo::QueryStatus> status, topo::NormalFrame frame,
                               std::span<topo::QueryStatus> normalStatus,
                               std::span<std::uint32_t> contributors) const {
  const std::size_t n = latsDeg.size();
  if (lonsDeg.size() != n || outHeights.size() != n || outNormals.size() != n ||
      (!status.empty() && status.size() != n) ||
      (!normalStatus.empty() && normalStatus.size() != n) ||
      (!contributors.empty() && contributors.size() != n)) {
    throw InvalidArgument(
        core::format({.operation = "compose::ComposedSurface::surfaces()",
                      .field = "array lengths",
                      .value = std::to_string(n) + " latitudes, " + std::to_string(lonsDeg.size()) +
                               " longitudes, " + std::to_string(outHeights.size()) + " heights, " +
                               std::to_string(outNormals.size()) + " normals",
                      .expected = "equal (statuses empty or equal too)"}));
  }
  for (std::size_t i = 0; i < n; ++i) {
    ComposedSample c;
    if (pointOk(latsDeg[i], lonsDeg[i])) c = surface(latsDeg[i], lonsDeg[i], frame);
    outHeights[i] = c.height;
    outNormals[i] = c.normal;
    if (!status.empty()) status[i] = c.status;
    if (!normalStatus.empty()) normalStatus[i] = c.normalStatus;
    if (!contributors.empty()) contributors[i] = c.contributors;
  }
}

}  // namespace regolith::compose
