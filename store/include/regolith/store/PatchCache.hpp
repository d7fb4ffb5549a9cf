#pragma once
/// \file
/// A byte-budgeted cache of grid patches, with selectable eviction policies.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace regolith::store {

class BlockTable;

/// Identifies one patch: an aligned block of one pyramid level of one grid.
struct PatchKey {
  std::uint32_t grid = 0;   // the pager's grid id
  std::uint32_t level = 0;  // pyramid level
  std::uint32_t row = 0;    // patch row (sample row / patch rows)
  std::uint32_t col = 0;    // patch column
  friend bool operator==(const PatchKey&, const PatchKey&) = default;
};

struct PatchKeyHash {
  std::size_t operator()(const PatchKey& k) const noexcept;
};

/// std::allocator whose value-less construct() default-initialises: resize() of a vector of
/// floats then costs no memset. A patch is filled by its hyperslab read right after being
/// sized, and zeroing 256 KiB first took a third of a cold patch load.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  UninitAllocator() noexcept = default;
  template <class U>
  explicit UninitAllocator(const UninitAllocator<U>& /*other*/) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// One patch of heights (metres, NaN where missing), row-major. Edge patches may be
/// smaller than the nominal patch size. Immutable once made; shared by the cache and its
/// readers.
struct Patch {
  PatchKey key;
  std::size_t rows = 0, cols = 0;
  std::vector<float, UninitAllocator<float>> samples;
  /// What the patch costs against the cache's budget: its samples plus a fixed overhead.
  [[nodiscard]] std::size_t bytes() const noexcept;
};

/// Eviction policy (docs/cache-policies.md measures them on recorded traces).
enum class CachePolicy : std::uint8_t {
  /// The JPL paper's policy as written: each patch counts its hits; the patch with the
  /// fewest hits is evicted first (ties: the least recently used).
  HitCount,
  /// Least recently used.
  Lru,
  /// Aging: hit counts decay (halve every `decayPeriod` accesses to the cache), so patches
  /// that were popular long ago lose their protection.
  DecayingHitCount,
};

[[nodiscard]] std::string_view toString(CachePolicy p) noexcept;

/// Counters since construction or the last resetStats().
struct CacheStats {
  std::uint64_t hits = 0;
  std::uint64_t misses = 0;
  std::uint64_t loads = 0;  // loader calls that produced a patch
  std::uint64_t evictions = 0;
  std::uint64_t bytesLoaded = 0;      // sum of Patch::bytes() of loaded patches
  std::size_t residentBytes = 0;      // now held by the cache
  std::size_t peakResidentBytes = 0;  // the most ever held at once (since the last reset)
  std::size_t residentPatches = 0;
  std::size_t capacityBytes = 0;
};

/// Holds patches up to a byte budget set at run time. Lookup is O(1) (hash map); eviction
/// is O(log n) (an ordered index, amortised over lock-free hits: see PatchCache.cpp).
///
/// Invariant: residentBytes ≤ capacityBytes at every moment, under any concurrency. A
/// patch larger than the whole budget is returned to the caller but not kept.
///
/// Thread-safety: every member may be called concurrently. Loads of different keys run in
/// parallel outside the lock; concurrent requests for one key wait for a single load.
/// Patches handed out stay valid (shared ownership) after eviction; they no longer count
/// against the budget then. Hit counts taken without the lock (blockTable()) may miss a hit
/// when two threads enter one patch at the same instant.
class PatchCache {
 public:
  using Loader = std::function<std::shared_ptr<const Patch>(const PatchKey&)>;

  /// The default policy is LRU, chosen by measurement on rover traces
  /// (docs/cache-policies.md); the paper's HitCount is there to select.
  explicit PatchCache(std::size_t capacityBytes, CachePolicy policy = CachePolicy::Lru,
                      std::uint64_t decayPeriod = 4096);
  ~PatchCache();
  PatchCache(const PatchCache&) = delete;
  PatchCache& operator=(const PatchCache&) = delete;

  /// The patch for `key`: from the cache (a hit), or from `load` (a miss; the result is
  /// inserted, evicting as the policy says). Exceptions from `load` propagate and nothing
  /// is inserted.
  [[nodiscard]] std::shared_ptr<const Patch> get(const PatchKey& key, const Loader& load);
  /// The cached patch or nullptr; counts as a hit or a miss.
  [[nodiscard]] std::shared_ptr<const Patch> find(const PatchKey& key);
  /// True if cached; does not count and does not touch the policy's bookkeeping.
  [[nodiscard]] bool contains(const PatchKey& key) const;
  /// Inserts a patch loaded elsewhere (prefetch); counts as a load, not a hit or miss.
  void insert(std::shared_ptr<const Patch> patch);

  /// The lock-free table of one grid level's resident patches (store/BlockTable.hpp), made
  /// on first request and kept for the cache's life: with Lru and HitCount, every resident
  /// patch of that level is published there, and queries entering it count their hit without
  /// the lock (DecayingHitCount publishes nothing). Throws InvalidArgument if the level was
  /// registered before with other sizes.
  [[nodiscard]] std::shared_ptr<const BlockTable> blockTable(std::uint32_t grid,
                                                             std::uint32_t level, std::size_t rows,
                                                             std::size_t cols,
                                                             std::size_t patchRows,
                                                             std::size_t patchCols);

  [[nodiscard]] CacheStats stats() const;
  void resetStats();
  [[nodiscard]] std::size_t capacityBytes() const;
  /// Changes the budget, evicting at once if needed.
  void setCapacityBytes(std::size_t bytes);
  [[nodiscard]] CachePolicy policy() const noexcept;
  /// Evicts everything.
  void clear();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace regolith::store
