#pragma once
/// \file
/// Background loading of patches on an executor, windows by priority.

#include <regolith/core/Executor.hpp>
#include <regolith/store/Pager.hpp>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <queue>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace regolith::store {

/// A block of samples of one level: rows [row0, row0 + rows), cols [col0, col0 + cols).
struct LevelWindow {
  std::size_t level = 0;
  std::size_t row0 = 0, col0 = 0, rows = 0, cols = 0;
};

/// Counters since construction.
struct PrefetchStats {
  std::uint64_t queued = 0;     // patches put in the queue
  std::uint64_t loaded = 0;     // patches fetched by a worker (cache hits included)
  std::uint64_t cancelled = 0;  // patches dropped from the queue by cancel()
  std::uint64_t failed = 0;     // loads that threw (the error is kept, see lastError())
};

/// Loads patches in the background so that queries find them resident, e.g. the lazy-load
/// window around a moving focus. Work runs by priority: a request's coarse levels before
/// its finer ones, and among requests the higher priority first (then the older).
/// Requests can be cancelled; a focus that moves cancels its previous window.
///
/// Loads run as tasks on a core::Executor: up to maxTasks at once, each draining the queue
/// and returning when it is empty, so no thread waits on the executor while there is
/// nothing to load.
///
/// Thread-safety: every member may be called from any thread. The destructor cancels what
/// is queued and waits for the loads in progress to finish; it may run on a thread of the
/// executor (a task queued behind it then returns without loading).
class Prefetcher {
 public:
  using Ticket = std::uint64_t;

  /// Loads on a core::ThreadPool of `threads` made for this prefetcher. Throws
  /// InvalidArgument if pager is null or threads is 0.
  Prefetcher(std::shared_ptr<const Pager> pager, std::size_t threads = 2);
  /// Loads on `executor`, at most `maxTasks` patches at once (0: the executor's
  /// concurrency). Throws InvalidArgument if pager or executor is null.
  Prefetcher(std::shared_ptr<const Pager> pager, std::shared_ptr<core::Executor> executor,
             std::size_t maxTasks = 0);
  ~Prefetcher();
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  /// Queues the patches covering the windows of `grid` (windows are clipped to their
  /// levels; an unknown grid or level throws StoreError at once). Within the request,
  /// coarser levels load first. Returns a ticket for wait() and cancel().
  Ticket request(std::string_view grid, const std::vector<LevelWindow>& windows, int priority = 0);
  /// The windows of every level of `grid` that cover a square of half-width `radius`
  /// level-0 samples around level-0 sample (row, col), from `finestLevel` up to the
  /// coarsest stored level.
  [[nodiscard]] std::vector<LevelWindow> focusWindows(std::string_view grid, std::size_t row,
                                                      std::size_t col, std::size_t radius,
                                                      std::size_t finestLevel = 0) const;
  /// Makes the patches covering the windows of `grid` resident now (a renderer's window it
  /// is about to read): loads them on the calling thread, ahead of every queued request,
  /// returning when each is loaded or failed (a failure is counted and kept in lastError(); the
  /// read that follows reports it). So a call from a task on the executor's only worker cannot wait
  /// for a task queued behind it. Throws StoreError for an unknown grid or level.
  void load(std::string_view grid, const std::vector<LevelWindow>& windows);
  /// Drops the ticket's queued patches (loads in progress finish).
  void cancel(Ticket ticket);
  /// Blocks until the ticket's patches are all loaded, cancelled or failed.
  void wait(Ticket ticket);
  /// Blocks until the queue is empty and no worker is busy.
  void waitIdle();

  [[nodiscard]] PrefetchStats stats() const;
  /// Message of the last failed load (empty if none).
  [[nodiscard]] std::string lastError() const;
  /// Called by a loading task after each patch it fetched (for tests and progress); may be empty.
  void setOnLoaded(std::function<void(const PatchKey&)> fn);

 private:
  struct Item {
    int priority = 0;
    std::uint32_t level = 0;
    std::uint64_t sequence = 0;
    Ticket ticket = 0;
    PatchKey key;
  };
  struct ItemOrder {
    bool operator()(const Item& a, const Item& b) const noexcept;
  };
  /// What the loading tasks read, shared with them: a task the executor starts after the
  /// prefetcher is gone (queued behind other work) finds `stopping` and returns, touching
  /// only this. So the destructor waits only for loads in progress, never for a task still
  /// queued, and may run on a thread of the executor itself (a 1-worker executor, whose
  /// queued task could otherwise never start).
  struct State {
    std::shared_ptr<const Pager> pager;
    std::mutex mutex;
    std::size_t maxTasks = 1;
    std::size_t tasks = 0;         // loading tasks submitted and not yet returned
    std::condition_variable done;  // waiters: a ticket, the queue drained, a load finished
    std::priority_queue<Item, std::vector<Item>, ItemOrder> queue;
    std::unordered_map<Ticket, std::size_t> pending;  // ticket → patches not yet finished
    std::size_t busy = 0;                             // loads in progress
    bool stopping = false;
    Ticket nextTicket = 1;
    std::uint64_t nextSequence = 0;
    PrefetchStats stats;
    std::string lastError;
    std::function<void(const PatchKey&)> onLoaded;
  };
  /// Drains the queue (a task on the executor).
  static void work(const std::shared_ptr<State>& state);
  /// Loads one item and counts it (lock held on entry and on return; released while loading).
  static void loadItem(State& s, std::unique_lock<std::mutex>& lock, const Item& item);
  /// The patches covering `windows`, each once (StoreError for an unknown grid or level).
  [[nodiscard]] std::vector<Item> itemsOf(std::string_view grid,
                                          const std::vector<LevelWindow>& windows,
                                          int priority) const;
  /// Submits loading tasks for the queue, up to maxTasks running (lock held on entry and
  /// on return; released while submitting).
  void startTasks(std::unique_lock<std::mutex>& lock);

  std::shared_ptr<State> state_;
  /// Last, so that a pool of the prefetcher's own is joined before anything else goes.
  std::shared_ptr<core::Executor> executor_;
};

}  // namespace regolith::store
