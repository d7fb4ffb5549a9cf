// PatchCache: a byte-budgeted patch cache with three eviction policies
// (docs/cache-policies.md).
//
// One mutex guards the maps and the index. Every policy ranks resident patches in one
// ordered index (std::set) of (score, lastUse), whose first element is the next victim:
//   Lru               score 0, so the order is lastUse                        O(log n)
//   HitCount          score = hits                                            O(log n)
//   DecayingHitCount  score = decayed hits                                    O(log n)
// A hit under the lock re-ranks at once: in place when the order allows it (the patch in
// use is usually the last element), else by moving the std::set node with extract()/
// insert(); either way a hit allocates nothing.
//
// Lock-free hits. With Lru and HitCount, every resident patch of a grid level that has a
// BlockTable (Pager sources register one) is published there, and queries entering it
// count their hit in the patch's own counters without the lock (store/BlockTable.hpp). The
// index then lags behind those counters; eviction corrects it lazily: while the first
// element's live (hits, lastUse) is newer than its indexed key, it is re-ranked with the live
// key and the next first element examined. Keys only grow, so the victim is the one an eager
// index would choose. Recency: events under the lock take a tick of the cache's clock (its
// HazardDomain's; exact order); a lock-free hit is stamped with the clock's current value
// without advancing it (BlockIndex::now()), so lock-free hits between two locked
// events tie, and
// ties go to the lower key. Each lock-free hit costs at most one re-rank, so
// eviction stays O(log n) amortised. DecayingHitCount publishes nothing: its scores are
// rescaled under the lock, so all its hits take the lock.
//
// Reclamation. An evicted patch is retracted from its table and kept on a retired list until
// no hazard record of the cache's domain names it (checked after a process-wide barrier), so
// a query that
// found it in the table a moment before can finish reading it. Retired patches no longer
// count against the budget, like patches handed out by get(); each thread protects at most
// one, so at most one per querying thread is retired at a time.
//
// Decay is lazy. Halving every resident count at each period boundary would be O(n) per
// period; instead a hit made e periods after the last rescale adds 2^e to the patch's score.
// Comparing scores is then the same as comparing counts that halve (exactly, without
// rounding down) once per period, and the ordering of resident patches never changes
// between hits, so the index stays valid. When 2^e reaches 2^64, every score is scaled down
// by 2^64 and the index rebuilt (O(n log n) once every 64 periods).
//
// Misses: the first thread to miss a key registers a Pending record in `inFlight` and runs
// the loader outside the lock. Later requests for that key wait on the record's condition
// variable (which releases the lock) and receive the same patch, or the same exception. The
// patch is inserted, the record completed and removed under one lock, so a request sees the
// key either resident or in flight, never neither while a load is running. (A condition
// variable rather than std::promise/shared_future: libstdc++'s promise runs a call_once per
// value, and glibc's pthread_once makes a futex system call each time: 410 instead of
// 260 ns of bookkeeping per miss.)

#include <regolith/core/Error.hpp>
#include <regolith/store/BlockTable.hpp>
#include <regolith/store/PatchCache.hpp>
#include <regolith/topo/Bilinear.hpp>

#include <cmath>
#include <condition_variable>
#include <exception>
#include <iterator>
#include <mutex>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>

