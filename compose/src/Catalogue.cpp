#include <regolith/compose/Catalogue.hpp>
#include <regolith/core/Error.hpp>
#include <regolith/core/Message.hpp>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>

namespace regolith::compose {

namespace {
/// True if the segment p0 + t·d, t ∈ [0, 1], meets the box [lo, hi] (slab test; a zero
/// component of d gives ±inf or NaN bounds that the comparisons below treat as "no limit"
/// or "outside" correctly).
bool segmentHitsBox(const glm::dvec3& p0, const glm::dvec3& inv, const glm::dvec3& lo,
                    const glm::dvec3& hi) noexcept {
  double t0 = 0.0, t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (std::isinf(inv[a])) {  // parallel to this slab: inside it or never
      if (p0[a] < lo[a] || p0[a] > hi[a]) return false;
      continue;
    }
    double ta = (lo[a] - p0[a]) * inv[a], tb = (hi[a] - p0[a]) * inv[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

bool boxesOverlap(const glm::dvec3& alo, const glm::dvec3& ahi, const glm::dvec3& blo,
                  const glm::dvec3& bhi) noexcept {
  return alo.x <= bhi.x && blo.x <= ahi.x && alo.y <= bhi.y && blo.y <= ahi.y && alo.z <= bhi.z &&
         blo.z <= ahi.z;
}

constexpr int kLatCells = 180, kLonCells = 360;  // cellCandidates(): 1° cells

bool boxOutsidePlane(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec4& p) noexcept {
  // The box corner farthest along the plane's normal.
  const glm::dvec3 v(p.x >= 0.0 ? hi.x : lo.x, p.y >= 0.0 ? hi.y : lo.y, p.z >= 0.0 ? hi.z : lo.z);
  return p.x * v.x + p.y * v.y + p.z * v.z + p.w < 0.0;
}
}  // namespace

bool tierBefore(std::span<const CatalogueEntry> entries, std::uint32_t ia,
                std::uint32_t ib) noexcept {
  const Dataset& a = *entries[ia].dataset;
  const Dataset& b = *entries[ib].dataset;
  if (a.options().priority != b.options().priority)
    return a.options().priority > b.options().priority;
  if (a.groundSpacing() != b.groundSpacing()) return a.groundSpacing() < b.groundSpacing();
  return ia < ib;
}

Snapshot::Snapshot(topo::Body body, std::vector<CatalogueEntry> entries, std::uint64_t version)
    : body_(std::move(body)), entries_(std::move(entries)), version_(version) {
  order_.resize(entries_.size());
  std::iota(order_.begin(), order_.end(), 0U);
  if (!entries_.empty()) {
    hLow_ = std::numeric_limits<double>::infinity();
    hHigh_ = -hLow_;
    bandLow_ = hLow_;
    bandHigh_ = hHigh_;
    for (const auto& e : entries_) {
      hLow_ = std::min(hLow_, e.dataset->heightRange()[0]);
      hHigh_ = std::max(hHigh_, e.dataset->heightRange()[1]);
      bandLow_ = std::min(bandLow_, e.dataset->ellipsoidHeightRange()[0]);
      bandHigh_ = std::max(bandHigh_, e.dataset->ellipsoidHeightRange()[1]);
    }
    nodes_.reserve(2 * entries_.size());
    build(0, static_cast<std::uint32_t>(entries_.size()));
  }
}

/// A lazily filled list per cell: published with a compare-and-swap, so two threads that
/// build one cell at once keep the first list and free the second. (Hand-written: no Debian
/// library offers a lock-free, grow-only table, and a mutex here would serialise queries.)
struct Snapshot::CellTable {
  // Inline (the table is allocated whole): a look-up reads its cell's pointer at a fixed
  // offset from the table, no pointer to the array between.
  // Mutable: cells are built on first look-up behind a const query, each published once.
  mutable std::array<std::atomic<const Cell*>, static_cast<std::size_t>(kLatCells) * kLonCells>
      lists{};
  Role role;
  explicit CellTable(Role r) : role(r) {}
  CellTable(const CellTable&) = delete;
  CellTable& operator=(const CellTable&) = delete;
  CellTable(CellTable&&) = delete;
  CellTable& operator=(CellTable&&) = delete;
  ~CellTable() {
    for (std::size_t i = 0; i < static_cast<std::size_t>(kLatCells) * kLonCells; ++i) {
      delete lists[i].load(std::memory_order_relaxed);
    }
  }
};

Snapshot::~Snapshot() {
  for (auto& table : cells_) delete table.load(std::memory_order_relaxed);
}

std::vector<std::uint32_t> Snapshot::cellList(int latCell, int lonCell, Role role) const {
  std::vector<std::uint32_t> out;
  if (nodes_.empty()) return out;
  // The cell's shell between the lowest and highest height, boxed: its points at every half
  // degree and both heights, grown by more than any arc between them bulges (a chord over
  // half a degree stands R·(1 − cos 0.25°) off its arc; the margin is R·(1 − cos 1°)).
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  const double lat0 = latCell - 90.0, lon0 = lonCell - 180.0;
  for (int i = 0; i <= 2; ++i) {
    for (int j = 0; j <= 2; ++j) {
      for (const double h : {bandLow_, bandHigh_}) {
        const glm::dvec3 p = body_.toBodyFixed({lat0 + 0.5 * i, lon0 + 0.5 * j, h});
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
    }
  }
  const double reach = body_.equatorialRadius() + std::max(std::abs(bandLow_), std::abs(bandHigh_));
  const double margin = reach * (1.0 - std::cos(std::numbers::pi / 180.0)) + 1.0;
  lo -= glm::dvec3(margin);
  hi += glm::dvec3(margin);
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (!boxesOverlap(lo, hi, n.lo, n.hi)) continue;
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const std::uint32_t e = order_[i];
        const auto& b = entries_[e].dataset->bounds();
        if (entries_[e].dataset->options().role == role && boxesOverlap(lo, hi, b[0], b[1])) {
          out.push_back(e);
        }
      }
    } else {
      stack[top++] = n.right;
      stack[top++] = n.left;
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

const Snapshot::CellTable& Snapshot::cellTable(Role role) const {
  std::atomic<CellTable*>& slot = cells_[static_cast<std::size_t>(role) % kRoles];
  CellTable* table = slot.load(std::memory_order_acquire);
  if (table == nullptr) {
    auto fresh = std::make_unique<CellTable>(role);
    if (slot.compare_exchange_strong(table, fresh.get(), std::memory_order_acq_rel)) {
      table = fresh.release();
    }
  }
  return *table;
}

namespace {
// At namespace scope: a function's static with a destructor costs every call a test of its
// guard (and the call a stack frame).
const Snapshot::Cell kEmptyCell;
}  // namespace

const Snapshot::Cell& Snapshot::cell(const CellTable& table, double latDeg, double lonDeg) const {
  if (nodes_.empty() || !std::isfinite(latDeg) || !std::isfinite(lonDeg)) return kEmptyCell;
  // [-180, 180): most points are there already (and a division is a tenth of the look-up).
  const double lon = lonDeg >= -180.0 && lonDeg < 180.0
                         ? lonDeg
                         : lonDeg - 360.0 * std::floor((lonDeg + 180.0) / 360.0);
  // Clamped first, then truncated: the floor of a value in [0, n - 1], without a floor()
  // call or a conversion of a huge value.
  const auto cellOf = [](double x, int n) {
    return static_cast<int>(std::clamp(x, 0.0, static_cast<double>(n - 1)));
  };
  const int latCell = cellOf(latDeg + 90.0, kLatCells);
  const int lonCell = cellOf(lon + 180.0, kLonCells);
  const std::size_t index =
      static_cast<std::size_t>(latCell) * kLonCells + static_cast<std::size_t>(lonCell);
  // The common case, a built cell, without a call or a saved register.
  if (const Cell* built = table.lists[index].load(std::memory_order_acquire)) [[likely]] {
    return *built;
  }
  return buildCell(table, latCell, lonCell);
}

const Snapshot::Cell& Snapshot::buildCell(const CellTable& table, int latCell, int lonCell) const {
  std::atomic<const Cell*>& slot =
      table
          .lists[static_cast<std::size_t>(latCell) * kLonCells + static_cast<std::size_t>(lonCell)];
  const Cell* built = slot.load(std::memory_order_acquire);
  if (built == nullptr) {
    auto fresh = std::make_unique<Cell>();
    fresh->candidates = cellList(latCell, lonCell, table.role);
    if (!fresh->candidates.empty()) {
      std::uint32_t top = fresh->candidates.front();
      for (const std::uint32_t e : fresh->candidates) {
        if (tierBefore(entries_, e, top)) top = e;
      }
      fresh->top = entries_[top].dataset.get();
      fresh->topEntry = top;
    }
    if (slot.compare_exchange_strong(built, fresh.get(), std::memory_order_acq_rel)) {
      built = fresh.release();
    }
  }
  return *built;
}

std::uint32_t Snapshot::build(std::uint32_t first, std::uint32_t count) {
  Node node;
  node.lo = glm::dvec3(std::numeric_limits<double>::infinity());
  node.hi = -node.lo;
  for (std::uint32_t i = first; i < first + count; ++i) {
    const auto& b = entries_[order_[i]].dataset->bounds();
    node.lo = glm::min(node.lo, b[0]);
    node.hi = glm::max(node.hi, b[1]);
  }
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back(node);
  constexpr std::uint32_t kLeafSize = 2;
  if (count <= kLeafSize) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  // Split at the median of the box centres along the longest axis of their spread.
  glm::dvec3 clo(std::numeric_limits<double>::infinity()), chi(-clo);
  for (std::uint32_t i = first; i < first + count; ++i) {
    const auto& b = entries_[order_[i]].dataset->bounds();
    const glm::dvec3 c = 0.5 * (b[0] + b[1]);
    clo = glm::min(clo, c);
    chi = glm::max(chi, c);
  }
  const glm::dvec3 spread = chi - clo;
  const int axis =
      spread.x >= spread.y && spread.x >= spread.z ? 0 : (spread.y >= spread.z ? 1 : 2);
  const std::uint32_t half = count / 2;
  auto centre = [&](std::uint32_t e) {
    const auto& b = entries_[e].dataset->bounds();
    return b[0][axis] + b[1][axis];
  };
  std::nth_element(order_.begin() + first, order_.begin() + first + half,
                   order_.begin() + first + count,
                   [&](std::uint32_t a, std::uint32_t b) { return centre(a) < centre(b); });
  const std::uint32_t left = build(first, half);
  const std::uint32_t right = build(first + half, count - half);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

std::size_t Snapshot::covering(double latDeg, double lonDeg, std::vector<std::uint32_t>& out,
                               Role role) const {
  if (nodes_.empty()) return 0;
  // The normal line through the band of heights: p(h) = p(0) + h·n, with one
  // sine and cosine per angle (Body::toBodyFixed() twice would take them twice).
  const double phi = latDeg * (std::numbers::pi / 180.0), lam = lonDeg * (std::numbers::pi / 180.0);
  const double sp = std::sin(phi), cp = std::cos(phi), sl = std::sin(lam), cl = std::cos(lam);
  const double a = body_.equatorialRadius(), e2 = body_.eccentricitySquared();
  const double nu = a / std::sqrt(1.0 - e2 * sp * sp);  // prime-vertical radius N
  const glm::dvec3 up(cp * cl, cp * sl, sp);
  const glm::dvec3 p0 =
      glm::dvec3(nu * cp * cl, nu * cp * sl, nu * (1.0 - e2) * sp) + bandLow_ * up;
  const glm::dvec3 d = (bandHigh_ - bandLow_) * up;
  const glm::dvec3 inv(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  std::size_t visited = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    ++visited;
    if (!segmentHitsBox(p0, inv, n.lo, n.hi)) continue;
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const std::uint32_t e = order_[i];
        const auto& b = entries_[e].dataset->bounds();
        if (entries_[e].dataset->options().role == role && segmentHitsBox(p0, inv, b[0], b[1])) {
          out.push_back(e);
        }
      }
    } else {  // median splits: depth ≤ log2(2^32) + 1, so 64 entries never overflow
      stack[top++] = n.right;
      stack[top++] = n.left;
    }
  }
  return visited;
}

std::size_t Snapshot::visible(std::span<const glm::dvec4> planes,
                              std::vector<std::uint32_t>& out) const {
  if (nodes_.empty()) return 0;
  auto outside = [&](const glm::dvec3& lo, const glm::dvec3& hi) {
    return std::any_of(planes.begin(), planes.end(),
                       [&](const glm::dvec4& p) { return boxOutsidePlane(lo, hi, p); });
  };
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  std::size_t visited = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    ++visited;
    if (outside(n.lo, n.hi)) continue;
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const auto& b = entries_[order_[i]].dataset->bounds();
        if (!outside(b[0], b[1])) out.push_back(order_[i]);
      }
    } else {  // median splits: depth ≤ log2(2^32) + 1, so 64 entries never overflow
      stack[top++] = n.right;
      stack[top++] = n.left;
    }
  }
  return visited;
}

