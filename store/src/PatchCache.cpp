// PatchCache: a byte-budgeted patch cache with three eviction policies
// (docs/cache-policies.md).
//
// One mutex guards everything. A hit is one hash lookup plus the policy's bookkeeping:
//   Lru               splice the entry's list node to the back               O(1)
//   HitCount          re-rank the entry in an ordered index (hits, lastUse)  O(log n)
//   DecayingHitCount  the same index, keyed by a decayed score               O(log n)
// Re-ranking updates the key in place when the order allows it (the patch in use is usually
// the last element), else moves the std::set node with extract()/insert(); either way a hit
// allocates nothing. The victim is the front of the list or the first element of the index.
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

#include <regolith/store/PatchCache.hpp>
#include <regolith/topo/Error.hpp>

#include <cmath>
#include <condition_variable>
#include <exception>
#include <iterator>
#include <list>
#include <mutex>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>

namespace regolith::store {

namespace {

/// Bytes charged per patch on top of its samples: what the patch and the cache's
/// bookkeeping take besides the sample array, rounded up. On x86-64 with glibc and
/// libstdc++: the Patch in its make_shared block (80 B), the hash-map node (80 B) and its
/// bucket slot (8 B), the policy's index node (48 B list node or 80 B set node, with
/// malloc's header) and the sample buffer's malloc header (16 B): 230 to 270 B. The rest
/// covers an in-flight record and allocator rounding.
constexpr std::size_t kPatchOverheadBytes = 320;

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
  /// score and lastUse are mutable so that rerank() can raise them in place when that keeps
  /// the set's order (see there).
  struct Rank {
    mutable double score = 0.0;         // hits (HitCount) or decayed hits (DecayingHitCount)
    mutable std::uint64_t lastUse = 0;  // unique tick: ties in score go to the least recent
    PatchKey key;
  };
  struct RankLess {
    bool operator()(const Rank& a, const Rank& b) const noexcept {
      return a.score < b.score || (a.score == b.score && a.lastUse < b.lastUse);
    }
  };
  using RankIndex = std::set<Rank, RankLess>;
  using LruList = std::list<PatchKey>;

  struct Entry {
    PatchPtr patch;
    std::size_t bytes = 0;
    std::uint64_t hits = 0;
    RankIndex::iterator rank;  // HitCount, DecayingHitCount
    LruList::iterator lru;     // Lru
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

  const CachePolicy policy;
  const std::uint64_t decayPeriod;

  mutable std::mutex mutex;
  // Everything below is guarded by `mutex`.
  std::size_t capacity;
  std::unordered_map<PatchKey, Entry, PatchKeyHash> entries;
  RankIndex ranks;
  LruList lru;
  std::unordered_map<PatchKey, std::shared_ptr<Pending>, PatchKeyHash> inFlight;
  std::size_t residentBytes = 0;
  CacheStats counters;           // hits, misses, loads, evictions, bytesLoaded
  std::uint64_t clock = 0;       // lastUse ticks
  std::uint64_t untilNextEpoch;  // accesses left in this decay period
  double hitWeight = 1.0;        // 2^(decay periods since the last rescale)

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

  /// Moves an entry to its new rank, which is above its old one (a higher score or an equal
  /// one with a later tick). When it still sorts below its successor, as for the patch in
  /// use (usually the last), the order is unchanged and the key is updated in place.
  void rerank(Entry& e, double score) {
    const Rank updated{score, ++clock, e.rank->key};
    if (const auto next = std::next(e.rank); next == ranks.end() || RankLess{}(updated, *next)) {
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
      return it->second.patch;
    }
    ++counters.misses;
    return nullptr;
  }

  /// Records a hit on a resident entry.
  void touch(Entry& e) {
    ++e.hits;
    switch (policy) {
      case CachePolicy::Lru: lru.splice(lru.end(), lru, e.lru); break;
      case CachePolicy::HitCount: rerank(e, static_cast<double>(e.hits)); break;
      case CachePolicy::DecayingHitCount: rerank(e, e.rank->score + hitWeight); break;
    }
  }

  void evictOne() {
    const PatchKey victim = policy == CachePolicy::Lru ? lru.front() : ranks.begin()->key;
    const auto it = entries.find(victim);
    if (policy == CachePolicy::Lru) {
      lru.erase(it->second.lru);
    } else {
      ranks.erase(it->second.rank);
    }
    residentBytes -= it->second.bytes;
    entries.erase(it);
    ++counters.evictions;
  }

  /// Evicts until `incoming` more bytes fit (incoming <= capacity).
  void makeRoom(std::size_t incoming) {
    while (residentBytes > capacity - incoming && !(lru.empty() && ranks.empty())) evictOne();
  }

  /// Makes `patch` resident under `key`, unless it is larger than the whole budget or the key
  /// is resident already (then the resident patch and its counts are kept).
  void insertLocked(const PatchKey& key, PatchPtr patch) {
    const std::size_t bytes = patch->bytes();
    if (bytes > capacity) return;
    const auto [it, inserted] = entries.try_emplace(key);
    if (!inserted) return;
    makeRoom(bytes);  // the new entry is not in the policy's index yet, so it stays
    Entry& e = it->second;
    e.patch = std::move(patch);
    e.bytes = bytes;
    try {
      if (policy == CachePolicy::Lru) {
        e.lru = lru.insert(lru.end(), key);
      } else {
        e.rank = ranks.insert(Rank{0.0, ++clock, key}).first;
      }
    } catch (...) {
      entries.erase(it);
      throw;
    }
    residentBytes += bytes;
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

CacheStats PatchCache::stats() const {
  const Impl& m = *impl_;
  const std::lock_guard lock(m.mutex);
  CacheStats s = m.counters;
  s.residentBytes = m.residentBytes;
  s.residentPatches = m.entries.size();
  s.capacityBytes = m.capacity;
  return s;
}

void PatchCache::resetStats() {
  const std::lock_guard lock(impl_->mutex);
  impl_->counters = CacheStats{};
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
  m.counters.evictions += m.entries.size();
  m.entries.clear();
  m.ranks.clear();
  m.lru.clear();
  m.residentBytes = 0;
}

}  // namespace regolith::store