namespace regolith::store {

namespace {

/// Bytes charged per patch on top of its samples: what the patch and the cache's
/// bookkeeping take besides the sample array, rounded up. On x86-64 with glibc and
/// libstdc++: the Patch in its make_shared block (80 B), the hash-map node (64 B) and its
/// bucket slot (8 B), the index's set node (80 B), the Resident record with its published
/// block (112 B) and the sample buffer's malloc header (16 B): 360 B, with malloc's headers.
/// The rest covers allocator rounding.
constexpr std::size_t kPatchOverheadBytes = 384;

/// Scores of DecayingHitCount are rescaled when a hit's weight reaches 2^kRescaleExponent.
constexpr int kRescaleExponent = 64;

std::uint64_t mix64(std::uint64_t x) noexcept {
  // SplitMix64's finaliser: every input bit affects every output bit.
  x ^= x >> 30U;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27U;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31U;
  return x;
}

using PatchPtr = std::shared_ptr<const Patch>;

std::string describe(const PatchKey& k) {
  return "grid " + std::to_string(k.grid) + " level " + std::to_string(k.level) + " patch (" +
         std::to_string(k.row) + ", " + std::to_string(k.col) + ")";
}

}  // namespace

std::size_t PatchKeyHash::operator()(const PatchKey& k) const noexcept {
  const std::uint64_t gridLevel = (std::uint64_t{k.grid} << 32U) | k.level;
  const std::uint64_t rowCol = (std::uint64_t{k.row} << 32U) | k.col;
  return static_cast<std::size_t>(mix64(rowCol ^ (gridLevel * 0x9e3779b97f4a7c15ULL)));
}

std::size_t Patch::bytes() const noexcept {
  return samples.size() * sizeof(float) + kPatchOverheadBytes;
}

std::string_view toString(CachePolicy p) noexcept {
  switch (p) {
    case CachePolicy::HitCount: return "HitCount";
    case CachePolicy::Lru: return "Lru";
    case CachePolicy::DecayingHitCount: return "DecayingHitCount";
  }
  return "unknown";
}

struct PatchCache::Impl {
  /// Position of a patch in the ranked index: the first element is the next victim.
  /// score and lastUse are mutable so that rerank() can change them in place when that keeps
  /// the set's order (see there).
  struct Rank {
    mutable double score = 0.0;         // 0 (Lru), hits (HitCount) or decayed hits
    mutable std::uint64_t lastUse = 0;  // recency tick: ties in score go to the least recent
    PatchKey key;
  };
  struct RankLess {
    bool operator()(const Rank& a, const Rank& b) const noexcept {
      // The key breaks ties: lock-free hits between two locked events share a stamp.
      if (a.score != b.score) return a.score < b.score;
      if (a.lastUse != b.lastUse) return a.lastUse < b.lastUse;
      return std::tie(a.key.grid, a.key.level, a.key.row, a.key.col) <
             std::tie(b.key.grid, b.key.level, b.key.row, b.key.col);
    }
  };
  using RankIndex = std::set<Rank, RankLess>;

  /// A resident patch. Separately allocated: its address is published in a BlockTable, and
  /// it may outlive its map entry on the retired list.
  struct Resident {
    PublishedBlock block;  // the patch's samples and geometry, and its live counters
    PatchPtr patch;
    std::uint64_t lockedHits = 0;  // hits taken under the lock
    [[nodiscard]] std::uint64_t hits() const noexcept {
      return lockedHits + block.fastHits.load(std::memory_order_relaxed);
    }
  };

  struct Entry {
    std::unique_ptr<Resident> res;
    std::size_t bytes = 0;
    RankIndex::iterator rank;
    BlockTable* table = nullptr;  // where the patch is published, if anywhere
  };

  /// A load in flight; the fields are guarded by the cache's mutex.
  struct Pending {
    std::condition_variable done;
    bool finished = false;
    PatchPtr patch;
    std::exception_ptr error;
  };

  Impl(std::size_t capacityBytes, CachePolicy p, std::uint64_t period)
      : policy(p), decayPeriod(period), capacity(capacityBytes), untilNextEpoch(period) {}