Catalogue::Catalogue(topo::Body body)
    : body_(std::move(body)),
      current_(std::make_shared<const Snapshot>(body_, std::vector<CatalogueEntry>{}, 0)) {}

namespace {
void checkBody(const topo::Body& body, const std::shared_ptr<const Dataset>& dataset) {
  if (!dataset) {
    throw InvalidArgument(core::format({.operation = "compose::Catalogue::add()",
                                        .field = "dataset",
                                        .value = "null",
                                        .expected = "a dataset"}));
  }
  const topo::Body& b = dataset->body();
  if (std::abs(b.equatorialRadius() - body.equatorialRadius()) > 1e-3 ||
      std::abs(b.polarRadius() - body.polarRadius()) > 1e-3) {
    throw InvalidArgument(core::format(
        {.operation = "compose::Catalogue::add()",
         .field = "dataset '" + dataset->name() + "' body radii",
         .value = core::number(b.equatorialRadius()) + " / " + core::number(b.polarRadius()) + " m",
         .expected = "the catalogue's body " + body.name() + " (" +
                     core::number(body.equatorialRadius()) + " / " +
                     core::number(body.polarRadius()) + " m)"}));
  }
}
}  // namespace

DatasetId Catalogue::add(std::shared_ptr<const Dataset> dataset) {
  const std::shared_ptr<const Dataset> one[] = {std::move(dataset)};
  return add(std::span<const std::shared_ptr<const Dataset>>(one)).front();
}

std::vector<DatasetId> Catalogue::add(std::span<const std::shared_ptr<const Dataset>> datasets) {
  for (const auto& d : datasets) checkBody(body_, d);
  const std::lock_guard lock(writers_);
  std::vector<DatasetId> ids;
  ids.reserve(datasets.size());
  for (const auto& d : datasets) {
    ids.push_back(nextId_++);
    entries_.push_back({ids.back(), d});
  }
  current_.store(std::make_shared<const Snapshot>(body_, entries_, ++version_));
  return ids;
}

bool Catalogue::remove(DatasetId id) {
  const std::lock_guard lock(writers_);
  const auto it = std::find_if(entries_.begin(), entries_.end(),
                               [id](const CatalogueEntry& e) { return e.id == id; });
  if (it == entries_.end()) return false;
  entries_.erase(it);
  current_.store(std::make_shared<const Snapshot>(body_, entries_, ++version_));
  return true;
}

std::shared_ptr<const Snapshot> Catalogue::snapshot() const { return current_.load(); }

}  // namespace regolith::compose
