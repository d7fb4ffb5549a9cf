#include <regolith/core/Error.hpp>
#include <regolith/store/Prefetcher.hpp>

#include <algorithm>
#include <string>
#include <unordered_set>

namespace regolith::store {

bool Prefetcher::ItemOrder::operator()(const Item& a, const Item& b) const noexcept {
  // std::priority_queue pops the greatest: higher priority, then coarser level, then older.
  if (a.priority != b.priority) return a.priority < b.priority;
  if (a.level != b.level) return a.level < b.level;
  return a.sequence > b.sequence;
}

namespace {

std::shared_ptr<core::Executor> poolOf(std::size_t threads) {
  if (threads == 0) throw InvalidArgument("store::Prefetcher(): threads is 0, expected >= 1");
  return std::make_shared<core::ThreadPool>(static_cast<unsigned>(threads));
}

}  // namespace

Prefetcher::Prefetcher(std::shared_ptr<const Pager> pager, std::size_t threads)
    : Prefetcher(std::move(pager), poolOf(threads), threads) {}

Prefetcher::Prefetcher(std::shared_ptr<const Pager> pager, std::shared_ptr<core::Executor> executor,
                       std::size_t maxTasks)
    : state_(std::make_shared<State>()), executor_(std::move(executor)) {
  if (!pager) throw InvalidArgument("store::Prefetcher(): pager is null");
  if (!executor_) throw InvalidArgument("store::Prefetcher(): executor is null");
  state_->pager = std::move(pager);
  state_->maxTasks = maxTasks != 0 ? maxTasks : std::max(1U, executor_->concurrency());
}

Prefetcher::~Prefetcher() {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  s.stopping = true;
  s.stats.cancelled += s.queue.size();
  s.queue = {};
  s.pending.clear();
  s.done.notify_all();
  // A load in progress may call onLoaded, which may refer to what outlives this object only
  // until the destructor returns: wait for those. A task not yet started holds the state
  // and returns as it starts (work()).
  s.done.wait(lock, [&] { return s.busy == 0; });
}

void Prefetcher::startTasks(std::unique_lock<std::mutex>& lock) {
  State& s = *state_;
  // One task per queued patch, up to maxTasks; each drains the queue and then returns, so
  // the executor's threads are never held while there is nothing to load.
  const std::size_t start =
      s.tasks < s.maxTasks ? std::min(s.maxTasks - s.tasks, s.queue.size()) : 0;
  s.tasks += start;
  lock.unlock();
  for (std::size_t i = 0; i < start; ++i) executor_->submit([state = state_] { work(state); });
  lock.lock();
}

void Prefetcher::load(std::string_view grid, const std::vector<LevelWindow>& windows) {
  // Loaded here, not queued: ahead of every request by construction, on the thread that
  // waits for them (loading them on the tasks' thread too made more loads and slower
  // frames: docs/architecture.md), and never behind a task that cannot start.
  const std::vector<Item> items = itemsOf(grid, windows, 0);
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  for (const Item& item : items) {
    if (s.stopping) break;
    loadItem(s, lock, item);
  }
}

std::vector<Prefetcher::Item> Prefetcher::itemsOf(std::string_view grid,
                                                  const std::vector<LevelWindow>& windows,
                                                  int priority) const {
  const Pager& pager = *state_->pager;
  const GridInfo& info = pager.grid(grid);  // throws StoreError for unknown grids
  std::vector<Item> items;
  for (const LevelWindow& w : windows) {
    (void)pager.keyOf(grid, w.level, 0, 0);  // throws StoreError for a missing level
    const std::size_t rows = info.levelRows(w.level), cols = info.levelCols(w.level);
    if (w.rows == 0 || w.cols == 0 || w.row0 >= rows || w.col0 >= cols) continue;
    const std::size_t r1 = std::min(rows, w.row0 + w.rows), c1 = std::min(cols, w.col0 + w.cols);
    for (std::size_t pr = w.row0 / info.patchRows; pr * info.patchRows < r1; ++pr) {
      for (std::size_t pc = w.col0 / info.patchCols; pc * info.patchCols < c1; ++pc) {
        const PatchKey key = pager.keyOf(grid, w.level, pr * info.patchRows, pc * info.patchCols);
        items.push_back({priority, key.level, 0, 0, key});
      }
    }
  }
  // Each patch once, though windows overlap (a renderer's runs of rows share patches).
  std::unordered_set<PatchKey, PatchKeyHash> seen;
  std::erase_if(items, [&](const Item& it) { return !seen.insert(it.key).second; });
  return items;
}

Prefetcher::Ticket Prefetcher::request(std::string_view grid,
                                       const std::vector<LevelWindow>& windows, int priority) {
  std::vector<Item> items = itemsOf(grid, windows, priority);
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  const Ticket ticket = s.nextTicket++;
  for (Item& it : items) {
    it.ticket = ticket;
    it.sequence = s.nextSequence++;
    s.queue.push(it);
  }
  if (!items.empty()) s.pending[ticket] = items.size();
  s.stats.queued += items.size();
  startTasks(lock);
  return ticket;
}

std::vector<LevelWindow> Prefetcher::focusWindows(std::string_view grid, std::size_t row,
                                                  std::size_t col, std::size_t radius,
                                                  std::size_t finestLevel) const {
  const GridInfo& info = state_->pager->grid(grid);
  std::vector<LevelWindow> out;
  for (std::size_t level = finestLevel; level < info.levels; ++level) {
    const std::size_t r = row >> level, c = col >> level;
    const std::size_t rad =
        std::max<std::size_t>(1, (radius + (std::size_t{1} << level) - 1) >> level);
    const std::size_t r0 = r > rad ? r - rad : 0, c0 = c > rad ? c - rad : 0;
    out.push_back({level, r0, c0, r + rad + 1 - r0, c + rad + 1 - c0});
  }
  return out;
}

void Prefetcher::cancel(Ticket ticket) {
  State& s = *state_;
  const std::lock_guard lock(s.mutex);
  std::vector<Item> keep;
  std::size_t dropped = 0;
  while (!s.queue.empty()) {
    if (s.queue.top().ticket == ticket) {
      ++dropped;
    } else {
      keep.push_back(s.queue.top());
    }
    s.queue.pop();
  }
  for (const Item& it : keep) s.queue.push(it);
  s.stats.cancelled += dropped;
  if (auto p = s.pending.find(ticket); p != s.pending.end()) {
    p->second -= dropped;
    if (p->second == 0) s.pending.erase(p);
  }
  s.done.notify_all();
}

void Prefetcher::wait(Ticket ticket) {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  s.done.wait(lock, [&] { return s.stopping || !s.pending.contains(ticket); });
}

void Prefetcher::waitIdle() {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  s.done.wait(lock, [&] { return s.stopping || (s.queue.empty() && s.busy == 0); });
}

PrefetchStats Prefetcher::stats() const {
  const std::lock_guard lock(state_->mutex);
  return state_->stats;
}

std::string Prefetcher::lastError() const {
  const std::lock_guard lock(state_->mutex);
  return state_->lastError;
}

void Prefetcher::setOnLoaded(std::function<void(const PatchKey&)> fn) {
  const std::lock_guard lock(state_->mutex);
  state_->onLoaded = std::move(fn);
}

void Prefetcher::loadItem(State& s, std::unique_lock<std::mutex>& lock, const Item& item) {
  ++s.busy;
  const auto onLoaded = s.onLoaded;
  lock.unlock();
  std::string error;
  try {
    (void)s.pager->patch(item.key);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (error.empty() && onLoaded) onLoaded(item.key);
  lock.lock();
  --s.busy;
  if (error.empty()) {
    ++s.stats.loaded;
  } else {
    ++s.stats.failed;
    s.lastError = std::move(error);
  }
  if (auto p = s.pending.find(item.ticket); p != s.pending.end() && --p->second == 0) {
    s.pending.erase(p);
  }
  s.done.notify_all();
}

void Prefetcher::work(const std::shared_ptr<State>& state) {
  State& s = *state;
  std::unique_lock lock(s.mutex);
  while (!s.stopping && !s.queue.empty()) {
    const Item item = s.queue.top();
    s.queue.pop();
    loadItem(s, lock, item);
  }
  --s.tasks;
  s.done.notify_all();
}

}  // namespace regolith::store