  ~Impl() {
    // No source of this cache is alive (each holds the cache), so no query can be reading a
    // retired patch: free them all, and clear the hazard records that still name them.
    for (const auto& r : retired) hazards->forget(&r->block);
    for (const auto& [key, e] : entries) {
      if (e.table != nullptr) hazards->forget(&e.res->block);
    }
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  const CachePolicy policy;
  const std::uint64_t decayPeriod;
  /// The hazard records of this cache's readers and its recency clock, shared with its
  /// tables (which outlive neither the cache nor their sources).
  const std::shared_ptr<HazardDomain> hazards = std::make_shared<HazardDomain>();

  mutable std::mutex mutex;
  // Everything below is guarded by `mutex`.
  std::size_t capacity;
  std::unordered_map<PatchKey, Entry, PatchKeyHash> entries;
  RankIndex ranks;
  std::unordered_map<PatchKey, std::shared_ptr<Pending>, PatchKeyHash> inFlight;
  /// Block tables by (grid << 32 | level).
  std::unordered_map<std::uint64_t, std::shared_ptr<BlockTable>> tables;
  std::vector<std::unique_ptr<Resident>> retired;
  std::size_t residentBytes = 0;
  CacheStats counters;  // hits (under the lock), misses, loads, evictions, bytesLoaded
  std::uint64_t fastHitsEvicted = 0;  // lock-free hits of patches no longer resident
  std::uint64_t fastHitsBase = 0;     // lock-free hits before the last resetStats()
  std::uint64_t untilNextEpoch;       // accesses left in this decay period
  double hitWeight = 1.0;             // 2^(decay periods since the last rescale)

  static std::uint64_t tableKey(std::uint32_t grid, std::uint32_t level) noexcept {
    return (std::uint64_t{grid} << 32U) | level;
  }
  [[nodiscard]] bool publishes() const noexcept { return policy != CachePolicy::DecayingHitCount; }

  /// Counts one access (get or find) towards the decay period.
  void countAccess() {
    if (policy != CachePolicy::DecayingHitCount || --untilNextEpoch != 0) return;
    untilNextEpoch = decayPeriod;
    hitWeight *= 2.0;
    if (hitWeight >= std::ldexp(1.0, kRescaleExponent)) rescale();
  }

  /// Divides every score and the hit weight by 2^kRescaleExponent. The order is kept but
  /// tiny scores may underflow into ties, so the index is rebuilt rather than patched.
  void rescale() {
    hitWeight = std::ldexp(hitWeight, -kRescaleExponent);
    RankIndex rebuilt;
    while (!ranks.empty()) {
      auto node = ranks.extract(ranks.begin());
      node.value().score = std::ldexp(node.value().score, -kRescaleExponent);
      const PatchKey key = node.value().key;
      entries.find(key)->second.rank = rebuilt.insert(std::move(node)).position;
    }
    ranks.swap(rebuilt);
  }

  /// Gives an entry the rank (score, lastUse): in place when it still sorts between its
  /// neighbours (the patch in use is usually the last element), else by moving its node.
  void rerank(Entry& e, double score, std::uint64_t lastUse) {
    const Rank updated{score, lastUse, e.rank->key};
    const bool afterPrev = e.rank == ranks.begin() || RankLess{}(*std::prev(e.rank), updated);
    const auto next = std::next(e.rank);
    if (afterPrev && (next == ranks.end() || RankLess{}(updated, *next))) {
      e.rank->score = updated.score;
      e.rank->lastUse = updated.lastUse;
      return;
    }
    auto node = ranks.extract(e.rank);
    node.value() = updated;
    e.rank = ranks.insert(std::move(node)).position;
  }

  /// One request (get or find), under the lock: the resident patch and a hit, or nullptr
  /// and a miss.
  std::shared_ptr<const Patch> lookup(const PatchKey& key) {
    countAccess();
    if (const auto it = entries.find(key); it != entries.end()) {
      ++counters.hits;
      touch(it->second);
      return it->second.res->patch;
    }
    ++counters.misses;
    return nullptr;
  }

  /// Records a hit on a resident entry.
  void touch(Entry& e) {
    constexpr auto relaxed = std::memory_order_relaxed;
    PublishedBlock& b = e.res->block;
    ++e.res->lockedHits;
    const std::uint64_t hits = e.res->hits();
    const std::uint64_t now = hazards->tick();
    b.lastUse.store(now, relaxed);
    switch (policy) {
      case CachePolicy::Lru: rerank(e, 0.0, now); break;
      case CachePolicy::HitCount: rerank(e, static_cast<double>(hits), now); break;
      case CachePolicy::DecayingHitCount: rerank(e, e.rank->score + hitWeight, now); break;
    }
  }

  /// The entry's live rank, from its counters (lock-free hits included).
  Rank liveRank(const Entry& e) const {
    constexpr auto relaxed = std::memory_order_relaxed;
    const PublishedBlock& b = e.res->block;
    const double score = policy == CachePolicy::HitCount
                             ? static_cast<double>(e.res->hits())
                             : e.rank->score;  // Lru: 0; Decaying: only locked hits
    return {score, b.lastUse.load(relaxed), e.rank->key};
  }

  /// Evicts the policy's victim (the index must not be empty).
  void evictOne() {
    // Lazy correction of ranks that lock-free hits have made stale (bounded: each entry is
    // corrected at most once per call, then the first element is taken as it is).
    for (std::size_t corrections = 0; publishes() && corrections < ranks.size(); ++corrections) {
      Entry& first = entries.find(ranks.begin()->key)->second;
      const Rank live = liveRank(first);
      if (live.score == first.rank->score && live.lastUse == first.rank->lastUse) break;
      rerank(first, live.score, live.lastUse);
    }
    const auto it = entries.find(ranks.begin()->key);
    Entry& e = it->second;
    ranks.erase(e.rank);
    if (e.table != nullptr) e.table->retract(it->first.row, it->first.col);
    residentBytes -= e.bytes;
    fastHitsEvicted += e.res->block.fastHits.load(std::memory_order_relaxed);
    if (e.table != nullptr) retired.push_back(std::move(e.res));
    entries.erase(it);
    ++counters.evictions;
  }

  /// Frees the retired patches that no thread may be reading any more.
  void reclaim() {
    if (retired.empty() || !HazardDomain::barrier()) return;
    std::erase_if(retired, [this](const std::unique_ptr<Resident>& r) {
      return !hazards->isProtected(&r->block);
    });
  }

  /// Evicts until `incoming` more bytes fit (incoming <= capacity).
  void makeRoom(std::size_t incoming) {
    bool evicted = false;
    while (residentBytes > capacity - incoming && !ranks.empty()) {
      evictOne();
      evicted = true;
    }
    if (evicted) reclaim();
  }

  /// Publishes a resident entry in `table` (which must be its grid level's).
  static void publishIn(BlockTable& table, const PatchKey& key, Entry& e) {
    if (!table.hasBlock(key.row, key.col)) return;  // a key outside the registered level
    PublishedBlock& b = e.res->block;
    const Patch& p = *e.res->patch;
    b.data = p.samples.data();
    b.row0 = std::size_t{key.row} * table.blockRows();
    b.col0 = std::size_t{key.col} * table.blockCols();
    b.rows = p.rows;
    b.cols = p.cols;
    b.stride = p.cols;
    const auto d = [](std::size_t i) { return static_cast<double>(i); };
    b.uLo = d(b.col0);
    b.uHi = d(b.col0 + b.cols) - 1.0;
    b.vLo = d(b.row0);
    b.vHi = d(b.row0 + b.rows) - 1.0;
    b.origin = topo::kernel::originOf(b.data, b.row0, b.col0, b.stride);
    table.publish(key.row, key.col, &b);
    e.table = &table;
  }

  /// Makes `patch` resident under `key`, unless it is larger than the whole budget or the key
  /// is resident already (then the resident patch and its counts are kept).
  void insertLocked(const PatchKey& key, PatchPtr patch) {
    const std::size_t bytes = patch->bytes();
    if (bytes > capacity) return;
    if (entries.contains(key)) return;
    makeRoom(bytes);
    auto res = std::make_unique<Resident>();
    res->patch = std::move(patch);
    const std::uint64_t now = hazards->tick();
    res->block.lastUse.store(now, std::memory_order_relaxed);
    const auto rank = ranks.insert(Rank{0.0, now, key}).first;
    Entry* e = nullptr;
    try {
      e = &entries.try_emplace(key).first->second;
    } catch (...) {
      ranks.erase(rank);
      throw;
    }
    e->res = std::move(res);
    e->bytes = bytes;
    e->rank = rank;
    residentBytes += bytes;
    counters.peakResidentBytes = std::max(counters.peakResidentBytes, residentBytes);
    if (publishes()) {
      if (const auto t = tables.find(tableKey(key.grid, key.level)); t != tables.end()) {
        publishIn(*t->second, key, *e);
      }
    }
  }

  /// Lock-free hits counted so far (resident and evicted patches).
  [[nodiscard]] std::uint64_t fastHitsTotal() const {
    std::uint64_t n = fastHitsEvicted;
    for (const auto& [key, e] : entries) n += e.res->block.fastHits.load(std::memory_order_relaxed);
    return n;
  }
};

PatchCache::PatchCache(std::size_t capacityBytes, CachePolicy policy, std::uint64_t decayPeriod) {
  if (decayPeriod == 0) {
    throw InvalidArgument("store::PatchCache(): decayPeriod is 0 accesses, expected > 0");
  }
  impl_ = std::make_unique<Impl>(capacityBytes, policy, decayPeriod);
}

PatchCache::~PatchCache() = default;

std::shared_ptr<const Patch> PatchCache::get(const PatchKey& key, const Loader& load) {
  Impl& m = *impl_;
  std::shared_ptr<Impl::Pending> pending;
  {
    std::unique_lock lock(m.mutex);
    if (auto hit = m.lookup(key)) return hit;
    if (const auto it = m.inFlight.find(key); it != m.inFlight.end()) {
      // Another thread is loading this key: wait for it (the wait releases the lock).
      const std::shared_ptr<Impl::Pending> other = it->second;
      other->done.wait(lock, [&other] { return other->finished; });
      if (other->error) std::rethrow_exception(other->error);
      return other->patch;
    }
    pending = std::make_shared<Impl::Pending>();
    m.inFlight.emplace(key, pending);
  }

  // This thread loads; the lock is free meanwhile.
  PatchPtr patch;
  std::exception_ptr error;
  try {
    patch = load(key);
    if (!patch) {
      throw InvalidArgument("store::PatchCache::get(): the loader returned no patch for " +
                            describe(key));
    }
  } catch (...) {
    error = std::current_exception();
  }
  {
    const std::lock_guard lock(m.mutex);
    if (!error) {
      ++m.counters.loads;
      m.counters.bytesLoaded += patch->bytes();
      try {
        m.insertLocked(key, patch);
      } catch (...) {
        error = std::current_exception();  // out of memory: the waiters get the error too
      }
    }
    pending->finished = true;
    if (error) {
      pending->error = error;
    } else {
      pending->patch = patch;
    }
    m.inFlight.erase(key);
  }
  pending->done.notify_all();
  if (error) std::rethrow_exception(error);
  return patch;
}

std::shared_ptr<const Patch> PatchCache::find(const PatchKey& key) {
  Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  return m.lookup(key);
}

bool PatchCache::contains(const PatchKey& key) const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->entries.contains(key);
}

void PatchCache::insert(std::shared_ptr<const Patch> patch) {
  if (!patch) throw InvalidArgument("store::PatchCache::insert(): the patch is null");
  Impl& m = *impl_;
  const PatchKey key = patch->key;
  const std::lock_guard lock(m.mutex);
  ++m.counters.loads;
  m.counters.bytesLoaded += patch->bytes();
  m.insertLocked(key, std::move(patch));
}

std::shared_ptr<const BlockTable> PatchCache::blockTable(std::uint32_t grid, std::uint32_t level,
                                                         std::size_t rows, std::size_t cols,
                                                         std::size_t patchRows,
                                                         std::size_t patchCols) {
  Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  const std::uint64_t tkey = Impl::tableKey(grid, level);
  if (const auto it = m.tables.find(tkey); it != m.tables.end()) {
    const std::shared_ptr<BlockTable>& slot = it->second;
    if (slot->rows() != rows || slot->cols() != cols || slot->blockRows() != patchRows ||
        slot->blockCols() != patchCols) {
      throw InvalidArgument("store::PatchCache::blockTable(): grid " + std::to_string(grid) +
                            " level " + std::to_string(level) + " was registered as " +
                            std::to_string(slot->rows()) + "x" + std::to_string(slot->cols()) +
                            " samples in " + std::to_string(slot->blockRows()) + "x" +
                            std::to_string(slot->blockCols()) + " patches, now requested as " +
                            std::to_string(rows) + "x" + std::to_string(cols) + " in " +
                            std::to_string(patchRows) + "x" + std::to_string(patchCols));
    }
    return slot;
  }
  // Made before it is entered in the map, so a throwing constructor leaves no empty entry.
  auto table = std::make_shared<BlockTable>(rows, cols, patchRows, patchCols, m.hazards);
  m.tables.emplace(tkey, table);
  if (m.publishes()) {
    for (auto& [key, e] : m.entries) {
      if (key.grid == grid && key.level == level) Impl::publishIn(*table, key, e);
    }
  }
  return table;
}

CacheStats PatchCache::stats() const {
  const Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  CacheStats s = m.counters;
  s.hits += m.fastHitsTotal() - m.fastHitsBase;
  s.residentBytes = m.residentBytes;
  s.residentPatches = m.entries.size();
  s.capacityBytes = m.capacity;
  return s;
}

void PatchCache::resetStats() {
  Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  m.counters = CacheStats{};
  m.counters.peakResidentBytes = m.residentBytes;
  m.fastHitsBase = m.fastHitsTotal();
}

std::size_t PatchCache::capacityBytes() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->capacity;
}

void PatchCache::setCapacityBytes(std::size_t bytes) {
  Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  m.capacity = bytes;
  m.makeRoom(0);
}

CachePolicy PatchCache::policy() const noexcept { return impl_->policy; }

void PatchCache::clear() {
  Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  while (!m.ranks.empty()) m.evictOne();
  m.reclaim();
}

}  // namespace regolith::store
